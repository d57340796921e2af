#!/bin/sh
# with_xvfb.sh COMMAND...: runs COMMAND with DISPLAY on a private Xvfb server started for it and
# stopped after it, and exits with COMMAND's status alone (xvfb-run's own clean-up can fail and
# replace it). Xvfb picks a free display itself (-displayfd) and says when it is ready.
dir=$(mktemp -d) || exit 125
trap 'rm -rf "$dir"' EXIT
mkfifo "$dir/ready" || exit 125
Xvfb -displayfd 3 -screen 0 1400x900x24 -nolisten tcp 3>"$dir/ready" 2>"$dir/log" &
server=$!
if ! read -r display < "$dir/ready" || [ -z "$display" ]; then
  echo "with_xvfb.sh: Xvfb did not start:" >&2
  cat "$dir/log" >&2
  exit 125
fi
DISPLAY=":$display" "$@"
code=$?
kill "$server" 2>/dev/null
wait "$server" 2>/dev/null
exit "$code"
