"""DXF output through ezdxf: one layer per part, kind of line and occlusion level, LWPOLYLINE
entities (circles and arcs where a line is one), each with its source edges as XDATA.

Coordinates are the page's (pixels, or paper millimetres for a drawing to scale) with y up,
as CAD expects. Every layer carries its kind's and level's colour (true colour), linetype (a
dash pattern of its own, ``BP_L<k>``, or ``BP_<kind>_L<k>`` where the kind's dash is not the
level's), lineweight and transparency. XDATA of the application ``BLUEPRINT`` on every line:
its kind's name (group code 1000), then its source edges, one long (1071) each; a section's
lines (layer SECTION), a sheet's marks (SHEET), dimensions (DIMENSIONS) and glyphs (GLYPHS)
carry their kind alone.
"""

from __future__ import annotations

import os
import re

import numpy as np

from .linework import KINDS
from .section import SECTION_HATCH_WIDTH, SECTION_OUTLINE_WIDTH
from .svg import _decimals

__all__ = ["APP_ID", "ARC_SAGITTA", "ARC_TOLERANCE", "fit_arc", "layer_name", "write_dxf"]

# The application name of the XDATA that carries each line's kind and source edges.
APP_ID = "BLUEPRINT"

# A line is drawn as a circle or an arc where its vertices lie this close to one (pixels) and
# no chord strays from its arc by more than ARC_SAGITTA: what the simplified polyline of a
# finely tessellated rim is (Douglas-Peucker at 0.25 px leaves chords of about that sagitta).
ARC_TOLERANCE = 0.1
ARC_SAGITTA = 0.5

# the layers of a sheet's marks, by their kind
_MARK_LAYERS = {"sheet": "SHEET", "dimension": "DIMENSIONS"}

_BAD = re.compile(r'[<>/\\":;?*|=`,\x00-\x1f]+')
# DXF lineweights, 1/100 mm.
_WEIGHTS = (
    0,
    5,
    9,
    13,
    15,
    18,
    20,
    25,
    30,
    35,
    40,
    50,
    53,
    60,
    70,
    80,
    90,
    100,
    106,
    120,
    140,
    158,
    200,
    211,
)


def layer_name(part: str, level: int, kind: str = "") -> str:
    """A DXF layer name for a part's lines of one kind at one level: 'gear-crease-L1'."""
    base = _BAD.sub("_", part).strip() or "part"
    return f"{base[:200]}{'-' + kind if kind else ''}-L{level}"


def _lineweight(mm: float) -> int:
    value = mm * 100
    return min(_WEIGHTS, key=lambda w: abs(w - value))


def _sheet(doc, msp, drawing, base_mm: float) -> None:
    """A sheet's border, title block and view labels on the layer SHEET, dimensions on the
    layer DIMENSIONS, every line and text with its kind as XDATA."""
    page, marks = drawing.page, drawing.marks
    for kind in sorted({*marks.kinds.tolist(), *(t.kind for t in marks.texts)}):
        layer = doc.layers.add(_MARK_LAYERS[kind])
        layer.rgb = tuple(round(c * 255) for c in drawing.style.title_color)
    ends = marks.lines.reshape(-1, 2) * page.factor
    ends[:, 1] = page.height - ends[:, 1]
    for (start, end), width, kind in zip(
        ends.reshape(-1, 2, 2).tolist(), marks.widths.tolist(), marks.kinds.tolist(), strict=True
    ):
        attribs = {"layer": _MARK_LAYERS[kind], "lineweight": _lineweight(width * base_mm)}
        msp.add_line(start, end, dxfattribs=attribs).set_xdata(APP_ID, [(1000, kind)])
    for text in marks.texts:
        attribs = {"layer": _MARK_LAYERS[text.kind], "rotation": text.angle}
        entity = msp.add_text(text.text, height=text.height * page.factor, dxfattribs=attribs)
        align = "BOTTOM_CENTER" if text.anchor == "middle" else "BOTTOM_LEFT"
        entity.set_placement((text.x * page.factor, page.height - text.y * page.factor), align=_align(align))
        entity.set_xdata(APP_ID, [(1000, text.kind)])


def fit_arc(points: np.ndarray, tolerance: float, sagitta: float, min_points: int = 6):
    """The circle or arc a polyline (N, 2) draws, where it is one at the drawing's resolution:
    every vertex within ``tolerance`` of one circle, every chord within ``sagitta`` of its
    arc (a hexagon is no circle), turning one way by less than a full turn. Returns
    (cx, cy, r, None, None) for a closed polyline, (cx, cy, r, start, end) in degrees
    counterclockwise for an open one, else None."""
    if len(points) < min_points:
        return None
    # algebraic least squares: x^2 + y^2 + D x + E y + F = 0, around the centroid
    mean = points.mean(axis=0)
    p = points - mean
    system = np.column_stack([p, np.ones(len(p))])
    (d, e, f), *_ = np.linalg.lstsq(system, -(p**2).sum(axis=1), rcond=None)
    centre = np.array([-d / 2, -e / 2])
    r2 = centre @ centre - f
    if not np.isfinite(r2) or r2 <= 0:
        return None
    radius = float(np.sqrt(r2))
    if np.abs(np.linalg.norm(p - centre, axis=1) - radius).max() > tolerance:
        return None
    chord = np.linalg.norm(np.diff(p, axis=0), axis=1)
    if chord.max() >= 2 * radius:
        return None
    if radius - np.sqrt(radius**2 - (chord.max() / 2) ** 2) > sagitta:
        return None
    angle = np.arctan2(p[:, 1] - centre[1], p[:, 0] - centre[0])
    turn = (np.diff(angle) + np.pi) % (2 * np.pi) - np.pi
    if not (np.all(turn > 0) or np.all(turn < 0)):
        return None
    cx, cy = (centre + mean).tolist()
    closed = np.allclose(points[0], points[-1], atol=tolerance)
    if closed:
        return (cx, cy, radius, None, None) if abs(abs(turn.sum()) - 2 * np.pi) < 1e-6 else None
    if abs(turn.sum()) >= 2 * np.pi:
        return None
    first, last = np.degrees(angle[0]) % 360, np.degrees(angle[-1]) % 360
    # an ARC runs counterclockwise from its start to its end
    return (cx, cy, radius, first, last) if turn.sum() > 0 else (cx, cy, radius, last, first)


def _lines(doc, msp, drawing, groups, points, layers, made_linetypes, base: float, base_mm: float) -> None:
    """The lines of ``groups`` (``VectorDrawing.groups``) as LWPOLYLINEs, a layer per part,
    kind and level (made on first use, ``layers`` and ``made_linetypes`` keeping what exists);
    lines that are circles or arcs at the drawing's resolution (``fit_arc``: the rims of round
    holes and shafts seen square on) as CIRCLE and ARC entities; each with its kind and source
    edges as XDATA."""
    style, names, lines = drawing.style, drawing.part_names, drawing.lines
    offsets = lines.offsets
    page_per_px = drawing.page.factor
    # the names taken, looked up once a new layer is named (not a scan of every layer made)
    taken = set(layers.values())
    for part, kind, level, index in groups:
        if not style.shows(kind):
            continue
        line = style.line(kind, level, part in drawing.highlight)
        linetype = "CONTINUOUS"
        if line.dash:
            own = line.dash != style.level(level).dash
            linetype = f"BP_{KINDS[kind]}_L{level}" if own else f"BP_L{level}"
            if linetype not in made_linetypes:
                on = line.dash[0] * base
                off = (line.dash[1] if len(line.dash) > 1 else line.dash[0]) * base
                doc.linetypes.add(
                    linetype, pattern=[on + off, on, -off], description=f"blueprint level {level}"
                )
                made_linetypes.add(linetype)
        name = layers.get((part, kind, level))
        if name is None:
            part_name = names[part] if part < len(names) else f"part{part}"
            name = layer_name(part_name, level, KINDS[kind])
            if name in taken:  # two parts whose names sanitise alike
                name = layer_name(f"{part_name}_{part}", level, KINDS[kind])
            layers[(part, kind, level)] = name
            taken.add(name)
            layer = doc.layers.add(name)
            layer.rgb = tuple(round(c * 255) for c in line.color)
            layer.dxf.linetype = linetype
            layer.dxf.lineweight = _lineweight(line.width * base_mm)
            layer.transparency = 1.0 - line.opacity
        attribs = {"layer": name}
        head = [(1000, KINDS[kind])]
        for i in index.tolist():
            chunk = points[offsets[i] : offsets[i + 1]]
            if len(chunk) < 2 or not np.ptp(chunk, axis=0).any():
                continue
            arc = fit_arc(chunk, ARC_TOLERANCE * page_per_px, ARC_SAGITTA * page_per_px)
            if arc is None:
                entity = msp.add_lwpolyline(chunk.tolist(), format="xy", dxfattribs=attribs)
            elif arc[3] is None:
                entity = msp.add_circle(arc[:2], arc[2], dxfattribs=attribs)
            else:
                entity = msp.add_arc(arc[:2], arc[2], arc[3], arc[4], dxfattribs=attribs)
            entity.set_xdata(APP_ID, head + [(1071, e) for e in lines.edges_of(i).tolist()])


def _shading(doc, msp, drawing) -> None:
    """Shaded faces as SOLID triangles on the layer SHADING, back to front."""
    page, shading = drawing.page, drawing.shading
    layer = doc.layers.add("SHADING")
    layer.transparency = 1.0 - shading.opacity
    corners = shading.points * page.factor
    corners[..., 1] = page.height - corners[..., 1]
    for (a, b, c), color in zip(corners.tolist(), shading.color.tolist(), strict=True):
        # SOLID's corners run in a Z: the third and fourth are one point for a triangle
        msp.add_solid([a, b, c, c], dxfattribs={"layer": "SHADING", "true_color": _true_color(color)})


def _glyphs(doc, msp, drawing) -> None:
    """Glyphs on the layer GLYPHS, each polyline in its glyph's colour; the stretches behind
    the model on GLYPHS-HIDDEN, dashed or dimmed as the glyphs' hidden mode says."""
    glyphs, page = drawing.glyphs, drawing.page
    px_mm = page.factor if page.unit == "mm" else 25.4 / 96
    doc.layers.add("GLYPHS")
    hidden_layer = doc.layers.add("GLYPHS-HIDDEN")
    if glyphs.mode.mode == "dashed":
        on, off = glyphs.mode.dash[0] * page.factor, glyphs.mode.dash[-1] * page.factor
        doc.linetypes.add(
            "BP_GLYPH_HIDDEN", pattern=[on + off, on, -off], description="glyphs behind the model"
        )
        hidden_layer.dxf.linetype = "BP_GLYPH_HIDDEN"
    elif glyphs.mode.mode == "dim":
        hidden_layer.transparency = 1.0 - glyphs.mode.opacity
    points = glyphs.points * page.factor
    points[:, 1] = page.height - points[:, 1]
    for i in range(len(glyphs)):
        color, width, _, _ = glyphs.style(i)
        chunk = points[glyphs.offsets[i] : glyphs.offsets[i + 1]]
        attribs = {
            "layer": "GLYPHS-HIDDEN" if glyphs.hidden[i] else "GLYPHS",
            "true_color": _true_color(color),
            "lineweight": _lineweight(width * px_mm),
        }
        msp.add_lwpolyline(chunk.tolist(), format="xy", dxfattribs=attribs).set_xdata(
            APP_ID, [(1000, "glyph")]
        )
    for text in glyphs.texts:
        attribs = {
            "layer": "GLYPHS-HIDDEN" if text.hidden else "GLYPHS",
            "true_color": _true_color(text.color),
        }
        entity = msp.add_text(text.text, height=0.72 * text.size * page.factor, dxfattribs=attribs)
        entity.set_placement((text.x * page.factor, page.height - text.y * page.factor))
        entity.set_xdata(APP_ID, [(1000, "glyph")])


def _true_color(color) -> int:
    from ezdxf import colors

    return colors.rgb2int(tuple(round(c * 255) for c in color[:3]))


def _align(name: str):
    from ezdxf.enums import TextEntityAlignment

    return TextEntityAlignment[name]


def write_dxf(drawing, path: str | os.PathLike) -> None:
    """Write the drawing as a DXF R2010 file."""
    try:
        import ezdxf
    except ImportError as exc:  # pragma: no cover - depends on the environment
        from blueprint.errors import InputError

        raise InputError("DXF output needs the ezdxf package (pip install ezdxf)") from exc

    page = drawing.page
    doc = ezdxf.new("R2010")
    doc.header["$INSUNITS"] = 4 if page.unit == "mm" else 0
    doc.header["$MEASUREMENT"] = 1
    msp = doc.modelspace()
    base = drawing.page_width()
    # the pen's width in millimetres: pixels are taken at 96 per inch
    base_mm = base if page.unit == "mm" else base * 25.4 / 96
    style = drawing.style
    points = drawing.points * page.factor
    points[:, 1] = page.height - points[:, 1]
    # the SVG writer's grid (a tenth of a pixel or finer): shorter numbers, same drawing
    points = np.round(points, _decimals(page.factor))
    made_linetypes: set[str] = set()
    layers: dict[tuple[int, int, int], str] = {}
    doc.appids.add(APP_ID)
    if drawing.shading is None:
        _lines(doc, msp, drawing, drawing.groups(), points, layers, made_linetypes, base, base_mm)
    else:
        # lines behind the shaded parts, the shading over them, then the rest (CAD programs
        # draw entities in the order written)
        _lines(doc, msp, drawing, drawing.groups(True), points, layers, made_linetypes, base, base_mm)
        _shading(doc, msp, drawing)
        _lines(doc, msp, drawing, drawing.groups(False), points, layers, made_linetypes, base, base_mm)
    if drawing.section is not None:
        section_layer = doc.layers.add("SECTION")
        section_layer.rgb = tuple(round(c * 255) for c in style.level(0).color)
        for segments, width, kind in (
            (drawing.section.hatch, SECTION_HATCH_WIDTH, "hatch"),
            (drawing.section.outline, SECTION_OUTLINE_WIDTH, "section"),
        ):
            ends = segments.reshape(-1, 2) * page.factor
            ends[:, 1] = page.height - ends[:, 1]
            attribs = {"layer": "SECTION", "lineweight": _lineweight(width * base_mm)}
            # a cut's lines run across faces: their XDATA is their kind, with no source edges
            for start, end in ends.reshape(-1, 2, 2).tolist():
                msp.add_line(start, end, dxfattribs=attribs).set_xdata(APP_ID, [(1000, kind)])
    if drawing.marks is not None:
        _sheet(doc, msp, drawing, base_mm)
    if drawing.glyphs is not None:
        _glyphs(doc, msp, drawing)
    if drawing.title:
        title_layer = doc.layers.add("TITLE")
        title_layer.rgb = tuple(round(c * 255) for c in style.title_color)
        text = msp.add_text(drawing.title, height=0.022 * page.height, dxfattribs={"layer": "TITLE"})
        text.set_placement((0.02 * page.width, 0.02 * page.height))
    doc.saveas(os.fspath(path))
