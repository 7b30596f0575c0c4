"""The package's layers only point down (see "Target layout" in ../shared/DESIGN.md).

An AST walk over ``src/blueprint`` finds every import, function-level ones included, and checks:

* each module belongs to a layer (``LAYERS``, matched by the longest package or module prefix);
* an import goes to a lower layer, or stays in its own layer where that layer's members may
  import each other (members of a ``siblings`` layer may not: render and ops, for one);
* a package restricted in ``ONLY`` imports nothing else of blueprint;
* no import cycle joins two members (packages, or modules placed on their own);
* only cli/ and viewer/ import the GUI libraries (click, glfw).

The checker itself is tested at the bottom on tiny fake packages, so that it cannot pass by
finding nothing.
"""

from __future__ import annotations

import ast
from dataclasses import dataclass
from itertools import pairwise
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src"


@dataclass(frozen=True)
class Layer:
    name: str
    members: tuple[str, ...]
    # members of a siblings layer may not import each other
    siblings: bool = False


# Lowest first. A member is a package or a module; a module belongs to the longest member that
# is its name or a package above it ("blueprint" itself matches only the top-level __init__).
LAYERS = (
    Layer(
        "leaves",
        (
            "blueprint.errors",
            "blueprint.color",
            "blueprint.settings",
            "blueprint.blas",
            "blueprint.columns",
            "blueprint.sorting",
            "blueprint.lazy",
        ),
    ),
    Layer("scene", ("blueprint.scene",)),
    # GPU-free code above the scene: the object-space silhouette method, the file writers and
    # the generated example models
    Layer("cpu", ("blueprint.silhouette", "blueprint.export", "blueprint.examples"), siblings=True),
    Layer("gpu", ("blueprint.gpu",)),
    # ops work on textures, not on peeling: neither knows the other
    Layer("render/ops", ("blueprint.render", "blueprint.ops"), siblings=True),
    # the GPU silhouettes (edge lines, ID buffer) use render and ops: they sit at the compose level
    Layer("compose", ("blueprint.compose", "blueprint.gpu_silhouettes"), siblings=True),
    Layer("pipeline", ("blueprint.pipeline",)),
    Layer("vector", ("blueprint.vector",)),
    Layer("api", ("blueprint.api", "blueprint")),
    Layer("tools", ("blueprint.bench",)),
    Layer("viewer", ("blueprint.viewer",)),
    Layer("cli", ("blueprint.cli", "blueprint.__main__")),
)

# Members that may import only these members (besides their own modules).
ONLY = {"blueprint.export": ("blueprint.errors", "blueprint.scene")}

GUI_LIBRARIES = ("click", "glfw")
GUI_MEMBERS = ("blueprint.cli", "blueprint.viewer")


# -- the checker -----------------------------------------------------------------------------------
@dataclass(frozen=True)
class Import:
    importer: str
    imported: str  # a module of the package, or the top-level name of another distribution
    file: str
    line: int

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


def imports_of(module: str, source: str, file: str, modules, package: str = "blueprint") -> list[Import]:
    """Every import in ``source`` at any depth: ``import``, ``from ... import`` (relative ones
    resolved, ``from pkg import submodule`` as the submodule) and ``importlib.import_module``
    with a constant name."""
    is_package = file.endswith("__init__.py")
    found: dict[Import, None] = {}

    def add(name: str, node: ast.AST) -> None:
        if name == package or name.startswith(package + "."):
            name = _resolve(name, modules)
        else:
            name = name.split(".")[0]
        found[Import(module, name, file, node.lineno)] = None

    for node in ast.walk(ast.parse(source, file)):
        if isinstance(node, ast.Import):
            for alias in node.names:
                add(alias.name, node)
        elif isinstance(node, ast.ImportFrom):
            base = _absolute(module, is_package, node.level, node.module) if node.level else node.module
            for alias in node.names:
                sub = f"{base}.{alias.name}"
                add(sub if sub in modules else base, node)
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


def member_of(module: str, layers=LAYERS) -> str | None:
    """The longest member of a layer that ``module`` is or lies in; a member without a dot (the
    top-level package) holds only its own ``__init__``."""
    best = None
    for layer in layers:
        for member in layer.members:
            inside = module == member or ("." in member and module.startswith(member + "."))
            if inside and (best is None or len(member) > len(best)):
                best = member
    return best


def _layer_index(member: str, layers) -> int:
    return next(i for i, layer in enumerate(layers) if member in layer.members)


def violations(imports, layers=LAYERS, only=ONLY) -> list[tuple[Import, str]]:
    """(import, rule broken) for every import that points up, sideways where forbidden, out of
    an ``only`` list, or to a GUI library outside cli/ and viewer/."""
    out = []
    for imp in imports:
        source = member_of(imp.importer, layers)
        if source is None:
            out.append((imp, f"{imp.importer} is in no layer: add it to LAYERS"))
            continue
        if imp.imported in GUI_LIBRARIES:
            if source not in GUI_MEMBERS:
                out.append((imp, f"only {' and '.join(GUI_MEMBERS)} may import {imp.imported}"))
            continue
        target = member_of(imp.imported, layers)
        if target is None or target == source:
            if target is None and imp.imported.split(".")[0] == imp.importer.split(".")[0]:
                out.append((imp, f"{imp.imported} is in no layer: add it to LAYERS"))
            continue
        if source in only and target not in only[source]:
            out.append((imp, f"{source} may import only {', '.join(only[source])}"))
            continue
        i, j = _layer_index(source, layers), _layer_index(target, layers)
        if j > i:
            out.append((imp, f"upward: layer {layers[i].name} imports layer {layers[j].name} above it"))
        elif j == i and layers[i].siblings:
            out.append((imp, f"sideways: {source} and {target} are siblings in layer {layers[i].name}"))
    return out


def member_cycles(imports, layers=LAYERS) -> list[list[Import]]:
    """Import cycles between members, one per strongly connected component of the member graph:
    the shortest cycle through the component's first member, as the imports that make it."""
    edges: dict[tuple[str, str], Import] = {}
    for imp in imports:
        a, b = member_of(imp.importer, layers), member_of(imp.imported, layers)
        if a and b and a != b:
            edges.setdefault((a, b), imp)
    graph: dict[str, list[str]] = {}
    for a, b in sorted(edges):
        graph.setdefault(a, []).append(b)
        graph.setdefault(b, [])

    # Tarjan's algorithm, iterative
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    components: list[set[str]] = []
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
                        components.append(component)
            elif child not in index:
                index[child] = low[child] = len(index)
                stack.append(child)
                on_stack.add(child)
                work.append((child, iter(graph[child])))
            elif child in on_stack:
                low[node] = min(low[node], index[child])

    cycles = []
    for component in sorted(components, key=min):
        first = min(component)
        # breadth-first from the first member back to it, inside the component
        parent: dict[str, str] = {}
        frontier = [first]
        while first not in parent:
            reached = []
            for node in frontier:
                for child in graph[node]:
                    if child in component and child not in parent:
                        parent[child] = node
                        reached.append(child)
            frontier = reached
        path = [first]
        while len(path) == 1 or path[-1] != first:
            path.append(parent[path[-1]])
        path.reverse()
        cycles.append([edges[pair] for pair in pairwise(path)])
    return cycles


def problems(imports, layers=LAYERS, only=ONLY) -> list[str]:
    """Every broken rule as one line naming the file, the line and the rule."""
    lines = [f"{imp.where()}: {rule}" for imp, rule in violations(imports, layers, only)]
    for cycle in member_cycles(imports, layers):
        members = " -> ".join(
            [member_of(imp.importer, layers) for imp in cycle] + [member_of(cycle[0].importer, layers)]
        )
        closing = "; ".join(imp.where() for imp in cycle)
        lines.append(f"import cycle {members}: {closing}")
    return lines


def package_imports(src: Path = SRC) -> list[Import]:
    modules = find_modules(src)
    found = []
    for module, path in modules.items():
        file = str(path.relative_to(src.parent))
        found.extend(imports_of(module, path.read_text(encoding="utf-8"), file, modules))
    return found


# -- the package -----------------------------------------------------------------------------------
def test_layers_only_point_down():
    found = problems(package_imports())
    assert not found, "\n".join(found)


def test_every_module_has_a_layer():
    homeless = [m for m in find_modules(SRC) if member_of(m) is None]
    assert not homeless, f"modules in no layer (add them to LAYERS): {', '.join(homeless)}"


def test_the_walk_sees_function_level_and_relative_imports():
    found = {(i.importer, i.imported) for i in package_imports()}
    assert ("blueprint.cli.render", "blueprint.api") in found  # inside the command's function
    assert ("blueprint.silhouette.edges", "blueprint.silhouette.mesh") in found  # from .mesh import
    assert ("blueprint.viewer.window", "glfw") in found  # inside a function, another distribution


# -- the checker on tiny fake packages ---------------------------------------------------------------
FAKE = (
    Layer("low", ("pkg.base",)),
    Layer("mid", ("pkg.left", "pkg.right"), siblings=True),
    Layer("high", ("pkg.app", "pkg.tool")),
)


def fake(sources: dict[str, str]) -> list[Import]:
    """Imports of fake modules given as {module name: source}; a name ending in .__init__ is a
    package."""
    names = {m.removesuffix(".__init__") for m in sources}
    found = []
    for module, source in sources.items():
        file = module.replace(".", "/") + ".py"
        found.extend(imports_of(module.removesuffix(".__init__"), source, file, names, package="pkg"))
    return found


def test_checker_passes_a_clean_fake_package():
    imports = fake(
        {
            "pkg.base": "import numpy",
            "pkg.left.__init__": "from pkg.base import x\nfrom . import core",
            "pkg.left.core": "from ..base import y",
            "pkg.app": "import pkg.left\nfrom pkg import tool",
            "pkg.tool": "import click",
        }
    )
    assert {(i.importer, i.imported) for i in imports} == {
        ("pkg.base", "numpy"),
        ("pkg.left", "pkg.base"),
        ("pkg.left", "pkg.left.core"),
        ("pkg.left.core", "pkg.base"),
        ("pkg.app", "pkg.left"),
        ("pkg.app", "pkg.tool"),
        ("pkg.tool", "click"),
    }
    assert violations(imports, FAKE, {}) == [
        (
            Import("pkg.tool", "click", "pkg/tool.py", 1),
            "only blueprint.cli and blueprint.viewer may import click",
        )
    ]


def test_checker_fails_an_upward_import_inside_a_function():
    imports = fake({"pkg.base": "def f():\n    from pkg.app import run\n    return run", "pkg.app": ""})
    assert problems(imports, FAKE, {}) == [
        "pkg/base.py:2: pkg.base imports pkg.app: upward: layer low imports layer high above it"
    ]


def test_checker_fails_a_sibling_import():
    imports = fake({"pkg.left": "import pkg.right.deep", "pkg.right.__init__": "", "pkg.right.deep": ""})
    assert problems(imports, FAKE, {}) == [
        "pkg/left.py:1: pkg.left imports pkg.right.deep: sideways: pkg.left and pkg.right are siblings "
        "in layer mid"
    ]


def test_checker_fails_a_cycle_within_a_layer_through_a_lazy_import():
    imports = fake(
        {
            "pkg.app.__init__": "from pkg.tool import helper",
            "pkg.tool": "import pkg.base\n\ndef helper():\n    import importlib\n"
            "    return importlib.import_module('pkg.app.main')",
            "pkg.app.main": "",
        }
    )
    assert problems(imports, FAKE, {}) == [
        "import cycle pkg.app -> pkg.tool -> pkg.app: pkg/app/__init__.py:1: pkg.app imports pkg.tool; "
        "pkg/tool.py:5: pkg.tool imports pkg.app.main"
    ]


def test_checker_finds_every_member_of_a_longer_cycle():
    three = (Layer("one", ("pkg.a", "pkg.b", "pkg.c", "pkg.d")),)
    imports = fake(
        {
            "pkg.a": "import pkg.b",
            "pkg.b": "import pkg.c",
            "pkg.c": "import pkg.a\nimport pkg.d",
            "pkg.d": "",
        }
    )
    [cycle] = member_cycles(imports, three)
    assert [(i.importer, i.imported) for i in cycle] == [
        ("pkg.a", "pkg.b"),
        ("pkg.b", "pkg.c"),
        ("pkg.c", "pkg.a"),
    ]


def test_checker_fails_an_import_outside_an_only_list_and_a_module_without_a_layer():
    imports = fake(
        {"pkg.tool": "from pkg import base, left", "pkg.base": "", "pkg.left": "", "pkg.extra": "import os"}
    )
    assert problems(imports, FAKE, {"pkg.tool": ("pkg.base",)}) == [
        "pkg/tool.py:1: pkg.tool imports pkg.left: pkg.tool may import only pkg.base",
        "pkg/extra.py:1: pkg.extra imports os: pkg.extra is in no layer: add it to LAYERS",
    ]
