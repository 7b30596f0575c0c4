"""Hostile input (issue 17): every file a user gives, or a model references, is read only if
``stat`` says it is a regular file within its size limit, and every failure is one line whatever
the file's name holds.

The CLI runs in a subprocess with a timeout, so that a FIFO that blocks fails its test instead
of hanging the suite: opening a FIFO for reading waits for a writer that never comes.
"""

from __future__ import annotations

import os
import socket
import stat
import subprocess
import sys
import tracemalloc
from pathlib import Path

import numpy as np
import pytest
import trimesh
from helpers import hostile_corpus

import blueprint
from blueprint import examples, settings
from blueprint.errors import InputError, printable
from blueprint.scene import loader
from blueprint.scene.formats import gltf
from blueprint.settings import check_file, read_file, read_settings

TIMEOUT = 30  # seconds: a refusal takes well under one; only a hang reaches this

TRIANGLE_OBJ = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"

# the package under test, whatever the folder the command runs in (a relative PYTHONPATH would not)
ENV = {
    **os.environ,
    "PYTHONPATH": os.pathsep.join(
        [str(Path(blueprint.__file__).parents[1]), os.environ.get("PYTHONPATH", "")]
    ),
}


def run(*args, cwd: Path) -> subprocess.CompletedProcess:
    """The blueprint command in a subprocess; arguments may be bytes (names that are not UTF-8)."""
    return subprocess.run(
        [sys.executable, "-m", "blueprint.cli", *args],
        capture_output=True,
        cwd=cwd,
        env=ENV,
        timeout=TIMEOUT,
    )


def one_line(proc: subprocess.CompletedProcess) -> str:
    """The one error line of a failed run: exit 2, nothing on stdout, one line on stderr."""
    stderr = proc.stderr.decode("utf-8")  # strict: the line must be valid UTF-8 too
    assert proc.returncode == 2, (proc.returncode, stderr)
    assert proc.stdout == b"", proc.stdout
    assert stderr.endswith("\n") and stderr.count("\n") == 1, f"not one line: {stderr!r}"
    assert stderr.startswith("blueprint: error: "), stderr
    return stderr[len("blueprint: error: ") : -1]


def _box() -> trimesh.Trimesh:
    return trimesh.Trimesh(*examples.box((0, 0, 0), (1, 2, 3)), process=False)


# -- special files, through the command ------------------------------------------------------------
def test_fifo_as_the_model(tmp_path):
    os.mkfifo(tmp_path / "model.stl")
    line = one_line(run("render", "model.stl", "-o", "out.png", "--size", "32", "32", cwd=tmp_path))
    assert line == "model.stl: not a regular file (a FIFO)"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["model.stl"]


def test_directory_as_the_model(tmp_path):
    (tmp_path / "model.obj").mkdir()
    line = one_line(run("info", "model.obj", cwd=tmp_path))
    assert line == "model.obj: not a regular file (a directory)"


def test_character_device_as_the_model(tmp_path):
    line = one_line(run("info", "/dev/null", cwd=tmp_path))
    assert line == "/dev/null: not a regular file (a character device)"


def test_fifo_as_a_glyph_file(tmp_path):
    _box().export(tmp_path / "box.stl")
    os.mkfifo(tmp_path / "marks.toml")
    line = one_line(
        run(
            "render", "box.stl", "-o", "out.png", "--size", "32", "32", "--glyphs", "marks.toml", cwd=tmp_path
        )
    )
    assert line == "marks.toml: not a regular file (a FIFO)"


def test_fifo_as_a_line_style_file(tmp_path):
    _box().export(tmp_path / "box.stl")
    os.mkfifo(tmp_path / "lines.toml")
    line = one_line(run("render", "box.stl", "-o", "out.svg", "--style", "lines.toml", cwd=tmp_path))
    assert line == "lines.toml: not a regular file (a FIFO)"


def test_fifo_as_an_obj_mtllib(tmp_path):
    (tmp_path / "model.obj").write_bytes(b"mtllib materials.mtl\n" + TRIANGLE_OBJ)
    os.mkfifo(tmp_path / "materials.mtl")
    line = one_line(run("info", "model.obj", cwd=tmp_path))
    assert line == f"model.obj: {tmp_path / 'materials.mtl'}: not a regular file (a FIFO)"


def test_fifo_as_an_obj_texture(tmp_path):
    (tmp_path / "materials.mtl").write_bytes(b"newmtl a\nKd 1 0 0\nmap_Kd picture.png\n")
    (tmp_path / "model.obj").write_bytes(
        b"mtllib materials.mtl\nusemtl a\nvt 0 0\nvt 1 0\nvt 0 1\n"
        + TRIANGLE_OBJ.replace(b"f 1 2 3", b"f 1/1 2/2 3/3")
    )
    os.mkfifo(tmp_path / "picture.png")
    line = one_line(run("info", "model.obj", cwd=tmp_path))
    assert line == f"model.obj: {tmp_path / 'picture.png'}: not a regular file (a FIFO)"


def test_fifo_as_a_gltf_buffer(tmp_path):
    for name, data in _box().export(file_type="gltf").items():
        (tmp_path / name).write_bytes(data)
    buffer = tmp_path / "gltf_buffer_0.bin"
    buffer.unlink()
    os.mkfifo(buffer)
    line = one_line(run("info", "model.gltf", cwd=tmp_path))
    assert line == f"model.gltf: {buffer}: not a regular file (a FIFO)"


def test_a_missing_mtllib_is_still_no_error(tmp_path):
    """Only refusals stop a model: a material file that is not there never did."""
    (tmp_path / "model.obj").write_bytes(b"mtllib missing.mtl\n" + TRIANGLE_OBJ)
    proc = run("info", "model.obj", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert b"1 triangles" in proc.stdout


INVERT = """
[pipeline]
output = "out"
[images.picture]
[passes.out]
op = "invert"
inputs = { source = "picture" }
"""


def test_fifo_as_a_pipeline_file(tmp_path):
    os.mkfifo(tmp_path / "style.toml")
    line = one_line(run("pipeline", "run", "style.toml", "-o", "out.png", cwd=tmp_path))
    assert line == "style.toml: not a regular file (a FIFO)"


def test_fifo_as_a_pipeline_image_input(tmp_path):
    (tmp_path / "invert.toml").write_text(INVERT)
    os.mkfifo(tmp_path / "picture.png")
    proc = run(
        "pipeline", "run", "invert.toml", "-o", "out.png", "--image", "picture=picture.png", cwd=tmp_path
    )
    assert one_line(proc).endswith("picture.png: not a regular file (a FIFO)")
    assert not (tmp_path / "out.png").exists()


# -- names that would break the line -------------------------------------------------------------------
def test_a_name_with_a_newline_stays_on_one_line(tmp_path):
    (tmp_path / "two\nlines.obj").write_bytes(b"v 0 0 0\n")
    line = one_line(run("info", "two\nlines.obj", cwd=tmp_path))
    assert line == "two\\nlines.obj: no triangles in the file"


def test_a_name_that_is_not_utf8_is_escaped(tmp_path):
    name = b"bad\xff.obj"
    Path(os.fsdecode(os.fsencode(tmp_path) + b"/" + name)).write_bytes(b"v 0 0 0\n")
    line = one_line(run("info", name, cwd=tmp_path))
    assert line == "bad\\xff.obj: no triangles in the file"


def test_a_model_whose_name_is_not_utf8_loads(tmp_path):
    """trimesh names meshes after the file and hashes the names as UTF-8."""
    path = Path(os.fsdecode(os.fsencode(tmp_path) + b"/bad\xff.stl"))
    _box().export(path)
    model = loader.load_model(path)
    assert len(model.faces) == 12


def test_printable_escapes_what_would_break_a_line():
    name = os.fsdecode(b"a\xfe\n\r\tb\x1b[2J\xe2\x80\xa8c")  # U+2028 separates lines too
    assert printable(name + " é") == "a\\xfe\\n\\r\\tb\\x1b[2J\\u2028c é"


# -- sizes, checked before reading ---------------------------------------------------------------------
@pytest.fixture
def no_open(monkeypatch):
    """Fails the test if a file is opened: a size over the limit must be refused by stat."""

    def refuse(*args, **kwargs):
        raise AssertionError(f"opened {args[0]!r}")

    monkeypatch.setattr(settings.os, "open", refuse)


def test_an_oversized_settings_file_is_refused_before_reading(tmp_path, monkeypatch, no_open):
    path = tmp_path / "marks.toml"
    path.write_bytes(b"#" * 3000)
    monkeypatch.setattr(settings, "SETTINGS_FILE_LIMIT", 2048)
    with pytest.raises(InputError) as error:
        read_settings(path, "glyph file")
    assert str(error.value) == f"{path}: 2.93 KiB is over the limit of 2 KiB for a glyph file"


def test_an_oversized_model_is_refused_before_reading(tmp_path, monkeypatch):
    path = tmp_path / "box.stl"
    _box().export(path)
    monkeypatch.setattr(loader, "MODEL_FILE_LIMIT", 100)
    monkeypatch.setattr(loader, "_load_scene", lambda *a: pytest.fail("the model was read"))
    with pytest.raises(InputError) as error:
        loader.load_model(path)
    assert str(error.value) == f"{path}: 684 bytes is over the limit of 100 bytes for a model file"


def test_an_oversized_file_a_model_references_is_refused(tmp_path, monkeypatch):
    (tmp_path / "model.obj").write_bytes(b"mtllib materials.mtl\n" + TRIANGLE_OBJ)
    (tmp_path / "materials.mtl").write_bytes(b"newmtl a\nKd 1 0 0\n" * 100)
    monkeypatch.setattr(loader, "MODEL_FILE_LIMIT", 1000)
    with pytest.raises(InputError) as error:
        loader.load_model(tmp_path / "model.obj")
    assert str(error.value) == (
        f"{tmp_path / 'model.obj'}: {tmp_path / 'materials.mtl'}: 1.76 KiB is over the limit of "
        "1000 bytes for a file a model references"
    )


def test_a_sparse_file_is_refused_by_its_size(tmp_path, no_open):
    path = tmp_path / "huge.bin"
    with open(path, "wb") as fh:
        fh.truncate(3 << 30)  # sparse: takes no disk
    with pytest.raises(InputError) as error:
        check_file(path, 2 << 30, "a model file")
    assert str(error.value) == f"{path}: 3 GiB is over the limit of 2 GiB for a model file"


def test_read_file_checks_the_open_file_too(tmp_path, monkeypatch):
    """A FIFO put where a regular file was stat'ed is refused without blocking."""
    path = tmp_path / "f"
    os.mkfifo(path)
    regular = os.stat(__file__)
    real_stat = os.stat
    monkeypatch.setattr(
        settings.os, "stat", lambda p, *a, **k: regular if p == path else real_stat(p, *a, **k)
    )
    with pytest.raises(InputError) as error:
        read_file(path, 1 << 20)
    assert str(error.value) == f"{path}: not a regular file (a FIFO)"


def test_read_file_takes_room_for_the_file_not_the_limit(tmp_path):
    """A file of kilobytes under a limit of a gigabyte is read into room for its own bytes:
    ``read(limit + 1)`` took room for the limit at once."""
    path = tmp_path / "small.bin"
    path.write_bytes(bytes(range(256)) * 64)
    tracemalloc.start()
    try:
        data = read_file(path, 1 << 30)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert data == path.read_bytes()
    assert peak < 1 << 20


@pytest.mark.parametrize(("grown", "limit", "refused"), [(0, 100, False), (50, 100, False), (60, 100, True)])
def test_read_file_reads_on_where_the_file_grew_after_its_size_was_taken(
    tmp_path, monkeypatch, grown, limit, refused
):
    """The sizes the checks and the read take are 50 bytes; the file holds ``grown`` more: read
    on to the limit, and past it refused, as a file over the limit is."""
    path = tmp_path / "growing.bin"
    path.write_bytes(bytes(range(50 + grown)))
    real_stat, real_fstat = os.stat, os.fstat

    def taken(found: os.stat_result) -> os.stat_result:
        return os.stat_result((*found[:6], 50, *found[7:])) if stat.S_ISREG(found.st_mode) else found

    monkeypatch.setattr(settings.os, "stat", lambda p, *a, **k: taken(real_stat(p, *a, **k)))
    monkeypatch.setattr(settings.os, "fstat", lambda fd: taken(real_fstat(fd)))
    if refused:
        with pytest.raises(InputError, match="over the limit"):
            read_file(path, limit)
    else:
        assert read_file(path, limit) == path.read_bytes()


def test_a_socket_is_refused(tmp_path):
    path = tmp_path / "s"
    with socket.socket(socket.AF_UNIX) as server:
        server.bind(str(path))
        with pytest.raises(InputError) as error:
            check_file(path, None)
    assert str(error.value) == f"{path}: not a regular file (a socket)"


def test_a_model_name_too_long_for_the_file_system(tmp_path):
    path = tmp_path / ("a" * 300 + ".obj")
    with pytest.raises(InputError) as error:
        loader.load_model(path)
    assert str(error.value) == f"{path}: cannot read (File name too long)"


# -- settings and pipeline files: nesting depth and number sizes ---------------------------------------
@pytest.mark.parametrize(
    ("name", "text", "message"),
    [
        ("deep.json", "[" * 100_000 + "]" * 100_000, "tables or arrays nested deeper than 32"),
        ("deep.toml", "a = " + "[" * 10_000 + "]" * 10_000, "tables or arrays nested deeper than 32"),
        ("digits.json", '{"a": ' + "7" * 5000 + "}", "a number of 5000 digits (at most 100)"),
        ("e400.json", '{"a": 1' + "0" * 400 + "}", "a number of 401 digits (at most 100)"),
        ("digits.toml", "a = " + "7" * 5000, "a number of too many digits (at most 100)"),
        ("wide.toml", "[t]\na = " + "7" * 200, "t.a: a number of too many digits (at most 100)"),
        ("nested.json", '{"a": ' + "[" * 40 + "]" * 40 + "}", "a" + "[0]" * 32 + ": nested deeper than 32"),
    ],
)
def test_settings_nesting_and_numbers_are_bounded(tmp_path, name, text, message):
    (tmp_path / name).write_text(text)
    with pytest.raises(InputError) as caught:
        read_settings(tmp_path / name, "glyph file")
    assert str(caught.value) == f"{tmp_path / name}: {message}"


def test_settings_within_the_bounds_read_as_written(tmp_path):
    (tmp_path / "ok.json").write_text('{"a": [1, 2.5, {"b": ' + "9" * 100 + "}]}")
    assert read_settings(tmp_path / "ok.json", "glyph file") == {"a": [1, 2.5, {"b": int("9" * 100)}]}


def test_a_pipeline_file_with_a_huge_number_is_one_line(tmp_path):
    (tmp_path / "p.toml").write_text("[variables]\nn = " + "7" * 5000 + "\n" + INVERT)
    line = one_line(
        run("pipeline", "run", "p.toml", "-o", "out.png", "--image", "picture=x.png", cwd=tmp_path)
    )
    assert line == "p.toml: a number of too many digits (at most 100)"
    assert not (tmp_path / "out.png").exists()


# -- pipeline expressions --------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("expression", "message"),
    [
        ("= -s", "arithmetic on a non-number in '-s'"),
        ("= max(1)", "max takes two or more numbers in 'max(1)'"),
        ("= min(1, s)", "arithmetic on a non-number in 'min(1, s)'"),
        ("= " + "-" * 5000 + "1", "an expression of 5001 characters (at most 1000)"),
        ("= " + "-" * 990 + "1", "the expression nests too deeply"),
    ],
)
def test_expression_errors_name_the_file_and_key(expression, message):
    from blueprint.pipeline.expressions import evaluate

    with pytest.raises(InputError) as caught:
        evaluate(expression, {"s": "text"}, "p.toml", "passes.a.k")
    assert message in str(caught.value) and str(caught.value).startswith("p.toml")
    assert "passes.a.k" in str(caught.value)


def test_expressions_still_evaluate():
    from blueprint.pipeline.expressions import evaluate

    assert evaluate("= max(x, 3, 1.5) - -1", {"x": 2}, "p.toml", "k") == 4


# -- image inputs: the header's size before any pixel --------------------------------------------------
def _png_header_only(path: Path, width: int, height: int) -> None:
    """A PNG whose IHDR declares width x height, with no pixel data worth decoding."""
    import struct
    import zlib

    def chunk(kind: bytes, body: bytes) -> bytes:
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))

    ihdr = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    path.write_bytes(
        b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(b"")) + chunk(b"IEND", b"")
    )


@pytest.mark.parametrize(("width", "height"), [(100_000, 100_000), (10_000, 10_000)])
def test_an_image_declaring_too_many_pixels_is_one_line(tmp_path, width, height):
    from blueprint.pipeline.media import read_image

    _png_header_only(tmp_path / "big.png", width, height)
    with pytest.raises(InputError) as caught:
        read_image(tmp_path / "big.png", "rgba8")
    assert str(caught.value).startswith(f"{tmp_path / 'big.png'}: the image declares ")
    assert "pixels" in str(caught.value) and "Error" not in str(caught.value)


# -- instanced scenes: named and sorted in one pass --------------------------------------------------
def test_instances_of_one_mesh_are_numbered_in_order():
    scene = trimesh.Scene()
    scene.add_geometry(trimesh.creation.box(), geom_name="box", node_name="n0")
    for i in range(1, 300):
        matrix = trimesh.transformations.translation_matrix([3 * i, 0, 0])
        scene.graph.update(frame_to=f"n{i}", frame_from=scene.graph.base_frame, geometry="box", matrix=matrix)
    model = loader.model_from_object(scene)
    assert list(model.part_names) == ["box"] + [f"box[{k}]" for k in range(2, 301)]
    # a row of boxes: none encloses the rest or lies under it, so every one is drawn
    assert len(model.part_names) == 300 and model.positions[:, 0].max() == pytest.approx(3 * 299 + 0.5)


# -- header counts against the file's size ---------------------------------------------------------

ASCII_PLY = (
    "ply\nformat ascii 1.0\nelement vertex {v}\nproperty float x\nproperty float y\nproperty float z\n"
    "element face {f}\nproperty list uchar int vertex_indices\nend_header\n"
    "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"
)


def test_ascii_ply_declaring_a_trillion_faces_is_refused_before_reading(tmp_path):
    path = tmp_path / "lie.ply"
    path.write_text(ASCII_PLY.format(v=3, f=10**12))
    size = path.stat().st_size
    with pytest.raises(InputError) as info:
        blueprint.load_model(path)
    assert str(info.value) == (
        f"{path}: the header declares {10**12} face elements, more than the file's {size} bytes can hold"
    )
    proc = run("render", str(path), "-o", "out.png", "--size", "32", "32", cwd=tmp_path)
    assert "declares 1000000000000 face elements" in one_line(proc)
    assert not (tmp_path / "out.png").exists()


def test_off_claiming_ten_times_its_faces_is_refused(tmp_path):
    faces = "".join("3 0 1 2\n" for _ in range(20))
    path = tmp_path / "lie.off"
    path.write_text(f"OFF\n3 200 0\n0 0 0\n1 0 0\n0 1 0\n{faces}")
    with pytest.raises(InputError, match=r"lie\.off: the header declares 200 faces, more than the file's"):
        blueprint.load_model(path)


def test_honest_headers_still_load(tmp_path):
    ply = tmp_path / "ok.ply"
    ply.write_text(ASCII_PLY.format(v=3, f=1))
    off = tmp_path / "ok.off"
    off.write_text("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")
    assert blueprint.load_model(ply).triangle_count == 1
    assert blueprint.load_model(off).triangle_count == 1


# -- compressed models: expanded with bounds ------------------------------------------------------
def _bomb_bytes(size: int) -> bytes:
    return b"\0" * size


@pytest.mark.parametrize("kind", ["gz", "bz2", "xz"])
def test_a_compressed_model_loads(tmp_path, kind):
    import bz2
    import gzip
    import lzma

    compress = {"gz": gzip.compress, "bz2": bz2.compress, "xz": lzma.compress}[kind]
    path = tmp_path / f"box.stl.{kind}"
    path.write_bytes(compress(_box().export(file_type="stl")))
    model = loader.load_model(path)
    assert model.triangle_count == 12 and model.up == "z"
    assert model.positions.max(axis=0).tolist() == [1, 2, 3]


@pytest.mark.parametrize("kind", ["gz", "bz2", "xz"])
def test_a_compressed_bomb_is_refused_while_expanding(tmp_path, kind, monkeypatch):
    import bz2
    import gzip
    import lzma

    compress = {"gz": gzip.compress, "bz2": bz2.compress, "xz": lzma.compress}[kind]
    path = tmp_path / f"bomb.stl.{kind}"
    path.write_bytes(compress(_bomb_bytes(64 << 20)))
    assert path.stat().st_size < 70_000
    with pytest.raises(InputError) as caught:
        loader.load_model(path)
    assert str(caught.value).startswith(
        f"{path}: the compressed stream expands to more than 200 times its compressed size ("
    )
    monkeypatch.setattr(settings, "EXPANDED_LIMIT", 8 << 20)
    monkeypatch.setattr(settings, "EXPANSION_RATIO_LIMIT", 10**6)
    with pytest.raises(InputError) as caught:
        loader.load_model(path)
    assert str(caught.value) == (
        f"{path}: the compressed stream expands to more than 8 MiB, the limit for a model's contents "
        "(set from this machine's memory; BLUEPRINT_MEMORY_LIMIT changes it)"
    )


def _zip(path: Path, files: dict[str, bytes]) -> None:
    import zipfile

    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        for name, data in files.items():
            archive.writestr(name, data)


@pytest.mark.parametrize("suffix", ["zip", "3mf", "3dxml"])
def test_zip_bombs_are_refused_by_their_directory(tmp_path, suffix, monkeypatch):
    path = tmp_path / f"bomb.{suffix}"
    _zip(path, {"[Content_Types].xml": b"<Types/>", "3D/3dmodel.model": _bomb_bytes(32 << 20)})
    read = []
    monkeypatch.setattr(loader, "_trimesh_scene", lambda *a: read.append(a))
    with pytest.raises(InputError) as caught:
        loader.load_model(path)
    assert "expands to more than 200 times its compressed size" in str(caught.value)
    assert str(caught.value).startswith(f"{path}: the archive ")
    assert read == []


def test_a_zip_of_models_loads_each(tmp_path):
    path = tmp_path / "two.zip"
    moved = _box()
    moved.apply_translation([10, 0, 0])
    _zip(path, {"a.stl": _box().export(file_type="stl"), "b.obj": moved.export(file_type="obj").encode()})
    model = loader.load_model(path)
    assert model.triangle_count == 24 and len(model.part_names) == 2
    assert model.positions.min(axis=0).tolist() == [0, 0, 0]
    assert model.positions.max(axis=0).tolist() == [11, 2, 3]


def test_a_zip_without_models_is_one_line(tmp_path):
    path = tmp_path / "notes.zip"
    _zip(path, {"readme.txt": b"hello"})
    with pytest.raises(InputError) as caught:
        loader.load_model(path)
    assert str(caught.value) == f"{path}: the archive holds no model file (it holds: readme.txt)"


# -- binary STL counts -----------------------------------------------------------------------------------
def test_binary_stl_whose_count_lies_is_refused(tmp_path):
    import struct

    data = _box().export(file_type="stl")
    path = tmp_path / "lie.stl"
    path.write_bytes(data[:80] + struct.pack("<I", 10**9) + data[84:])
    with pytest.raises(InputError) as caught:
        loader.load_model(path)
    assert str(caught.value) == (
        f"{path}: the header declares 1000000000 triangles, more than the file's 684 bytes can hold "
        "(50000000084 bytes)"
    )


def test_binary_stl_over_the_triangle_limit_is_refused(tmp_path, monkeypatch):
    path = tmp_path / "box.stl"
    _box().export(path)
    monkeypatch.setattr(settings, "MEMORY_BUDGET", 12 * settings.TRIANGLE_BYTES - 1)
    with pytest.raises(InputError) as caught:
        loader.load_model(path)
    assert str(caught.value) == (
        f"{path}: 12 triangles to draw need about 10.5 KiB of memory at 896 bytes a triangle, more "
        "than the memory budget of 10.5 KiB (BLUEPRINT_MEMORY_LIMIT sets the budget)"
    )


# -- glTF node graphs: walked once ----------------------------------------------------------------------
def _glb(path: Path, nodes: list, roots: list) -> None:
    """A GLB of one triangle mesh placed by ``nodes`` (glTF node objects) under ``roots``."""
    import json
    import struct

    import numpy as np

    binary = (
        np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32).tobytes()
        + np.arange(3, dtype="<u4").tobytes()
    )
    doc = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": roots}],
        "nodes": nodes,
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "buffers": [{"byteLength": len(binary)}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 12},
        ],
        "accessors": [
            {
                "bufferView": 0,
                "componentType": 5126,
                "count": 3,
                "type": "VEC3",
                "min": [0, 0, 0],
                "max": [1, 1, 0],
            },
            {"bufferView": 1, "componentType": 5125, "count": 3, "type": "SCALAR"},
        ],
    }
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    body = (
        struct.pack("<II", len(text), 0x4E4F534A)
        + text
        + struct.pack("<II", len(binary), 0x004E4942)
        + binary
    )
    path.write_bytes(struct.pack("<III", 0x46546C67, 2, 12 + len(body)) + body)


@pytest.mark.parametrize(
    ("nodes", "roots", "message"),
    [
        (
            [{"mesh": 0, "children": [1]}, {"mesh": 0, "children": [0]}],
            [0],
            "its nodes form a cycle (0 → 1 → 0)",
        ),
        ([{"mesh": 0, "children": [0]}], [0], "its nodes form a cycle (0 → 0)"),
        ([{"mesh": 0, "children": [5]}], [0], "node 0 refers to node 5, which does not exist"),
        ([{"mesh": 0}], [3], "a scene refers to node 3, which does not exist"),
        (
            [{"mesh": 0, "children": [i + 1]} for i in range(10**4)] + [{"mesh": 0}],
            [0],
            "its nodes nest more than 64 deep (the limit)",
        ),
    ],
)
def test_broken_node_graphs_are_one_line(tmp_path, nodes, roots, message):
    path = tmp_path / "graph.glb"
    _glb(path, nodes, roots)
    with pytest.raises(InputError) as caught:
        loader.load_model(path)
    assert str(caught.value) == f"{path}: {message}"


def test_instance_and_triangle_limits_of_a_graph(tmp_path, monkeypatch):
    path = tmp_path / "many.glb"
    # a node placing a group twice: four instances of the mesh from three nodes
    _glb(path, [{"children": [1, 1]}, {"mesh": 0, "children": [2]}, {"mesh": 0}], [0])
    monkeypatch.setattr(settings, "INSTANCE_LIMIT", 3)
    with pytest.raises(InputError) as caught:
        loader.load_model(path)
    budget = settings.human_size(settings.MEMORY_BUDGET)
    assert str(caught.value) == (
        f"{path}: its scene holds more than 3 mesh instances, the most the memory budget of {budget} "
        f"holds at {settings.INSTANCE_BYTES} bytes an instance (BLUEPRINT_MEMORY_LIMIT sets the budget)"
    )


def test_many_instances_of_one_mesh_still_load(tmp_path):
    path = tmp_path / "rows.glb"
    count = 20_000
    _glb(
        path,
        [{"mesh": 0, "translation": [2.0 * (i % 200), 2.0 * (i // 200), 0]} for i in range(count)],
        list(range(count)),
    )
    model = loader.load_model(path)
    assert model.triangle_count == count and len(model.part_names) == count
    assert model.positions.max(axis=0).tolist() == [2.0 * 199 + 1, 2.0 * 99 + 1, 0]


# -- work bounded before it starts ------------------------------------------------------------------
def test_off_face_with_a_billion_corners_is_refused(tmp_path):
    path = tmp_path / "corners.off"
    path.write_text("OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n1000000000 0 1 2\n")
    with pytest.raises(InputError) as caught:
        loader.load_model(path)
    assert str(caught.value) == f"{path}: face 1 declares 1000000000 corners and lists 3"


def test_one_triangle_over_and_over_is_refused(tmp_path):
    path = tmp_path / "same.obj"
    path.write_text(
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 5 5 5\nv 6 5 5\nv 5 6 5\n" + "f 1 2 3\n" * 257 + "f 4 5 6\n"
    )
    with pytest.raises(InputError) as caught:
        loader.load_model(path)
    assert str(caught.value) == (
        f"{path}: 257 faces lie on one another (one triangle over and over), more than the 256 layers "
        "a drawing can peel"
    )
    path.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\n" + "f 1 2 3\n" * 256)
    assert loader.load_model(path).triangle_count == 256


@pytest.mark.parametrize("threads", [1, 3])
def test_the_copies_bucketed_a_block_a_thread_bound_the_most_copies(threads, monkeypatch):
    """The coincidence check's buckets, counted a block a thread and added: at least the most
    copies of one value (their copies spread over every block), -0.0 with 0.0; every value a
    bucket where one is NaN."""
    monkeypatch.setattr(settings, "THREADS", threads)
    monkeypatch.setattr(loader, "_BLOCK", 100)
    rng = np.random.default_rng(9)
    for copies in (1, 40, 300):
        key = rng.random(2_000)
        key[rng.choice(len(key), copies, replace=False)] = 0.25
        key[:2] = 0.0, -0.0
        most = max(copies, 2)
        assert most <= loader._bucketed_most(key) < most + 20
    key[5] = np.nan
    assert loader._bucketed_most(key) == len(key)


def test_frames_glyph_counts_and_glyph_coordinates_are_bounded(tmp_path):
    _box().export(tmp_path / "box.stl")
    line = one_line(
        run(
            "silhouettes",
            "box.stl",
            "-o",
            "s.mp4",
            "--animate",
            "twist",
            "--frames",
            "1000000000",
            cwd=tmp_path,
        )
    )
    assert line == "frames must be at most 100000 (the limit), got 1000000000"
    (tmp_path / "many.toml").write_text("[[box]]\nmin = [0, 0, 0]\nmax = [1, 1, 1]\n" * 10_001)
    line = one_line(run("render", "box.stl", "-o", "out.png", "--glyphs", "many.toml", cwd=tmp_path))
    assert line == "many.toml: 10001 glyphs, over the limit of 10000"
    (tmp_path / "far.toml").write_text("[[box]]\nmin = [0, 0, 0]\nmax = [1e300, 1e308, 1]\n")
    line = one_line(run("render", "box.stl", "-o", "out.png", "--glyphs", "far.toml", cwd=tmp_path))
    assert line == "far.toml: box 1: max must be finite numbers within ±1e+18, got [1e+300, 1e+308, 1]"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["box.stl", "far.toml", "many.toml"]


def test_the_memory_budget_is_set_from_the_environment(tmp_path):
    code = "from blueprint import settings as s; print(s.MEMORY_BUDGET, s.MODEL_FILE_LIMIT, s.EXPANDED_LIMIT)"
    for value, budget in (("64M", 64 << 20), ("1G", 1 << 30), ("123456789", 123456789)):
        env = {**ENV, settings.MEMORY_ENV: value}
        out = subprocess.run(
            [sys.executable, "-c", code], capture_output=True, env=env, text=True, check=True
        )
        assert out.stdout.split() == [str(budget), str(budget // 4), str(budget // 4)]


# -- outputs: temporaries gone with the process, paths refused up front ----------------------------
KILLED_WRITER = """
import os, sys, time
from blueprint.export import files
if sys.argv[2] == "named":
    del files.os.O_TMPFILE  # as on a system without unnamed files
def write(tmp):
    with open(tmp, "wb") as fh:
        fh.write(b"half")
        fh.flush()
        print("writing", flush=True)
        time.sleep(60)
files.atomic_write(sys.argv[1], write)
"""


@pytest.mark.parametrize("mode", ["unnamed", "named"])
def test_a_writer_killed_mid_write_leaves_nothing_where_the_user_looks(tmp_path, mode):
    import signal

    from blueprint.export import files

    (tmp_path / "out.png").write_bytes(b"old")
    child = subprocess.Popen(
        [sys.executable, "-c", KILLED_WRITER, str(tmp_path / "out.png"), mode],
        stdout=subprocess.PIPE,
        env=ENV,
    )
    assert child.stdout.readline() == b"writing\n"
    left = sorted(p.name for p in tmp_path.iterdir())
    os.kill(child.pid, signal.SIGKILL)
    child.wait(TIMEOUT)
    child.stdout.close()
    after = sorted(p.name for p in tmp_path.iterdir())
    assert (tmp_path / "out.png").read_bytes() == b"old"
    if mode == "unnamed":
        # never named: nothing but the old file, during the write and after the kill
        assert left == after == ["out.png"]
        return
    # named: ours, with the dead process's id, swept by the next write once it is stale
    (stale,) = set(after) - {"out.png"}
    assert stale.startswith(f".out.png.bp{child.pid}.") and stale.endswith(".tmp")
    assert files.sweep_temporaries(tmp_path) == []  # written just now: it might be another host's
    os.utime(tmp_path / stale, (0, 0))
    (tmp_path / ".notes.bp1.x.txt").write_text("not ours")
    files.save_png(tmp_path / "out.png", np.zeros((2, 2, 3), np.uint8))
    assert sorted(p.name for p in tmp_path.iterdir()) == [".notes.bp1.x.txt", "out.png"]


def test_output_written_in_place_has_the_usual_permissions(tmp_path):
    from blueprint.export import files

    files.save_png(tmp_path / "a.png", np.zeros((2, 2, 3), np.uint8))
    umask = os.umask(0)
    os.umask(umask)
    assert (tmp_path / "a.png").stat().st_mode & 0o777 == 0o666 & ~umask
    os.chmod(tmp_path / "a.png", 0o640)
    files.save_png(tmp_path / "a.png", np.ones((2, 2, 3), np.uint8))
    assert (tmp_path / "a.png").stat().st_mode & 0o777 == 0o640
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.png"]


def test_outputs_that_cannot_be_written_are_one_line_before_any_work(tmp_path):
    _box().export(tmp_path / "box.stl")
    long = "a" * 300 + ".png"
    line = one_line(run("render", "box.stl", "-o", long, "--size", "32", "32", cwd=tmp_path))
    assert line == f"{long}: cannot write (File name too long)"
    line = one_line(run("turntable", "box.stl", "-o", "/proc/out.mp4", "--size", "32", "32", cwd=tmp_path))
    assert line.startswith("/proc/out.mp4: folder /proc takes no new files (")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["box.stl"]


def test_a_dump_that_cannot_be_written_leaves_no_output(tmp_path):
    from PIL import Image

    (tmp_path / "invert.toml").write_text(INVERT)
    Image.new("RGB", (8, 8)).save(tmp_path / "picture.png")
    (tmp_path / "out.out.png").mkdir()
    proc = run(
        "pipeline",
        "run",
        "invert.toml",
        "-o",
        "out.png",
        "--image",
        "picture=picture.png",
        "--dump",
        "out",
        cwd=tmp_path,
    )
    assert one_line(proc) == "out.out.png: cannot write (Is a directory)"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["invert.toml", "out.out.png", "picture.png"]


def test_out_of_memory_names_the_pipeline(tmp_path, monkeypatch):
    from PIL import Image

    from blueprint.api import files
    from blueprint.pipeline.executor import Executor

    (tmp_path / "invert.toml").write_text(INVERT)
    Image.new("RGB", (8, 8)).save(tmp_path / "picture.png")

    def exhausted(*args, **kwargs):
        raise MemoryError

    monkeypatch.setattr(Executor, "run", exhausted)
    with pytest.raises(InputError) as caught:
        files.run_pipeline(
            tmp_path / "invert.toml", None, tmp_path / "out.png", image={"picture": tmp_path / "picture.png"}
        )
    assert str(caught.value) == f"{tmp_path / 'invert.toml'}: out of memory (try a smaller --size)"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["invert.toml", "picture.png"]


def test_numpy_warnings_are_our_one_line_warnings():
    code = (
        "import numpy as np\nfrom blueprint.cli.shell import setup_logging\nsetup_logging()\n"
        "np.array([1e308]) * 10\nnp.array([1e308]) * 10\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, env=ENV, text=True)
    assert proc.stderr == "blueprint: warning: numeric trouble: overflow encountered in multiply\n"


# -- the corpus of benchmarks/hostile.py: a fast subset --------------------------------------------
FAST = (
    "FIFO mtllib",
    "zip of no model",
    "GLB nodes 0 -> 1 -> 0",
    "pipeline digits.toml",
    "model name with a newline",
    "OBJ nan vertex",
    "OBJ vertices cut to two numbers",
    "encrypted .3mf",
    "GLB 10^5 instances of a box",
    "glTF document a list",
    "GLB nodes an object",
)


def test_a_fast_subset_of_the_hostile_corpus_runs_clean(tmp_path):
    """The same generator as the whole run (``python benchmarks/hostile.py``): a few cases of
    every cheap kind, and mutated files; each clean, or the reason it is not."""
    from concurrent.futures import ThreadPoolExecutor

    corpus = hostile_corpus()
    kinds = (
        "special",
        "sparse",
        "bomb",
        "header",
        "graph",
        "settings",
        "pipeline",
        "names",
        "numbers",
        "shape",
    )
    chosen = [c for c in corpus.generate(17, 0, kinds) if c.label in FAST]
    chosen += corpus.generate(17, 3, ("mutated",))
    assert len(chosen) == len(FAST) + 3
    with ThreadPoolExecutor(2) as pool:
        outcomes = list(
            pool.map(lambda ic: corpus.run_case(ic[1], tmp_path / str(ic[0]), TIMEOUT), enumerate(chosen))
        )
    assert [(o.case.label, o.reason) for o in outcomes if not o.clean] == []
    assert all(o.case.valid or o.reason == "refused" for o in outcomes)


def _threemf(path: Path, components: int) -> None:
    corpus = hostile_corpus()
    path.write_bytes(corpus.threemf(components))


def test_a_deep_chain_of_3mf_components_is_refused(tmp_path):
    path = tmp_path / "chain.3mf"
    _threemf(path, 10**4)
    with pytest.raises(InputError) as caught:
        loader.load_model(path)
    assert str(caught.value) == f"{path}: its objects nest more than 64 deep (the limit)"
    _threemf(path, 20)
    model = loader.load_model(path)
    assert model.triangle_count == 12 and model.positions.max(axis=0).tolist() == [1, 2, 3]


def test_a_cycle_of_3mf_components_is_refused(tmp_path):
    path = tmp_path / "cycle.3mf"
    _threemf(path, 3)
    import zipfile

    with zipfile.ZipFile(path) as archive:
        model = archive.read("3D/3dmodel.model").replace(
            b'<component objectid="1"/>', b'<component objectid="4"/>'
        )
    _zip(path, {"[Content_Types].xml": b"<Types/>", "3D/3dmodel.model": model})
    with pytest.raises(InputError) as caught:
        loader.load_model(path)
    assert str(caught.value) == f"{path}: its objects form a cycle (4 → 3 → 2 → 4)"


def test_image_inputs_that_are_not_images_say_so_in_user_words(tmp_path):
    from PIL import Image

    from blueprint.pipeline.media import read_image

    (tmp_path / "text.png").write_bytes(b"not a picture at all")
    with pytest.raises(InputError) as caught:
        read_image(tmp_path / "text.png", "rgba8")
    assert str(caught.value) == f"{tmp_path / 'text.png'}: not an image in a format Pillow reads"
    Image.effect_noise((64, 64), 40).convert("RGB").save(tmp_path / "noise.png")
    (tmp_path / "cut.png").write_bytes((tmp_path / "noise.png").read_bytes()[:200])
    with pytest.raises(InputError) as caught:
        read_image(tmp_path / "cut.png", "rgba8")
    assert str(caught.value) == f"{tmp_path / 'cut.png'}: cannot read the image (it is damaged or cut short)"


@pytest.mark.parametrize("label", ["3mf #108", "3mf #117"])
def test_corpus_finds_stay_fixed(tmp_path, label):
    """Mutated 3MF files whose deflate streams break mid-member: a traceback from zlib in the
    walk of the component graph, found by the whole corpus."""
    (case,) = [c for c in hostile_corpus().generate(17, 160, ("mutated",)) if c.label == label]
    case.make(tmp_path)
    with pytest.raises(InputError) as caught:
        loader.load_model(tmp_path / "m.3mf")
    assert str(caught.value).startswith(f"{tmp_path / 'm.3mf'}: ")
    assert "Error" not in str(caught.value)


# -- issue 36: OBJ rows cut short, glTF JSON of the wrong types, encrypted archives, instances ---------
def _case(label: str):
    (case,) = [c for c in hostile_corpus().generate(17, 0) if c.label == label]
    return case


def test_short_vertex_lines_are_found_as_a_line_by_line_reading_finds_them(monkeypatch):
    """``short_vertex`` against a plain reading of every line, across blocks of a few bytes."""
    from blueprint.scene.formats import obj

    rng = np.random.default_rng(36)
    for trial in range(200):
        lines = []
        for _ in range(rng.integers(1, 30)):
            kind = rng.choice(["v", "vn", "vt", "f", "#", "", " v"])
            numbers = " ".join(f"{x:.3g}" for x in rng.normal(size=rng.choice([3, 3, 3, 4, 6, 2, 1, 0])))
            space = rng.choice([" ", "  ", "\t "])
            lines.append(f"{kind}{space}{numbers}" if kind else "")
        ending = rng.choice(["\n", "\r\n"])
        data = ending.join(lines).encode() + (ending.encode() if trial % 2 else b"")
        expected = None
        for number, line in enumerate(data.split(b"\n"), 1):
            if line.startswith(b"v ") and len(line.split()) < 4:
                expected = (number, len(line.split()) - 1)
                break
        monkeypatch.setattr(obj, "_BLOCK", int(rng.integers(1, 64)))
        assert obj.short_vertex(data) == expected, data


def test_an_obj_vertex_of_two_numbers_is_refused_naming_its_line(tmp_path):
    """trimesh reads every vertex cut to the shortest vertex line: a box of 2-D vertices, or a
    traceback where the vertices meet their transform."""
    path = tmp_path / "box.obj"
    path.write_bytes(hostile_corpus()._short_vertex_obj())
    with pytest.raises(InputError) as caught:
        loader.load_model(path)
    assert str(caught.value) == f"{path}: line 4: a vertex of 2 numbers (x, y and z are needed)"
    path.write_bytes(b"vn 0 0 1\nv 0 0 0\nv 1\nv 0 1 0\nf 1//1 2//1 3//1\n")
    with pytest.raises(InputError) as caught:
        loader.load_model(path)
    assert str(caught.value) == f"{path}: line 3: a vertex of 1 number (x, y and z are needed)"


@pytest.mark.parametrize(
    ("line", "message"),
    [
        (b"v nan 2.0 3.0", "1 vertices have NaN or infinite coordinates"),
        (b"v 1e20 2.0 3.0", "coordinates beyond 1e+18 cannot be drawn"),
    ],
)
def test_obj_vertices_of_nan_or_huge_numbers_are_refused(tmp_path, line, message):
    path = tmp_path / "box.obj"
    lines = hostile_corpus()._short_vertex_obj().split(b"\n")
    lines[3] = line
    path.write_bytes(b"\n".join(lines))
    with pytest.raises(InputError) as caught:
        loader.load_model(path)
    assert str(caught.value) == f"{path}: {message}"


SHAPES = {
    "document a list": "not a glTF document (its JSON is a list, not an object)",
    "document a string": "not a glTF document (its JSON is a string, not an object)",
    "document a number": "not a glTF document (its JSON is 2.0, not an object)",
    "nodes an object": "nodes is an object, not a list",
    "scenes a number": "scenes is 0, not a list",
    "meshes a number": "meshes is 3, not a list",
    "an accessor a number": "accessors[0] is 7, not an object",
    "componentType a list": "accessors[0].componentType is a list, not a whole number",
    "count a string": "accessors[1].count is a string, not a whole number",
    "mesh index a string": "nodes[1].mesh is a string, not a whole number",
    "mesh index -1": "nodes[1].mesh is -1, not a whole number",
    "scene -1": "scene is -1, not a whole number",
    "children an object": "nodes[0].children is an object, not a list",
    "translation of booleans": "nodes[1].translation holds true, not only numbers",
    "attributes a list": "meshes[0].primitives[0].attributes is a list, not an object",
    "primitives of numbers": "meshes[0].primitives holds 0, not only objects",
    "indices past the accessors": (
        "meshes[0].primitives[0].indices refers to accessor 9, which does not exist"
    ),
}


@pytest.mark.parametrize("suffix", ["gltf", "glb"])
def test_gltf_json_of_the_wrong_shape_is_one_line_naming_the_field(tmp_path, suffix):
    """Every case of the corpus's kind ``shape``, once as .gltf and once as GLB."""
    cases = [c for c in hostile_corpus().generate(17, 0, ("shape",)) if c.args[1] == f"m.{suffix}"]
    assert sorted(c.label.split(" ", 1)[1] for c in cases) == sorted(SHAPES)
    for k, case in enumerate(cases):
        folder = tmp_path / str(k)
        folder.mkdir()
        case.make(folder)
        with pytest.raises(InputError) as caught:
            loader.load_model(folder / f"m.{suffix}")
        assert str(caught.value) == f"{folder / f'm.{suffix}'}: {SHAPES[case.label.split(' ', 1)[1]]}"


@pytest.mark.parametrize(
    ("suffix", "member"), [("3mf", "[Content_Types].xml"), ("3dxml", "[Content_Types].xml"), ("zip", "a.stl")]
)
def test_encrypted_archive_members_are_one_line(tmp_path, suffix, member):
    """Python's zipfile would raise RuntimeError ("password required") at the first read."""
    _case(f"encrypted .{suffix}").make(tmp_path)
    path = tmp_path / f"m.{suffix}"
    with pytest.raises(InputError) as caught:
        loader.load_model(path)
    assert (
        str(caught.value) == f"{path}: {member} in the archive is encrypted (a password is needed to read it)"
    )


def _box_rows(path: Path, count: int) -> None:
    corpus = hostile_corpus()
    box, faces = corpus.box_arrays()
    nodes = [{"mesh": 0, "translation": [2.0 * (i % 50), 3.0 * (i // 50), 0.0]} for i in range(count)]
    path.write_bytes(corpus.glb(nodes, list(range(count)), box, faces=faces))


def test_instances_beyond_the_memory_budget_are_refused_before_any_is_made(tmp_path, monkeypatch):
    path = tmp_path / "rows.glb"
    _box_rows(path, 2000)
    # kept as instances: the box's 12 triangles and 2000 instances, one short of the budget
    estimate = 12 * settings.TRIANGLE_BYTES + 2000 * settings.INSTANCE_BYTES
    monkeypatch.setattr(settings, "MEMORY_BUDGET", estimate - 1)

    def made(*args):
        raise AssertionError("the instances were read")

    monkeypatch.setattr(gltf, "read_glb", made)
    with pytest.raises(InputError) as caught:
        loader.load_model(path)
    assert str(caught.value) == (
        f"{path}: 24000 triangles to draw (2000 mesh instances of 12 unique triangles) need about "
        f"{settings.human_size(estimate)} of memory at 896 bytes a unique triangle and "
        f"{settings.INSTANCE_BYTES} an instance, more than the memory budget of "
        f"{settings.human_size(estimate - 1)} (BLUEPRINT_MEMORY_LIMIT sets the budget)"
    )
    monkeypatch.undo()
    monkeypatch.setattr(settings, "MEMORY_BUDGET", estimate)
    model = loader.load_model(path)
    assert model.instances is not None
    assert model.triangle_count == 24_000 and len(model.part_names) == 2000
    assert model.bounds.tolist() == [[0, 0, 0], [2.0 * 49 + 1, 3.0 * 39 + 2, 3]]


def test_joined_instances_are_each_mesh_placed_by_its_transform(monkeypatch):
    """``_joined`` places the instances of a mesh a block at a time; the same arrays, to the
    bit, as placing them one by one in order."""
    from blueprint.scene.formats import Instance, placed_of

    rng = np.random.default_rng(7)
    meshes = [(rng.normal(size=(n, 3)), rng.integers(0, n, size=(m, 3))) for n, m in ((4, 2), (9, 7), (3, 1))]
    instances = []
    for k in range(40):
        vertices, faces = meshes[int(rng.integers(0, 3))]
        transform = (
            None if k % 5 == 0 else np.r_[np.c_[rng.normal(size=(3, 3)), rng.normal(size=3)], [[0, 0, 0, 1]]]
        )
        instances.append(Instance(f"n{k}", f"mesh{id(vertices) % 7}", vertices, faces, transform))
    instances.insert(3, Instance("empty", "none", None, None, None))
    instances.insert(9, Instance("flat", "flat", np.zeros((3, 3)), np.zeros((0, 3), int), None))
    one_by_one, offset = [], 0
    drawn = [i for i in instances if i.faces is not None and len(i.faces)]
    for i in drawn:
        placed = (
            i.vertices if i.transform is None else i.vertices @ i.transform[:3, :3].T + i.transform[:3, 3]
        )
        one_by_one.append((placed, i.faces + offset))
        offset += len(i.vertices)
    monkeypatch.setattr(loader, "_PLACED_ROWS", 20)  # blocks of two instances of the largest mesh
    positions, faces, parts, names = loader._joined(placed_of(instances, "scene"), None, "scene")
    assert np.array_equal(positions, np.concatenate([p for p, _ in one_by_one]))
    assert np.array_equal(faces, np.concatenate([f for _, f in one_by_one]))
    assert parts.tolist() == [k for k, i in enumerate(drawn) for _ in range(len(i.faces))]
    assert len(names) == len(drawn)


def test_smoothing_a_block_of_corners_at_a_time_changes_no_normal(monkeypatch):
    from blueprint.scene import normals

    sphere = trimesh.creation.icosphere(subdivisions=3)
    fan = np.r_[
        [[0, 0, 2.0]], np.c_[np.cos(np.linspace(0, 6, 90)), np.sin(np.linspace(0, 6, 90)), np.full(90, 2.0)]
    ]
    positions = np.r_[sphere.vertices, fan]
    faces = np.r_[
        sphere.faces, np.c_[np.zeros(89, int), np.arange(1, 90), np.arange(2, 91)] + len(sphere.vertices)
    ]
    whole = normals.corner_normals(positions, faces)
    monkeypatch.setattr(normals, "_PAIR_BLOCK", 5)
    assert np.array_equal(normals.corner_normals(positions, faces), whole)
