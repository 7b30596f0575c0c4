"""DXF output through ezdxf: one layer per part and occlusion level, LWPOLYLINE entities.

Coordinates are the page's (pixels, or paper millimetres for a drawing to scale) with y up,
as CAD expects. Every layer carries its level's colour (true colour), linetype (a dash
pattern of its own, ``BP_L<k>``), lineweight and transparency.
"""

from __future__ import annotations

import os
import re

import numpy as np

from .section import SECTION_HATCH_WIDTH, SECTION_OUTLINE_WIDTH
from .svg import _decimals

__all__ = ["layer_name", "write_dxf"]

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


def layer_name(part: str, level: int) -> str:
    """A DXF layer name for a part's lines at one level: 'gear-L1'."""
    base = _BAD.sub("_", part).strip() or "part"
    return f"{base[:200]}-L{level}"


def _lineweight(mm: float) -> int:
    value = mm * 100
    return min(_WEIGHTS, key=lambda w: abs(w - value))


def _sheet(doc, msp, drawing, base_mm: float) -> None:
    """A sheet's border, title block and view labels on the layer SHEET."""
    page = drawing.page
    layer = doc.layers.add("SHEET")
    layer.rgb = tuple(round(c * 255) for c in drawing.style.title_color)
    marks = drawing.marks
    ends = marks.lines.reshape(-1, 2) * page.factor
    ends[:, 1] = page.height - ends[:, 1]
    for (start, end), width in zip(ends.reshape(-1, 2, 2).tolist(), marks.widths.tolist(), strict=True):
        msp.add_line(start, end, dxfattribs={"layer": "SHEET", "lineweight": _lineweight(width * base_mm)})
    for text in marks.texts:
        attribs = {"layer": "SHEET", "rotation": text.angle}
        entity = msp.add_text(text.text, height=text.height * page.factor, dxfattribs=attribs)
        align = "BOTTOM_CENTER" if text.anchor == "middle" else "BOTTOM_LEFT"
        entity.set_placement((text.x * page.factor, page.height - text.y * page.factor), align=_align(align))


def _lines(doc, msp, drawing, groups, points, layers, made_linetypes, base: float, base_mm: float) -> None:
    """The lines of ``groups`` (``Drawing.groups``) as LWPOLYLINEs, a layer per part and
    level (made on first use, ``layers`` and ``made_linetypes`` keeping what exists)."""
    style, names, offsets = drawing.style, drawing.part_names, drawing.offsets
    for part, level, index in groups:
        line = style.level(level, part in drawing.highlight)
        linetype = "CONTINUOUS"
        if line.dash:
            linetype = f"BP_L{level}"
            if linetype not in made_linetypes:
                on = line.dash[0] * base
                off = (line.dash[1] if len(line.dash) > 1 else line.dash[0]) * base
                doc.linetypes.add(
                    linetype, pattern=[on + off, on, -off], description=f"blueprint level {level}"
                )
                made_linetypes.add(linetype)
        name = layers.get((part, level))
        if name is None:
            name = layer_name(names[part] if part < len(names) else f"part{part}", level)
            while name in layers.values():  # two parts whose names sanitise alike
                name = name[: name.rfind("-L")] + f"_{part}-L{level}"
            layers[(part, level)] = name
            layer = doc.layers.add(name)
            layer.rgb = tuple(round(c * 255) for c in line.color)
            layer.dxf.linetype = linetype
            layer.dxf.lineweight = _lineweight(line.width * base_mm)
            layer.transparency = 1.0 - line.opacity
        attribs = {"layer": name}
        for i in index.tolist():
            chunk = points[offsets[i] : offsets[i + 1]]
            if len(chunk) >= 2 and np.ptp(chunk, axis=0).any():
                msp.add_lwpolyline(chunk.tolist(), format="xy", dxfattribs=attribs)


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
        msp.add_lwpolyline(chunk.tolist(), format="xy", dxfattribs=attribs)
    for text in glyphs.texts:
        attribs = {
            "layer": "GLYPHS-HIDDEN" if text.hidden else "GLYPHS",
            "true_color": _true_color(text.color),
        }
        entity = msp.add_text(text.text, height=0.72 * text.size * page.factor, dxfattribs=attribs)
        entity.set_placement((text.x * page.factor, page.height - text.y * page.factor))


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
    layers: dict[tuple[int, int], str] = {}
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
        for segments, width in (
            (drawing.section.hatch, SECTION_HATCH_WIDTH),
            (drawing.section.outline, SECTION_OUTLINE_WIDTH),
        ):
            ends = segments.reshape(-1, 2) * page.factor
            ends[:, 1] = page.height - ends[:, 1]
            attribs = {"layer": "SECTION", "lineweight": _lineweight(width * base_mm)}
            for start, end in ends.reshape(-1, 2, 2).tolist():
                msp.add_line(start, end, dxfattribs=attribs)
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
