#!/bin/sh
# The add-on (blender/) in Debian's Blender: installed by its install command into a fresh user
# folder, its message when mbi is not found, then live_cage.py under --factory-startup.
#   run.sh <mbi executable> <folder holding the mbi package> <work dir>
set -u
mbi_exe=$1 module_dir=$2 work=$3
if ! command -v blender > /dev/null 2>&1; then
  echo "skipped: blender is not installed (apt-get install blender)"; exit 77
fi
if [ ! -f "$module_dir/mbi/__init__.py" ]; then
  echo "skipped: the mbi Python module is not built in $module_dir (target mbi_python)"; exit 77
fi
here=$(cd "$(dirname "$0")" && pwd)
install="$here/../../blender/install.py"
rm -rf "$work" && mkdir -p "$work/home" || exit 1
export HOME="$work/home"  # Blender's user folder: the add-on is installed there, not in the real one
unset MBI_PYTHON_DIR

echo "== install with a folder that holds no mbi: refused with the fix"
blender -b --python "$install" -- --module-dir "$work/nowhere" > "$work/bad.txt" 2>&1
code=$?
cat "$work/bad.txt"
[ "$code" = 1 ] || { echo "FAIL: exit code $code, expected 1"; exit 1; }
grep -q "cannot import mbi" "$work/bad.txt" && grep -q "mbi module folder" "$work/bad.txt" ||
  { echo "FAIL: no message naming the fix"; exit 1; }

echo "== install"
blender -b --python "$install" -- --module-dir "$module_dir" > "$work/install.txt" 2>&1
code=$?
cat "$work/install.txt"
[ "$code" = 0 ] && grep -q "installed and enabled" "$work/install.txt" || { echo "FAIL: install"; exit 1; }

echo "== cage, bind, animate, save, reopen"
MBI_PYTHON_DIR="$module_dir" blender -b --factory-startup --python "$here/live_cage.py" -- "$work" "$mbi_exe" \
  > "$work/live.txt" 2>&1
code=$?
cat "$work/live.txt"
[ "$code" = 0 ] && grep -q "^PASS" "$work/live.txt" || { echo "FAIL: live_cage.py (exit code $code)"; exit 1; }
