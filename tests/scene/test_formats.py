"""The registry of model formats (``blueprint.scene.formats``) and the NumPy readers of PLY, OFF
and ASCII STL against trimesh, which they stand in for: the same vertices and faces, in the
same order, where they read a file, None (trimesh then reads it) for anything else; small files
against arrays written by hand."""

from __future__ import annotations

import io
import os
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
import trimesh
from helpers import loaded_in_a_process

import blueprint
from blueprint import parallel, settings
from blueprint.api.batch import MODEL_SUFFIXES
from blueprint.errors import InputError
from blueprint.scene import loader
from blueprint.scene.formats import FORMATS, Format, Formats, Instance, placed_of
from blueprint.scene.formats.off import off_arrays
from blueprint.scene.formats.ply import ply_arrays
from blueprint.scene.formats.stl import read_stl

RNG = np.random.default_rng(11)
VERTICES = RNG.normal(size=(12, 3))


def trimesh_arrays(data: bytes, ext: str) -> tuple[np.ndarray, np.ndarray]:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        scene = trimesh.load_scene(io.BytesIO(data), file_type=ext, process=False)
    (mesh,) = scene.geometry.values()
    return np.asarray(mesh.vertices), np.asarray(mesh.faces)


def assert_as_trimesh(found, data: bytes, ext: str, types=(np.float64, np.int64)) -> None:
    """``found`` (positions, faces) holds trimesh's values, in ``types``."""
    assert found is not None, "left to trimesh"
    positions, faces = trimesh_arrays(data, ext)
    np.testing.assert_array_equal(found[0], positions)
    np.testing.assert_array_equal(found[1], faces)
    assert (found[0].dtype, found[1].dtype) == tuple(np.dtype(t) for t in types)


# -- the registry ----------------------------------------------------------------------------------
def test_each_suffix_finds_its_format_in_any_case():
    assert FORMATS.find("STL").name == "STL" and FORMATS.find(".Glb").name == "glTF"
    assert FORMATS.find("stp") is FORMATS.find("step")
    assert FORMATS.find("xyz1") is None
    # the up axis and unit each format's record states
    assert [FORMATS.find(s).up for s in ("stl", "obj", "ply", "off", "glb", "3mf", "3dxml", "step")] == [
        "z",
        "guess",
        "guess",
        "guess",
        "y",
        "z",
        "z",
        "z",
    ]
    assert FORMATS.unit("a.glb", "glb") == ("m", "glTF is in metres by its specification")
    assert FORMATS.unit("a.ply", "ply") == (None, "PLY files carry no unit")


def test_an_unknown_suffix_is_one_line_naming_the_formats(tmp_path):
    with pytest.raises(InputError) as caught:
        FORMATS.choose(tmp_path / "model.xyz1")
    assert str(caught.value) == (
        f"{tmp_path / 'model.xyz1'}: unknown model format '.xyz1' (supported: obj, stl, ply, off, glb, "
        "gltf, 3mf, 3dxml, step, stp and more; zip, gz, bz2, xz of them)"
    )


def test_folders_are_searched_for_the_common_formats():
    assert MODEL_SUFFIXES == tuple(f".{s}" for s in FORMATS.common_suffixes())
    assert {".obj", ".stl", ".ply", ".off", ".glb", ".step"} <= set(MODEL_SUFFIXES)
    assert set(loader.supported_formats()) >= {s.lstrip(".") for s in MODEL_SUFFIXES} | {"zip", "gz", "xz"}


def test_every_function_a_record_names_is_in_its_module():
    """The records name their formats' functions without importing them (``deferred``): each
    name must be a function of its module, or a file of the format fails only when read."""
    import importlib

    named = [
        (fmt.name, getattr(fmt, role))
        for fmt in FORMATS
        for role in ("check", "read", "read_data", "stated_unit")
        if getattr(fmt, role) is not None
    ]
    assert len(named) == 15
    for name, function in named:
        assert callable(getattr(importlib.import_module(function.module), function.name)), (name, function)


def test_the_readers_are_imported_by_the_files_that_need_them(tmp_path):
    """``import blueprint`` and the API import no format's module; a binary STL imports the STL
    reader's (and its text helpers) and no other."""
    path = tmp_path / "a.stl"
    triangle = np.array([0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0], "<f4").tobytes() + b"\0\0"
    path.write_bytes(b"\0" * 80 + (1).to_bytes(4, "little") + triangle)
    code = (
        "import sys, blueprint\nfrom blueprint.api import draw, renderer\n"
        "from blueprint.export import writers\n"
        "def readers(): return sorted(m for m in sys.modules if m.startswith('blueprint.scene.formats.'))\n"
        f"print(readers()); blueprint.load_model({str(path)!r}); print(readers())"
    )
    env = {**os.environ, "PYTHONPATH": str(Path(blueprint.__file__).parents[1])}
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=120)
    assert done.returncode == 0, done.stderr
    at_import, after_stl = done.stdout.splitlines()
    assert at_import == "['blueprint.scene.formats.base']"
    assert after_stl == str(
        ["blueprint.scene.formats.base", "blueprint.scene.formats.stl", "blueprint.scene.formats.text"]
    )


def test_a_suffix_is_registered_once():
    formats = Formats()
    formats.add(Format("A", ("a", "aa")))
    with pytest.raises(ValueError, match="'aa' is registered already"):
        formats.add(Format("B", ("aa",)))
    with pytest.raises(ValueError, match="lower case without the dot"):
        Format("C", (".c",))


def test_a_missing_optional_package_fails_when_used_in_one_line(tmp_path):
    fmt = Format("Q", ("q",), needs=(("blueprint_no_such_module", "no-such-package"),))
    with pytest.raises(InputError) as caught:
        fmt.check_header(tmp_path / "a.q", 10)
    assert (
        str(caught.value)
        == f"{tmp_path / 'a.q'}: reading this file needs the Python package 'no-such-package'"
    )


def test_a_format_without_its_package_is_refused_by_the_loader(tmp_path, monkeypatch):
    """pycollada taken away where it is installed: the loader asks ``find_spec`` for it."""
    import importlib.util

    found = importlib.util.find_spec
    monkeypatch.setattr(
        importlib.util, "find_spec", lambda name, *a: None if name == "collada" else found(name, *a)
    )
    path = tmp_path / "scene.dae"
    path.write_bytes(b"<COLLADA/>")
    with pytest.raises(InputError) as caught:
        loader.load_model(path)
    assert str(caught.value) == f"{path}: reading this file needs the Python package 'pycollada'"


# -- PLY -------------------------------------------------------------------------------------------
def ply(faces, fmt: str = "ascii", vtype: str = "float", color: bool = False) -> bytes:
    """A PLY file of ``VERTICES`` and ``faces`` (lists of corners) written line by line."""
    head = (
        f"ply\nformat {fmt} 1.0\ncomment made by a test\nelement vertex {len(VERTICES)}\n"
        + "".join(f"property {vtype} {axis}\n" for axis in "xyz")
        + f"element face {len(faces)}\nproperty list uchar int vertex_indices\n"
        + ("property uchar red\n" if color else "")
        + "end_header\n"
    )
    if fmt == "ascii":
        body = "".join(" ".join(repr(float(c)) for c in v) + "\n" for v in VERTICES)
        body += "".join(" ".join(map(str, [len(f), *f])) + (" 9" if color else "") + "\n" for f in faces)
        return head.encode() + body.encode()
    endian = "<" if "little" in fmt else ">"
    body = np.asarray(VERTICES, endian + {"float": "f4", "double": "f8"}[vtype]).tobytes()
    for f in faces:
        body += bytes([len(f)]) + np.asarray(f, endian + "i4").tobytes() + (b"\x09" if color else b"")
    return head.encode() + body


TRIANGLES = RNG.integers(0, 12, (10, 3)).tolist()
QUADS = RNG.integers(0, 12, (6, 4)).tolist()
PENTAGONS = RNG.integers(0, 12, (4, 5)).tolist()
MIXED = [RNG.integers(0, 12, k).tolist() for k in (3, 4, 5, 3, 6, 4, 3, 2)]


@pytest.mark.parametrize("fmt", ["ascii", "binary_little_endian", "binary_big_endian"])
@pytest.mark.parametrize("faces", ["triangles", "quads", "pentagons"])
@pytest.mark.parametrize("kind", ["float", "double", "float and colour"])
def test_ply_reads_as_trimesh_does(fmt, faces, kind):
    data = ply(
        {"triangles": TRIANGLES, "quads": QUADS, "pentagons": PENTAGONS}[faces],
        fmt,
        kind.split()[0],
        color="colour" in kind,
    )
    # float coordinates kept float32; a binary file's triangles keep their int32 indices
    kept = (
        np.float64 if kind == "double" else np.float32,
        np.int32 if fmt != "ascii" and faces == "triangles" else np.int64,
    )
    assert_as_trimesh(ply_arrays(data), data, "ply", kept)


def test_ascii_ply_faces_of_several_sizes_read_as_trimesh_does():
    data = ply(MIXED)
    assert_as_trimesh(ply_arrays(data), data, "ply", (np.float32, np.int64))


def test_a_ply_written_by_hand_reads_as_written():
    """A quad and a triangle: trimesh's order puts the triangle first, then each half of the
    quad; the float vertices are rounded to float32 as the header declares them."""
    data = (
        b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
        b"element face 2\nproperty list uchar int vertex_indices\nend_header\n"
        b"0 0 0\n1 0 0\n1 1 0\n0 1 0.1\n4 0 1 2 3\n3 2 1 0\n"
    )
    positions, faces = ply_arrays(data)
    np.testing.assert_array_equal(positions, [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, np.float32(0.1)]])
    np.testing.assert_array_equal(faces, [[2, 1, 0], [0, 1, 2], [2, 3, 0]])


LEFT_PLY = {
    "texture coordinates": ply(TRIANGLES).replace(
        b"property float z\n", b"property float z\nproperty float u\n"
    ),
    "edges": ply(TRIANGLES).replace(b"end_header", b"element edge 0\nproperty int vertex1\nend_header"),
    "short binary": ply(TRIANGLES, "binary_little_endian")[:-3],
    "texture file": ply(TRIANGLES).replace(b"comment made by a test", b"comment TextureFile a.png"),
    "not a ply": b"plyx\nformat ascii 1.0\nend_header\n",
}


@pytest.mark.parametrize("name", LEFT_PLY)
def test_anything_else_ply_is_left_to_trimesh(name):
    assert ply_arrays(LEFT_PLY[name]) is None


# -- OFF -------------------------------------------------------------------------------------------
def off(faces, head: str = "OFF\n", after_counts: str = "", colours: str = "") -> bytes:
    text = head + f"{len(VERTICES)} {len(faces)} 0\n" + after_counts
    text += "".join(" ".join(repr(float(c)) for c in v) + colours + "\n" for v in VERTICES)
    text += "".join(" ".join(map(str, [len(f), *f])) + "\n" for f in faces)
    return text.encode()


OFFS = {
    "triangles": off(TRIANGLES),
    "quads": off(QUADS),
    "pentagons": off(PENTAGONS),
    "triangles and quads": off([*TRIANGLES[:3], *QUADS[:3], TRIANGLES[5]]),
    "counts on the keyword's line": off(TRIANGLES, head="OFF "),
    "coloured vertices": off(TRIANGLES, head="COFF\n", colours=" 255 0 0 255"),
    "comments at the top and at a line's start": off(TRIANGLES, head="# made\nOFF\n# vertices\n"),
    "crlf": off(TRIANGLES).replace(b"\n", b"\r\n"),
}


@pytest.mark.parametrize("name", OFFS)
def test_off_reads_as_trimesh_does(name):
    assert_as_trimesh(off_arrays(OFFS[name]), OFFS[name], "off")


def test_an_off_of_polygons_of_several_sizes_reads_as_written():
    """trimesh fails on these (its fans of string corners); made as its triangulation makes
    polygons: triangles, then each half of every quad, then fans, faces of two corners left
    out."""
    data = b"OFF\n6 4 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 2 0\n3 3 0\n5 0 1 2 3 4\n4 0 1 2 3\n3 5 4 3\n2 0 1\n"
    positions, faces = off_arrays(data)
    np.testing.assert_array_equal(
        positions, [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 2, 0], [3, 3, 0]]
    )
    np.testing.assert_array_equal(faces, [[5, 4, 3], [0, 1, 2], [2, 3, 0], [0, 1, 2], [0, 2, 3], [0, 3, 4]])


LEFT_OFF = {
    # trimesh's comment stripping repeats the lines before such a comment
    "a comment after the counts": off(TRIANGLES, after_counts="# vertices\n"),
    "a comment at a line's end": off(TRIANGLES).replace(b"\n3 ", b" # face\n3 ", 1),
    "another keyword": off(TRIANGLES, head="NOFF\n"),
    "too few lines": off(TRIANGLES)[: -len(b"3 1 2 3\n") * 3],
    "a corner out of range": off([[0, 1, 12]]),
    "more corners than listed": off([[0, 1, 2]]).replace(b"\n3 0 1 2", b"\n4 0 1 2"),
}


@pytest.mark.parametrize("name", LEFT_OFF)
def test_anything_else_off_is_left_to_trimesh(name):
    assert off_arrays(LEFT_OFF[name]) is None


# -- ASCII STL -------------------------------------------------------------------------------------
ICOSPHERE = trimesh.creation.icosphere(2)
ASCII_STL = trimesh.exchange.stl.export_stl_ascii(ICOSPHERE).encode()
STLS = {
    "trimesh's export": ASCII_STL,
    "upper case": ASCII_STL.upper(),
    "crlf": ASCII_STL.replace(b"\n", b"\r\n"),
    "exponents and signs": b"solid t\n facet normal 0 0 1\n  outer loop\n   vertex 1e-3 2.5E+01 -0\n"
    b"   vertex +1 0 0\n   vertex 0 1 0\n  endloop\n endfacet\nendsolid t\n",
}


@pytest.mark.parametrize("name", STLS)
def test_ascii_stl_reads_as_trimesh_does(name, tmp_path):
    path = tmp_path / "a.stl"
    path.write_bytes(STLS[name])
    found = read_stl(path, path.stat().st_size)
    assert_as_trimesh(None if found is None else (found.positions, found.faces), STLS[name], "stl")


def test_an_ascii_stl_written_by_hand_reads_as_written(tmp_path):
    path = tmp_path / "a.stl"
    path.write_bytes(STLS["exponents and signs"])
    found = read_stl(path, path.stat().st_size)
    np.testing.assert_array_equal(found.positions, [[1e-3, 25, 0], [1, 0, 0], [0, 1, 0]])
    np.testing.assert_array_equal(found.faces, [[0, 1, 2]])


@pytest.mark.parametrize(
    "data",
    [
        ASCII_STL + ASCII_STL,  # two solids
        ASCII_STL.replace(b"vertex", b"vertex 1 vertex", 1),  # two on a line
        ASCII_STL.replace(b"vertex ", b"vertex 1.2.3 ", 1),  # not a number
    ],
    ids=["two solids", "two vertex keywords on a line", "not a number"],
)
def test_anything_else_ascii_stl_is_left_to_trimesh(data, tmp_path):
    path = tmp_path / "a.stl"
    path.write_bytes(data)
    assert read_stl(path, path.stat().st_size) is None


def _binary_stl(path: Path, corners: np.ndarray) -> None:
    """A binary STL of ``corners`` (3F, 3) float32, three a triangle, normals left zero."""
    records = np.zeros(len(corners) // 3, [("normal", "<f4", 3), ("triangle", "<f4", (3, 3)), ("a", "<u2")])
    records["triangle"] = corners.reshape(-1, 3, 3)
    path.write_bytes(b"\0" * 80 + len(records).to_bytes(4, "little") + records.tobytes())


@pytest.mark.parametrize("threads", [1, 3])
def test_a_binary_stl_holds_each_distinct_corner_once(tmp_path, monkeypatch, threads):
    """A binary STL's corners, repeated by every face around them, are the model's vertices
    once each, bit for bit, numbered by first corner (``np.unique`` of their bits in the order
    of first occurrence), on any number of threads; corners a bit apart stay apart, and a -0.0
    anywhere keeps every corner a vertex of its own."""
    monkeypatch.setattr(settings, "THREADS", threads)
    monkeypatch.setattr(parallel, "MIN_BLOCK", 100)
    corners = ICOSPHERE.vertices[ICOSPHERE.faces].reshape(-1, 3).astype(np.float32)
    corners[5] = np.nextafter(corners[5], np.float32(2))
    path = tmp_path / "a.stl"
    _binary_stl(path, corners)
    found = read_stl(path, path.stat().st_size)
    bits = corners.view(np.uint32)
    _, first = np.unique(bits.view(np.dtype((np.void, 12))).ravel(), return_index=True)
    assert found.soup and found.faces.dtype == np.int32 and found.faces.shape == (len(ICOSPHERE.faces), 3)
    np.testing.assert_array_equal(found.positions.view(np.uint32), bits[np.sort(first)])
    np.testing.assert_array_equal(found.positions[found.faces].reshape(-1, 3).view(np.uint32), bits)
    assert len(found.positions) == len(ICOSPHERE.vertices) + 1
    model = loader.load_model(path)
    assert model.soup and len(model.positions) == len(found.positions)

    zero = np.flatnonzero(corners == 0)[0]
    corners.reshape(-1)[zero] = -0.0
    _binary_stl(path, corners)
    found = read_stl(path, path.stat().st_size)
    assert not found.soup
    np.testing.assert_array_equal(found.positions.view(np.uint32), corners.view(np.uint32))
    np.testing.assert_array_equal(found.faces.reshape(-1), np.arange(len(corners)))


# -- the shared models and whole loads -------------------------------------------------------------
@pytest.mark.parametrize(
    "name",
    [
        "Euclid/dragon.ply",
        "libigl-tutorial-data/bunny.off",
        "libigl-tutorial-data/fertility.off",
        "libigl-tutorial-data/screwdriver.off",
        "trimesh/1002_tray_bottom.STL",
    ],
)
def test_shared_models_load_as_through_trimesh(name, shared_models):
    path = shared_models / name
    fast = loader.load_model(path)
    ext = path.suffix.lower().lstrip(".")
    slow = loader._scene_model(loader._load_scene(path, ext), path.stem, str(path), None, ext, None, None)
    for field in ("positions", "faces", "face_part"):
        np.testing.assert_array_equal(getattr(fast, field), getattr(slow, field))
    assert (fast.part_names, fast.up, fast.up_reason, fast.unit) == (
        slow.part_names,
        slow.up,
        slow.up_reason,
        slow.unit,
    )


@pytest.mark.parametrize("suffix", ["ply", "off", "stl"])
def test_text_formats_load_without_trimesh(suffix, tmp_path):
    data = {"ply": ply(QUADS), "off": off(QUADS), "stl": ASCII_STL}[suffix]
    path = tmp_path / f"model.{suffix}"
    path.write_bytes(data)
    faces = {"ply": 12, "off": 12, "stl": len(ICOSPHERE.faces)}[suffix]
    assert loaded_in_a_process(path, "len(m.faces)") == [str(faces), "False"]


@pytest.mark.parametrize("threads", [1, 4])
def test_meshes_placed_once_each_are_placed_as_one_by_one(threads, monkeypatch):
    """Distinct meshes of one instance each are placed a block of one vertex count at a time,
    and a mesh drawn several times a block of its instances at a time, the blocks side by
    side on the thread pool: the same arrays, to the bit, as placing each alone."""
    from blueprint import settings

    monkeypatch.setattr(settings, "THREADS", threads)
    shared_vertices, shared_faces = RNG.normal(size=(4, 3)), RNG.integers(0, 4, (3, 3))
    meshes = []
    for k in range(60):
        n = int(RNG.integers(3, 6))
        transform = (
            None if k % 7 == 0 else np.r_[np.c_[RNG.normal(size=(3, 3)), RNG.normal(size=3)], [[0, 0, 0, 1]]]
        )
        if k % 5 == 0:  # a mesh drawn twelve times over, among the distinct ones
            meshes.append(Instance(f"n{k}", "shared", shared_vertices, shared_faces, transform))
            continue
        meshes.append(
            Instance(f"n{k}", f"m{k}", RNG.normal(size=(n, 3)), RNG.integers(0, n, (k % 4 + 1, 3)), transform)
        )
    expected, offset = [], 0
    for m in meshes:
        placed = (
            m.vertices if m.transform is None else m.vertices @ m.transform[:3, :3].T + m.transform[:3, 3]
        )
        expected.append((placed, m.faces + offset))
        offset += len(m.vertices)
    monkeypatch.setattr(loader, "_PLACED_ROWS", 16)  # blocks of three to five meshes
    positions, faces, parts, names = loader._joined(placed_of(meshes, "scene"), None, "scene")
    np.testing.assert_array_equal(positions, np.concatenate([p for p, _ in expected]))
    np.testing.assert_array_equal(faces, np.concatenate([f for _, f in expected]))
    assert parts.tolist() == [k for k, m in enumerate(meshes) for _ in range(len(m.faces))]
    assert len(names) == 60 and names[1] == "m1" and sum(name.startswith("shared") for name in names) == 12


def test_off_header_checks_still_refuse_in_one_line(tmp_path):
    path = tmp_path / "lying.off"
    path.write_bytes(b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n9 0 1 2\n")
    with pytest.raises(InputError) as caught:
        loader.load_model(path)
    assert str(caught.value) == f"{path}: face 0 declares 9 corners and lists 3"


def test_the_read_arrays_go_to_the_model_unchanged(tmp_path):
    """A binary PLY's float32 vertices are the model's, bit for bit, in the file's order."""
    path = tmp_path / "m.ply"
    path.write_bytes(ply(TRIANGLES, "binary_little_endian"))
    model = loader.load_model(path)
    np.testing.assert_array_equal(model.positions, VERTICES.astype(np.float32))
    np.testing.assert_array_equal(model.faces, TRIANGLES)
    assert (model.part_names, model.unit) == (("m",), None)
