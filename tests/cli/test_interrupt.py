"""Ctrl-C: ``blueprint render`` of a big model stops within a second of SIGINT in whichever phase
it is, prints one line, exits 130, and leaves no output, no temporary and no process behind
(``blueprint.cli.supervise``)."""

import os
import signal
import struct
import subprocess
import time
import uuid
from pathlib import Path

import numpy as np
import pytest
from helpers import BLUEPRINT, needs_cli

TRIANGLES = 2_000_000


@pytest.fixture(scope="module")
def big_soup(tmp_path_factory) -> Path:
    """A binary STL of ``TRIANGLES`` random small triangles in a unit cube: some seconds of
    reading, preparing and drawing on llvmpipe."""
    rng = np.random.default_rng(7)
    corners = rng.random((TRIANGLES, 1, 3), np.float32) + rng.normal(0, 0.003, (TRIANGLES, 3, 3)).astype(
        np.float32
    )
    records = np.zeros(TRIANGLES, [("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")])
    records["v"] = corners
    path = tmp_path_factory.mktemp("big") / "soup.stl"
    path.write_bytes(b"\0" * 80 + struct.pack("<I", TRIANGLES) + records.tobytes())
    return path


def _marked(mark: str) -> list[int]:
    """Processes whose environment holds ``mark``."""
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                if mark.encode() in (entry / "environ").read_bytes():
                    found.append(int(entry.name))
            except OSError:
                continue
    return found


@needs_cli
@pytest.mark.parametrize("delay", [1.5, 4.0])
def test_sigint_stops_the_drawing_at_once_and_leaves_nothing(big_soup, tmp_path, delay):
    out, scratch, mark = tmp_path / "out", tmp_path / "tmp", f"blueprint-test-{uuid.uuid4().hex}"
    out.mkdir()
    scratch.mkdir()
    env = {**os.environ, "TMPDIR": str(scratch), "BLUEPRINT_TEST_MARK": mark}
    proc = subprocess.Popen(
        [str(BLUEPRINT), "render", str(big_soup), "-o", str(out / "soup.png")],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    time.sleep(delay)
    assert proc.poll() is None, "the drawing ended before it was interrupted"
    sent = time.monotonic()
    proc.send_signal(signal.SIGINT)
    stdout, stderr = proc.communicate(timeout=30)
    stopped = time.monotonic() - sent
    assert (proc.returncode, stdout, stderr) == (130, "", "blueprint: interrupted\n")
    assert stopped < 1.0, stopped
    assert list(out.iterdir()) == [] and list(scratch.iterdir()) == []
    assert _marked(mark) == []


@needs_cli
def test_a_drawing_not_interrupted_ends_as_before(tmp_path):
    """The child's exit code and lines come through the parent: a user error is one line, exit 2."""
    missing = tmp_path / "missing.stl"
    proc = subprocess.run(
        [str(BLUEPRINT), "render", str(missing), "-o", str(tmp_path / "x.png")],
        capture_output=True,
        text=True,
        env={**os.environ, "TMPDIR": str(tmp_path)},
    )
    assert (proc.returncode, proc.stdout) == (2, "")
    assert proc.stderr == f"blueprint: error: {missing}: no such file\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == []


@pytest.mark.parametrize("args", [["--help"], ["render", "--help"], ["--version"]])
def test_a_help_prints_without_a_child(args, monkeypatch, capsys):
    """A help or the version has no phase to stop: it prints from the program's own process."""
    from blueprint import cli
    from blueprint.cli import supervise

    def forked(*_):
        raise AssertionError("a child was started")

    monkeypatch.setattr(supervise, "supervised", forked)
    monkeypatch.setattr("sys.argv", ["blueprint", *args])
    # what main sets for its own process, left to this one as it was
    monkeypatch.setenv("BLUEPRINT_ONE_ARENA", os.environ.get("BLUEPRINT_ONE_ARENA", "0"))
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", os.environ.get("OPENBLAS_NUM_THREADS", "1"))
    with pytest.raises(SystemExit) as ended:
        cli.main()
    assert ended.value.code in (0, None)
    assert "blueprint" in capsys.readouterr().out
