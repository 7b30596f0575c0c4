"""The layer budget says when it cut a drawing short, and depth masking is not cut.

Ten parallel squares one behind the other, seen from the front, are ten depth layers at every
pixel they cover. A peel capped at 4 draws 4 and says "4 of 10 layers" (the count of what is
left comes from one extra pass, only when the cap was hit); a cap the model does not reach says
nothing; depth masking of the last square peels past the default cap until it shows.
"""

from __future__ import annotations

import re

import numpy as np
import pytest
from helpers import run_cli

from blueprint import Model
from blueprint.api import render_frame

SQUARES = 10


def squares() -> Model:
    """``SQUARES`` 2 x 2 squares facing +z at z = 0, -1, ..., one part each."""
    quad = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], np.float32)
    positions = np.concatenate([quad - (0, 0, k) for k in range(SQUARES)])
    faces = np.concatenate([np.array([[0, 1, 2], [0, 2, 3]]) + 4 * k for k in range(SQUARES)])
    part = np.repeat(np.arange(SQUARES), 2)
    return Model.from_arrays(positions, faces, part, [f"square{k}" for k in range(SQUARES)])


@pytest.mark.parametrize(
    ("cap", "layers", "shown"),
    [(4, 4, "4 of 10 layers"), (9, 9, "9 of 10 layers"), (10, 10, "10 layers"), (None, 10, "10 layers")],
)
def test_a_capped_peel_says_how_many_layers_it_left(renderer, cap, layers, shown):
    frame = render_frame(squares(), size=(64, 64), view="front", max_layers=cap, renderer=renderer)
    assert frame.layers == layers
    assert frame.layers_left == SQUARES - layers
    assert frame.layers_shown == shown


def test_depth_masking_peels_past_the_cap(renderer):
    # the last square is behind nine others: the default cap of 8 would stop before it
    frame = render_frame(
        squares(), size=(64, 64), view="front", highlight="square9", reveal=1.0, renderer=renderer
    )
    assert frame.layers == SQUARES and frame.revealed == pytest.approx(1.0)
    assert frame.layers_left == 0


def test_the_printed_line_names_the_layers_left(tmp_path):
    path = tmp_path / "squares.ply"
    model = squares()
    import trimesh

    trimesh.Trimesh(model.positions, model.faces, process=False).export(path)
    proc = run_cli(
        "render",
        path,
        "-o",
        tmp_path / "s.png",
        "--size",
        "64",
        "64",
        "--view",
        "front",
        "--max-layers",
        "3",
        "--up",
        "y",
    )
    assert proc.returncode == 0, proc.stderr
    assert re.search(r", 3 of 10 layers, ", proc.stdout), proc.stdout
