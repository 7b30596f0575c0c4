"""Measures of the house (issue 37), read from the code: how many functions outside cli/ take
more than 12 parameters, how many functions are longer than 100 lines, that no file of the
package imports a file that imports it back, through any number of files, and that the tests
mirror the package. The counters are tested on small sources of their own, so that they cannot
pass by finding nothing."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

from import_graph import components, find_modules, imports_of

SRC = Path(__file__).resolve().parents[1] / "src"
PACKAGE = SRC / "blueprint"
TESTS = SRC.parent / "tests"
MOST = 12

# Public entry points that may list every drawing option as keywords: none needs to, since
# ``blueprint.api.options.takes_options`` makes their keywords from DrawOptions' fields.
ALLOWED: set[str] = set()
LONGEST = 100
# The functions longer than LONGEST lines, five at most: each named, so that a new one fails.
LONG: set[str] = set()


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


# File-level import cycles allowed: none (a cycle a change brings in fails here, named).
KNOWN_CYCLES: set[frozenset[str]] = set()


def long_functions(root: Path, longest: int = LONGEST) -> dict[str, int]:
    """``file:function`` -> lines of every function under ``root`` longer than ``longest``
    lines, from its ``def`` to its last line (decorators left out, docstring counted)."""
    found = {}
    for path in sorted(root.rglob("*.py")):
        where = path.relative_to(root).as_posix()
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), where)):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                lines = node.end_lineno - node.lineno + 1
                if lines > longest:
                    found[f"{where}:{node.name}"] = lines
    return found


def file_cycles(modules: dict[str, Path]) -> list[set[str]]:
    """The sets of modules that import one another round a cycle of any length (the strongly
    connected components of the file import graph), imports inside functions and those for
    annotations (``if TYPE_CHECKING:``) included. Left out: shader paths (they name a package's
    files, not its modules), and a package's ``__init__`` importing its own modules (it holds
    them: a module may look a name up in its package's ``__init__``)."""
    graph: dict[str, list[str]] = {name: [] for name in modules}
    for name, path in modules.items():
        package = path.name == "__init__.py"
        for imp in imports_of(name, path.read_text(encoding="utf-8"), str(path), modules):
            inside = package and imp.imported.startswith(name + ".")
            if imp.how != "shader" and imp.imported in modules and imp.imported != name and not inside:
                graph[name].append(imp.imported)
    return components(graph)


# The test files that stay at tests/, each testing the whole product rather than one package, and
# why; any other there is named after a module at the package's root (test_sorting.py: sorting.py).
WHOLE_PRODUCT = {
    "test_golden.py": "golden frames of every style, through the whole drawing",
    "test_layers_oracle.py": "every way of capturing layers, and `blueprint layers`, against ray casting",
    "test_hlr_oracle.py": "drawings of STEP parts, through the command, against exact hidden-line removal",
    "test_hostile.py": "every file the product reads or writes, through the command line",
    "test_notebook.py": "the example notebook in a real Jupyter kernel",
    "test_docs.py": "the README and docs/ against the code",
    "test_package.py": "the wheel as pip builds it",
    "test_layers.py": "the import layers of the whole package",
    "test_house.py": "the measures of the whole package and of its tests",
}


def misplaced_tests(tests: Path, package: Path, whole_product=WHOLE_PRODUCT) -> list[str]:
    """Every test file under ``tests`` out of the package's mirror, with why: one at the top
    neither in ``whole_product`` nor named after a module at ``package``'s root, one in a folder
    that is no package of ``package`` (``tests/scene/`` mirrors ``scene/``), or in a folder
    without ``__init__.py`` (pytest would take two test files of one name for one module)."""
    found = []
    for path in sorted(tests.rglob("test_*.py")):
        where = path.relative_to(tests)
        folder = where.parent
        if folder == Path("."):
            module = package / where.name.removeprefix("test_")
            if where.name not in whole_product and not module.is_file():
                found.append(f"{where}: at the top, neither whole-product nor named after a module there")
        elif not (package / folder / "__init__.py").is_file():
            found.append(f"{where}: {folder.as_posix()}/ is no package of {package.name}")
        elif not all((tests / up / "__init__.py").is_file() for up in [folder, *folder.parents[:-1]]):
            found.append(f"{where}: {folder.as_posix()}/ or a folder above it has no __init__.py")
    return found


def imports_of_test_files(tests: Path) -> list[str]:
    """``file:line`` of every import of a test module (``test_*``) under ``tests``: what tests
    share lives in helper modules and ``conftest.py``."""
    found = []
    for path in sorted(tests.rglob("*.py")):
        where = path.relative_to(tests).as_posix()
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), where)):
            if isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom):
                names = [f"{node.module or ''}.{alias.name}" for alias in node.names]
            else:
                continue
            if any(part.startswith("test_") for name in names for part in name.split(".")):
                found.append(f"{where}:{node.lineno}")
    return found


def test_at_most_two_functions_outside_cli_take_more_than_twelve_parameters():
    found = long_parameter_lists(PACKAGE)
    assert len(ALLOWED) <= 2
    assert set(found) <= ALLOWED, {k: v for k, v in found.items() if k not in ALLOWED}


def test_at_most_five_functions_are_longer_than_a_hundred_lines():
    found = long_functions(PACKAGE)
    assert len(LONG) <= 5
    assert set(found) <= LONG, {k: v for k, v in found.items() if k not in LONG}


def test_no_file_imports_a_file_that_imports_it():
    found = {frozenset(cycle) for cycle in file_cycles(find_modules(SRC))}
    assert found <= KNOWN_CYCLES, [sorted(cycle) for cycle in found - KNOWN_CYCLES]


def test_the_tests_mirror_the_package():
    assert misplaced_tests(TESTS, PACKAGE) == []
    assert imports_of_test_files(TESTS) == []
    assert all((TESTS / name).is_file() for name in WHOLE_PRODUCT)


def test_the_function_blueprint_render_is_not_hidden_by_the_subpackage_render():
    # (the subpackage keeps its name: renaming it would touch most files of the tree)
    code = (
        "import blueprint.render.capture, blueprint\n"
        "from blueprint.render.table import choose\n"
        "from blueprint.api.frames import peel, render\n"
        "assert (blueprint.render, blueprint.peel) == (render, peel), blueprint.render\n"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr


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

    def body(indent: int) -> str:
        return "".join(f"{' ' * indent}x{i} = {i}\n" for i in range(98))

    (tmp_path / "long.py").write_text(
        f'@decorated\ndef hundred():\n    """Doc."""\n{body(4)}'
        f'class C:\n    def longer(self):\n        """Doc\n        on two lines."""\n{body(8)}'
        f"    def nested(self):\n        def inner():\n{body(12)}            return 1\n"
    )
    assert long_functions(tmp_path) == {"long.py:longer": 101, "long.py:nested": 101}

    package = tmp_path / "src" / "blueprint"
    (package / "api").mkdir(parents=True)
    (package / "gpu").mkdir(parents=True)
    (package / "__init__.py").write_text("")
    (package / "api" / "__init__.py").write_text("from blueprint.api import three\n")
    (package / "api" / "one.py").write_text("def f():\n    from blueprint.api import two\n")
    (package / "api" / "two.py").write_text("from blueprint.api.one import f\n")
    (package / "api" / "three.py").write_text("from blueprint.api import one\nimport blueprint.api\n")
    (package / "gpu" / "__init__.py").write_text("")
    (package / "gpu" / "a.py").write_text("from blueprint.gpu import b\n")
    (package / "gpu" / "b.py").write_text("import blueprint.gpu.c\nSHADER = 'blueprint.gpu.d:glsl/x.frag'\n")
    (package / "gpu" / "c.py").write_text("import blueprint.gpu.a\n")
    (package / "gpu" / "d.py").write_text("from blueprint.gpu.b import SHADER\n")
    (package / "gpu" / "e.py").write_text(
        "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from blueprint.gpu.f import F\n"
    )
    (package / "gpu" / "f.py").write_text("from blueprint.gpu import e\n")
    modules = find_modules(tmp_path / "src")
    # three files round one cycle; an annotation's import closes one, a shader path none
    assert file_cycles(modules) == [
        {"blueprint.api.one", "blueprint.api.two"},
        {"blueprint.gpu.a", "blueprint.gpu.b", "blueprint.gpu.c"},
        {"blueprint.gpu.e", "blueprint.gpu.f"},
    ]


def test_the_mirror_check_finds_what_it_should(tmp_path):
    package, tests = tmp_path / "src" / "blueprint", tmp_path / "tests"
    for folder in (
        package / "scene" / "formats",
        package / "render",
        tests / "scene" / "formats",
        tests / "render",
    ):
        folder.mkdir(parents=True)
    for module in ("scene/__init__.py", "scene/formats/__init__.py", "render/__init__.py", "sorting.py"):
        (package / module).write_text("")
    for name in ("scene/__init__.py", "scene/formats/__init__.py", "conftest.py", "helpers.py"):
        (tests / name).write_text("")
    (tests / "views").mkdir()
    for name in (
        "test_sorting.py",
        "test_docs.py",
        "test_stray.py",
        "scene/test_model.py",
        "scene/formats/test_obj.py",
    ):
        (tests / name).write_text("")
    (tests / "render" / "test_peel.py").write_text("from test_sorting import x\n")
    (tests / "views" / "test_front.py").write_text("import helpers\nfrom scene import test_model\n")
    (tests / "views" / "__init__.py").write_text("")
    assert misplaced_tests(tests, package, {"test_docs.py": "the docs"}) == [
        "render/test_peel.py: render/ or a folder above it has no __init__.py",
        "test_stray.py: at the top, neither whole-product nor named after a module there",
        "views/test_front.py: views/ is no package of blueprint",
    ]
    assert imports_of_test_files(tests) == ["render/test_peel.py:1", "views/test_front.py:2"]
