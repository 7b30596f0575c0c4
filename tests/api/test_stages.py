"""Stage timings (``blueprint.api.stages``): a stage timed within another counts to itself
alone, and ``blueprint render`` with ``BLUEPRINT_STAGES=1`` accounts for the mesh's preparation
and the contour lines where the lines prepare the mesh before the frame."""

from __future__ import annotations

import json
import time

import pytest
import trimesh
from helpers import run_cli
from scan_helpers import noisy_sphere

import blueprint
from blueprint.api import stages


@pytest.fixture
def fresh_stages(monkeypatch):
    """The module's counts empty for the test, and as they were after it."""
    for name in ("_SECONDS", "_OUTERMOST"):
        monkeypatch.setattr(stages, name, {})
    monkeypatch.setattr(stages, "_OPEN", [])


def test_a_stage_within_another_counts_to_itself_alone(fresh_stages):
    told = []
    with stages.listen(lambda name, detail=None: told.append(name)):
        with stages.timed("outer"):
            time.sleep(0.05)
            with stages.timed("inner"):
                time.sleep(0.1)
            time.sleep(0.05)
        with stages.timed("inner"):
            time.sleep(0.02)
    seconds = stages._SECONDS
    assert 0.1 <= seconds["outer"] < 0.15
    assert 0.12 <= seconds["inner"] < 0.17
    # the outer stage is told again as the inner one ends: a progress display shows it
    assert told == ["outer", "inner", "outer", "inner"]
    # the frame's own capture is less only the preparation timed within no other stage
    assert set(stages._OUTERMOST) == {"outer", "inner"} and stages._OUTERMOST["inner"] < 0.05


def test_the_mesh_prepared_for_the_contour_lines_is_told_within_them(renderer, fresh_stages):
    """The contour lines of a dense mesh prepare it through the renderer: the preparation is
    timed and told there (``stages.watch``), within the lines' stage, which is told again after
    it; the frame finds the mesh prepared."""
    ball = noisy_sphere(0.02, subdivisions=5)
    told = []
    try:
        with stages.listen(lambda name, detail=None: told.append(name)):
            stages.watch(renderer)
            blueprint.render_frame(ball, renderer=renderer, size=(64, 64), smooth_contours=True)
    finally:
        vars(renderer.capturer).pop("mesh", None)
    assert told[:3] == ["contours", "prepare_upload", "contours"]
    assert told[-2:] == ["prepare_upload", "capture_edges"] and told.count("prepare_upload") == 2
    assert set(stages._OUTERMOST) == {"contours", "prepare_upload"}
    assert stages._SECONDS["prepare_upload"] > stages._OUTERMOST["prepare_upload"]


def _stages(result) -> dict[str, float]:
    lines = [line for line in result.stderr.splitlines() if line.startswith('{"stages"')]
    assert len(lines) == 1, result.stderr
    return json.loads(lines[0])["stages"]


def test_render_accounts_for_the_contour_lines_and_the_preparation_before_them(tmp_path):
    """A dense mesh's contour lines prepare and upload it before the frame: its preparation
    counts to ``prepare_upload``, the lines to ``contours``, and the frame's capture is not
    short of either (the stages add up to no more than the process took)."""
    path = tmp_path / "ball.stl"
    ball = noisy_sphere(0.02, subdivisions=5)
    trimesh.Trimesh(ball.positions, ball.faces, process=False).export(path)
    out = tmp_path / "ball.png"
    start = time.perf_counter()
    result = run_cli("render", path, "-o", out, "--size", 64, 64, env={stages.ENV: "1"})
    took = time.perf_counter() - start
    assert result.returncode == 0, result.stderr
    seen = _stages(result)
    assert {"read", "prepare_upload", "contours", "capture_edges", "write"} <= set(seen)
    assert seen["prepare_upload"] > 0 and seen["contours"] > 0 and seen["capture_edges"] > 0
    assert sum(seen.values()) < took

    plain = run_cli(
        "render", path, "-o", out, "--size", 64, 64, "--no-smooth-contours", env={stages.ENV: "1"}
    )
    assert plain.returncode == 0, plain.stderr
    seen = _stages(plain)
    assert "contours" not in seen and seen["prepare_upload"] > 0 and seen["capture_edges"] > 0
