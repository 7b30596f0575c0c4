"""The memory guard: a model whose peak memory, foretold from its header's counts, passes the
budget is refused in one line before its body is read; a frame whose GPU buffers would pass the
memory the device has free is refused before any is allocated (``render.budget``)."""

import os
import subprocess
import time

import numpy as np
import pytest
from helpers import BLUEPRINT, needs_cli, one_error

from blueprint import settings
from blueprint.errors import InputError
from blueprint.examples import assemble, box
from blueprint.render import budget
from blueprint.scene.headers import peak_estimate

FACES = 400_000


def _ply_of_garbage(path, faces: int) -> None:
    """A binary PLY whose header declares ``faces`` triangles over 3 vertices, and whose body,
    of the right length, is bytes no reader takes (every face's corner count 255)."""
    header = (
        "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        f"property float z\nelement face {faces}\nproperty list uchar int vertex_indices\nend_header\n"
    )
    path.write_bytes(header.encode() + b"\xff" * (3 * 12 + faces * 13))


@needs_cli
def test_a_model_over_the_budget_is_refused_from_its_header(tmp_path):
    model, out = tmp_path / "big.ply", tmp_path / "out"
    out.mkdir()
    _ply_of_garbage(model, FACES)
    budget_bytes = 64 << 20  # holds the file (a quarter of it is the file limit), not its triangles
    start = time.monotonic()
    proc = subprocess.run(
        [str(BLUEPRINT), "render", str(model), "-o", str(out / "big.png")],
        capture_output=True,
        text=True,
        env={**os.environ, "BLUEPRINT_MEMORY_LIMIT": str(budget_bytes)},
    )
    took = time.monotonic() - start
    estimate = FACES * settings.TRIANGLE_BYTES
    one_error(
        proc,
        f"{model}: {FACES} triangles to draw need about {estimate / 2**20:.3g} MiB of memory at "
        f"{settings.TRIANGLE_BYTES} bytes a triangle, more than the memory budget of 64 MiB",
    )
    assert list(out.iterdir()) == []
    assert took < 10, took  # refused at its header: no GL context, no drawing
    # its body is not one a reader takes: refused above before it was read
    proc = subprocess.run(
        [str(BLUEPRINT), "render", str(model), "-o", str(out / "big.png")],
        capture_output=True,
        text=True,
        env={**os.environ, "BLUEPRINT_MEMORY_LIMIT": "4G"},
    )
    assert proc.returncode == 2 and "memory" not in proc.stderr, proc.stderr


def test_the_estimate_is_the_triangles_at_the_measured_bytes():
    assert peak_estimate(0) == 0
    assert peak_estimate(5_242_880) == 5_242_880 * settings.TRIANGLE_BYTES


def test_a_frames_gpu_memory_is_sized_by_kind():
    # 28-byte vertex records (position, normal: 3 float32 each, part: int32), three a
    # triangle at most, and three uint32 indices
    need = budget.frame_bytes(1000, 64 * 64, 2, 1 << 30)
    assert need == {"mesh": 96_000, "gbuffers": 24 * 4096 * 2, "lists": 16 * 4096 * 2}
    # all layers: as many as a pass holds (8); the lists at most the A-buffer row's cap
    assert budget.frame_bytes(0, 100, 0, 1000) == {"mesh": 0, "gbuffers": 24 * 100 * 8, "lists": 1000}
    assert budget.frame_bytes(10, 100, 20, None)["lists"] == 0


def test_a_frame_over_the_gpus_free_memory_is_refused_before_it_is_drawn(renderer, monkeypatch):
    model = assemble({"box": box((0, 0, 0), (1, 2, 3))})
    drawn = []
    monkeypatch.setattr(budget, "free_gpu_memory", lambda device: 1 << 20)
    capturer = renderer.capturer
    monkeypatch.setattr(type(capturer), "mesh", lambda *a, **k: drawn.append(a))
    with pytest.raises(InputError) as caught:
        renderer.render(model, size=(256, 256), supersample=2, max_layers=4)
    pixels = 512 * 512
    need = 96 * model.triangle_count + 24 * pixels * 4 + 16 * pixels * 4
    message = str(caught.value)
    assert message.startswith(f"{model.source or 'the model'}: the frame needs about {need / 2**20:.3g} MiB")
    assert "more than the 1 MiB free on " in message
    assert drawn == []
    monkeypatch.undo()
    frame = renderer.render(model, size=(64, 64))
    assert np.asarray(frame.image).shape == (64, 64, 4)
