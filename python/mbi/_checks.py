"""What `import mbi` checks before it loads the compiled module: that the module was built for
this interpreter (its ABI tag) and that this interpreter has numpy, each with an ImportError that
says which interpreter the module was built for and how to get one that works."""
import glob
import importlib.machinery
import importlib.util
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))


def this_python() -> str:
    return f"{sys.executable} ({sys.version_info.major}.{sys.version_info.minor})"


def built_for() -> str:
    """The interpreter CMake built mbi._mbi for, as "path (version)" (mbi/_build.py)."""
    try:
        from . import _build
    except ImportError:
        return "another Python"
    return f"{_build.PYTHON} ({_build.VERSION})"


def built_python() -> str:
    built = built_for()
    return built.split(" (")[0] if built != "another Python" else "python3"


def require_module() -> None:
    """Raises ImportError when mbi/_mbi*.so is absent or built for another Python."""
    if importlib.util.find_spec("mbi._mbi") is not None:
        return
    built = sorted(os.path.basename(f) for f in glob.glob(os.path.join(HERE, "_mbi.*")) if not f.endswith(".pyi"))
    if not built:
        raise ImportError(f"mbi's compiled module (_mbi) is missing from {HERE}: build it (cmake --build --preset "
                          f"release --target mbi_python) or pip install mbi (docs/python.md, Install)")
    wanted = [s for s in importlib.machinery.EXTENSION_SUFFIXES if s != ".so"][0]
    raise ImportError(f"mbi's compiled module {built[0]} was built for {built_for()}; this is {this_python()}, which "
                      f"loads _mbi{wanted}: run {built_python()}, or build mbi for this interpreter "
                      f"({sys.executable} -m pip install --no-build-isolation --no-index <mbi source>/python, in a "
                      f"virtual environment; docs/python.md, Install)")


def require_numpy() -> None:
    """Raises ImportError when this interpreter has no numpy."""
    try:
        import numpy  # noqa: F401
    except ImportError as e:
        raise ImportError(f"mbi needs numpy, which this interpreter, {this_python()}, cannot import ({e}); mbi was "
                          f"built for {built_for()}: run that one, or a virtual environment made from it that sees "
                          f"its numpy ({built_python()} -m venv --system-site-packages VENV; docs/python.md, "
                          f"Install)") from None

