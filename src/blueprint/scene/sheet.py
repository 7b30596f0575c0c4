"""The layout of a plan sheet, one for pictures and vector drawings: views placed with even gaps
fitted to their sizes (third angle: top above front, right beside front, iso in the free corner),
each labelled, inside a border with a title block after ISO 7200 (title, scale, units, date,
sheet size).

Everything here is in the sheet's pixels: a picture draws them (``blueprint.compose.glyphs.marks``),
the vector writers turn them into page units. No GPU here.
"""

from __future__ import annotations

import datetime
import math
import os
import re
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from blueprint.errors import InputError
from blueprint.scene.camera import SHEET_CELLS
from blueprint.scene.model import Model

__all__ = [
    "MARK_KINDS",
    "PAPER_MM",
    "Marks",
    "SheetLayout",
    "Text",
    "fit_scale",
    "lay_out_sheet",
    "paper_size",
    "picture_per_mm",
    "place_views",
    "model_name",
    "sheet_fields",
    "sheet_marks",
    "today",
]

#: ISO 216 paper, landscape, in millimetres.
PAPER_MM: dict[str, tuple[float, float]] = {
    "A4": (297.0, 210.0),
    "A3": (420.0, 297.0),
    "A2": (594.0, 420.0),
    "A1": (841.0, 594.0),
    "A0": (1189.0, 841.0),
}
# ISO 5457: a 20 mm filing margin on the left, 10 mm elsewhere; ISO 7200's block is 180 mm wide.
BORDER_MM = (20.0, 10.0)
TITLE_BLOCK_MM = (180.0, 20.0)
LABEL_MM = 5.0
TEXT_MM = 3.5
# widths in base line widths: the border heavy (0.7 mm), the title block's rules medium
BORDER_WIDTH = 2.8
RULE_WIDTH = 1.4


#: What a mark is, as the vector writers tag it (the kinds of line ``blueprint.KINDS`` names):
#: the sheet's own (border, title block, view labels) or a dimension's.
MARK_KINDS = ("sheet", "dimension")


@dataclass(frozen=True)
class Text:
    """A line of text at ``(x, y)`` pixels (its baseline), ``height`` pixels high; ``anchor``
    'start' or 'middle'; ``angle`` degrees anticlockwise on the page; ``kind`` one of
    ``MARK_KINDS``."""

    x: float
    y: float
    height: float
    text: str
    anchor: str = "start"
    angle: float = 0.0
    kind: str = "sheet"


@dataclass(frozen=True)
class Marks:
    """The sheet's own lines and texts and its dimensions': ``lines`` (K, 2, 2) pixels with
    ``widths`` (K,) in base line widths, ``texts``, and ``kinds`` (K,) str, each line's kind
    (one of ``MARK_KINDS``; None: all ``sheet``)."""

    lines: np.ndarray
    widths: np.ndarray
    texts: tuple[Text, ...]
    kinds: np.ndarray | None = None

    def __post_init__(self) -> None:
        if self.kinds is None:
            object.__setattr__(self, "kinds", np.full(len(self.widths), MARK_KINDS[0]))

    def shifted(self, by: np.ndarray) -> Marks:
        """The same marks moved by ``by`` (2,) pixels."""
        dx, dy = (float(v) for v in by)
        texts = tuple(replace(t, x=t.x + dx, y=t.y + dy) for t in self.texts)
        return Marks(self.lines + np.array([dx, dy]), self.widths, texts, self.kinds)

    @staticmethod
    def concatenate(items: list[Marks]) -> Marks:
        """All of ``items``' lines and texts as one ``Marks``, in their order."""
        return Marks(
            np.concatenate([m.lines for m in items]).reshape(-1, 2, 2),
            np.concatenate([m.widths for m in items]),
            tuple(t for m in items for t in m.texts),
            np.concatenate([m.kinds for m in items]),
        )


def paper_size(sheet: str) -> tuple[float, float]:
    """Width and height in mm of ``sheet`` ('A4' ... 'A0', landscape)."""
    key = str(sheet).strip().upper()
    if key not in PAPER_MM:
        raise InputError(f"unknown sheet {sheet!r} (choose {', '.join(PAPER_MM)})")
    return PAPER_MM[key]


def parse_scale(scale: str | float | None) -> float | None:
    """'1:50' (or '50', 50) to 50.0; '2:1' to 0.5; None stays None."""
    if scale is None:
        return None
    if isinstance(scale, int | float):
        value = float(scale)
    else:
        text = str(scale).strip()
        match = re.fullmatch(r"\s*([0-9.]+)\s*[:/]\s*([0-9.]+)\s*", text)
        try:
            value = float(match.group(2)) / float(match.group(1)) if match else float(text)
        except (ValueError, ZeroDivisionError):
            raise InputError(f"scale must look like 1:50, got {scale!r}") from None
    if not (math.isfinite(value) and value > 0):
        raise InputError(f"scale must look like 1:50, got {scale!r}")
    return value


def fit_scale(needed: float) -> float:
    """The smallest standard scale denominator (ISO 5455: 1, 2, 5 times a power of ten, or
    enlargements 2:1, 5:1, 10:1 ...) at least ``needed``."""
    if needed <= 0 or not math.isfinite(needed):
        return 1.0
    k = math.floor(math.log10(needed))
    for step in (1.0, 2.0, 5.0, 10.0):
        candidate = step * 10.0**k
        if candidate >= needed * (1 - 1e-9):
            return candidate
    return 10.0 ** (k + 1)


def place_views(
    extents: dict[str, np.ndarray], cells: dict[str, tuple[int, int]], gap: float, label: float
) -> tuple[dict[str, np.ndarray], tuple[float, float]]:
    """Where each view's cell goes so that the views lie ``gap`` pixels apart and from the
    sheet's edge, with room for a label ``label`` pixels high under each: the columns and rows
    keep the views of the third-angle projection aligned (top over front, right beside front).

    Parameters
    ----------
    extents : dict of view name to (2, 2) float
        Each view's extent in its own cell's pixels.
    cells : dict of view name to (column, row)
    gap, label : float

    Returns
    -------
    shifts : dict of view name to (2,) float
        What to add to a view's pixels.
    size : (float, float)
        The width and height the views take, gaps around included.
    """
    columns = sorted({c for c, _ in cells.values()})
    rows = sorted({r for _, r in cells.values()})
    spans_x = {c: _union([extents[n][:, 0] for n, (cc, _) in cells.items() if cc == c]) for c in columns}
    spans_y = {r: _union([extents[n][:, 1] for n, (_, rr) in cells.items() if rr == r]) for r in rows}
    x, starts_x = gap, {}
    for c in columns:
        starts_x[c] = x - spans_x[c][0]
        x += spans_x[c][1] - spans_x[c][0] + gap
    y, starts_y = gap, {}
    for r in rows:
        starts_y[r] = y - spans_y[r][0]
        y += spans_y[r][1] - spans_y[r][0] + label + gap
    shifts = {n: np.array([starts_x[c], starts_y[r]]) for n, (c, r) in cells.items()}
    return shifts, (x, y)


def _union(spans: list[np.ndarray]) -> tuple[float, float]:
    return float(min(s[0] for s in spans)), float(max(s[1] for s in spans))


@dataclass(frozen=True)
class SheetLayout:
    """Where a sheet's views go and what it draws of its own, in the sheet's pixels.

    Attributes
    ----------
    width, height : float
        The sheet.
    shifts : dict of view name to (2,) float
        What to add to a view's pixels (in its own cell) to place it on the sheet.
    boxes : dict of view name to (2, 2) float
        Each view's extent on the sheet, its label not included.
    frame : (2, 2) float
        The border's corners.
    block : (2, 2) float
        The title block's corners.
    labels : tuple of Text
        The views' labels, under them.
    per_mm : float
        Pixels a millimetre of ISO 5457's and 7200's measures.
    overflow : float
        How much larger the views are than the room the sheet leaves them (at most 1: they fit).
    """

    width: float
    height: float
    shifts: dict[str, np.ndarray]
    boxes: dict[str, np.ndarray]
    frame: np.ndarray
    block: np.ndarray
    labels: tuple[Text, ...]
    per_mm: float
    overflow: float

    def marks(self, fields: dict[str, str]) -> Marks:
        """The border, the title block with ``fields`` (name to value, in rows: as many as the
        layout was made for) and the views' labels."""
        return sheet_marks(self.frame, self.per_mm, list(self.labels), fields)


def picture_per_mm(size: tuple[float, float] | None = None) -> float:
    """Pixels a millimetre of ISO's measures (text heights, the title block, dimensions' arrows)
    on a picture of ``size`` pixels: 96 pixels an inch, less on a picture too small to hold
    100 mm (an A6 card's width, about) across its shorter side at that."""
    dpi = 96.0 / 25.4
    return dpi if size is None else min(dpi, min(size) / 100.0)


def lay_out_sheet(
    extents: dict[str, np.ndarray],
    rows: int,
    cell: tuple[float, float],
    mm_per_px: float | None = None,
    paper: tuple[float, float] | None = None,
) -> SheetLayout:
    """Lay a plan sheet out: the views of ``SHEET_CELLS`` with even gaps fitted to their
    ``extents``, each labelled with its name, inside a border with a title block of ``rows``
    fields (``SheetLayout.marks`` draws them).

    Parameters
    ----------
    extents : dict of view name to (2, 2) float
        Each view's extent (min and max corner) in its own cell's pixels.
    rows : int
        The title block's fields (ISO 7200: title, scale, units, date, sheet).
    cell : (float, float)
        A cell's size in pixels: on a sheet in pixels the gaps and labels are fractions of it.
    mm_per_px : float, optional
        Page millimetres per pixel of a sheet to scale; None for a sheet in pixels, where the
        measures of ISO 5457 and 7200 are taken as ``picture_per_mm`` has them.
    paper : (float, float), optional
        The sheet's size in pixels (a paper size, or a picture's); the views are centred in the
        room the border and title block leave. None: the sheet is as large as its views need.
    """
    per_mm = 1.0 / mm_per_px if mm_per_px else picture_per_mm(paper)
    small = min(cell)
    gap = 10.0 * per_mm if mm_per_px else 0.06 * small
    label = LABEL_MM * per_mm if mm_per_px else 0.045 * small
    shifts, (views_w, views_h) = place_views(extents, SHEET_CELLS, gap, 1.4 * label)
    if mm_per_px:
        border = (BORDER_MM[0] * per_mm, BORDER_MM[1] * per_mm)
    else:  # a picture has no filing margin
        border = (min(BORDER_MM[1] * per_mm, 0.03 * small),) * 2
    block_h = rows * 1.8 * _text_height(per_mm, rows)
    if paper is not None:
        width, height = (float(v) for v in paper)
        room_w, room_h = width - border[0] - border[1], height - 2 * border[1] - block_h
        overflow = max(views_w / max(room_w, 1e-9), views_h / max(room_h, 1e-9))
        origin = np.array([border[0] + (room_w - views_w) / 2, border[1] + max(room_h - views_h, 0) / 2])
    else:
        width = border[0] + border[1] + max(views_w, TITLE_BLOCK_MM[0] * per_mm if mm_per_px else 0)
        height = 2 * border[1] + views_h + block_h
        overflow = 1.0
        origin = np.array([border[0], border[1]])
    shifts = {name: shift + origin for name, shift in shifts.items()}
    boxes = {name: extents[name] + shifts[name] for name in extents}
    labels = []
    for name, box in boxes.items():
        (x0, _), (x1, y1) = box
        labels.append(Text((x0 + x1) / 2, y1 + 1.2 * label, label, name.upper(), "middle"))
    frame = np.array([[border[0], border[1]], [width - border[1], height - border[1]]])
    block_w = min(TITLE_BLOCK_MM[0] * per_mm, 0.6 * (frame[1, 0] - frame[0, 0]))
    block = np.array([[frame[1, 0] - block_w, frame[1, 1] - block_h], frame[1]])
    return SheetLayout(width, height, shifts, boxes, frame, block, tuple(labels), per_mm, float(overflow))


def _text_height(per_mm: float, rows: int) -> float:
    """The title block's text height: ISO 7200's 3.5 mm, smaller where many rows share it."""
    return min(TEXT_MM * per_mm, 0.6 * TITLE_BLOCK_MM[1] * per_mm / max(rows, 1) * 2)


def sheet_marks(frame: np.ndarray, per_mm: float, labels: list[Text], fields: dict[str, str]) -> Marks:
    """The border along ``frame`` ((2, 2) corners, pixels), the title block in its bottom right
    corner (its ``fields`` in rows) and the views' ``labels``, with ``per_mm`` pixels a
    millimetre of ISO 7200's measures."""
    (x0, y0), (x1, y1) = frame
    lines = [
        [[x0, y0], [x1, y0]],
        [[x1, y0], [x1, y1]],
        [[x1, y1], [x0, y1]],
        [[x0, y1], [x0, y0]],
    ]
    widths = [BORDER_WIDTH] * 4
    block_w = min(TITLE_BLOCK_MM[0] * per_mm, 0.6 * (x1 - x0))
    rows = len(fields)
    text = _text_height(per_mm, rows)
    row_h = 1.8 * text
    bx, by = x1 - block_w, y1 - rows * row_h
    lines.append([[bx, by], [x1, by]])
    lines.append([[bx, by], [bx, y1]])
    widths += [RULE_WIDTH, RULE_WIDTH]
    texts = []
    for i, (key, value) in enumerate(fields.items()):
        top = by + i * row_h
        if i:
            lines.append([[bx, top], [x1, top]])
            widths.append(RULE_WIDTH / 2)
        texts.append(Text(bx + 0.4 * text, top + 1.35 * text, 0.6 * text, key.upper()))
        texts.append(Text(bx + 0.28 * block_w, top + 1.35 * text, text, value))
    lines.append([[bx + 0.25 * block_w, by], [bx + 0.25 * block_w, y1]])
    widths.append(RULE_WIDTH / 2)
    return Marks(np.asarray(lines, np.float64), np.asarray(widths, np.float64), (*labels, *texts))


def today() -> str:
    """The date of a sheet, ISO 8601: today's, or that of ``SOURCE_DATE_EPOCH`` (seconds since
    1970, UTC) where it is set, so that builds can reproduce a sheet to the byte."""
    epoch = os.environ.get("SOURCE_DATE_EPOCH", "").strip()
    if epoch.isdigit():
        return datetime.datetime.fromtimestamp(int(epoch), datetime.UTC).date().isoformat()
    return datetime.date.today().isoformat()


def model_name(model: Model) -> str:
    """A sheet's default title: the model file's name without its suffix."""
    return Path(model.source).stem if model.source and model.source != "generated" else "model"


def sheet_fields(title: str, scale: str | None, model_unit: str | None, sheet: str) -> dict[str, str]:
    """ISO 7200's fields of a title block: ``title``; ``scale`` ('1:2', the iso view never to
    scale; None: not to scale); the units (the drawing's millimetres, and ``model_unit`` where it
    differs; None: pixels); today's date; ``sheet`` (the paper's name or the sheet's size)."""
    if model_unit is None:
        units = "px (not to scale)"
    else:
        units = "mm" if model_unit == "mm" else f"mm (model in {model_unit})"
    return {
        "title": title,
        "scale": f"{scale} (iso not to scale)" if scale is not None else "not to scale",
        "units": units,
        "date": today(),
        "sheet": sheet.strip().upper() if sheet.strip().upper() in PAPER_MM else sheet,
    }
