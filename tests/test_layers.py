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

import re
from dataclasses import dataclass
from itertools import pairwise
from pathlib import Path

from import_graph import SHADER_SUFFIXES, Import, components, find_modules, imports_of

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
            "blueprint.allocator",
            "blueprint.color",
            "blueprint.settings",
            "blueprint.blas",
            "blueprint.columns",
            "blueprint.sorting",
            "blueprint.parallel",
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

# Members that may import only these members (besides their own modules): the writers take the
# base's settings and thread pool (a big PNG deflated in pieces side by side), nothing that draws.
ONLY = {
    "blueprint.export": ("blueprint.errors", "blueprint.settings", "blueprint.parallel", "blueprint.scene")
}

GUI_LIBRARIES = ("click", "glfw")
GUI_MEMBERS = ("blueprint.cli", "blueprint.viewer")


# -- the checker -----------------------------------------------------------------------------------
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
