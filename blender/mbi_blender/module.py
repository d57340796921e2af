"""Finds the mbi Python module for Blender's interpreter, or says in one message how to fix it."""
import importlib
import os
import sys

ENV_DIR = "MBI_PYTHON_DIR"  # a folder holding the package mbi (e.g. <build>/python), as the preference


def _preference_dir():
    addon = __package__ and _addon_preferences()
    return addon.module_dir if addon else ""


def _addon_preferences():
    import bpy
    entry = bpy.context.preferences.addons.get(__package__)
    return entry.preferences if entry else None


def _put_on_path(folder):
    folder = os.path.abspath(os.path.expanduser(folder))
    if folder not in sys.path:
        sys.path.insert(0, folder)


def load():
    """The mbi module; raises RuntimeError with the fix when Blender's Python cannot import it."""
    for folder in (_preference_dir(), os.environ.get(ENV_DIR, "")):
        if folder:
            _put_on_path(folder)
    try:
        mbi = importlib.import_module("mbi")
    except ImportError as error:
        raise RuntimeError(missing_message(error)) from error
    built = getattr(importlib.import_module("mbi._build"), "VERSION", None)
    here = "%d.%d" % sys.version_info[:2]
    if built is not None and built != here:
        raise RuntimeError("mbi was built for Python %s, Blender runs Python %s (prefix %s): %s"
                           % (built, here, sys.base_prefix, _fix()))
    return mbi


def _fix():
    return ("set the add-on's preference 'mbi module folder' (or the environment variable %s) to a folder "
            "holding an mbi built for this Python: <mbi build>/python, or the site-packages of a virtual "
            "environment where mbi was pip-installed (Debian's Blender runs /usr/bin/python3: build with that); "
            "a blender.org build ships its own Python, for which mbi must be built with "
            "-DPython_EXECUTABLE=<its python>" % ENV_DIR)


def missing_message(error):
    return "Blender's Python %d.%d (prefix %s) cannot import mbi (%s): %s" % (
        sys.version_info[0], sys.version_info[1], sys.base_prefix, str(error).splitlines()[0], _fix())
