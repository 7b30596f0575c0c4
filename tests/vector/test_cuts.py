"""Intersection lines with the GPU's pairs (vector/cuts.py): the same lines as NumPy's, bit for
bit, on soups made to be hard (corners within the touch tolerance of a plane, coplanar and
touching triangles) and on a real assembly."""

import numpy as np
import pytest

from blueprint.examples import assemble, box
from blueprint.scene.model import Model
from blueprint.vector import cuts
from blueprint.vector.lines import _TOUCH_REL, _diagonal, _intersections


@pytest.fixture
def every_grid(monkeypatch):
    """The passes run however few partners the grid has (llvmpipe would leave them to NumPy)."""
    monkeypatch.setattr(cuts, "SOFTWARE_MIN_PARTNERS", 0)


def _same(a, b):
    for field in ("points", "faces", "part", "kind"):
        np.testing.assert_array_equal(getattr(a, field), getattr(b, field))


def _soup(seed: int, count: int = 4000, parts: int = 4) -> Model:
    """Triangles of a few parts crowded into a unit cube, and as many again poking through one
    of them: across its plane by a few touch tolerances on one side (0, 0.5, 1, 1.5 or 2 of
    them, where rounding decides whether NumPy calls a corner touching) and by far on the
    other; every tenth a coplanar copy instead."""
    rng = np.random.default_rng(seed)
    centre = rng.uniform(0, 1, (count, 1, 3))
    tri = centre + rng.normal(0, 0.06, (count, 3, 3))
    eps = _TOUCH_REL * _diagonal(tri.reshape(-1, 3))
    poking = []
    for k, o in enumerate(rng.integers(0, count, count)):
        edge_u, edge_v = tri[o, 1] - tri[o, 0], tri[o, 2] - tri[o, 0]
        normal = np.cross(edge_u, edge_v)
        normal /= np.linalg.norm(normal)
        u = edge_u / np.linalg.norm(edge_u)
        v = np.cross(normal, u)
        at = tri[o].mean(axis=0) + rng.normal(0, 0.01) * u + rng.normal(0, 0.01) * v
        if k % 10 == 9:
            poking.append(tri[o] + 0.01 * u)
            continue
        near = eps * rng.choice([0.0, 0.5, 1.0, 1.5, 2.0]) * rng.choice([-1.0, 1.0])
        third = 0.02 if k % 2 else -0.02  # the far corners on one side, or one on each
        poking.append(
            [
                at + 0.03 * u + near * normal,
                at - 0.03 * u + 0.02 * v - 0.02 * normal,
                at + 0.03 * v + third * normal,
            ]
        )
    tri = np.concatenate([tri, np.array(poking)])
    positions = tri.reshape(-1, 3)
    faces = np.arange(len(positions)).reshape(-1, 3)
    part = rng.integers(0, parts, len(tri))
    return Model.from_arrays(positions, faces, part, tuple(f"p{i}" for i in range(parts)))


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_gpu_pairs_give_numpys_lines_on_hard_soups(renderer, every_grid, seed):
    model = _soup(seed)
    numpy_lines = _intersections(model, None)
    assert len(numpy_lines) > 100
    _same(_intersections(model, renderer), numpy_lines)


def test_gpu_pairs_give_numpys_lines_on_boxes_cutting_and_touching(renderer, every_grid):
    model = assemble(
        {
            "a": box((-1, -1, -1), (1, 1, 1)),
            "b": box((0, 0, -0.5), (2, 2, 0.5)),  # cuts through a
            "c": box((1, -1, -1), (2, 0, 0)),  # touches a: no line
        }
    )
    numpy_lines = _intersections(model, None)
    assert len(numpy_lines) > 0
    _same(_intersections(model, renderer), numpy_lines)


def test_gpu_pairs_give_numpys_lines_on_the_engine(renderer, shared_models):
    from blueprint.scene.loader import load_model

    model = load_model(shared_models / "glTF-Sample-Models" / "2CylinderEngine.glb")
    _same(_intersections(model, renderer), _intersections(model, None))


def test_gpu_pairs_run_in_the_renderers_own_context(renderer, every_grid):
    """The passes are a drawing's first GL work: they must not land in whichever context was
    current before (a window's, another renderer's)."""
    from blueprint.gpu.device import Device

    model = _soup(1, count=1000)
    with Device() as other:
        other.make_current()
        got = _intersections(model, renderer)
    renderer.make_current()
    _same(got, _intersections(model, None))
