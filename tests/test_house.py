"""Measures of the house (issue 37), read from the code: how many functions outside cli/ take
more than 12 parameters, and that the drawing options' modules import no file that imports
them back. The counters are tested on small sources of their own, so that they cannot pass by
finding nothing."""

from __future__ import annotations

import ast
from pathlib import Path

from test_layers import find_modules, imports_of

SRC = Path(__file__).resolve().parents[1] / "src"
PACKAGE = SRC / "blueprint"
MOST = 12

# Public entry points that may list every drawing option as keywords: none needs to, since
# ``blueprint.api.options.takes_options`` makes their keywords from DrawOptions' fields.
ALLOWED: set[str] = set()
# The layer capture's own, in its refactoring (render/, pipeline/executor.py, vector/occlusion/).
CAPTURE = {"pipeline/executor.py:run", "render/capture.py:__init__"}


def parameters(node: ast.FunctionDef | ast.AsyncFunctionDef) -> list[str]:
    """Every parameter of a function, ``*args`` and ``**kwargs`` included, but ``self`` and
    ``cls``."""
    a = node.args
    names = [p.arg for p in (*a.posonlyargs, *a.args, *a.kwonlyargs)]
    names += [p.arg for p in (a.vararg, a.kwarg) if p is not None]
    return [n for n in names if n not in ("self", "cls")]


def long_parameter_lists(root: Path, most: int = MOST) -> dict[str, int]:
    """``file:function`` -> parameter count of every function under ``root`` (cli/ left out)
    that takes more than ``most``."""
    found = {}
    for path in sorted(root.rglob("*.py")):
        where = path.relative_to(root).as_posix()
        if where.startswith("cli/"):
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), where)):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef) and len(parameters(node)) > most:
                found[f"{where}:{node.name}"] = len(parameters(node))
    return found


def file_cycles(modules: dict[str, Path], within: str) -> list[tuple[str, str]]:
    """Pairs of modules below package ``within`` (its ``__init__`` left out: it imports its
    modules, and its shared renderer is looked up from them) that import each other, at any
    depth of the file."""
    edges = set()
    for name, path in modules.items():
        if name.startswith(within + "."):
            for imp in imports_of(name, path.read_text(encoding="utf-8"), str(path), modules):
                edges.add((name, imp.imported))
    return sorted((a, b) for a, b in edges if a < b and (b, a) in edges)


def test_at_most_two_functions_outside_cli_take_more_than_twelve_parameters():
    found = long_parameter_lists(PACKAGE)
    assert len(ALLOWED) <= 2
    assert set(found) - CAPTURE <= ALLOWED, {k: v for k, v in found.items() if k not in CAPTURE | ALLOWED}


def test_the_api_modules_import_no_file_that_imports_them():
    assert file_cycles(find_modules(SRC), "blueprint.api") == []


def test_the_counters_find_what_they_should(tmp_path):
    (tmp_path / "cli").mkdir()
    many = ", ".join(f"a{i}" for i in range(12))
    (tmp_path / "mod.py").write_text(
        f"def twelve({many}): pass\n"
        f"def thirteen({many}, *rest): pass\n"
        f"class A:\n    def method(self, {many}): pass\n    def wide(self, {many}, **more): pass\n"
        f"def outer():\n    def inner({many}, *, b): pass\n"
    )
    (tmp_path / "cli" / "command.py").write_text(f"def command({many}, b, c): pass\n")
    assert long_parameter_lists(tmp_path) == {"mod.py:thirteen": 13, "mod.py:wide": 13, "mod.py:inner": 13}

    package = tmp_path / "src" / "blueprint"
    (package / "api").mkdir(parents=True)
    (package / "__init__.py").write_text("")
    (package / "api" / "__init__.py").write_text("from blueprint.api import three\n")
    (package / "api" / "one.py").write_text("def f():\n    from blueprint.api import two\n")
    (package / "api" / "two.py").write_text("from blueprint.api.one import f\n")
    (package / "api" / "three.py").write_text("from blueprint.api import one\nimport blueprint.api\n")
    modules = find_modules(tmp_path / "src")
    assert file_cycles(modules, "blueprint.api") == [("blueprint.api.one", "blueprint.api.two")]
