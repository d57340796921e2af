"""Installs the mbi add-on into the user's Blender, enables it and saves the preferences.

    blender -b --python blender/install.py -- [--module-dir <mbi build>/python]

Copies blender/mbi_blender into Blender's user add-ons folder (replacing an older copy).
--module-dir: where the mbi package is, when Blender's Python does not find it alone.
"""
import argparse
import os
import shutil
import sys

import addon_utils
import bpy

NAME = "mbi_blender"


def main(argv):
    parser = argparse.ArgumentParser(prog="blender -b --python install.py --")
    parser.add_argument("--module-dir", default="", help="folder holding the mbi package")
    args = parser.parse_args(argv)
    source = os.path.join(os.path.dirname(os.path.abspath(__file__)), NAME)
    target = os.path.join(bpy.utils.user_resource("SCRIPTS", path="addons", create=True), NAME)
    shutil.rmtree(target, ignore_errors=True)
    shutil.copytree(source, target, ignore=shutil.ignore_patterns("__pycache__"))
    bpy.utils.refresh_script_paths()  # a user add-ons folder made just now is not on the path yet
    addon_utils.enable(NAME, default_set=True, persistent=True)
    if args.module_dir:
        bpy.context.preferences.addons[NAME].preferences.module_dir = os.path.abspath(args.module_dir)
    from mbi_blender import module
    try:
        module.load()
    except RuntimeError as error:
        print("mbi add-on installed in %s, but: %s" % (target, error))
        bpy.ops.wm.save_userpref()
        return 1
    bpy.ops.wm.save_userpref()
    print("mbi add-on installed and enabled: %s" % target)
    return 0


if __name__ == "__main__":
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    sys.exit(main(argv))
