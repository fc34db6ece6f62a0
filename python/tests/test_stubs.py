"""The type stubs name every public function, class and member of the module, and nothing else."""

import ast
import pathlib

import rgbl

STUB = pathlib.Path(rgbl.__file__).with_name("__init__.pyi")


def stub_names():
    tree = ast.parse(STUB.read_text())
    top, members = set(), {}
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            top.add(node.name)
        if isinstance(node, ast.ClassDef):
            names = set()
            for item in node.body:
                if isinstance(item, ast.FunctionDef):
                    names.add(item.name)
                elif isinstance(item, ast.AnnAssign):
                    names.add(item.target.id)
                elif isinstance(item, ast.Assign):
                    names.update(t.id for t in item.targets)
            members[node.name] = {n for n in names if not n.startswith("_")}
    return top, members


def test_stubs_cover_the_module():
    top, members = stub_names()
    assert top == set(rgbl.__all__) - {"__version__"}
    for name in rgbl.__all__:
        value = getattr(rgbl, name)
        if isinstance(value, type) and not issubclass(value, BaseException):
            public = {m for m in vars(value) if not m.startswith("_")}
            if hasattr(value, "__members__"):  # a pybind11 enum: name and value are Python's
                public -= {"name", "value"}
            assert members[name] == public, name


def test_help_reads_well():
    doc = rgbl.System.track.__doc__
    assert "track(self: rgbl.System, image" in doc and "GIL is released" in doc
    assert rgbl.System.__module__ == "rgbl"
    assert "rgbl run" in rgbl.Pipeline.__doc__
