"""The type stub (rangesynth/__init__.pyi) names exactly what the package has: every function,
class, method and property on both sides."""

import ast
from pathlib import Path

import rangesynth

STUB = Path(rangesynth.__file__).with_name("__init__.pyi")


def public(names):
    return {n for n in names if not n.startswith("_")}


def test_the_stub_and_the_package_name_the_same_things():
    tree = ast.parse(STUB.read_text())
    functions = {n.name for n in tree.body if isinstance(n, ast.FunctionDef)}
    classes = {n.name: n for n in tree.body if isinstance(n, ast.ClassDef)}
    assert public(functions | set(classes)) == set(rangesynth.__all__)
    for name, node in classes.items():
        stubbed = public(n.name for n in node.body if isinstance(n, ast.FunctionDef))
        runtime = public(dir(getattr(rangesynth, name))) - public(dir(Exception))
        assert stubbed == runtime, name
