"""PDF output through fpdf2: one page the size of the drawing, lines grouped by part and level.

A pixel drawing becomes a page of 0.75 pt per pixel (96 per inch, as browsers show SVG); a
drawing to scale a page in millimetres. fpdf2 has no per-name layers (its optional content
groups are keyed by visibility alone), so parts are grouped by drawing order: every part's
lines come together, deepest level first.
"""

from __future__ import annotations

from .section import SECTION_HATCH_WIDTH, SECTION_OUTLINE_WIDTH

__all__ = ["pdf_bytes"]

PT_PER_PX = 0.75


def _latin1(text: str) -> str:
    text = text.replace("\u2014", "-").replace("\u2013", "-")
    return text.encode("latin-1", "replace").decode("latin-1")


def _section(pdf, drawing, to_page: float, base: float) -> None:
    """A section's hatching and heavy cut outline in a graphics state group of their own."""
    color = tuple(round(c * 255) for c in drawing.style.level(0).color)
    for segments, width in (
        (drawing.section.hatch, SECTION_HATCH_WIDTH),
        (drawing.section.outline, SECTION_OUTLINE_WIDTH),
    ):
        with pdf.local_context():
            pdf.set_draw_color(*color)
            pdf.set_line_width(width * base)
            for (x0, y0), (x1, y1) in (segments * to_page).tolist():
                pdf.line(x0, y0, x1, y1)


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
    width, height = drawing.width * to_page, drawing.height * to_page
    pdf = FPDF(unit=unit, format=(width, height))
    pdf.set_auto_page_break(False)
    pdf.set_margin(0)
    pdf.set_creator("blueprint")
    pdf.set_title(_latin1(drawing.title or drawing.name))
    pdf.add_page()
    style = drawing.style
    if style.paper is not None:
        pdf.set_fill_color(*(round(c * 255) for c in style.paper))
        pdf.rect(0, 0, width, height, style="F")
    points = drawing.points * to_page
    offsets = drawing.offsets.tolist()
    for part, level, index in drawing.groups():
        line = style.level(level, part in drawing.highlight)
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
    pdf.set_dash_pattern()
    if drawing.section is not None:
        _section(pdf, drawing, to_page, base)
    if drawing.title:
        size_pt = 0.022 * drawing.height * to_page * (72 / 25.4 if unit == "mm" else 1.0)
        pdf.set_font("helvetica", size=size_pt)
        pdf.set_text_color(*(round(c * 255) for c in style.title_color))
        pdf.text(0.02 * width, height - 0.02 * height, _latin1(drawing.title))
    return bytes(pdf.output())
