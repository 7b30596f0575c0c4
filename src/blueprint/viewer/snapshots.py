"""Pictures out of the viewer: screenshots (P) of the full-quality drawing beside the model, and
frame dumps. ``BLUEPRINT_VIEWER_DUMP=FOLDER`` writes every presented frame as a PNG (read back
from the window: what is shown) plus one JSON line of state to ``FOLDER/frames.jsonl`` (for tests
and bug reports)."""

from __future__ import annotations

import json
import logging
from pathlib import Path

import numpy as np

from blueprint.errors import BlueprintError
from blueprint.export.files import save_png
from blueprint.scene.model import Model
from blueprint.viewer.overlay import LINE_HEIGHT, screenshot_path
from blueprint.viewer.state import ViewState

log = logging.getLogger("blueprint")

DUMP_ENV = "BLUEPRINT_VIEWER_DUMP"


def save_screenshot(model_path: Path, drawing: np.ndarray) -> str:
    """Save `drawing`, (H, W, 4) uint8, as NAME-N.png beside the model; the message to show."""
    path = screenshot_path(model_path)
    try:
        save_png(path, drawing)
    except BlueprintError as exc:
        log.warning(str(exc))
        return f"screenshot failed: {exc}"
    h, w = drawing.shape[:2]
    print(f"{path}: screenshot {w}x{h}", flush=True)
    return f"saved {path.name}"


class FrameDump:
    """Presented frames as ``frame-NNNNN.png`` in `folder`, numbered from 1, each with a line of
    ``frames.jsonl``: the frame's file, how it was drawn, the view state and the heads-up lines."""

    def __init__(self, folder: Path) -> None:
        self.folder = folder
        self.frames = 0

    def write(
        self,
        image: np.ndarray,
        lines: list[str],
        *,
        last: dict,
        state: ViewState,
        model: Model,
        renderer_name: str,
    ) -> None:
        self.frames += 1
        self.folder.mkdir(parents=True, exist_ok=True)
        name = f"frame-{self.frames:05d}.png"
        save_png(self.folder / name, image)
        record = {
            "n": self.frames,
            "file": name,
            **last,
            "max_layers": state.max_layers,
            "style": state.style,
            "view": state.view,
            "azimuth": state.azimuth,
            "elevation": state.elevation,
            "zoom": state.zoom,
            "pan": list(state.pan),
            "ortho": state.ortho,
            "turntable": state.turntable,
            "help": state.help,
            "mask": state.mask,
            "part": None if state.part is None else model.part_names[state.part],
            "part_index": state.part,
            "hud": lines,
            "hud_height": LINE_HEIGHT * len(lines),
            "renderer": renderer_name,
        }
        with open(self.folder / "frames.jsonl", "a", encoding="utf-8") as fh:
            fh.write(json.dumps(record) + "\n")
