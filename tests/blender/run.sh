#!/bin/sh
# The add-on (blender/) in Debian's Blender, installed by its install command into a fresh user folder.
#   run.sh live <mbi executable> <folder holding the mbi package> <work dir>
#     its message when mbi is not found, then live_cage.py under blender -b --factory-startup
#   run.sh undo <same>: undo_ui.py in Blender's UI under Xvfb (undo needs a window)
#   run.sh <name> <same>: <name>.py under blender -b --factory-startup
set -u
mode=$1 mbi_exe=$2 module_dir=$3 work=$4
if ! command -v blender > /dev/null 2>&1; then
  echo "skipped: blender is not installed (apt-get install blender)"; exit 77
fi
if [ ! -f "$module_dir/mbi/__init__.py" ]; then
  echo "skipped: the mbi Python module is not built in $module_dir (target mbi_python)"; exit 77
fi
if [ "$mode" = undo ] && ! command -v xvfb-run > /dev/null 2>&1; then
  echo "skipped: xvfb-run is not installed (apt-get install xvfb): undo needs Blender's window"; exit 77
fi
here=$(cd "$(dirname "$0")" && pwd)
install="$here/../../blender/install.py"
rm -rf "$work" && mkdir -p "$work/home" || exit 1
export HOME="$work/home"  # Blender's user folder: the add-on is installed there, not in the real one
unset MBI_PYTHON_DIR

if [ "$mode" = live ]; then
  echo "== install with a folder that holds no mbi: refused with the fix"
  blender -b --python "$install" -- --module-dir "$work/nowhere" > "$work/bad.txt" 2>&1
  code=$?
  cat "$work/bad.txt"
  [ "$code" = 1 ] || { echo "FAIL: exit code $code, expected 1"; exit 1; }
  grep -q "cannot import mbi" "$work/bad.txt" && grep -q "mbi module folder" "$work/bad.txt" ||
    { echo "FAIL: no message naming the fix"; exit 1; }
fi

echo "== install"
blender -b --python "$install" -- --module-dir "$module_dir" > "$work/install.txt" 2>&1
code=$?
cat "$work/install.txt"
[ "$code" = 0 ] && grep -q "installed and enabled" "$work/install.txt" || { echo "FAIL: install"; exit 1; }

if [ "$mode" = live ]; then
  echo "== cage, bind, animate, save, reopen, edit in place, bad input"
  MBI_PYTHON_DIR="$module_dir" blender -b --factory-startup --python "$here/live_cage.py" -- "$work" "$mbi_exe" \
    > "$work/out.txt" 2>&1
elif [ "$mode" != undo ]; then
  echo "== $mode.py"
  MBI_PYTHON_DIR="$module_dir" blender -b --factory-startup --python "$here/$mode.py" -- "$work" "$mbi_exe" \
    > "$work/out.txt" 2>&1
else
  echo "== undo and redo of a bind and of a cage edit, in the UI"
  MBI_PYTHON_DIR="$module_dir" xvfb-run -a blender --factory-startup --python "$here/undo_ui.py" -- "$work" \
    "$mbi_exe" > "$work/out.txt" 2>&1
fi
code=$?
cat "$work/out.txt"
[ "$code" = 0 ] && grep -q "^PASS" "$work/out.txt" || { echo "FAIL: $mode (exit code $code)"; exit 1; }
