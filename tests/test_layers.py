"""The package's layers only point down (see "Target layout" in ../shared/DESIGN.md).

An AST walk over ``src/blueprint`` finds every import, function-level ones included, and checks:

* each module belongs to a layer (``LAYERS``, matched by the longest package or module prefix);
* an import goes to a lower layer, or stays in its own layer where that layer's members may
  import each other (members of a ``siblings`` layer may not: render and ops, for one);
* a package restricted in ``ONLY`` imports nothing else of blueprint;
* no import cycle joins two members (packages, or modules placed on their own);
* only cli/ and viewer/ import the GUI libraries (click, glfw).

A shader named by its package path counts as an import of that package: a string such as
``"blueprint.ops:glsl/idsil_lines.geom"`` in a module, or an ``#include`` of another package's
shader in a shader file (whose module is the package its ``glsl`` folder lies in; an unqualified
include not found beside it is ``blueprint.gpu``'s, as ``gpu.shaders`` looks it up).

The checker itself is tested at the bottom on tiny fake packages, so that it cannot pass by
finding nothing.
"""

from __future__ import annotations

import ast
import re
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


def shader_imports(src: Path = SRC, package: str = "blueprint") -> list[Import]:
    """The ``#include`` lines of every shader file of ``package`` as imports of the package its
    ``glsl`` folder lies in: a qualified one of the package it names, an unqualified one not
    found beside the file of ``blueprint.gpu`` (as ``gpu.shaders`` resolves it)."""
    include = re.compile(r'^\s*#include\s+"([^"]+)"', re.MULTILINE)
    found = []
    for path in sorted((src / package).rglob("*")):
        if path.suffix not in SHADER_SUFFIXES or "glsl" not in path.parts:
            continue
        folder = next(up for up in path.parents if up.name == "glsl")
        module = ".".join(folder.parent.relative_to(src).parts)
        text = path.read_text(encoding="utf-8")
        for match in include.finditer(text):
            ref = match.group(1)
            if ":" in ref:
                named = ref.split(":", 1)[0]
            elif (path.parent / ref).is_file():
                continue
            else:
                named = f"{package}.gpu"
            line = text.count("\n", 0, match.start()) + 1
            found.append(Import(module, named, str(path.relative_to(src.parent)), line, "shader"))
    return found


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


def cycles_of(edges: dict[tuple[str, str], Import]) -> list[list[Import]]:
    """One cycle per strongly connected component of the graph of ``edges`` ((a, b) -> the
    import that makes a point to b): the shortest through the component's first node, as the
    imports that make it."""
    graph: dict[str, list[str]] = {}
    for a, b in sorted(edges):
        graph.setdefault(a, []).append(b)
        graph.setdefault(b, [])
    cycles = []
    for component in components(graph):
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


def member_cycles(imports, layers=LAYERS) -> list[list[Import]]:
    """Import cycles between members (``cycles_of`` the member graph): any import counts, a
    shader named or an annotation's too, since each ties one member to the other."""
    edges: dict[tuple[str, str], Import] = {}
    for imp in imports:
        a, b = member_of(imp.importer, layers), member_of(imp.imported, layers)
        if a and b and a != b:
            edges.setdefault((a, b), imp)
    return cycles_of(edges)


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
    """Every import of the package's modules, and its shader files' includes."""
    modules = find_modules(src)
    found = []
    for module, path in modules.items():
        file = str(path.relative_to(src.parent))
        found.extend(imports_of(module, path.read_text(encoding="utf-8"), file, modules))
    return found + shader_imports(src)


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
    # a shader file of pipeline/glsl includes one of render/glsl
    assert ("blueprint.pipeline", "blueprint.render") in found


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


def test_checker_counts_a_shader_named_by_its_package_path():
    imports = fake(
        {
            "pkg.base": 'LINES = "pkg.app:glsl/lines.geom"\nNOTES = "pkg.app:notes.txt"\nTEXT = "pkg.app"',
            "pkg.app": "",
        }
    )
    assert [(i.importer, i.imported, i.how) for i in imports] == [("pkg.base", "pkg.app", "shader")]
    assert problems(imports, FAKE, {}) == [
        "pkg/base.py:1: pkg.base imports pkg.app: upward: layer low imports layer high above it"
    ]


def test_checker_reads_the_includes_of_shader_files(tmp_path):
    shaders = tmp_path / "src" / "pkg" / "left" / "glsl"
    shaders.mkdir(parents=True)
    (shaders / "near.glsl").write_text("float near;\n")
    (shaders / "main.frag").write_text(
        '#include "pkg.app:glsl/other.glsl"\n#include "near.glsl"\nvoid main() {}\n#include "shared.glsl"\n'
    )
    (shaders / "notes.txt").write_text('#include "pkg.app:glsl/ignored.glsl"\n')
    assert shader_imports(tmp_path / "src", "pkg") == [
        Import("pkg.left", "pkg.app", "src/pkg/left/glsl/main.frag", 1, "shader"),
        Import("pkg.left", "pkg.gpu", "src/pkg/left/glsl/main.frag", 4, "shader"),
    ]


def test_checker_marks_imports_for_annotations_only():
    imports = fake(
        {
            "pkg.base": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from pkg.app import App\n",
            "pkg.app": "",
        }
    )
    assert {(i.imported, i.how) for i in imports} == {("typing", "import"), ("pkg.app", "typing")}
    # an annotation pointing up still breaks the layers
    assert problems(imports, FAKE, {}) == [
        "pkg/base.py:3: pkg.base imports pkg.app: upward: layer low imports layer high above it"
    ]
