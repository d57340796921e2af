"""The type stubs (mbi/_mbi.pyi) describe the extension module: every name the module has is in
the stubs with its methods and properties, the stubs name nothing the module lacks, every
function's parameters are the module's (names, order, keyword-only, defaults), and mypy's
stubtest finds no difference (read-only properties, types of constants)."""
import ast
import importlib.util
import os
import subprocess
import sys

import pytest

import mbi
from mbi import _errors, _mbi

STUBS = os.path.join(os.path.dirname(mbi.__file__), "_mbi.pyi")


def stub_names():
    tree = ast.parse(open(STUBS).read())
    names = {}
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            members = set()
            for item in node.body:
                if isinstance(item, ast.FunctionDef):
                    members.add(item.name)
                elif isinstance(item, ast.AnnAssign):
                    members.add(item.target.id)
            names[node.name] = members
        elif isinstance(node, ast.FunctionDef):
            names[node.name] = None
        elif isinstance(node, ast.AnnAssign) and (node.target.id.isupper() or node.target.id.startswith("_")):
            names[node.target.id] = None
    return names


def public(cls):
    return {n for n in dir(cls) if not n.startswith("_")}


def test_stubs_installed_beside_the_module():
    assert os.path.exists(STUBS)
    assert os.path.exists(os.path.join(os.path.dirname(mbi.__file__), "py.typed"))


def test_stubs_match_the_module():
    stubs = stub_names()
    module = {n for n in dir(_mbi) if not n.startswith("__")}
    assert module == set(stubs), (module ^ set(stubs))
    for name, members in stubs.items():
        if members is None:
            continue
        cls = getattr(_mbi, name)
        if issubclass(cls, BaseException):
            continue
        assert public(cls) == {m for m in members if not m.startswith("_")}, (name, public(cls) ^ members)


def test_every_public_name_is_exported():
    assert {n for n in dir(_mbi) if not n.startswith("_")} <= set(mbi.__all__)
    for name in mbi.__all__:
        assert hasattr(mbi, name), name


def stub_functions():
    """(owner, name, [(parameter, keyword-only, has a default)], overload) of every def in the
    stubs, overloads each, properties left out."""
    tree = ast.parse(open(STUBS).read())
    for node in tree.body:
        owner, defs = (node.name, node.body) if isinstance(node, ast.ClassDef) else (None, [node])
        for item in defs:
            if not isinstance(item, ast.FunctionDef):
                continue
            decorators = {d.id for d in item.decorator_list if isinstance(d, ast.Name)}
            if "property" in decorators:
                continue
            a = item.args
            positional = [p.arg for p in a.posonlyargs + a.args]
            if owner and "staticmethod" not in decorators:
                positional = positional[1:]  # self
            defaults = len(a.defaults)
            params = [(p, False, k >= len(positional) - defaults) for k, p in enumerate(positional)]
            params += [(p.arg, True, d is not None) for p, d in zip(a.kwonlyargs, a.kw_defaults)]
            yield owner, item.name, params, "overload" in decorators


def runtime_parameters(fn, method):
    """The same of a compiled function, from the signature pybind11 writes into its __doc__."""
    positional, keyword, kwargs = _errors.signature(fn)
    if method:
        positional = positional[1:]
    return [(p, False, d) for p, _, d in positional] + [(p, True, d) for p, _, d in keyword], kwargs


def test_every_signature_matches_the_module():
    checked = 0
    for owner, name, params, overload in stub_functions():
        if owner is None and not hasattr(_mbi, name):
            continue  # the stub's helpers
        where = getattr(_mbi, owner) if owner else _mbi
        fn = getattr(where, name)
        static = owner is not None and isinstance(vars(where).get(name), staticmethod)
        runtime, kwargs = runtime_parameters(fn, method=owner is not None and not static)
        if kwargs:  # **kwargs at run time (the simulator's parameters): the stub spells them out
            params = params[:len(runtime)]
        if overload:  # an overload may require what the function defaults (normals=True)
            params, runtime = [p[:2] for p in params], [p[:2] for p in runtime]
        assert params == runtime, (owner, name, params, runtime)
        checked += 1
    assert checked > 100  # every def of the stubs (102 now)


@pytest.mark.skipif(importlib.util.find_spec("mypy") is None, reason="needs mypy (python3-mypy)")
def test_stubtest_finds_no_difference():
    here = os.path.dirname(__file__)
    package = os.path.dirname(os.path.dirname(mbi.__file__))
    env = dict(os.environ, MYPYPATH=package)
    result = subprocess.run([sys.executable, "-m", "mypy.stubtest", "mbi._mbi", "--mypy-config-file",
                             os.path.join(here, os.pardir, "mypy.ini"), "--allowlist",
                             os.path.join(here, "stubtest_allowlist.txt")],
                            capture_output=True, text=True, env=env, timeout=600)
    assert result.returncode == 0, result.stdout + result.stderr


def test_timing_is_typed_and_none_in_the_shipped_module():
    assert "_timing: Optional[types.ModuleType]" in open(STUBS).read()
    assert _mbi._timing is None or hasattr(_mbi._timing, "last_call")
