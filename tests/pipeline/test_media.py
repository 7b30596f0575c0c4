"""Images and video in and out: a video filtered frame by frame on the GPU (frame count, size,
content changed as the operation says), turntables, and the command line's exit codes."""

from __future__ import annotations

import json

import numpy as np
import pytest
from PIL import Image

from blueprint import examples
from blueprint.api.files import run_pipeline, turntable
from blueprint.errors import InputError
from blueprint.pipeline.media import VideoWriter, read_video, video_info
from blueprint.pipeline.run import orbit

INVERT = """
[pipeline]
output = "out"
[images.clip]
[passes.out]
op = "invert"
inputs = { source = "clip" }
"""


def frames(count=5, size=(32, 24)) -> list[np.ndarray]:
    """Smooth, distinct frames (video codecs keep these nearly intact)."""
    w, h = size
    y, x = np.mgrid[0:h, 0:w]
    out = []
    for k in range(count):
        r = 40 + 160 * x / w
        g = 40 + 160 * y / h
        b = np.full_like(r, 40 + 30 * k)
        out.append(np.dstack([r, g, b]).astype(np.uint8))
    return out


def write_video(path, clip, fps=10.0):
    with VideoWriter(path, (clip[0].shape[1], clip[0].shape[0]), fps=fps, crf=0) as video:
        for frame in clip:
            video.write(frame)


def test_video_round_trip_through_a_pipeline(tmp_path, renderer):
    clip = frames()
    write_video(tmp_path / "in.mp4", clip)
    (tmp_path / "invert.toml").write_text(INVERT)
    seen = []
    run_pipeline(
        tmp_path / "invert.toml",
        tmp_path / "in.mp4",
        tmp_path / "out.mp4",
        renderer=renderer,
        progress=lambda done, total: seen.append((done, total)),
    )
    size, fps, count = video_info(tmp_path / "out.mp4")
    assert size == (32, 24) and count == len(clip) and fps == pytest.approx(10.0)
    assert seen[-1] == (len(clip), len(clip))
    for original, filtered in zip(clip, read_video(tmp_path / "out.mp4"), strict=True):
        assert np.abs(filtered.astype(int) - (255 - original.astype(int))).mean() < 4
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []  # no temporary left


def test_video_frame_limit(tmp_path, renderer):
    write_video(tmp_path / "in.mp4", frames(6))
    (tmp_path / "invert.toml").write_text(INVERT)
    run_pipeline(
        tmp_path / "invert.toml", tmp_path / "in.mp4", tmp_path / "out.mp4", frames=2, renderer=renderer
    )
    assert video_info(tmp_path / "out.mp4")[2] == 2


def test_image_in_png_out(tmp_path, renderer):
    picture = frames(1, (20, 10))[0]
    Image.fromarray(picture).save(tmp_path / "in.png")
    (tmp_path / "invert.toml").write_text(INVERT)
    run_pipeline(tmp_path / "invert.toml", tmp_path / "in.png", tmp_path / "out.png", renderer=renderer)
    out = np.asarray(Image.open(tmp_path / "out.png"))
    np.testing.assert_array_equal(out[..., :3], 255 - picture)
    with pytest.raises(InputError, match=r"out\.mp4: output must end in \.png or \.npz"):
        run_pipeline(tmp_path / "invert.toml", tmp_path / "in.png", tmp_path / "out.mp4", renderer=renderer)


def test_turntable(tmp_path, renderer):
    model = examples.gearbox()
    cams = orbit(model, 4, (48, 32))
    distances = [np.linalg.norm(np.subtract(c.eye, c.target)) for c in cams]
    assert max(distances) - min(distances) < 1e-9 * max(distances)
    path = turntable(model, tmp_path / "spin.mp4", frames=4, size=(48, 32), fps=8, renderer=renderer)
    assert video_info(path)[::2] == ((48, 32), 4)
    shots = list(read_video(path))
    assert np.abs(shots[0].astype(int) - shots[1].astype(int)).mean() > 1  # the camera moved
    assert [p.name for p in tmp_path.iterdir()] == ["spin.mp4"]
    with pytest.raises(InputError, match="needs a pipeline that renders"):
        (tmp_path / "invert.toml").write_text(INVERT)
        turntable(
            model, tmp_path / "x.mp4", frames=2, pipeline=str(tmp_path / "invert.toml"), renderer=renderer
        )
    renderer.forget(model)


# -- the command line -----------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def cli():
    """blueprint.cli.main in this process."""
    from blueprint import cli as cli_module

    def call(*args):
        with pytest.raises(SystemExit) as info:
            cli_module.main([str(a) for a in args])
        return info.value.code

    return call


def test_cli_ops_lists_every_operation(cli, capsys):
    from blueprint.pipeline.spec import OPERATIONS

    assert cli("ops", "--json") == 0
    records = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert [r["name"] for r in records] == list(OPERATIONS)
    sobel = next(r for r in records if r["name"] == "sobel")
    assert sobel["inputs"] == {"source": "float"} and {p["name"] for p in sobel["params"]} == {
        "threshold",
        "channels",
        "invert",
    }
    assert cli("ops") == 0
    assert "composite: depth-sprite composite" in capsys.readouterr().out


def test_cli_check_and_bad_input_exit_2(cli, capsys, tmp_path):
    assert cli("pipeline", "check", "screening") == 0
    assert "ok: screening" in capsys.readouterr().out
    bad = tmp_path / "bad.toml"
    bad.write_text('[pipeline]\noutput = "e"\n[attributes]\nnormal = {}\n[passes.e]\nop = "robert"\n')
    assert cli("pipeline", "check", bad) == 2
    err = capsys.readouterr().err.strip()
    assert (
        err.startswith(f"blueprint: error: {bad}: passes.e.op: unknown operation 'robert'")
        and "\n" not in err
    )
    assert cli("pipeline", "run", "blueprint", tmp_path / "none.glb", "-o", tmp_path / "o.png") == 2
    assert cli("pipeline", "run", "blueprint", "-o", tmp_path / "o.png", "--set", "nope=1") == 2
    assert "variables.nope: unknown variable" in capsys.readouterr().err


def test_cli_run_model(cli, capsys, tmp_path):
    out = tmp_path / "edges.png"
    assert cli("pipeline", "run", "edges-roberts", examples.example_path(), "-o", out, "--size", 40, 30) == 0
    assert np.asarray(Image.open(out)).shape == (30, 40)
    assert "40x30 r8" in capsys.readouterr().out
