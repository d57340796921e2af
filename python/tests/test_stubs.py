"""The type stubs (mbi/_mbi.pyi) describe the extension module: every name the module has is in
the stubs with its methods and properties, and the stubs name nothing the module lacks."""
import ast
import os

import mbi
from mbi import _mbi

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
        elif isinstance(node, ast.AnnAssign) and node.target.id.isupper():
            names[node.target.id] = None
    return names


def public(cls):
    return {n for n in dir(cls) if not n.startswith("_")}


def test_stubs_installed_beside_the_module():
    assert os.path.exists(STUBS)
    assert os.path.exists(os.path.join(os.path.dirname(mbi.__file__), "py.typed"))


def test_stubs_match_the_module():
    stubs = stub_names()
    module = {n for n in dir(_mbi) if not n.startswith("__") and n != "_timing"}
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
