"""pip install of the package mbi (docs/python.md, "Install"): the pure-Python package of this
folder and the compiled module mbi._mbi, built by CMake from the repository for the interpreter
that runs pip (-DPython_EXECUTABLE), target mbi_python and what it needs, in
build/pip-<ABI tag> (kept between installs: a second install compiles only what changed).

MBI_PYTHON_BUILD_DIR=<a CMake build tree> (e.g. build/release) takes the module already built
there instead of compiling it again (CI's one build); it must be built for this interpreter.
The version is the project's (CMakeLists.txt)."""
import os
import re
import shutil
import subprocess
import sys
import sysconfig

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
SUFFIX = sysconfig.get_config_var("EXT_SUFFIX")  # _mbi.cpython-311-x86_64-linux-gnu.so


def project_version():
    with open(os.path.join(ROOT, "CMakeLists.txt"), encoding="utf-8") as f:
        return re.search(r"project\(mbi\s+VERSION\s+([0-9.]+)", f.read()).group(1)


def cmake_build():
    """Configures and builds mbi_python for this interpreter; returns the build tree."""
    try:
        import numpy  # noqa: F401  (CMake builds no module for an interpreter without it)
    except ImportError:
        raise RuntimeError(f"mbi needs numpy in the interpreter that runs pip, {sys.executable}: make the virtual "
                           f"environment with /usr/bin/python3 -m venv --system-site-packages (Debian's numpy)")
    tree = os.path.join(ROOT, "build", "pip-" + SUFFIX.strip(".").rsplit(".", 1)[0])
    subprocess.run(["cmake", "-S", ROOT, "-B", tree, "-DCMAKE_BUILD_TYPE=Release", f"-DPython_EXECUTABLE={sys.executable}",
                    "-DMBI_BUILD_PYTHON=ON", "-DMBI_BUILD_TESTS=OFF", "-DMBI_BUILD_BENCH=OFF"], check=True)
    jobs = os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL", str(os.cpu_count() or 1))
    subprocess.run(["cmake", "--build", tree, "--target", "mbi_python", "-j", jobs], check=True)
    return tree


class CMakeBuild(build_ext):
    """Puts the CMake-built mbi/_mbi<ABI>.so and mbi/_build.py (the interpreter it is for) into
    the wheel."""

    def build_extension(self, ext):
        tree = os.environ.get("MBI_PYTHON_BUILD_DIR") or cmake_build()
        built = os.path.join(os.path.abspath(tree), "python", "mbi")
        module = os.path.join(built, "_mbi" + SUFFIX)
        if not os.path.isfile(module):
            found = [f for f in os.listdir(built) if f.startswith("_mbi.")] if os.path.isdir(built) else []
            raise RuntimeError(f"MBI_PYTHON_BUILD_DIR={tree}: no _mbi{SUFFIX} for {sys.executable} there (found: "
                               f"{', '.join(found) or 'nothing'}); build the target mbi_python there for this "
                               f"interpreter (-DPython_EXECUTABLE={sys.executable}), or unset MBI_PYTHON_BUILD_DIR")
        target = self.get_ext_fullpath(ext.name)
        os.makedirs(os.path.dirname(target), exist_ok=True)
        shutil.copyfile(module, target)
        shutil.copyfile(os.path.join(built, "_build.py"), os.path.join(os.path.dirname(target), "_build.py"))


os.makedirs(os.path.join(HERE, "build"), exist_ok=True)  # setuptools' scratch (ignored by git), metadata too
setup(
    name="mbi",
    version=project_version(),
    description="Physics-driven deformation of dense meshes by modified barycentric interpolation",
    python_requires=">=3.8",
    packages=["mbi"],
    package_data={"mbi": ["py.typed", "_mbi.pyi"]},
    ext_modules=[Extension("mbi._mbi", sources=[])],
    cmdclass={"build_ext": CMakeBuild},
    zip_safe=False,
    options={"egg_info": {"egg_base": os.path.join(HERE, "build")}},
)
