"""The package's imports read from its source, for the house's measures (test_layers.py,
test_house.py): its modules, every import of a module (function-level, relative,
``importlib.import_module`` and shader paths named in strings included), and the strongly
connected components of a graph."""

from __future__ import annotations

import ast
import re
from dataclasses import dataclass
from pathlib import Path


@dataclass(frozen=True)
class Import:
    importer: str
    imported: str  # a module of the package, or the top-level name of another distribution
    file: str
    line: int
    # how: "import" (Python), "typing" (under ``if TYPE_CHECKING:``: never run), or "shader"
    # (a shader file named by its package path)
    how: str = "import"

    def where(self) -> str:
        return f"{self.file}:{self.line}: {self.importer} imports {self.imported}"


def find_modules(src: Path, package: str = "blueprint") -> dict[str, Path]:
    """Module name -> file for every .py file of ``package`` under ``src``."""
    modules = {}
    for path in sorted((src / package).rglob("*.py")):
        parts = path.relative_to(src).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        modules[".".join(parts)] = path
    return modules


def _absolute(module: str, is_package: bool, level: int, name: str | None) -> str:
    """The module named by ``from <level dots><name> import ...`` inside ``module``."""
    base = module.split(".")
    if not is_package:
        base = base[:-1]
    if level > 1:
        base = base[: len(base) - (level - 1)]
    return ".".join([*base, name] if name else base)


def _resolve(name: str, modules) -> str:
    """The longest known module that ``name`` is or lies in (``pkg.func`` -> ``pkg``)."""
    parts = name.split(".")
    while parts and ".".join(parts) not in modules:
        parts.pop()
    return ".".join(parts) if parts else name


SHADER_SUFFIXES = (".glsl", ".frag", ".vert", ".geom", ".comp")


def shader_package(text: str, package: str = "blueprint") -> str | None:
    """The package a shader path such as ``"blueprint.ops:glsl/edges.frag"`` names, else None."""
    match = re.fullmatch(rf"({re.escape(package)}(?:\.\w+)*):([\w./-]+)", text)
    return match.group(1) if match and match.group(2).endswith(SHADER_SUFFIXES) else None


def _typing_only(tree: ast.AST) -> set[int]:
    """ids of the import nodes under ``if TYPE_CHECKING:`` (annotations only; never run)."""
    held = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and (
            (isinstance(node.test, ast.Name) and node.test.id == "TYPE_CHECKING")
            or (isinstance(node.test, ast.Attribute) and node.test.attr == "TYPE_CHECKING")
        ):
            held.update(id(n) for top in node.body for n in ast.walk(top))
    return held


def imports_of(module: str, source: str, file: str, modules, package: str = "blueprint") -> list[Import]:
    """Every import in ``source`` at any depth: ``import``, ``from ... import`` (relative ones
    resolved, ``from pkg import submodule`` as the submodule), ``importlib.import_module``
    with a constant name, and shader files named by their package path (``how`` "shader");
    those under ``if TYPE_CHECKING:`` have ``how`` "typing"."""
    is_package = file.endswith("__init__.py")
    found: dict[Import, None] = {}
    tree = ast.parse(source, file)
    typing = _typing_only(tree)

    def add(name: str, node: ast.AST, how: str = "import") -> None:
        if name == package or name.startswith(package + "."):
            name = _resolve(name, modules)
        else:
            name = name.split(".")[0]
        found[Import(module, name, file, node.lineno, "typing" if id(node) in typing else how)] = None

    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                add(alias.name, node)
        elif isinstance(node, ast.ImportFrom):
            base = _absolute(module, is_package, node.level, node.module) if node.level else node.module
            for alias in node.names:
                sub = f"{base}.{alias.name}"
                add(sub if sub in modules else base, node)
        elif isinstance(node, ast.Constant) and isinstance(node.value, str):
            named = shader_package(node.value, package)
            if named is not None:
                add(named, node, "shader")
        elif (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Attribute | ast.Name)
            and (node.func.attr if isinstance(node.func, ast.Attribute) else node.func.id) == "import_module"
            and node.args
            and isinstance(node.args[0], ast.Constant)
            and isinstance(node.args[0].value, str)
            and not node.args[0].value.startswith(".")
        ):
            add(node.args[0].value, node)
    return list(found)


def components(graph: dict[str, list[str]]) -> list[set[str]]:
    """The strongly connected components of more than one node of ``graph`` (node -> the nodes
    it points to), by Tarjan's algorithm, iterative."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[set[str]] = []
    for start in sorted(graph):
        if start in index:
            continue
        index[start] = low[start] = len(index)
        stack.append(start)
        on_stack.add(start)
        work = [(start, iter(graph[start]))]
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is None:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[node])
                if low[node] == index[node]:
                    component = set()
                    top = None
                    while top != node:
                        top = stack.pop()
                        on_stack.discard(top)
                        component.add(top)
                    if len(component) > 1:
                        found.append(component)
            elif child not in index:
                index[child] = low[child] = len(index)
                stack.append(child)
                on_stack.add(child)
                work.append((child, iter(graph[child])))
            elif child in on_stack:
                low[node] = min(low[node], index[child])
    return sorted(found, key=min)
