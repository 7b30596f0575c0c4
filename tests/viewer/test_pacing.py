"""The viewer's quality ladder while the view moves, without a window: the steps, the choice of
a step from measured frame times (with hysteresis), the pacer's memory of them, the heads-up
line that names the step, and the coarse mesh of its last steps."""

from __future__ import annotations

import numpy as np
import pytest

from blueprint import InputError, Model
from blueprint.cli import STYLE_NAMES
from blueprint.viewer.lod import coarse_model
from blueprint.viewer.pacing import (
    COLD_SHARE,
    FORGET_SECONDS,
    PROBE_SHARE,
    UP_SHARE,
    FrameRate,
    Pacer,
    Step,
    choose_step,
    ladder,
)
from blueprint.viewer.present import hud_lines
from blueprint.viewer.state import Options, ViewState

BUDGET = 100.0


def _fields(steps) -> list[tuple]:
    return [(s.scale, s.supersample, s.layers, s.coarse, s.label) for s in steps]


def test_the_ladder_goes_from_the_full_drawing_to_less_work_each_step():
    assert _fields(ladder(2, 5)) == [
        (1.0, 2, 5, False, "full"),
        (1.0, 1, 5, False, "supersample 1"),
        (1.0, 1, 2, False, "2 layers"),
        (0.5, 1, 2, False, "1/2 size, 2 layers"),
        (0.5, 1, 1, False, "1/2 size, 1 layer"),
        (0.25, 1, 1, False, "1/4 size, 1 layer"),
    ]
    # every layer: the steps cap them; supersample 1 and one layer: the same steps drop out
    assert [s.layers for s in ladder(3, None)] == [None, None, 2, 2, 1, 1]
    assert _fields(ladder(1, 1)) == [
        (1.0, 1, 1, False, "full"),
        (0.5, 1, 1, False, "1/2 size"),
        (0.25, 1, 1, False, "1/4 size"),
    ]
    assert _fields(ladder(1, 2, coarse=True))[-2:] == [
        (0.5, 1, 2, True, "coarse mesh, 1/2 size"),
        (0.25, 1, 1, True, "coarse mesh, 1/4 size, 1 layer"),
    ]
    # a fixed interactive scale is the one quality while moving
    assert _fields(ladder(2, 5, fixed_scale=0.6)) == [(0.6, 1, 5, False, "0.6 size")]
    assert _fields(ladder(2, None, fixed_scale=0.75)) == [(0.75, 1, None, False, "3/4 size")]
    assert _fields(ladder(2, 5, fixed_scale=1.0)) == [(1.0, 1, 5, False, "supersample 1")]


def test_a_step_slower_than_the_budget_gives_way_to_the_next_one_not_known_slower():
    # nothing measured: the step is kept (and measured)
    assert choose_step(0, [None] * 4, BUDGET) == 0
    # too slow by less than twice: the next step, measured or not
    assert choose_step(0, [190.0, None, None, None], BUDGET) == 1
    assert choose_step(1, [250.0, 101.0, 60.0, None], BUDGET) == 2
    # far too slow: down as many steps as halving the cost a step takes to come within it,
    # a step measured within the budget before that taken
    assert choose_step(0, [250.0, None, None, None], BUDGET) == 2
    assert choose_step(0, [2300.0, None, None, None, None, None, None], BUDGET) == 5
    assert choose_step(0, [2300.0, None, None, 90.0, None, None, None], BUDGET) == 3
    assert choose_step(0, [2300.0, None, None, None], BUDGET) == 3
    # steps measured slower are passed over; below every step, the last
    assert choose_step(0, [250.0, 150.0, 120.0, None], BUDGET) == 3
    assert choose_step(1, [250.0, 150.0, 120.0, 110.0], BUDGET) == 3
    assert choose_step(3, [250.0, 150.0, 120.0, 110.0], BUDGET) == 3


def test_a_richer_step_comes_back_only_well_inside_the_budget():
    edge = UP_SHARE * BUDGET
    # within the budget, the richer step inside the band between UP_SHARE and 1: no change
    assert choose_step(2, [300.0, edge + 1, 50.0, 20.0], BUDGET) == 2
    assert choose_step(2, [300.0, BUDGET, 50.0, 20.0], BUDGET) == 2
    # below the band: up, as far as the steps stay below it
    assert choose_step(2, [300.0, edge, 50.0, 20.0], BUDGET) == 1
    assert choose_step(3, [60.0, 50.0, 40.0, 20.0], BUDGET) == 0
    assert choose_step(3, [90.0, 50.0, 40.0, 20.0], BUDGET) == 1
    # a richer step not measured lately: tried only where the current one is cheap, one step
    probe = PROBE_SHARE * BUDGET
    assert choose_step(2, [None, None, probe + 1, 10.0], BUDGET) == 2
    assert choose_step(2, [None, None, probe, 10.0], BUDGET) == 1
    assert choose_step(3, [None, 30.0, 35.0, 10.0], BUDGET) == 0
    assert choose_step(3, [None, 50.0, 35.0, 10.0], BUDGET) == 1


def test_the_choice_settles_and_does_not_flicker_around_the_budget():
    """Frames whose cost is a step's own, within 15 % of it, frame to frame: the pacer walks
    down to the richest step that keeps the budget and stays there."""
    costs = [260.0, 130.0, 92.0, 45.0, 30.0, 12.0]
    pacer = Pacer(1000.0 / BUDGET)
    pacer.settle(("key",), 2, 5)
    rng = np.random.default_rng(3)
    chosen = []
    now = 0.0
    for _ in range(300):
        step = pacer.next_step(now)
        chosen.append(step)
        ms = costs[step] * rng.uniform(0.85, 1.15)
        now += ms / 1000.0
        pacer.record(step, ms, now)
    settled = chosen[10:]
    changes = sum(a != b for a, b in zip(settled, settled[1:], strict=False))
    # step 2 (92 ms) now and then measures above the budget: the pacer may leave it for step
    # 3, and comes back only after forgetting its slow figures, not frame to frame
    assert set(settled) <= {2, 3}
    assert changes <= 2 * (now / FORGET_SECONDS) + 2
    # 260 ms is some 2.6 budgets: the first moving frame goes two steps down at once
    assert chosen[:2] == [0, 2]


def test_the_pacer_measures_medians_forgets_and_starts_again_on_new_settings():
    pacer = Pacer(10.0)
    pacer.settle((800, 600, 2, 5), 2, 5)
    assert pacer.full == Step(1.0, 2, 5) and pacer.full_index == 0
    assert len(pacer.steps) == 6 and pacer.costs(0.0) == [None] * 6
    for when, ms in ((0.0, 300.0), (0.25, 90.0), (0.5, 120.0), (0.75, 100.0)):
        pacer.record(1, ms, when)
    # the median of the last three, for FORGET_SECONDS after the last
    assert pacer.costs(1.0)[1] == 100.0
    assert pacer.costs(0.75 + FORGET_SECONDS)[1] == 100.0
    assert pacer.costs(1.0 + FORGET_SECONDS)[1] is None
    pacer.current = 3
    pacer.settle((800, 600, 2, 5), 2, 5)
    assert pacer.current == 3 and pacer.costs(1.0)[1] == 100.0
    # a frame drawn unlike the one before it, over the budget by less than COLD_SHARE: measured
    # again by the next one
    pacer.record(2, 150.0, 1.0, cold=True)
    pacer.record(3, COLD_SHARE * 100.0 + 1, 1.0, cold=True)
    pacer.record(4, 90.0, 1.0, cold=True)
    assert pacer.costs(1.0)[2:5] == [None, COLD_SHARE * 100.0 + 1, 90.0]
    pacer.record(2, 150.0, 1.0)
    assert pacer.costs(1.0)[2] == 150.0
    # one layer: a shorter ladder, nothing measured, the step kept where it still is one
    pacer.settle((800, 600, 2, 1), 2, 1)
    assert [s.label for s in pacer.steps] == ["full", "supersample 1", "1/2 size", "1/4 size"]
    assert pacer.current == 3 and pacer.costs(1.0) == [None] * 4
    pacer.current = 3
    pacer.settle((800, 600, 1, 1), 1, 1)
    assert pacer.current == 2
    # a fixed scale: the full drawing is not a step of its ladder
    fixed = Pacer(10.0, fixed_scale=0.5)
    fixed.settle((1,), 2, 5)
    assert fixed.full_index is None and fixed.full == Step(1.0, 2, 5)
    assert fixed.next_step(0.0) == 0 and fixed.steps[0].scale == 0.5


def test_frame_rate_report_counts_steps():
    rate = FrameRate()
    steps = ("full", "full", "full", "2 layers", "full", "1/2 size", "1/2 size")
    for now, step in zip((0.0, 1.0, 2.0, 2.5, 3.0, 3.125, 3.25), steps, strict=True):
        rate.tick(10.0, step, now)
    report = rate.report()
    # after two frames of warm-up (the second's end starts the clock): five frames in 2.25 s
    assert report["frames"] == 5 and report["fps"] == round(5 / 2.25, 2)
    assert report["steps"] == {"full": 2, "2 layers": 1, "1/2 size": 2}
    assert report["draw_ms_median"] == 10.0
    # the last two frames at 1/2 size, since 3.0 s: 0.25 s
    assert (report["step"], report["step_frames"], report["step_fps"]) == ("1/2 size", 2, 8.0)


def test_heads_up_line_names_the_quality_while_moving():
    model = Model.from_arrays(np.eye(3, dtype=np.float32), np.array([[0, 1, 2]]))
    state = ViewState.start(STYLE_NAMES, max_layers=5)
    moving = {"ms": 50.0, "layers": 2, "quality": "moving", "step": "1/2 size, 2 layers"}
    line = hud_lines(state, model, moving, "llvmpipe", "")[0]
    assert line.startswith("20.0 fps | 2 layers (max 5) | 1 triangles | llvmpipe | blueprint | iso persp")
    assert line.endswith("| moving: 1/2 size, 2 layers | H: help")
    still = {"ms": 250.0, "layers": 5, "quality": "full", "step": "full"}
    line = hud_lines(state, model, still, "llvmpipe", "")[0]
    assert line == "4.0 fps | 5 layers (max 5) | 1 triangles | llvmpipe | blueprint | iso persp | H: help"


def test_viewer_options_are_checked():
    with pytest.raises(InputError, match=r"moving-fps must be in \[0.1, 1000\]"):
        Options(moving_fps=0.0)
    with pytest.raises(InputError, match="moving-fps"):
        Options(moving_fps=float("nan"))
    with pytest.raises(InputError, match="interactive-scale"):
        Options(interactive_scale=2.0)
    assert Options(moving_fps=30.0, interactive_scale=0.5).moving_fps == 30.0


def _sphere(subdivisions: int) -> tuple[np.ndarray, np.ndarray]:
    """A unit icosphere, (V, 3) float32 and (F, 3) int32."""
    t = (1.0 + 5.0**0.5) / 2.0
    v = np.array(
        [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t],
         [0, -1, -t], [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]], float
    )  # fmt: skip
    f = np.array(
        [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4],
         [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8],
         [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]]
    )  # fmt: skip
    v /= np.linalg.norm(v, axis=1)[:, None]
    for _ in range(subdivisions):
        edges = np.sort(f[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
        keys, inverse = np.unique(edges[:, 0] * len(v) + edges[:, 1], return_inverse=True)
        middle = (v[keys // len(v)] + v[keys % len(v)]) / 2.0
        middle /= np.linalg.norm(middle, axis=1)[:, None]
        ab, bc, ca = (inverse.reshape(-1, 3) + len(v)).T
        a, b, c = f.T
        f = np.concatenate([np.c_[a, ab, ca], np.c_[b, bc, ab], np.c_[c, ca, bc], np.c_[ab, bc, ca]])
        v = np.concatenate([v, middle])
    return v.astype(np.float32), f.astype(np.int32)


def test_coarse_mesh_keeps_shape_and_parts_with_about_the_triangles_asked_for():
    v, f = _sphere(6)  # 81 920 triangles
    # the upper half one part, the lower half another
    part = (v[f].mean(axis=1)[:, 1] < 0).astype(np.int32)
    model = Model.from_arrays(v, f, part, ("top", "bottom"))
    coarse = coarse_model(model, 5000)
    assert 5000 / 3 <= coarse.triangle_count <= 2 * 5000
    assert coarse.part_names == ("top", "bottom") and coarse.up == model.up
    # its vertices are means of points on the sphere: inside it, barely
    radius = np.linalg.norm(coarse.positions[np.unique(coarse.faces)], axis=1)
    assert radius.max() <= 1.0 + 1e-6 and radius.min() > 0.99
    # no triangle with a repeated corner, none twice
    faces = coarse.faces
    assert (faces[:, 0] != faces[:, 1]).all() and (faces[:, 1] != faces[:, 2]).all()
    assert (faces[:, 2] != faces[:, 0]).all()
    assert len(np.unique(np.sort(faces, axis=1), axis=0)) == len(faces)
    # each part's faces stay on its side, and both hemispheres are kept
    centres = coarse.positions[faces].mean(axis=1)[:, 1]
    assert (centres[coarse.face_part == 0] > -0.1).all() and (centres[coarse.face_part == 1] < 0.1).all()
    a, b, c = coarse.positions[faces].transpose(1, 0, 2).astype(np.float64)
    areas = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    assert areas.sum() == pytest.approx(4 * np.pi, rel=0.01)
    # a model within the count is its own coarse mesh
    assert coarse_model(model, model.triangle_count) is model


def test_heads_up_line_counts_a_picked_part_of_a_scene_kept_as_instances_unflattened():
    """The picked part's triangles come from the instances: the scene is not flattened for them."""
    from instanced_scenes import mixed_scene

    model = mixed_scene()
    state = ViewState.start(STYLE_NAMES, max_layers=5)
    state.part = 2
    lines = hud_lines(state, model, {"ms": 50.0, "layers": 2}, "llvmpipe", "")
    assert not model.is_flat
    counts = model.part_triangle_counts()
    assert lines[1].startswith(f"part 2: {model.part_names[2]} ({counts[2]:,} triangles)")
    assert counts.sum() == model.triangle_count and not counts.flags.writeable
