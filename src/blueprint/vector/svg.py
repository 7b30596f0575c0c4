"""SVG output: one group per part (an Inkscape layer), one path per occlusion level inside it."""

from __future__ import annotations

import math
import re
from html import escape as _escape

import numpy as np

from blueprint import parallel
from blueprint.compose.glyphs.raster import ANCHOR_SIDES
from blueprint.scene.sheet import MARK_KINDS

from .linework import KINDS, Lines
from .section import SECTION_HATCH_WIDTH, SECTION_OUTLINE_WIDTH
from .style import LineStyle

__all__ = ["edge_text", "format_numbers", "path_data", "safe_id", "svg_bytes"]

# Coordinates are written to a grid no coarser than this many pixels (well inside the
# Douglas–Peucker tolerance).
QUANTUM_PX = 0.1
# Decimals the path text is built for as bytes (``_number_table``); more take ``format_numbers``,
# whose shortest float strings switch to exponents below 1e-4.
_TEXT_DECIMALS = 4
_ID_BAD = re.compile(r"[^A-Za-z0-9_.-]+")


def _text(value: str) -> str:
    """``value`` as XML character data (xml.sax.saxutils would import urllib, http and email
    into a small drawing's process)."""
    return _escape(value, quote=False)


def safe_id(name: str, taken: set[str]) -> str:
    """An XML id (NCName) from a part name, unique among ``taken`` (which it joins)."""
    base = _ID_BAD.sub("_", name).strip("_.-") or "part"
    if not (base[0].isalpha() or base[0] == "_"):
        base = "p_" + base
    candidate, k = base, 2
    while candidate in taken:
        candidate = f"{base}-{k}"
        k += 1
    taken.add(candidate)
    return candidate


def _decimals(factor: float) -> int:
    """Decimals that put the page-unit grid at or below QUANTUM_PX pixels."""
    return max(0, math.ceil(-math.log10(QUANTUM_PX * factor) - 1e-9))


def format_numbers(values: np.ndarray, decimals: int) -> list[str]:
    """Shortest decimal strings of numbers that are multiples of 10**-decimals."""
    if decimals == 0:
        return [str(v) for v in np.rint(values).astype(np.int64).tolist()]
    text = [repr(v) for v in np.round(values, decimals).tolist()]
    return [t[:-2] if t.endswith(".0") else t for t in text]


def path_data(points: np.ndarray, offsets: np.ndarray, factor: float, decimals: int) -> str:
    """SVG path data of polylines: an absolute move to each start, relative lines after it.

    Points are snapped to the output grid first and the relative steps taken between snapped
    points, so rounding never accumulates. Repeated points and polylines that shrink to one
    point are dropped.
    """
    return paths_data(points, offsets, np.array([0, len(offsets) - 1]), factor, decimals)[0]


def paths_data(
    points: np.ndarray,
    offsets: np.ndarray,
    groups: np.ndarray,
    factor: float,
    decimals: int,
    drawn: np.ndarray | None = None,
    relative: bool = False,
) -> list[str]:
    """``path_data`` of each run of polylines ``groups[g]:groups[g + 1]``, in one pass over all
    of them: a drawing's paths are many, and most are short. ``drawn`` (P,) bool, where given,
    is set to whether each polyline is drawn (not shrunk to one point on the grid).
    ``relative`` moves to each polyline's start but a path's first from the end of the one
    before (``m``): nearby lines take shorter numbers."""
    unit = 10.0**decimals
    grid = np.rint(points * factor * unit).astype(np.int64)
    first = np.zeros(len(grid), bool)
    first[offsets[:-1]] = True
    step = np.diff(grid, axis=0, prepend=grid[:1])
    keep = first | np.any(step != 0, axis=1)
    owner = np.repeat(np.arange(len(offsets) - 1), np.diff(offsets))
    counts = np.bincount(owner[keep], minlength=len(offsets) - 1)
    keep &= counts[owner] >= 2
    if drawn is not None:
        drawn[:] = counts >= 2
    grid, first, owner = grid[keep], first[keep], owner[keep]
    # numbers of each group: two a point kept
    ends = 2 * np.searchsorted(owner, groups, side="left")
    if len(grid) == 0:
        return [""] * (len(groups) - 1)
    step = np.diff(grid, axis=0, prepend=grid[:1])
    absolute = first.copy()
    if relative:
        absolute[:] = False
        absolute[np.searchsorted(owner, groups[:-1])[np.diff(ends) > 0]] = True
    ticks = np.where(absolute[:, None], grid, step).reshape(-1)
    # each number's lead: M (m) before a polyline's start, l before its first step, else a space
    lead = np.full(len(ticks), ord(" "), np.uint8)
    starts = np.flatnonzero(first)
    lead[2 * starts] = ord("m")
    lead[2 * np.flatnonzero(absolute)] = ord("M")
    lead[2 * starts + 2] = ord("l")
    if decimals <= _TEXT_DECIMALS and np.abs(ticks).max() < 10**15:
        table, mask = _number_table(ticks, lead, decimals)
        text = table[mask].tobytes().decode("ascii")
        cut = np.r_[0, np.cumsum(mask.sum(axis=1))][ends].tolist()
        return [text[a:b] for a, b in zip(cut[:-1], cut[1:], strict=True)]
    numbers = format_numbers(ticks / unit, decimals)
    words = [chr(c) + t for c, t in zip(lead.tolist(), numbers, strict=True)]
    bounds = ends.tolist()
    return [_shorten("".join(words[a:b])) for a, b in zip(bounds[:-1], bounds[1:], strict=True)]


def _shorten(text: str) -> str:
    """A minus sign separates numbers by itself, and leading zeros are optional."""
    return (
        text.replace(" -", "-")
        .replace("-0.", "-.")
        .replace(" 0.", " .")
        .replace("l0.", "l.")
        .replace("m0.", "m.")
    )


def _number_table(ticks: np.ndarray, lead: np.ndarray, decimals: int) -> tuple[np.ndarray, np.ndarray]:
    """Path text of integers ``ticks`` (multiples of 10**-decimals), each after its ``lead``
    byte, as ``format_numbers`` and ``_shorten`` write it, as a row of characters a number
    (lead, sign, whole digits, point, fraction) and a mask of those written."""
    negative = ticks < 0
    magnitude = np.abs(ticks)
    scale = 10**decimals
    whole, fraction = magnitude // scale, magnitude % scale
    wide = max(len(str(int(whole.max()))), 1)
    powers = 10 ** np.arange(wide - 1, -1, -1, dtype=np.int64)
    whole_digits = (whole[:, None] // powers) % 10
    whole_len = 1 + (whole[:, None] >= powers[:-1]).sum(axis=1) if wide > 1 else np.ones(len(whole), np.int64)
    spaced = lead == ord(" ")
    columns = [
        lead[:, None],
        np.full((len(ticks), 1), ord("-"), np.uint8),
        (whole_digits + ord("0")).astype(np.uint8),
    ]
    shown = [
        (~(negative & spaced))[:, None],
        negative[:, None],
        np.arange(wide)[None] >= wide - whole_len[:, None],
    ]
    # "0.5" loses its zero after a space, an l or a minus sign: only "M0.5" keeps it
    bare = (whole == 0) & (fraction > 0) & (negative | (lead != ord("M")))
    shown[2][:, -1] &= ~bare
    if decimals:
        fraction_powers = 10 ** np.arange(decimals - 1, -1, -1, dtype=np.int64)
        fraction_digits = (fraction[:, None] // fraction_powers) % 10
        # the fraction ends at its last digit that is not zero
        nonzero = fraction_digits != 0
        fraction_len = np.where(nonzero.any(axis=1), decimals - np.argmax(nonzero[:, ::-1], axis=1), 0)
        columns += [
            np.full((len(ticks), 1), ord("."), np.uint8),
            (fraction_digits + ord("0")).astype(np.uint8),
        ]
        shown += [(fraction > 0)[:, None], np.arange(decimals)[None] < fraction_len[:, None]]
    return np.concatenate(columns, axis=1), np.concatenate(shown, axis=1)


def _stroke_attributes(line: LineStyle, base: float) -> dict[str, str]:
    attrs = {"stroke": line.hex, "stroke-width": f"{line.width * base:.4g}"}
    if line.opacity < 1.0:
        attrs["stroke-opacity"] = f"{line.opacity:.3g}"
    if line.dash:
        attrs["stroke-dasharray"] = " ".join(f"{d * base:.4g}" for d in line.dash)
    return attrs


def _stroke(line: LineStyle, base: float) -> str:
    return " ".join(f'{k}="{v}"' for k, v in _stroke_attributes(line, base).items())


# what a stroke attribute left out stands for, where a path must undo its group's
_STROKE_DEFAULTS = {"stroke-opacity": "1", "stroke-dasharray": "none"}


def _stroke_changes(line: LineStyle, shared: LineStyle, base: float) -> str:
    """The stroke attributes of ``line`` that differ from ``shared``'s, each after a space."""
    mine, theirs = _stroke_attributes(line, base), _stroke_attributes(shared, base)
    for key, value in _STROKE_DEFAULTS.items():
        if key in theirs:
            mine.setdefault(key, value)
    return "".join(f' {k}="{v}"' for k, v in mine.items() if theirs.get(k) != v)


def svg_bytes(drawing) -> bytes:
    """The drawing as an SVG document (UTF-8).

    The view box is the image in pixels, or the page in millimetres for a drawing to scale.
    Every part is a group whose id is its sanitised name (and an Inkscape layer labelled with
    the name itself); inside it one path per occlusion level, deepest first, with class
    ``level-K`` and the level's stroke style.
    """
    page = drawing.page
    factor = page.factor
    decimals = _decimals(factor)
    base = drawing.page_width()
    width, height = page.width, page.height
    size_unit = "mm" if page.unit == "mm" else ""
    out = [
        '<?xml version="1.0" encoding="UTF-8"?>\n',
        '<svg xmlns="http://www.w3.org/2000/svg" '
        'xmlns:inkscape="http://www.inkscape.org/namespaces/inkscape" version="1.1" '
        f'width="{width:.6g}{size_unit}" height="{height:.6g}{size_unit}" '
        f'viewBox="0 0 {width:.6g} {height:.6g}">\n',
        f"<title>{_text(drawing.title or drawing.name)}</title>\n",
        f"<desc>{_text(_description(drawing))}</desc>\n",
    ]
    style = drawing.style
    if style.paper is not None:
        paper = LineStyle(style.paper).hex
        out.append(
            f'<rect id="paper" x="0" y="0" width="{width:.6g}" height="{height:.6g}" fill="{paper}"/>\n'
        )
    taken = {"paper", "lines", "title", "shading", "lines-behind-shading", "glyphs"}
    if drawing.shading is None:
        out.append(_line_group(drawing, "lines", drawing.groups(), taken, factor, decimals, base))
    else:
        # lines behind the shaded parts, the shading over them, then the rest
        out.append(
            _line_group(drawing, "lines-behind-shading", drawing.groups(True), taken, factor, decimals, base)
        )
        out.append(_shading_group(drawing.shading, factor, decimals))
        out.append(_line_group(drawing, "lines", drawing.groups(False), taken, factor, decimals, base))
    if drawing.section is not None:
        out.append(_section_group(drawing, factor, decimals, base))
    if drawing.marks is not None:
        out.append(_sheet_group(drawing, factor, decimals, base))
    if drawing.glyphs is not None:
        out.append(_glyph_group(drawing.glyphs, factor, decimals))
    if drawing.title:
        size = 0.022 * height
        color = LineStyle(style.title_color).hex
        out.append(
            f'<text id="title" x="{0.02 * width:.6g}" y="{height - 0.02 * height:.6g}" '
            f'font-family="sans-serif" font-size="{size:.4g}" fill="{color}">{_text(drawing.title)}</text>\n'
        )
    out.append("</svg>\n")
    return "".join(out).encode("utf-8")


def _line_group(drawing, gid: str, groups, taken: set[str], factor: float, decimals: int, base: float) -> str:
    """The lines of ``groups`` (``VectorDrawing.groups``) as the group ``gid``: a layer per part
    (``data-part``), in it a group per level (``data-level``, the class ``level-K`` and the
    level's stroke), in that a path per kind (``data-kind``, its own stroke where it differs
    from the level's), a subpath a line, and the lines' source edges (``edge_text``).

    The group is scaled by the output grid (``transform="scale(.1)"`` on a drawing in pixels)
    and its coordinates and widths are whole multiples of the grid: no decimal point in the
    many numbers of the paths."""
    style, lines = drawing.style, drawing.lines
    unit = 10**decimals
    factor, base = factor * unit, base * unit
    scaled = f' transform="scale({_shorten(repr(1 / unit))})"' if decimals else ""
    out = [f'<g id="{gid}"{scaled} fill="none" stroke-linecap="round" stroke-linejoin="round">\n']
    shown = {kind: style.shows(kind) for kind in range(len(KINDS))}
    groups = [g for g in groups if shown[g[1]]]
    if not groups:
        return out[0] + "</g>\n"
    # within a path its lines by their lowest edge: the edges' differences stay small
    index = _by_lowest_edge(lines, [g[3] for g in groups])
    bounds = np.r_[0, np.cumsum([len(g[3]) for g in groups])]
    texts, edge_lists = _group_texts(lines, index, bounds, factor)
    current = None
    # a stroke is the same for every path of one kind, level and highlight: written once
    strokes: dict[tuple[int, bool], tuple[LineStyle, str]] = {}
    changes: dict[tuple[int, int, bool], str] = {}
    for g, ((part, kind, level, _), d) in enumerate(zip(groups, texts, strict=True)):
        if not d:
            continue
        highlighted = part in drawing.highlight
        if current is None or current[0] != part:
            if current is not None:
                out.append("</g>\n</g>\n")
            name = drawing.part_names[part] if part < len(drawing.part_names) else f"part{part}"
            part_id = safe_id(name, taken)
            out.append(
                f'<g id="{part_id}" inkscape:groupmode="layer" inkscape:label="{_escape(name)}" '
                f'data-part="{part}">\n'
            )
        elif current[1] != level:
            out.append("</g>\n")
        if current is None or current != (part, level):
            # the level's stroke is its outlines' (ISO 128's wide lines): most lines are those
            if (level, highlighted) not in strokes:
                shared = style.line("silhouette", level, highlighted)
                strokes[level, highlighted] = shared, _stroke(shared, base)
            shared, stroke = strokes[level, highlighted]
            out.append(f'<g class="level-{level}" data-level="{level}" {stroke}>\n')
            current = (part, level)
        if (kind, level, highlighted) not in changes:
            line = style.line(kind, level, highlighted)
            changes[kind, level, highlighted] = _stroke_changes(line, shared, base)
        own = changes[kind, level, highlighted]
        edges = f' data-edges="{edge_lists[g]}"' if edge_lists[g] else ""
        out.append(f'<path data-kind="{KINDS[kind]}"{own}{edges} d="{d}"/>\n')
    if current is not None:
        out.append("</g>\n</g>\n")
    out.append("</g>\n")
    return "".join(out)


def _group_texts(lines: Lines, index: np.ndarray, bounds: np.ndarray, factor: float) -> tuple[list, list]:
    """The path data (``paths_data``, relative, on a grid of ``factor``) and the source edges
    (``edge_texts``) of each group of the lines ``index[bounds[g]:bounds[g + 1]]``, blocks of
    groups of about equal points side by side on the pool (a group's text is its own)."""
    lengths = lines.offsets[index + 1] - lines.offsets[index]
    sub_offsets = np.r_[0, np.cumsum(lengths)]
    rows = np.repeat(lines.offsets[index] - sub_offsets[:-1], lengths) + np.arange(sub_offsets[-1])
    first_point = sub_offsets[bounds]
    cuts = [lo for lo, _ in parallel.cuts(int(first_point[-1]))]
    splits = np.unique(np.r_[np.searchsorted(first_point[:-1], cuts), len(bounds) - 1]).tolist()

    def block(g: int, h: int) -> tuple[list, list]:
        lo, hi = bounds[g], bounds[h]
        at, end = sub_offsets[lo], sub_offsets[hi]
        drawn = np.zeros(hi - lo, bool)
        texts = paths_data(
            lines.points[rows[at:end]],
            sub_offsets[lo : hi + 1] - at,
            bounds[g : h + 1] - lo,
            factor,
            0,
            drawn,
            relative=True,
        )
        edges = edge_texts(lines, index[lo:hi][drawn], np.r_[0, np.cumsum(drawn)][bounds[g : h + 1] - lo])
        return texts, edges

    found = parallel.each(lambda k: block(splits[k], splits[k + 1]), list(range(len(splits) - 1)))
    return [t for texts, _ in found for t in texts], [e for _, edges in found for e in edges]


def _by_lowest_edge(lines: Lines, groups: list[np.ndarray]) -> np.ndarray:
    """The lines of every group (an array of line indices each), group after group, each
    group's ordered by their lowest source edge, those without edges first."""
    index = np.concatenate(groups)
    group = np.repeat(np.arange(len(groups)), [len(g) for g in groups])
    size = lines.edge_offsets[index + 1] - lines.edge_offsets[index]
    lowest = np.full(len(index), -1, np.int64)
    has = np.flatnonzero(size > 0)
    if len(has):
        values, _ = _edges_of(lines, index[has])
        lowest[has] = np.minimum.reduceat(values, np.cumsum(size[has]) - size[has])
    return index[np.lexsort((lowest, group))]


def _edges_of(lines: Lines, index: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The source edges of the lines ``index``, one after the other, and the position in
    ``index`` of the line of each."""
    starts, ends = lines.edge_offsets[index], lines.edge_offsets[index + 1]
    size = ends - starts
    rows = np.repeat(starts - (np.cumsum(size) - size), size) + np.arange(int(size.sum()))
    return lines.edges[rows], np.repeat(np.arange(len(index)), size)


def edge_text(lines: Lines, index: np.ndarray) -> str:
    """``data-edges`` of a path whose subpaths are the lines ``index``: each line's source edges
    ascending, lines apart by ``;``, and every number written as its difference from the number
    before it in the attribute (the first as itself): a running sum over all the numbers, read
    in order, gives the edges back. A line with no edges (an intersection) has an empty entry."""
    if len(index) == 0:
        return ""
    text = edge_texts(lines, index, np.array([0, len(index)]))[0]
    return text or ";" * (len(index) - 1)


def edge_texts(lines: Lines, index: np.ndarray, groups: np.ndarray) -> list[str]:
    """``edge_text`` of each run of lines ``index[groups[g]:groups[g + 1]]``, all formatted in
    one pass ("" for a run whose lines have no edges at all, which writes no attribute)."""
    values, owner = _edges_of(lines, index)
    if len(values) == 0:
        return [""] * (len(groups) - 1)
    order = np.lexsort((values, owner))
    values, owner = values[order], owner[order]
    # an edge repeated within a line is written once
    keep = np.r_[True, (owner[1:] != owner[:-1]) | (values[1:] != values[:-1])]
    values, owner = values[keep], owner[keep]
    group = np.searchsorted(groups, owner, side="right") - 1
    opens = np.r_[True, group[1:] != group[:-1]]  # the group's first number: written as itself
    steps = np.where(opens, values, np.diff(values, prepend=0))
    line_first = np.r_[True, owner[1:] != owner[:-1]]
    # semicolons before a line's first number: one a line since the number before in the group
    previous = np.where(opens, groups[group], np.r_[0, owner[:-1]])
    semis = np.where(line_first, owner - previous, 0)
    closes = np.r_[opens[1:], True]
    tail = np.where(closes, groups[group + 1] - 1 - owner, 0)
    table, mask = _integer_table(steps, ~line_first)
    written = mask.sum(axis=1)
    chunk = semis + written + tail
    start = np.cumsum(chunk) - chunk
    out = np.full(int(chunk.sum()), ord(";"), np.uint8)
    row, column = np.nonzero(mask)
    out[start[row] + semis[row] + (np.cumsum(mask, axis=1) - 1)[row, column]] = table[row, column]
    text = out.tobytes().decode("ascii")
    first, last = np.flatnonzero(opens), np.flatnonzero(closes)
    texts = [""] * (len(groups) - 1)
    for g, a, b in zip(
        group[first].tolist(), start[first].tolist(), (start + chunk)[last].tolist(), strict=True
    ):
        texts[g] = text[a:b]
    return texts


def _integer_table(numbers: np.ndarray, spaced: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(N, W) uint8 characters of the (N,) int64 ``numbers`` as ``str`` writes them, each after
    a space where ``spaced``, and the (N, W) bool mask of those written, in order."""
    magnitude = np.abs(numbers)
    wide = max(len(str(int(magnitude.max()))), 1)
    powers = 10 ** np.arange(wide - 1, -1, -1, dtype=np.int64)
    digits = ((magnitude[:, None] // powers) % 10 + ord("0")).astype(np.uint8)
    shown = np.arange(wide)[None] >= wide - (1 + (magnitude[:, None] >= powers[:-1]).sum(axis=1))[:, None]
    table = np.concatenate(
        [
            np.full((len(numbers), 1), ord(" "), np.uint8),
            np.full((len(numbers), 1), ord("-"), np.uint8),
            digits,
        ],
        axis=1,
    )
    mask = np.concatenate([spaced[:, None], (numbers < 0)[:, None], shown], axis=1)
    return table, mask


def _shading_group(shading, factor: float, decimals: int) -> str:
    """Shaded faces as the layer ``shading``: filled triangles, back to front."""
    out = [
        '<g id="shading" inkscape:groupmode="layer" inkscape:label="shading" stroke="none"'
        + (f' opacity="{shading.opacity:.3g}"' if shading.opacity < 1 else "")
        + ">\n"
    ]
    corners = np.round(shading.points * factor, decimals).reshape(-1, 6)
    for (x0, y0, x1, y1, x2, y2), color in zip(corners.tolist(), shading.color.tolist(), strict=True):
        fill = "#" + "".join(f"{round(c * 255):02x}" for c in color)
        # the fill's own colour as a hairline too, so that neighbours leave no seam between them
        out.append(
            f'<path fill="{fill}" stroke="{fill}" stroke-width="{0.5 * factor:.3g}" '
            f'd="M{x0:g} {y0:g}L{x1:g} {y1:g}L{x2:g} {y2:g}z"/>\n'
        )
    out.append("</g>\n")
    return "".join(out)


def _section_group(drawing, factor: float, decimals: int, base: float) -> str:
    """A section's hatching (thin) and cut outline (heavy) as the group ``section``."""
    section = drawing.section
    color = drawing.style.level(0).hex
    out = [f'<g id="section" class="section" fill="none" stroke="{color}" stroke-linecap="round">\n']
    for name, kind, segments, width in (
        ("section-hatch", "hatch", section.hatch, SECTION_HATCH_WIDTH),
        ("section-outline", "section", section.outline, SECTION_OUTLINE_WIDTH),
    ):
        offsets = np.arange(0, 2 * len(segments) + 1, 2)
        d = path_data(segments.reshape(-1, 2), offsets, factor, decimals)
        if d:
            out.append(
                f'<path class="{name}" data-kind="{kind}" stroke-width="{width * base:.4g}" d="{d}"/>\n'
            )
    out.append("</g>\n")
    return "".join(out)


def _sheet_group(drawing, factor: float, decimals: int, base: float) -> str:
    """A sheet's border, title block and view labels, and dimensions, as the group ``sheet``:
    a path per kind of mark (``data-kind`` ``sheet`` or ``dimension``) and width, then the
    texts, each with its kind."""
    marks = drawing.marks
    color = LineStyle(drawing.style.title_color).hex
    out = [f'<g id="sheet" class="sheet" fill="none" stroke="{color}" stroke-linecap="square">\n']
    for kind in MARK_KINDS:
        of_kind = marks.kinds == kind
        for width in np.unique(marks.widths[of_kind]).tolist():
            segments = marks.lines[of_kind & (marks.widths == width)]
            d = path_data(segments.reshape(-1, 2), np.arange(0, 2 * len(segments) + 1, 2), factor, decimals)
            out.append(f'<path data-kind="{kind}" stroke-width="{width * base:.4g}" d="{d}"/>\n')
    for text in marks.texts:
        x, y = text.x * factor, text.y * factor
        turn = f' transform="rotate({-text.angle:g} {x:.6g} {y:.6g})"' if text.angle else ""
        out.append(
            f'<text data-kind="{text.kind}" x="{x:.6g}" y="{y:.6g}"{turn} font-family="sans-serif" '
            f'font-size="{text.height * factor:.4g}" text-anchor="{text.anchor}" fill="{color}" '
            f'stroke="none">{_text(text.text)}</text>\n'
        )
    out.append("</g>\n")
    return "".join(out)


def _glyph_group(glyphs, factor: float, decimals: int) -> str:
    """Glyphs as the layer ``glyphs``: one path per polyline in its glyph's style, class
    ``glyph-hidden`` where it runs behind the model (dashed or dimmed there), then the labels."""
    out = [
        '<g id="glyphs" inkscape:groupmode="layer" inkscape:label="glyphs" data-kind="glyph" fill="none" '
        'stroke-linecap="round" stroke-linejoin="round">\n'
    ]
    for i in range(len(glyphs)):
        color, width, dash, opacity = glyphs.style(i)
        a, b = glyphs.offsets[i], glyphs.offsets[i + 1]
        d = path_data(glyphs.points[a:b], np.array([0, b - a]), factor, decimals)
        if not d:
            continue
        attrs = [f'stroke="{LineStyle(color[:3]).hex}"', f'stroke-width="{width * factor:.4g}"']
        if dash:
            attrs.append(f'stroke-dasharray="{" ".join(f"{v * factor:.4g}" for v in dash)}"')
        alpha = opacity * (color[3] if len(color) > 3 else 1.0)
        if alpha < 1:
            attrs.append(f'stroke-opacity="{alpha:.3g}"')
        kind = "glyph-hidden" if glyphs.hidden[i] else "glyph"
        out.append(f'<path class="{kind}" {" ".join(attrs)} d="{d}"/>\n')
    for text in glyphs.texts:
        fx, fy = ANCHOR_SIDES[text.anchor]
        alpha = (glyphs.mode.opacity if text.hidden and glyphs.mode.mode == "dim" else 1.0) * text.color[3]
        opacity = f' fill-opacity="{alpha:.3g}"' if alpha < 1 else ""
        out.append(
            f'<text class="{"glyph-hidden" if text.hidden else "glyph"}" x="{text.x * factor:.6g}" '
            f'y="{text.y * factor:.6g}" font-family="sans-serif" font-size="{text.size * factor:.4g}" '
            f'text-anchor="{_HORIZONTAL[fx]}" dominant-baseline="{_VERTICAL[fy]}" '
            f'fill="{LineStyle(text.color[:3]).hex}"{opacity} stroke="none">{_text(text.text)}</text>\n'
        )
    out.append("</g>\n")
    return "".join(out)


# where a label's anchor point sits on the text: ANCHOR_SIDES' fractions as SVG's words
_HORIZONTAL = {0: "start", 0.5: "middle", 1: "end"}
_VERTICAL = {0: "hanging", 0.5: "central", 1: "alphabetic"}


def _description(drawing) -> str:
    levels = ", ".join(f"level {k}: {n}" for k, n in drawing.lines_per_level().items()) or "no lines"
    text = f"{drawing.name}, {drawing.camera.name} view, {drawing.width}x{drawing.height} px, {levels}"
    if drawing.page.scale is not None:
        text += f", scale {drawing.page.scale_label}, model unit {drawing.page.model_unit}"
    return text
