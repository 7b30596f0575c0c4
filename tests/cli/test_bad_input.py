"""Bad input through the installed console script: exactly one line on stderr naming the file
(where there is one) and the problem, exit code 2, no traceback, nothing on stdout, and no output
file nor temporary file left in the output folder. Recoverable oddities warn in one line.

The bad files are generated here. Tests run as root, where permission bits do not stop writes,
so unwritable outputs are made with a missing folder, an existing directory, a file size limit
(``RLIMIT_FSIZE``) and an address-space limit (``RLIMIT_AS``) for sizes too large for memory.
"""

from __future__ import annotations

import os
import resource
import struct
import subprocess
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest
import trimesh
from helpers import needs_cli, no_output, one_error, run_cli
from PIL import Image

from blueprint import examples

pytestmark = needs_cli


@pytest.fixture
def out(tmp_path) -> Path:
    """An empty folder for outputs: whatever a failed run leaves there shows up."""
    folder = tmp_path / "out"
    folder.mkdir()
    return folder


# -- inputs ------------------------------------------------------------------------------------------


def _box() -> trimesh.Trimesh:
    return trimesh.Trimesh(*examples.box((0, 0, 0), (1, 2, 3)), process=False)


def _binary_stl(triangles: np.ndarray, count: int | None = None) -> bytes:
    """A binary STL of (N, 3, 3) float32 triangles; ``count`` overrides the header's count."""
    n = len(triangles) if count is None else count
    records = b"".join(
        np.zeros(3, np.float32).tobytes() + t.astype(np.float32).tobytes() + b"\0\0" for t in triangles
    )
    return b"\0" * 80 + struct.pack("<I", n) + records


def _garbage(size: int = 2000) -> bytes:
    return np.random.default_rng(7).integers(0, 256, size, dtype=np.uint8).tobytes()


def _half(data: bytes) -> bytes:
    return data[: len(data) // 2]


INF_TRIANGLE = np.array([[[0, 0, 0], [1, 0, 0], [np.inf, 1, 0]]], np.float32)
HUGE_BOX = _box().vertices * 3e38

# name -> (file name, bytes or None for "do not create", words the message must contain)
BAD_FILES = {
    "missing": ("missing.stl", None, ["no such file"]),
    "unknown-format": ("model.xyz1", b"v 0 0 0\n", ["unknown model format", ".xyz1"]),
    "empty-file": ("empty.obj", b"", ["empty"]),
    "no-triangles-points": (
        "points.ply",
        b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        b"property float z\nend_header\n0 0 0\n1 0 0\n0 1 0\n",
        ["no triangles"],
    ),
    "no-triangles-lines": ("lines.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\nl 2 3\n", ["no triangles"]),
    "zero-triangle-stl": ("zero.stl", _binary_stl(np.zeros((0, 3, 3))), ["no triangles"]),
    "nan": ("nan.obj", b"v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n", ["NaN"]),
    "inf": ("inf.stl", _binary_stl(INF_TRIANGLE), ["infinite"]),
    "all-degenerate": ("flat.obj", b"v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\nf 1 1 2\n", ["degenerate"]),
    "face-index-out-of-range": ("badidx.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", []),
    "garbage-stl": ("garbage.stl", _garbage(), []),
    "garbage-glb": ("garbage.glb", _garbage(), []),
    "garbage-ply": ("garbage.ply", _garbage(), []),
    "text-as-3mf": ("text.3mf", b"this is not a zip archive", []),
    "truncated-binary-stl": ("half.stl", _half(_box().export(file_type="stl")), []),
    "truncated-glb": ("half.glb", _half(_box().export(file_type="glb")), []),
    "stl-header-lies": ("lies.stl", _binary_stl(np.zeros((2, 3, 3)), count=2**31 - 1), []),
    "gltf-missing-buffer": ("nobuffer.gltf", "written by the fixture", []),
}
# a good triangle, a collinear one and one with a repeated vertex
PARTLY_DEGENERATE = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 2 4\nf 1 1 3\n"


@pytest.fixture(scope="module")
def bad_dir(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("bad")
    for file, data, _ in BAD_FILES.values():
        if isinstance(data, bytes):
            (folder / file).write_bytes(data)
    for name, data in _box().export(file_type="gltf").items():
        if not name.endswith(".bin"):  # the glTF without its buffer file
            (folder / "nobuffer.gltf").write_bytes(data)
    (folder / "folder.stl").mkdir()
    (folder / "partly.obj").write_bytes(PARTLY_DEGENERATE)
    trimesh.Trimesh(HUGE_BOX, _box().faces, process=False).export(folder / "huge.obj")
    return folder


@pytest.fixture(scope="module")
def box_obj(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("model") / "box.obj"
    _box().export(path)
    return path


def _command(command: str, model: Path, out: Path) -> list:
    if command == "render":
        return ["render", model, "-o", out / "x.png", "--size", 32, 32]
    if command == "layers":
        return ["layers", model, "-o", out / "x.npz", "--size", 32, 32]
    return ["info", model]


# every command on a few files; the main command (render) on all
CORE = ["missing", "nan", "truncated-binary-stl", "truncated-glb"]
FILE_CASES = [(name, "render") for name in BAD_FILES] + [(n, c) for n in CORE for c in ("layers", "info")]
FILE_IDS = [f"{n}-{c}" for n, c in FILE_CASES]

# each fails in a check shared with others; the other ranges are tested through the API (test_gpu)
ARGUMENTS = {
    "render-size-0": ("render", ["--size", 0, 0], ["size", "0x0"]),
    "layers-size-0": ("layers", ["--size", 0, 0], ["size", "0x0"]),
    "render-size-too-large": ("render", ["--size", 100000, 100000], ["too large"]),
    "layers-size-too-large": ("layers", ["--size", 100000, 64], ["too large"]),
    "render-view": ("render", ["--view", "sideways"], ["unknown view", "sideways"]),
    "layers-view": ("layers", ["--view", "sideways"], ["unknown view", "sideways"]),
    "render-style": ("render", ["--style", "neon"], ["unknown style", "neon"]),
    "render-max-layers": ("render", ["--max-layers", -1], ["max-layers", "-1"]),
    "layers-max-layers": ("layers", ["--max-layers", -1], ["max-layers", "-1"]),
    "render-supersample": ("render", ["--supersample", 9], ["supersample"]),
    "render-line-width": ("render", ["--line-width", 0], ["line-width"]),
    "render-up": ("render", ["--up", "w"], ["--up"]),
    "render-size-not-int": ("render", ["--size", "wide", 3], ["--size"]),
    # bugs: ValueError traceback from math.cos; exit 0 with an empty drawing; exit 0
    "render-azimuth-inf": ("render", ["--azimuth", "inf"], ["azimuth"]),
    "render-azimuth-nan": ("render", ["--azimuth", "nan"], ["azimuth"]),
    "render-grid-nan": ("render", ["--grid", "nan"], ["grid"]),
}

# bench: --size and --max-layers add configurations, so the defaults go only where a case has none
BENCH = {
    "frames-0": (["--frames", 0], ["frames"]),
    "size-0": (["--size", 0, 8], ["size"]),
    "max-layers": (["--max-layers", -3], ["max-layers"]),
    "style": (["--style", "neon"], ["unknown style"]),
}


def _bench_args(extra: list) -> list:
    args = ["--frames", 1, "--warmup", 0]
    args += [] if "--size" in extra else ["--size", 8, 8]
    args += [] if "--max-layers" in extra else ["--max-layers", 1]
    return args + extra


@pytest.fixture(scope="module")
def runs(bad_dir, box_obj, tmp_path_factory) -> dict[str, tuple[subprocess.CompletedProcess, Path]]:
    """Most runs of this file, two at a time (each pays for a Python start-up and trimesh's
    import): key -> (completed process, its own output folder, empty before the run)."""
    base = tmp_path_factory.mktemp("runs")
    jobs: dict[str, tuple[list, Path]] = {}

    def add(key: str, make) -> None:
        out = base / f"job{len(jobs)}"
        out.mkdir()
        jobs[key] = (make(out), out)

    for (name, command), key in zip(FILE_CASES, FILE_IDS, strict=True):
        add(f"file:{key}", lambda out, n=name, c=command: _command(c, bad_dir / BAD_FILES[n][0], out))
    for key, (command, extra, _) in ARGUMENTS.items():
        suffix = ".png" if command == "render" else ".npz"
        add(
            f"arg:{key}",
            lambda out, c=command, e=extra, s=suffix: [c, box_obj, "-o", out / f"x{s}", "--size", 32, 32, *e],
        )
    for key, (extra, _) in BENCH.items():
        add(f"bench:{key}", lambda out, e=extra: ["bench", box_obj, *_bench_args(e)])
    add("bench:missing", lambda out: ["bench", bad_dir / "missing.glb", *_bench_args([])])
    add("huge", lambda out: _command("render", bad_dir / "huge.obj", out))
    add("partly", lambda out: ["render", bad_dir / "partly.obj", "-o", out / "x.png", "--size", 32, 24])
    add("long-name", lambda out: ["render", box_obj, "-o", out / ("a" * 250 + ".png"), "--size", 16, 16])
    with ThreadPoolExecutor(max_workers=max(2, os.cpu_count() or 1)) as pool:
        futures = {key: pool.submit(run_cli, *args) for key, (args, _) in jobs.items()}
        return {key: (future.result(), jobs[key][1]) for key, future in futures.items()}


# -- bad model files ---------------------------------------------------------------------------------


@pytest.mark.parametrize("name, command", FILE_CASES, ids=FILE_IDS)
def test_bad_model_file(bad_dir, runs, name, command):
    file, _, mentions = BAD_FILES[name]
    model = bad_dir / file
    proc, out = runs[f"file:{name}-{command}"]
    line = one_error(proc, str(model), *mentions)
    problem = line.split(str(model), 1)[1]
    assert len(problem.strip(" :")) >= 5, f"no problem stated: {line!r}"
    # a missing optional module is not the problem with the user's file (charset_normalizer,
    # which trimesh needs for text that is not UTF-8)
    assert "No module named" not in line, line
    no_output(out)


@pytest.mark.parametrize("command", ["render", "layers", "info"])
def test_directory_as_model(bad_dir, out, command):
    model = bad_dir / "folder.stl"
    one_error(run_cli(*_command(command, model, out)), str(model), "directory")
    no_output(out)


def test_huge_finite_coordinates_draw_or_fail_cleanly(bad_dir, runs):
    """Coordinates near the float32 limit are finite, so they load; the camera's matrices then
    overflow when cast to float32 (numpy RuntimeWarnings on stderr) and the drawing is empty."""
    proc, out = runs["huge"]
    if proc.returncode == 2:
        one_error(proc, str(bad_dir / "huge.obj"))
        no_output(out)
    else:
        assert proc.returncode == 0 and proc.stderr == "", proc.stderr
        assert " 0 layers" not in proc.stdout, f"nothing drawn: {proc.stdout}"


# -- bad arguments ----------------------------------------------------------------------------------


@pytest.mark.parametrize("key", list(ARGUMENTS))
def test_bad_argument(runs, key):
    proc, out = runs[f"arg:{key}"]
    one_error(proc, *ARGUMENTS[key][2])
    no_output(out)


@pytest.mark.parametrize(
    "command, output, mentions",
    [
        ("render", "missing_folder/x.png", ["does not exist"]),
        ("layers", "missing_folder/x.npz", ["does not exist"]),
        ("render", "a_folder.png", ["is a directory"]),
        ("layers", "a_folder.npz", ["is a directory"]),
        ("render", "x.jpg", [".png"]),
        ("layers", "x.png", [".npz"]),
        ("render", "box_file/x.png", ["does not exist"]),
    ],
    ids=["render-no-folder", "layers-no-folder", "render-dir", "layers-dir", "render-jpg", "layers-png",
         "folder-is-a-file"],
)  # fmt: skip
def test_unwritable_output(box_obj, out, command, output, mentions):
    (out / "a_folder.png").mkdir()
    (out / "a_folder.npz").mkdir()
    (out / "box_file").write_text("a file, not a folder")
    target = out / output
    one_error(run_cli(command, box_obj, "-o", target, "--size", 32, 32), str(target), *mentions)
    assert sorted(p.name for p in out.iterdir()) == ["a_folder.npz", "a_folder.png", "box_file"]
    assert not any((out / "a_folder.png").iterdir())


@pytest.mark.parametrize("command, suffix", [("render", ".png"), ("layers", ".npz")])
def test_write_failure_leaves_no_file(box_obj, out, command, suffix):
    """A write that fails half way (file size limit of 100 bytes: EFBIG) is reported in one
    line, and neither the output nor the temporary file stays behind."""
    target = out / f"x{suffix}"
    proc = run_cli(command, box_obj, "-o", target, "--size", 64, 64, limits={resource.RLIMIT_FSIZE: 100})
    one_error(proc, str(target), "cannot write")
    no_output(out)


@pytest.mark.parametrize(
    "command, size",
    [("render", (8192, 8192)), ("layers", (16384, 16384))],
    ids=["render", "layers"],
)
def test_size_too_large_for_memory(box_obj, out, command, size):
    """Within the texture limit but not within memory (address space capped at 1.5 GiB): GL
    cannot allocate the G-buffer and moderngl raises "the framebuffer is not complete
    (INCOMPLETE_ATTACHMENT)", which escapes as a traceback with exit code 1."""
    suffix = ".png" if command == "render" else ".npz"
    proc = run_cli(
        command, box_obj, "-o", out / f"x{suffix}", "--size", *size,
        limits={resource.RLIMIT_AS: 1536 * 2**20},
    )  # fmt: skip
    one_error(proc, "size")
    no_output(out)


def test_no_opengl_is_one_line():
    one_error(run_cli("info", env={"BLUEPRINT_GL_BACKEND": "no-such-backend"}), "OpenGL")


# -- bench -------------------------------------------------------------------------------------------


@pytest.mark.parametrize("key", list(BENCH))
def test_bench_bad_arguments(runs, key):
    """``--frames 0`` ends in AttributeError ('NoneType' has no 'layers') in bench.time_frames;
    ``--size 0 8`` reaches Camera.fit with aspect 0 first and prints numpy warnings."""
    one_error(runs[f"bench:{key}"][0], *BENCH[key][1], blank_stdout=True)


def test_bench_missing_model(bad_dir, runs):
    one_error(runs["bench:missing"][0], str(bad_dir / "missing.glb"), "no such file", blank_stdout=True)


# -- recoverable oddities and legal edge cases ----------------------------------------------------------


def test_some_degenerate_faces_render_with_one_warning(bad_dir, runs):
    proc, out = runs["partly"]
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == f"blueprint: warning: {bad_dir / 'partly.obj'}: dropped 2 degenerate faces\n"
    assert "3 triangles" in proc.stdout
    assert sorted(p.name for p in out.iterdir()) == ["x.png"]
    with Image.open(out / "x.png") as picture:
        assert picture.size == (32, 24)


def test_legal_long_output_name_is_written(runs):
    """A 254-character file name is legal (NAME_MAX 255) but the temporary file is named
    ``.{name}.XXXXXXXX.tmp`` (export/files.py), which is too long: "File name too long"."""
    proc, out = runs["long-name"]
    assert proc.returncode == 0, proc.stderr
    assert sorted(p.name for p in out.iterdir()) == ["a" * 250 + ".png"]
