"""PDF output through fpdf2: one page the size of the drawing, lines grouped by part and level.

A pixel drawing becomes a page of 0.75 pt per pixel (96 per inch, as browsers show SVG); a
drawing to scale a page in millimetres. Every part's lines come together, deepest level
first, as in the SVG; and as the SVG's part layers and level classes let an editor hide them,
the PDF has layers a viewer toggles: one optional content group per part, one per kind of
line and one per occlusion level (and one for a section, one for a sheet's marks). Each group
of lines is marked as content of its part's, its kind's and its level's group, so it shows
only while all three are on; a section's hatching and outline, a sheet's own marks, its
dimensions and glyphs are content of their kind's group too (``hatch``, ``section``, ``sheet``,
``dimension``, ``glyph``). fpdf2 writes no named optional content, so the marks go into its
content stream as they are and pikepdf adds the groups to the document afterwards.
"""

from __future__ import annotations

import io
import os

import numpy as np

from blueprint.compose.glyphs.raster import ANCHOR_SIDES
from blueprint.scene.sheet import MARK_KINDS

from .linework import GLYPH, HATCH, KINDS, SECTION
from .section import SECTION_HATCH_WIDTH, SECTION_OUTLINE_WIDTH

__all__ = ["level_name", "pdf_bytes"]

PT_PER_PX = 0.75


# Fonts with the glyphs of Unicode text, where the system has one: PDF's own fonts have Latin-1.
UNICODE_FONTS = (
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/truetype/freefont/FreeSans.ttf",
    "/System/Library/Fonts/Supplemental/Arial Unicode.ttf",
    "C:/Windows/Fonts/arial.ttf",
)


def unicode_font() -> str | None:
    """The first of ``UNICODE_FONTS`` that exists, else None (text then falls back to Latin-1)."""
    return next((path for path in UNICODE_FONTS if os.path.isfile(path)), None)


def _font(pdf, size_pt: float) -> None:
    path = unicode_font()
    if path is None:
        pdf.set_font("helvetica", size=size_pt)
        return
    if "unicode" not in pdf.fonts:
        pdf.add_font("unicode", fname=path)
    pdf.set_font("unicode", size=size_pt)


def _text(pdf, text: str) -> str:
    """``text`` as the current font can show it."""
    return text if pdf.font_family == "unicode" else _latin1(text)


def _latin1(text: str) -> str:
    text = text.replace("\u2014", "-").replace("\u2013", "-")
    return text.encode("latin-1", "replace").decode("latin-1")


def _begin(pdf, *groups: str) -> None:
    """Open marked content of the optional content groups named by their resource keys."""
    for key in groups:
        # fpdf2 has no call for marked content: the operator goes into the page as it is
        pdf._out(f"/OC /{key} BDC")


def _end(pdf, count: int = 1) -> None:
    for _ in range(count):
        pdf._out("EMC")


def level_name(level: int) -> str:
    """A level's layer name: what the SVG's ``level-K`` class stands for."""
    return "visible" if level == 0 else f"hidden {level}"


def _add_layers(data: bytes, layers: dict[str, str], order: list) -> bytes:
    """The PDF ``data`` with optional content groups: ``layers`` maps resource keys used in the
    page's marked content to layer names; ``order`` lists the viewer's entries: a key, or a
    branch ``[label, key, ...]``."""
    import pikepdf

    with pikepdf.open(io.BytesIO(data)) as doc:
        groups = {
            key: doc.make_indirect(pikepdf.Dictionary(Type=pikepdf.Name.OCG, Name=pikepdf.String(name)))
            for key, name in layers.items()
        }
        page = doc.pages[0]
        properties = pikepdf.Dictionary({f"/{key}": ref for key, ref in groups.items()})
        page.obj.Resources[pikepdf.Name.Properties] = properties

        def entry(item):
            # a list is a labelled branch: its label, then its groups
            if isinstance(item, list):
                return pikepdf.Array([pikepdf.String(item[0]), *(groups[key] for key in item[1:])])
            return groups[item]

        doc.Root.OCProperties = pikepdf.Dictionary(
            OCGs=pikepdf.Array(list(groups.values())),
            D=pikepdf.Dictionary(
                Name=pikepdf.String("blueprint"),
                BaseState=pikepdf.Name.ON,
                Order=pikepdf.Array([entry(item) for item in order]),
            ),
        )
        out = io.BytesIO()
        doc.save(out)
    return out.getvalue()


def _section(pdf, drawing, to_page: float, base: float) -> None:
    """A section's hatching and heavy cut outline in a graphics state group of their own, each
    marked as content of its kind's layer."""
    color = tuple(round(c * 255) for c in drawing.style.level(0).color)
    for segments, width, kind in (
        (drawing.section.hatch, SECTION_HATCH_WIDTH, HATCH),
        (drawing.section.outline, SECTION_OUTLINE_WIDTH, SECTION),
    ):
        if not len(segments):
            continue
        _begin(pdf, f"K{kind}")
        with pdf.local_context():
            pdf.set_draw_color(*color)
            pdf.set_line_width(width * base)
            for (x0, y0), (x1, y1) in (segments * to_page).tolist():
                pdf.line(x0, y0, x1, y1)
        _end(pdf)


def _section_kinds(section) -> list[int]:
    """The kinds of line a section draws: its hatching and its outline, where it has them."""
    return [k for k, lines in ((SECTION, section.outline), (HATCH, section.hatch)) if len(lines)]


def _mark_kinds(marks) -> list[int]:
    """The kinds of a sheet's marks drawn: ``sheet`` and ``dimension``, where there are some."""
    found = {*marks.kinds.tolist(), *(t.kind for t in marks.texts)}
    return [KINDS.index(kind) for kind in MARK_KINDS if kind in found]


def _sheet(pdf, drawing, to_page: float, base: float, unit: str) -> None:
    """A sheet's border, title block and view labels, and dimensions, in a graphics state group
    of their own, each kind marked as content of its kind's layer."""
    marks = drawing.marks
    color = tuple(round(c * 255) for c in drawing.style.title_color)
    points_per_unit = 72 / 25.4 if unit == "mm" else 1.0
    for code in _mark_kinds(marks):
        kind = KINDS[code]
        of_kind = marks.kinds == kind
        _begin(pdf, f"K{code}")
        with pdf.local_context():
            pdf.set_draw_color(*color)
            pdf.set_text_color(*color)
            for ((x0, y0), (x1, y1)), width in zip(
                (marks.lines[of_kind] * to_page).tolist(), marks.widths[of_kind].tolist(), strict=True
            ):
                pdf.set_line_width(width * base)
                pdf.line(x0, y0, x1, y1)
            for text in marks.texts:
                if text.kind != kind:
                    continue
                _font(pdf, text.height * to_page * points_per_unit)
                value = _text(pdf, text.text)
                x, y = text.x * to_page, text.y * to_page
                shift = pdf.get_string_width(value) / 2 if text.anchor == "middle" else 0.0
                with pdf.rotation(text.angle, x, y):
                    pdf.text(x - shift, y, value)
        _end(pdf)


def _lines(pdf, drawing, groups, points, offsets, base: float) -> None:
    """The lines of ``groups`` (``VectorDrawing.groups``), each group marked as content of its
    part's layer, its kind's and its level's."""
    style = drawing.style
    for part, kind, level, index in groups:
        if not style.shows(kind):
            continue
        line = style.line(kind, level, part in drawing.highlight)
        _begin(pdf, f"P{part}", f"K{kind}", f"L{level}")
        with pdf.local_context(stroke_opacity=line.opacity):
            pdf.set_draw_color(*(round(c * 255) for c in line.color))
            pdf.set_line_width(line.width * base)
            if line.dash:
                on = line.dash[0] * base
                off = (line.dash[1] if len(line.dash) > 1 else line.dash[0]) * base
                pdf.set_dash_pattern(dash=on, gap=off)
            else:
                pdf.set_dash_pattern()
            for i in index.tolist():
                chunk = points[offsets[i] : offsets[i + 1]]
                if len(chunk) >= 2:
                    pdf.polyline([tuple(p) for p in chunk.tolist()], style="D")
        _end(pdf, 3)


def _shading(pdf, shading, to_page: float) -> None:
    """Shaded faces filled back to front (each at the shading's opacity)."""
    with pdf.local_context(fill_opacity=shading.opacity, stroke_opacity=shading.opacity):
        pdf.set_line_width(0.5 * to_page)
        for corners, color in zip((shading.points * to_page).tolist(), shading.color.tolist(), strict=True):
            rgb = tuple(round(c * 255) for c in color)
            pdf.set_fill_color(*rgb)
            # the fill's own colour as a hairline too, so that neighbours leave no seam
            pdf.set_draw_color(*rgb)
            pdf.polygon([tuple(p) for p in corners], style="DF")


def _glyphs(pdf, glyphs, to_page: float, unit: str) -> None:
    """Glyph polylines in their styles (dashed or dimmed behind the model), then the labels."""
    points = glyphs.points * to_page
    for i in range(len(glyphs)):
        color, width, dash, opacity = glyphs.style(i)
        chunk = points[glyphs.offsets[i] : glyphs.offsets[i + 1]]
        if len(chunk) < 2:
            continue
        with pdf.local_context(stroke_opacity=opacity * color[3]):
            pdf.set_draw_color(*(round(c * 255) for c in color[:3]))
            pdf.set_line_width(width * to_page)
            if dash:
                pdf.set_dash_pattern(dash=dash[0] * to_page, gap=dash[-1 if len(dash) > 1 else 0] * to_page)
            else:
                pdf.set_dash_pattern()
            pdf.polyline([tuple(p) for p in chunk.tolist()], style="D")
    pdf.set_dash_pattern()
    points_per_unit = 72 / 25.4 if unit == "mm" else 1.0
    for text in glyphs.texts:
        alpha = (glyphs.mode.opacity if text.hidden and glyphs.mode.mode == "dim" else 1.0) * text.color[3]
        size = text.size * to_page
        with pdf.local_context(fill_opacity=alpha):
            _font(pdf, size * points_per_unit)
            pdf.set_text_color(*(round(c * 255) for c in text.color[:3]))
            value = _text(pdf, text.text)
            fx, fy = ANCHOR_SIDES[text.anchor]
            # fpdf2 places text by its baseline: a capital stands about 0.72 of the size above it
            x = text.x * to_page - fx * pdf.get_string_width(value)
            y = text.y * to_page + (1 - fy) * 0.72 * size
            pdf.text(x, y, value)


def pdf_bytes(drawing) -> bytes:
    """The drawing as a one-page PDF document."""
    try:
        from fpdf import FPDF
    except ImportError as exc:  # pragma: no cover - depends on the environment
        from blueprint.errors import InputError

        raise InputError("PDF output needs the fpdf2 package (pip install fpdf2)") from exc

    page = drawing.page
    if page.unit == "mm":
        unit, to_page = "mm", page.factor
        base = drawing.page_width()
    else:
        unit, to_page = "pt", PT_PER_PX
        base = drawing.line_width * PT_PER_PX
    # the page's own size: a sheet's paper is not a whole number of pixels
    width, height = page.width / page.factor * to_page, page.height / page.factor * to_page
    pdf = FPDF(unit=unit, format=(width, height))
    pdf.set_auto_page_break(False)
    pdf.set_margin(0)
    pdf.set_creator("blueprint")
    pdf.set_title(drawing.title or drawing.name)
    pdf.add_page()
    style = drawing.style
    if style.paper is not None:
        pdf.set_fill_color(*(round(c * 255) for c in style.paper))
        pdf.rect(0, 0, width, height, style="F")
    points = drawing.points * to_page
    offsets = drawing.offsets.tolist()
    shown = np.array([style.shows(k) for k in range(len(KINDS))])[drawing.kind]
    parts = sorted({int(p) for p in drawing.part[shown].tolist()})
    kinds = sorted({int(k) for k in drawing.kind[shown].tolist()})
    levels = sorted({int(k) for k in drawing.level[shown].tolist()})
    # the kinds of what is drawn besides the lines: a section, a sheet's marks, glyphs
    if drawing.section is not None:
        kinds += _section_kinds(drawing.section)
    if drawing.marks is not None:
        kinds += _mark_kinds(drawing.marks)
    if drawing.glyphs is not None:
        kinds.append(GLYPH)
    kinds = sorted(set(kinds))
    layers = {f"P{p}": drawing.part_names[p] for p in parts}
    layers.update({f"K{k}": KINDS[k] for k in kinds})
    layers.update({f"L{k}": level_name(k) for k in levels})
    order: list = [
        ["parts", *(f"P{p}" for p in parts)],
        ["kinds", *(f"K{k}" for k in kinds)],
        ["levels", *(f"L{k}" for k in levels)],
    ]
    if drawing.shading is None:
        _lines(pdf, drawing, drawing.groups(), points, offsets, base)
    else:
        # lines behind the shaded parts, the shading over them, then the rest
        _lines(pdf, drawing, drawing.groups(True), points, offsets, base)
        layers["SHADING"] = "shading"
        order.append("SHADING")
        _begin(pdf, "SHADING")
        _shading(pdf, drawing.shading, to_page)
        _end(pdf)
        _lines(pdf, drawing, drawing.groups(False), points, offsets, base)
    pdf.set_dash_pattern()
    if drawing.section is not None:
        layers["SECTION"] = "section"
        order.append("SECTION")
        _begin(pdf, "SECTION")
        _section(pdf, drawing, to_page, base)
        _end(pdf)
    if drawing.marks is not None:
        layers["SHEET"] = "sheet"
        order.append("SHEET")
        _begin(pdf, "SHEET")
        _sheet(pdf, drawing, to_page, base, unit)
        _end(pdf)
    if drawing.glyphs is not None:
        layers["GLYPHS"] = "glyphs"
        order.append("GLYPHS")
        _begin(pdf, "GLYPHS", f"K{GLYPH}")
        _glyphs(pdf, drawing.glyphs, to_page, unit)
        _end(pdf, 2)
    if drawing.title:
        size_pt = 0.022 * drawing.height * to_page * (72 / 25.4 if unit == "mm" else 1.0)
        _font(pdf, size_pt)
        pdf.set_text_color(*(round(c * 255) for c in style.title_color))
        pdf.text(0.02 * width, height - 0.02 * height, _text(pdf, drawing.title))
    data = bytes(pdf.output())
    return _add_layers(data, layers, order) if layers else data
