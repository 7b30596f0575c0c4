"""The installed package, from outside the source tree: every command and each major option, on
the shipped example model and models written here, each case checked by what it wrote.

Run by the python of a virtualenv that has the wheel installed without test extras (.ci/wheel.sh
does that); it prints one line per case (name, ok or FAIL, seconds, what was checked) and exits
1 if any case failed. The last cases install Jupyter's packages into that virtualenv, as a
notebook user would have them beside blueprint, and draw in a kernel.

    python .ci/smoke.py [--keep DIR]
"""

from __future__ import annotations

import argparse
import base64
import io
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
import traceback
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
from PIL import Image

import blueprint
from blueprint import examples

PACKAGE = Path(blueprint.__file__).resolve().parent
SCRIPT = Path(sys.executable).parent / "blueprint"
SIZE = ("320", "240")
GEARBOX_PARTS = examples.gearbox().part_names
# an L-shaped bracket outline (mm, counter-clockwise) extruded 30 mm: a STEP solid with a
# hidden inner corner from the iso view
BRACKET = [(0.0, 0.0), (80.0, 0.0), (80.0, 12.0), (14.0, 12.0), (14.0, 50.0), (0.0, 50.0)]
BRACKET_HEIGHT = 30.0
GLYPHS = """\
[[box]]
min = [-7, 14, -26]
max = [7, 66, 26]
color = "#ff8800"
width = 2

[[arrow]]
from = [-45, 110, 55]
to = [-45, 53, 0]
color = "#ff3b6b"
width = 2.5
label = "left bearing"
"""

LINES = """\
base = "paper"
paper = "#ffffff"

[[levels]]
color = "#000000"
width = 1.4

[[levels]]
color = "#1d4f91"
dash = [6, 3]
"""

CASES = []


class Failure(Exception):
    """A case's check that did not hold: the message is the case's line."""


def case(name):
    """Add the function to the cases, run in the order they are written."""

    def add(fn):
        CASES.append((name, fn))
        return fn

    return add


def check(condition, message):
    if not condition:
        raise Failure(message)


def cli(*args, expect=0, env=None, command=None):
    """Run the console script (or ``command``) and fail unless it exits with ``expect``."""
    proc = subprocess.run(
        [*(command or [str(SCRIPT)]), *map(str, args)], capture_output=True, text=True, env=env, timeout=300
    )
    if proc.returncode != expect:
        tail = (proc.stderr.strip() or proc.stdout.strip()).splitlines()[-3:]
        raise Failure(f"exit {proc.returncode}, not {expect}: {' | '.join(tail)}")
    return proc


def ink(image) -> tuple[float, np.ndarray]:
    """Fraction of pixels away from the paper (the commonest colour), and the RGBA array."""
    if not isinstance(image, np.ndarray):
        image = np.asarray(Image.open(image).convert("RGBA"))
    pixels = image.reshape(-1, 4).astype(np.int16)
    colours, counts = np.unique(pixels, axis=0, return_counts=True)
    paper = colours[counts.argmax()]
    away = np.abs(pixels - paper).max(axis=1) > 48
    return float(away.mean()), image


def drawn(path, size=SIZE, low=0.01, high=0.6) -> tuple[float, np.ndarray]:
    """A PNG of ``size`` whose ink covers between ``low`` and ``high`` of it."""
    path = Path(path)
    check(path.is_file() and path.stat().st_size > 0, f"{path.name} not written")
    fraction, image = ink(path)
    w, h = map(int, size)
    check(image.shape[:2] == (h, w), f"{path.name} is {image.shape[1]}x{image.shape[0]}, not {w}x{h}")
    check(low <= fraction <= high, f"{path.name}: ink on {fraction:.1%} of it")
    return fraction, image


def differs(a: np.ndarray, b: np.ndarray) -> float:
    """Fraction of pixels that differ between two RGBA images of one size."""
    return float((np.abs(a.astype(np.int16) - b.astype(np.int16)).max(axis=2) > 48).mean())


def svg_paths(path) -> tuple[ET.Element, dict[str, int]]:
    """The SVG's root, and how many drawing elements each group holds (nested ones included)."""
    root = ET.parse(path).getroot()
    groups = {}
    for g in root.iter("{http://www.w3.org/2000/svg}g"):
        kinds = ("path", "polyline", "line", "polygon")
        count = sum(1 for e in g.iter() if e.tag.rsplit("}", 1)[-1] in kinds)
        groups[g.get("id")] = count
    return root, groups


def subpaths(path) -> int:
    """The polylines an SVG path holds: its moves, absolute or relative."""
    d = path.get("d", "")
    return d.count("M") + d.count("m")


def bracket_step(name: str = "bracket") -> str:
    """A STEP (AP214) file of the BRACKET outline extruded along z, as one advanced B-rep solid
    in millimetres: planes bounded by lines, every edge shared by two faces."""
    lines: list[str] = []

    def add(text: str) -> int:
        lines.append(text)
        return len(lines)

    def point(p) -> int:
        return add("CARTESIAN_POINT('',({:.6f},{:.6f},{:.6f}))".format(*p))

    def direction(d) -> int:
        d = np.asarray(d, float) / np.linalg.norm(d)
        return add("DIRECTION('',({:.6f},{:.6f},{:.6f}))".format(*d))

    def placement(origin, normal, ref) -> int:
        return add(f"AXIS2_PLACEMENT_3D('',#{point(origin)},#{direction(normal)},#{direction(ref)})")

    outline = np.array(BRACKET)
    n = len(outline)
    bottom = np.column_stack([outline, np.zeros(n)])
    top = bottom + [0, 0, BRACKET_HEIGHT]
    vertex = {}
    for key, p in [(("b", i), bottom[i]) for i in range(n)] + [(("t", i), top[i]) for i in range(n)]:
        vertex[key] = add(f"VERTEX_POINT('',#{point(p)})")

    def edge(a, pa, b, pb) -> int:
        span = np.asarray(pb) - np.asarray(pa)
        vector = add(f"VECTOR('',#{direction(span)},{np.linalg.norm(span):.6f})")
        line = add(f"LINE('',#{point(pa)},#{vector})")
        return add(f"EDGE_CURVE('',#{vertex[a]},#{vertex[b]},#{line},.T.)")

    nxt = [(i + 1) % n for i in range(n)]
    bottom_edge = [edge(("b", i), bottom[i], ("b", nxt[i]), bottom[nxt[i]]) for i in range(n)]
    top_edge = [edge(("t", i), top[i], ("t", nxt[i]), top[nxt[i]]) for i in range(n)]
    rise = [edge(("b", i), bottom[i], ("t", i), top[i]) for i in range(n)]

    def face(loop, origin, normal, ref) -> int:
        oriented = [add(f"ORIENTED_EDGE('',*,*,#{e},{'.T.' if forward else '.F.'})") for e, forward in loop]
        edges = ",".join(f"#{o}" for o in oriented)
        bound = add(f"FACE_OUTER_BOUND('',#{add('EDGE_LOOP(' + repr('') + f',({edges}))')},.T.)")
        plane = add(f"PLANE('',#{placement(origin, normal, ref)})")
        return add(f"ADVANCED_FACE('',(#{bound}),#{plane},.T.)")

    faces = [
        face([(bottom_edge[i], False) for i in reversed(range(n))], bottom[0], (0, 0, -1), (1, 0, 0)),
        face([(top_edge[i], True) for i in range(n)], top[0], (0, 0, 1), (1, 0, 0)),
    ]
    for i in range(n):
        dx, dy = outline[nxt[i]] - outline[i]
        loop = [(bottom_edge[i], True), (rise[nxt[i]], True), (top_edge[i], False), (rise[i], False)]
        faces.append(face(loop, bottom[i], (dy, -dx, 0), (dx, dy, 0)))
    shell = add(f"CLOSED_SHELL('',({','.join(f'#{f}' for f in faces)}))")
    solid = add(f"MANIFOLD_SOLID_BREP('{name}',#{shell})")
    mm = add("( LENGTH_UNIT() NAMED_UNIT(*) SI_UNIT(.MILLI.,.METRE.) )")
    rad = add("( NAMED_UNIT(*) PLANE_ANGLE_UNIT() SI_UNIT($,.RADIAN.) )")
    sr = add("( NAMED_UNIT(*) SI_UNIT($,.STERADIAN.) SOLID_ANGLE_UNIT() )")
    tolerance = add(
        f"UNCERTAINTY_MEASURE_WITH_UNIT(LENGTH_MEASURE(1.E-07),#{mm},'distance_accuracy_value','')"
    )
    context = add(
        "( GEOMETRIC_REPRESENTATION_CONTEXT(3) "
        f"GLOBAL_UNCERTAINTY_ASSIGNED_CONTEXT((#{tolerance})) "
        f"GLOBAL_UNIT_ASSIGNED_CONTEXT((#{mm},#{rad},#{sr})) REPRESENTATION_CONTEXT('','') )"
    )
    origin = placement((0, 0, 0), (0, 0, 1), (1, 0, 0))
    shape = add(f"ADVANCED_BREP_SHAPE_REPRESENTATION('',(#{origin},#{solid}),#{context})")
    app = add("APPLICATION_CONTEXT('automotive design')")
    add(f"APPLICATION_PROTOCOL_DEFINITION('international standard','automotive_design',2000,#{app})")
    product_context = add(f"PRODUCT_CONTEXT('',#{app},'mechanical')")
    product = add(f"PRODUCT('{name}','{name}','',(#{product_context}))")
    formation = add(f"PRODUCT_DEFINITION_FORMATION('','',#{product})")
    definition_context = add(f"PRODUCT_DEFINITION_CONTEXT('part definition',#{app},'design')")
    definition = add(f"PRODUCT_DEFINITION('design','',#{formation},#{definition_context})")
    product_shape = add(f"PRODUCT_DEFINITION_SHAPE('','',#{definition})")
    add(f"SHAPE_DEFINITION_REPRESENTATION(#{product_shape},#{shape})")
    add(f"PRODUCT_RELATED_PRODUCT_CATEGORY('part',$,(#{product}))")
    data = "\n".join(f"#{k} = {text};" for k, text in enumerate(lines, start=1))
    return (
        "ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION(('blueprint smoke test'),'2;1');\n"
        f"FILE_NAME('{name}.step','2024-01-01T00:00:00',(''),(''),'','','');\n"
        "FILE_SCHEMA(('AUTOMOTIVE_DESIGN { 1 0 10303 214 1 1 1 1 }'));\nENDSEC;\n"
        f"DATA;\n{data}\nENDSEC;\nEND-ISO-10303-21;\n"
    )


class Smoke:
    def __init__(self, work: Path):
        self.work = work
        self.gearbox = examples.example_path()
        self.step = work / "bracket.step"
        self.step.write_text(bracket_step(), encoding="ascii")
        (work / "marks.toml").write_text(GLYPHS, encoding="utf-8")
        (work / "lines.toml").write_text(LINES, encoding="utf-8")
        self.images: dict[str, np.ndarray] = {}
        # polylines of the iso drawing in each vector format, which must agree
        self.polylines: dict[str, int] = {}

    def render(self, name, *options, model=None, size=SIZE):
        out = self.work / name
        cli("render", model or self.gearbox, "-o", out, *(("--size", *size) if size else ()), *options)
        return out


@case("installed")
def _installed(s: Smoke):
    check("site-packages" in PACKAGE.parts, f"blueprint imported from {PACKAGE}, not site-packages")
    version = cli("--version").stdout.strip()
    check(blueprint.__version__ in version, f"--version says {version!r}")
    check(s.gearbox.is_file() and s.gearbox.is_relative_to(PACKAGE), f"example at {s.gearbox}")
    return f"{version} from {PACKAGE}, example {s.gearbox.name} {s.gearbox.stat().st_size} B"


@case("info")
def _info(s: Smoke):
    gl = json.loads(cli("info", "--json").stdout)
    check(gl["renderer"] and gl["egl_devices"], f"info --json: {gl}")
    model = json.loads(cli("info", s.gearbox, "--json").stdout)
    names = sorted(p["name"] for p in model["parts"])
    check(names == sorted(GEARBOX_PARTS), f"parts {names}")
    lo, hi = np.array(model["bounds"])
    check(np.allclose(hi - lo, [140, 73.5, 70]), f"bounds {model['bounds']}")
    text = cli("info", s.gearbox).stdout
    check(all(n in text for n in GEARBOX_PARTS), "info MODEL does not list every part")
    return f"renderer {gl['renderer']!r}; {len(names)} parts as examples.gearbox(), bounds 140x73.5x70"


@case("render png")
def _render_png(s: Smoke):
    fraction, s.images["iso"] = drawn(s.render("iso.png"))
    return f"320x240, ink {fraction:.1%}"


@case("render svg")
def _render_svg(s: Smoke):
    root, groups = svg_paths(s.render("iso.svg"))
    parts = [n for n in GEARBOX_PARTS if groups.get(n, 0) > 0]
    check(parts == list(GEARBOX_PARTS), f"part groups with lines: {parts}")
    s.polylines["svg"] = sum(subpaths(p) for p in root.iter("{http://www.w3.org/2000/svg}path"))
    check(s.polylines["svg"] > 50, f"{s.polylines['svg']} polylines")
    paths = sum(groups[n] for n in parts)
    return f"{s.polylines['svg']} polylines in {paths} paths, a group for each of {len(parts)} parts"


@case("render svg, every layer")
def _render_svg_every_layer(s: Smoke):
    # every layer's faces at the probed pixels, read from the A-buffer's lists where the
    # driver has one (its shader is package data like the rest)
    root, groups = svg_paths(s.render("iso-all.svg", "--max-layers", "0"))
    levels = {
        int(g.get("data-level")) for g in root.iter("{http://www.w3.org/2000/svg}g") if g.get("data-level")
    }
    check(max(levels) > 8, f"levels drawn: {sorted(levels)}")
    parts = [n for n in GEARBOX_PARTS if groups.get(n, 0) > 0]
    check(parts == list(GEARBOX_PARTS), f"part groups with lines: {parts}")
    polylines = sum(subpaths(p) for p in root.iter("{http://www.w3.org/2000/svg}path"))
    check(
        polylines > s.polylines.get("svg", 50),
        f"{polylines} polylines, the default's 8 layers {s.polylines.get('svg')}",
    )
    return f"{polylines} polylines over levels 0 to {max(levels)}"


@case("render pdf")
def _render_pdf(s: Smoke):
    import pikepdf

    with pikepdf.open(s.render("iso.pdf")) as pdf:
        pages = len(pdf.pages)
        layers = [str(g.Name) for g in pdf.Root.OCProperties.OCGs]
        strokes = sum(str(i.operator) == "S" for i in pikepdf.parse_content_stream(pdf.pages[0]))
    s.polylines["pdf"] = strokes
    check(pages == 1, f"{pages} pages")
    check({"visible", *GEARBOX_PARTS} <= set(layers), f"layers {layers}")
    check(
        strokes == s.polylines.get("svg"),
        f"{strokes} stroked polylines, the SVG has {s.polylines.get('svg')}",
    )
    return (
        f"{pages} page, {strokes} stroked polylines (as the SVG), {len(layers)} layers: visible, each part..."
    )


@case("render dxf")
def _render_dxf(s: Smoke):
    import ezdxf

    doc = ezdxf.readfile(s.render("iso.dxf"))
    entities = list(doc.modelspace())
    layers = {e.dxf.layer for e in entities}
    check(
        len(entities) == s.polylines.get("svg"),
        f"{len(entities)} entities, the SVG has {s.polylines.get('svg')}",
    )
    check(all(any(n.lower() in layer.lower() for layer in layers) for n in GEARBOX_PARTS), f"{layers}")
    return (
        f"{len(entities)} entities (as the SVG's polylines) on {len(layers)} layers, each part's among them"
    )


@case("--style")
def _style(s: Smoke):
    paper, image = drawn(s.render("paper.png", "--style", "paper"))
    corner = tuple(image[0, 0])
    check(corner[:3] != tuple(s.images["iso"][0, 0][:3]), f"paper style keeps the blue paper {corner}")
    root, _ = svg_paths(s.render("lines.svg", "--style", s.work / "lines.toml"))
    # a level's stroke sits on its group, a kind's own on its path
    styled = [e for e in root.iter() if e.get("stroke") is not None]
    strokes = {e.get("stroke") for e in styled}
    dashed = sum(e.get("stroke-dasharray") is not None for e in styled)
    check({"#000000", "#1d4f91"} <= strokes and dashed > 0, f"strokes {strokes}, {dashed} dashed")
    return f"paper png ink {paper:.1%}; line style file: strokes {sorted(strokes)}, {dashed} dashed"


@case("--include --exclude")
def _include(s: Smoke):
    _, groups = svg_paths(s.render("include.svg", "--include", "gear,shaft,hub"))
    drawn_parts = sorted(n for n in GEARBOX_PARTS if groups.get(n, 0) > 0)
    check(drawn_parts == ["gear", "hub", "shaft"], f"parts drawn {drawn_parts}")
    _, groups = svg_paths(s.render("exclude.svg", "--exclude", "cover,bolt_*"))
    left = sorted(n for n in GEARBOX_PARTS if groups.get(n, 0) > 0)
    check(left == sorted(n for n in GEARBOX_PARTS if n != "cover" and not n.startswith("bolt")), f"{left}")
    return f"--include draws {', '.join(drawn_parts)}; --exclude leaves {len(left)} parts"


@case("front ortho png")
def _front(s: Smoke):
    fraction, s.images["front"] = drawn(s.render("front.png", "--view", "front", "--ortho"))
    return f"ink {fraction:.1%}"


@case("--smooth-contours png")
def _smooth_contours(s: Smoke):
    # a scan-like ball: a UV sphere whose vertices the noise moves along their radius
    lat, lon = np.meshgrid(
        np.linspace(0.05, np.pi - 0.05, 60), np.linspace(0, 2 * np.pi, 120, endpoint=False)
    )
    radius = 1 + 0.006 * np.random.default_rng(7).standard_normal(lat.shape)
    points = (
        np.stack([np.sin(lat) * np.cos(lon), np.cos(lat), np.sin(lat) * np.sin(lon)], -1) * radius[..., None]
    )
    i, j = np.meshgrid(np.arange(120), np.arange(59), indexing="ij")
    a, b, c, d = points[i, j], points[(i + 1) % 120, j], points[(i + 1) % 120, j + 1], points[i, j + 1]
    triangles = np.concatenate([np.stack([a, c, b], -2), np.stack([a, d, c], -2)]).reshape(-1, 3, 3)
    record = np.dtype([("normal", "<f4", 3), ("triangle", "<f4", (3, 3)), ("attribute", "<u2")])
    data = np.zeros(len(triangles), record)
    data["triangle"] = triangles
    ball = s.work / "ball.stl"
    ball.write_bytes(b"\0" * 80 + len(data).to_bytes(4, "little") + data.tobytes())
    _, plain = drawn(s.render("ball.png", "--no-smooth-contours", model=ball), low=0.005)
    fraction, image = drawn(s.render("ball-contours.png", "--smooth-contours", model=ball), low=0.005)
    changed = differs(image, plain)
    check(changed > 0.0005, f"the contour lines change {changed:.3%} of the ball's picture")
    # a picture of one mesh: drawn with the lines unasked
    _, default = drawn(s.render("ball-default.png", model=ball), low=0.005)
    check(differs(default, image) == 0.0, "the ball's default picture is not the one with its contour lines")
    # at 96 x 96 its triangles lie under a pixel: the lines are found on the GPU (their shaders
    # are package data like the rest), by default too
    small = ("96", "96")
    _, dense_plain = drawn(s.render("ball-96.png", "--no-smooth-contours", model=ball, size=small), small)
    _, dense = drawn(s.render("ball-96-contours.png", "--smooth-contours", model=ball, size=small), small)
    dense_changed = differs(dense, dense_plain)
    check(dense_changed > 0.0005, f"the GPU's contour lines change {dense_changed:.3%} of the small picture")
    _, dense_default = drawn(s.render("ball-96-default.png", model=ball, size=small), small)
    check(differs(dense_default, dense) == 0.0, "the small ball's default picture lacks its lines")
    return (
        f"ink {fraction:.1%}, {changed:.2%} of pixels changed from the mesh's outline, the default alike;"
        f" at 96 x 96 (found on the GPU) {dense_changed:.2%}"
    )


@case("--dimensions png")
def _dimensions(s: Smoke):
    fraction, image = drawn(
        s.render("dims.png", "--view", "front", "--ortho", "--dimensions", "--units", "mm")
    )
    added = differs(image, s.images["front"])
    check(added > 0.005, f"dimensions change {added:.2%} of the front view")
    return f"ink {fraction:.1%}, {added:.1%} of pixels changed from the front view"


@case("--dimensions svg")
def _dimensions_svg(s: Smoke):
    root, _ = svg_paths(s.render("dims.svg", "--view", "front", "--ortho", "--dimensions", "--units", "mm"))
    texts = ["".join(t.itertext()) for t in root.iter("{http://www.w3.org/2000/svg}text")]
    check(any("140" in t for t in texts) and any("73.5" in t for t in texts), f"texts {texts}")
    values = [t for t in texts if re.search(r"\d", t)]
    return f"values {', '.join(values)}"


@case("--section png")
def _section_png(s: Smoke):
    out = s.render("section.png", "--view", "front", "--ortho", "--section", "z=0")
    fraction, image = drawn(out)
    changed = differs(image, s.images["front"])
    check(changed > 0.02, f"section changes {changed:.2%} of the front view")
    return f"ink {fraction:.1%}, {changed:.1%} of pixels changed from the front view (hatching)"


@case("--section svg")
def _section_svg(s: Smoke):
    root, groups = svg_paths(s.render("section.svg", "--view", "front", "--ortho", "--section", "z=0"))
    (section,) = [g for g in root.iter("{http://www.w3.org/2000/svg}g") if g.get("id") == "section"]
    cuts = sum(subpaths(p) for p in section.iter("{http://www.w3.org/2000/svg}path"))
    check(cuts > 20, f"the section group holds {cuts} hatch and outline lines")
    parts = sum(groups.get(n, 0) for n in GEARBOX_PARTS)
    return f"section group: {cuts} hatch and outline lines in {groups['section']} paths; {parts} part paths"


@case("--view plan png")
def _plan_png(s: Smoke):
    fraction, _ = drawn(s.render("plan.png", "--view", "plan", size=("640", "480")), size=("640", "480"))
    return f"640x480 sheet, ink {fraction:.1%}"


@case("--view plan --sheet svg")
def _plan_svg(s: Smoke):
    out = s.render("plan.svg", "--view", "plan", "--sheet", "A3", "--title", "Smoke", size=None)
    root, groups = svg_paths(out)
    texts = " ".join("".join(t.itertext()) for t in root.iter("{http://www.w3.org/2000/svg}text"))
    for label in ("TOP", "FRONT", "RIGHT", "ISO", "Smoke"):
        check(label in texts, f"{label} not on the sheet: {texts[:200]}")
    check(root.get("width", "").startswith("420"), f"A3 landscape width {root.get('width')}")
    return f"A3 {root.get('width')} x {root.get('height')}, labels and title, {sum(groups.values())} paths"


@case("--view plan --sheet pdf")
def _plan_pdf(s: Smoke):
    import pikepdf

    with pikepdf.open(s.render("plan.pdf", "--view", "plan", "--sheet", "A4", size=None)) as pdf:
        box = [float(v) for v in pdf.pages[0].MediaBox]
        layers = [str(g.Name) for g in pdf.Root.OCProperties.OCGs]
    check(round(box[2] / 72 * 25.4) == 297 and round(box[3] / 72 * 25.4) == 210, f"page {box}")
    check("sheet" in layers, f"layers {layers}")
    return f"1 A4 landscape page, layers include sheet ({len(layers)} in all)"


@case("STEP")
def _step(s: Smoke):
    model = json.loads(cli("info", s.step, "--json").stdout)
    names = [p["name"] for p in model["parts"]]
    lo, hi = np.array(model["bounds"])
    # OpenCASCADE hands the mesh over in metres
    check(names == ["bracket"], f"parts {names}")
    # two caps of n - 2 triangles, n sides of 2
    check(model["triangles"] == 4 * len(BRACKET) - 4, f"{model['triangles']} triangles")
    check(np.allclose(hi - lo, [0.08, 0.05, 0.03], atol=1e-6), f"bounds {model['bounds']}")
    fraction, _ = drawn(s.render("bracket.png", model=s.step))
    return f"part {names[0]}, {model['triangles']} triangles, 80x50x30 mm as metres; png ink {fraction:.1%}"


@case("--glyphs")
def _glyphs(s: Smoke):
    fraction, image = drawn(s.render("glyphs.png", "--glyphs", s.work / "marks.toml"))
    changed = differs(image, s.images["iso"])
    check(changed > 0.005, f"glyphs change {changed:.2%} of the drawing")
    _, groups = svg_paths(s.render("glyphs.svg", "--glyphs", s.work / "marks.toml"))
    check(groups.get("glyphs", 0) > 0, f"svg glyphs group: {groups.get('glyphs')}")
    return f"png: {changed:.1%} of pixels changed; svg glyphs group: {groups['glyphs']} elements"


@case("--shade")
def _shade(s: Smoke):
    fraction, image = drawn(s.render("shade.png", "--shade", "gear*,shaft"), high=0.9)
    changed = differs(image, s.images["iso"])
    check(changed > 0.01, f"shading changes {changed:.2%} of the drawing")
    return f"ink {fraction:.1%}, {changed:.1%} of pixels changed"


@case("--highlight --reveal")
def _highlight(s: Smoke):
    fraction, image = drawn(s.render("reveal.png", "--highlight", "gear*", "--reveal", "0.9"))
    changed = differs(image, s.images["iso"])
    check(changed > 0.005, f"highlight changes {changed:.2%} of the drawing")
    return f"ink {fraction:.1%}, {changed:.1%} of pixels changed"


for _method in ("gpu-edges", "gpu-vertex", "gpu-idlist", "cpu"):

    @case(f"silhouettes {_method}")
    def _silhouettes(s: Smoke, method=_method):
        out = s.work / f"sil-{method}.png"
        cli("silhouettes", s.gearbox, "-o", out, "--size", *SIZE, "--method", method)
        fraction, _ = drawn(out, low=0.005)
        return f"ink {fraction:.1%}"


@case("silhouettes --animate")
def _animate(s: Smoke):
    import imageio.v3 as iio

    out = s.work / "twist.mp4"
    cli("silhouettes", s.gearbox, "-o", out, "--size", "160", "120", "--animate", "twist", "--frames", "4")
    frames = [np.dstack([f, np.full(f.shape[:2], 255, np.uint8)]) for f in iio.imiter(out)]
    check(len(frames) == 4 and frames[0].shape[:2] == (120, 160), f"{len(frames)} frames")
    inks = [ink(f)[0] for f in frames]
    check(min(inks) > 0.005, f"ink per frame {inks}")
    return f"4 frames of 160x120, ink {min(inks):.1%}-{max(inks):.1%}"


@case("layers")
def _layers(s: Smoke):
    out = s.work / "layers.npz"
    said = cli("layers", s.gearbox, "-o", out, "--size", "160", "120").stdout
    data = np.load(out)
    depth, triangle, part = data["depth"], data["triangle"], data["part"]
    count = int(re.search(r"(\d+) layers", said).group(1))
    check(depth.shape == (count, 120, 160) == triangle.shape == part.shape, f"{depth.shape}, said {said!r}")
    held = triangle >= 0
    check(held.sum(axis=0).max() == count, "no pixel holds the last layer")
    check(part[held].max() < len(GEARBOX_PARTS) and part[held].min() >= 0, "part IDs out of range")
    check(triangle[held].max() < 2144, "triangle IDs out of range")
    both = held[1:] & held[:-1]
    check((depth[1:][both] >= depth[:-1][both]).all(), "depth does not grow layer by layer")
    return f"{count} layers of 160x120 (printed = npz), IDs in range, depth growing"


@case("turntable")
def _turntable(s: Smoke):
    import imageio.v3 as iio

    out = s.work / "orbit.mp4"
    cli("turntable", s.gearbox, "-o", out, "--frames", "6", "--size", "160", "120")
    frames = [np.dstack([f, np.full(f.shape[:2], 255, np.uint8)]) for f in iio.imiter(out)]
    check(len(frames) == 6 and frames[0].shape[:2] == (120, 160), f"{len(frames)} frames")
    inks = [ink(f)[0] for f in frames]
    check(min(inks) > 0.01, f"ink per frame {inks}")
    # the gearbox looks the same after half a turn: compare a sixth of one
    turned = differs(frames[0], frames[1])
    check(turned > 0.01, f"frames 0 and 1 differ in {turned:.2%} of pixels")
    return f"6 frames of 160x120, ink {min(inks):.1%}-{max(inks):.1%}, a sixth of a turn changes {turned:.0%}"


@case("pipeline run")
def _pipeline(s: Smoke):
    out = s.work / "sobel.png"
    cli("pipeline", "run", "edges-sobel", s.gearbox, "-o", out, "--size", *SIZE)
    fraction, _ = drawn(out, low=0.005)
    own = s.work / "own.toml"
    plan = cli("pipeline", "check", "toon").stdout
    check(plan.strip(), "pipeline check toon printed nothing")
    own.write_text(
        (PACKAGE / "pipeline" / "presets" / "toon.toml").read_text(encoding="utf-8"), encoding="utf-8"
    )
    out2 = s.work / "toon.png"
    cli("pipeline", "run", own, s.gearbox, "-o", out2, "--size", *SIZE)
    fraction2, _ = drawn(out2, low=0.005, high=1.0)
    return f"preset edges-sobel ink {fraction:.1%}; toon as a user's file ink {fraction2:.1%}"


@case("ops")
def _ops(s: Smoke):
    ops = [json.loads(line) for line in cli("ops", "--json").stdout.splitlines() if line.strip()]
    names = {op["name"] for op in ops}
    for name in ("edges", "sobel", "blur", "threshold"):
        check(name in names, f"{name} not among {sorted(names)}")
    text = cli("ops").stdout
    check(all(n in text for n in names), "ops does not list what ops --json lists")
    return f"{len(ops)} operations (edges, sobel, blur, threshold...)"


@case("batch")
def _batch(s: Smoke):
    inputs = s.work / "inputs"
    inputs.mkdir()
    shutil.copy(s.gearbox, inputs)
    out = s.work / "batch"
    # a folder and a file
    options = "--views iso,top --formats png,svg --size 128 96 --workers 1".split()
    cli("batch", inputs, s.step, "-o", out, *options)
    manifest = json.loads((out / "manifest.json").read_text())
    check(manifest["failed"] == 0 and manifest["drawn"] == 2, f"manifest {manifest}")
    outputs = [Path(o) for entry in manifest["inputs"] for o in entry["outputs"]]
    check(len(outputs) == 8, f"outputs {outputs}")
    for o in outputs:
        o = o if o.is_absolute() else s.work / o
        check(o.is_file(), f"{o} missing")
        if o.suffix == ".png":
            drawn(o, size=("128", "96"), low=0.005)
        else:
            check(sum(svg_paths(o)[1].values()) > 0, f"{o.name} has no paths")
    return (
        f"a folder's GLB and a STEP file x 2 views x 2 formats = {len(outputs)} drawings, each with ink/paths"
    )


@case("bench")
def _bench(s: Smoke):
    said = cli(
        "bench", s.gearbox, "--size", "128", "128", "--max-layers", "0", "--frames", "2", "--warmup", "1"
    )
    rows = [json.loads(line) for line in said.stdout.splitlines() if line.startswith("{")]
    check(len(rows) == 1 and rows[0]["ms"] > 0 and rows[0]["layers"] >= 2, f"{rows}")
    return f"1 JSON row: {rows[0]['layers']} layers, {rows[0]['ms']:.0f} ms"


@case("blueprint.draw")
def _draw(s: Smoke):
    drawing = blueprint.draw(s.gearbox, size=(256, 192))
    check(drawing.image.shape == (192, 256, 4) and drawing.layers >= 2, f"{drawing.image.shape}")
    fraction, _ = ink(drawing.image)
    check(fraction > 0.01, f"ink {fraction:.2%}")
    sizes = {}
    for suffix in ("png", "svg", "pdf", "dxf"):
        sizes[suffix] = drawing.save(s.work / f"api.{suffix}").stat().st_size
        check(sizes[suffix] > 1000, f"api.{suffix}: {sizes[suffix]} B")
    return f"{drawing.layers} layers, ink {fraction:.1%}; saved " + ", ".join(
        f"{k} {v} B" for k, v in sizes.items()
    )


@case("broken install")
def _broken(s: Smoke):
    copy = s.work / "broken"
    shutil.copytree(PACKAGE, copy / "blueprint", ignore=shutil.ignore_patterns("__pycache__"))
    (copy / "blueprint" / "gpu_silhouettes" / "glsl" / "idsil_lines.geom").unlink(missing_ok=True)
    out = s.work / "broken.png"
    env = {**os.environ, "PYTHONPATH": str(copy)}
    proc = cli(
        "silhouettes", s.gearbox, "-o", out, expect=2, env=env, command=[sys.executable, "-m", "blueprint"]
    )
    line = proc.stderr
    check(line.count("\n") == 1 and "Traceback" not in line, f"not one line: {line!r}")
    check(line.startswith("blueprint: error: ") and "idsil_lines.geom" in line, line)
    check(not out.exists(), "an output was written")
    return f"exit 2, {line.strip()!r}"


@case("jupyter install")
def _jupyter_install(s: Smoke):
    cli("-m", "pip", "install", "-q", "ipykernel", "nbclient", "nbformat", command=[sys.executable])
    import nbclient  # noqa: F401
    import nbformat  # noqa: F401

    return "pip install ipykernel nbclient nbformat after the wheel"


@case("jupyter blueprint.draw")
def _jupyter(s: Smoke):
    import nbformat
    from nbclient import NotebookClient

    cells = [
        "import sys, blueprint\nfrom blueprint import examples\nprint(sys.prefix, blueprint.__file__)",
        "blueprint.draw(examples.example_path(), size=(320, 240))",
        "blueprint.draw(examples.example_path(), vector=True, view='front', ortho=True)",
    ]
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(c) for c in cells])
    env_before = os.environ.get("JUPYTER_PREFER_ENV_PATH")
    os.environ["JUPYTER_PREFER_ENV_PATH"] = "1"
    log = s.work / "kernel.log"
    try:
        with log.open("w") as kernel_stderr:
            client = NotebookClient(
                nb, timeout=300, kernel_name="python3", resources={"metadata": {"path": str(s.work)}}
            )
            client.execute(stderr=kernel_stderr)
    except Exception as exc:
        raise Failure(f"{exc}; kernel stderr: {log.read_text()[-300:]}") from None
    finally:
        if env_before is None:
            os.environ.pop("JUPYTER_PREFER_ENV_PATH")
    printed = nb.cells[0].outputs[0]["text"].split()
    check(printed[0] == sys.prefix and Path(printed[1]).resolve().parent == PACKAGE, f"kernel ran {printed}")
    png = [o.data["image/png"] for o in nb.cells[1].outputs if "image/png" in o.get("data", {})]
    check(len(png) == 1, f"cell 2 shows {[list(o.get('data', {})) for o in nb.cells[1].outputs]}")
    fraction, image = ink(np.asarray(Image.open(io.BytesIO(base64.b64decode(png[0]))).convert("RGBA")))
    check(image.shape[:2] == (240, 320) and fraction > 0.01, f"{image.shape}, ink {fraction:.2%}")
    svg = [o.data["image/svg+xml"] for o in nb.cells[2].outputs if "image/svg+xml" in o.get("data", {})]
    check(len(svg) == 1 and svg[0].count("<path") > 10, "cell 3 shows no SVG drawing")
    return f"kernel in {sys.prefix}; PNG 320x240 ink {fraction:.1%}; SVG {svg[0].count('<path')} paths"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--keep", type=Path, help="folder to write into and keep (default: a temporary one)")
    args = parser.parse_args()
    work = args.keep.resolve() if args.keep else Path(tempfile.mkdtemp(prefix="blueprint-smoke-"))
    work.mkdir(parents=True, exist_ok=True)
    os.chdir(work)
    print(f"smoke: {sys.executable} (Python {sys.version.split()[0]}), writing in {work}", flush=True)
    failed = 0
    smoke = Smoke(work)
    for name, fn in CASES:
        start = time.perf_counter()
        try:
            said, status = fn(smoke), "ok"
        except Exception as exc:  # every case reports, whatever it raised
            failed += 1
            status = "FAIL"
            said = (
                str(exc)
                if isinstance(exc, Failure)
                else "".join(traceback.format_exception_only(exc)).strip()
            )
            said = " ".join(said.split())[:400]
        print(f"{name:<26} {status:<4} {time.perf_counter() - start:6.1f}s  {said}", flush=True)
    print(f"smoke: {len(CASES) - failed} passed, {failed} failed", flush=True)
    if failed and not args.keep:
        print(f"smoke: outputs kept in {work}", flush=True)
    elif not args.keep:
        shutil.rmtree(work, ignore_errors=True)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
