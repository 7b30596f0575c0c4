"""Hostile input: a seeded corpus of bad and hostile inputs run through the command line, each in
a subprocess of its own with a time limit and an address-space limit; prints ``N/M clean``, the
counts by kind, peak memory, and one JSON object.

    python benchmarks/hostile.py [--seed 17] [--mutations 160] [--jobs 2] [--timeout 60]
                                 [--memory 4G] [--kinds fifo,bomb,...] [--keep DIR]

A run is clean when it exits 2 with exactly one line on stderr, ``blueprint: error: ...``
naming the file at fault (or the option), no traceback, nothing left in its folder but the
files the case made; or, for inputs that may turn out valid (mutated files, many instances),
when it exits 0 without a traceback. Anything else is listed with its first stderr line.

Kinds: special (FIFOs, devices, directories, sockets, for the model and everything it
references), sparse (files far larger than memory), bomb (zip, 3MF, 3DXML, .gz, .bz2, .xz;
encrypted members), header (counts a header declares against the file's size), graph (glTF
cycles, depth, dangling children, instances, instances drawing more triangles than the
memory budget holds), work (coincident triangles, frames, glyph counts), settings (glyph,
style and pipeline files: digits, nesting, types, encodings), pipeline (expressions, image
inputs, dumps), names (not UTF-8, newlines, too long, unwritable places), numbers (NaN,
infinite and huge coordinates, OBJ vertices of two numbers), arguments (sizes, layers,
views), mutated (valid files of every format with bytes flipped, cut, repeated or inserted),
and shape (glTF and GLB documents whose JSON has the wrong types: a list for the document,
an object for the nodes, a string for an index).
"""

from __future__ import annotations

import argparse
import bz2
import collections
import copy
import gzip
import json
import lzma
import os
import random
import resource
import shutil
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import threading
import time
import zipfile
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


@dataclass
class Case:
    """One run: ``args`` of the blueprint command in a folder ``make(folder)`` fills;
    ``names`` must appear in the error line (printed as the message prints them); ``valid``
    where exit 0 is clean too."""

    kind: str
    label: str
    args: list
    make: object = None
    names: tuple = ()
    valid: bool = False
    env: dict = field(default_factory=dict)


@dataclass
class Outcome:
    case: Case
    clean: bool
    code: int
    reason: str
    seconds: float
    peak_mib: float


# -- small valid files -------------------------------------------------------------------------------
def box_arrays(lo=(0.0, 0.0, 0.0), hi=(1.0, 2.0, 3.0)) -> tuple[np.ndarray, np.ndarray]:
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    v = np.array(
        [[x, y, z] for x in (x0, x1) for y in (y0, y1) for z in (z0, z1)], np.float64
    )  # index = 4x + 2y + z
    f = np.array(
        [
            [0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
            [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3],
        ]
    )  # fmt: skip
    return v, f


def stl_binary(v, f, count=None) -> bytes:
    tri = v[f].astype("<f4")
    record = np.dtype([("normal", "<f4", 3), ("triangle", "<f4", (3, 3)), ("attribute", "<u2")])
    data = np.zeros(len(tri), record)
    data["triangle"] = tri
    n = len(tri) if count is None else count
    return b"\0" * 80 + struct.pack("<I", n) + data.tobytes()


def stl_ascii(v, f) -> bytes:
    out = ["solid box"]
    for a, b, c in v[f]:
        out += ["facet normal 0 0 0", "outer loop", *(f"vertex {p[0]} {p[1]} {p[2]}" for p in (a, b, c))]
        out += ["endloop", "endfacet"]
    return ("\n".join(out + ["endsolid box"]) + "\n").encode()


def obj_text(v, f) -> bytes:
    return (
        "".join(f"v {a} {b} {c}\n" for a, b, c in v)
        + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in f)
    ).encode()


def off_text(v, f, faces=None) -> bytes:
    head = f"OFF\n{len(v)} {len(f) if faces is None else faces} 0\n"
    return (
        head + "".join(f"{a} {b} {c}\n" for a, b, c in v) + "".join(f"3 {a} {b} {c}\n" for a, b, c in f)
    ).encode()


def ply_ascii(v, f, faces=None) -> bytes:
    head = (
        f"ply\nformat ascii 1.0\nelement vertex {len(v)}\n"
        "property float x\nproperty float y\nproperty float z\n"
        f"element face {len(f) if faces is None else faces}\n"
        "property list uchar int vertex_indices\nend_header\n"
    )
    return (
        head + "".join(f"{a} {b} {c}\n" for a, b, c in v) + "".join(f"3 {a} {b} {c}\n" for a, b, c in f)
    ).encode()


def ply_binary(v, f, faces=None) -> bytes:
    head = (
        f"ply\nformat binary_little_endian 1.0\nelement vertex {len(v)}\nproperty float x\nproperty float y\n"
        f"property float z\nelement face {len(f) if faces is None else faces}\n"
        "property list uchar int vertex_indices\nend_header\n"
    ).encode()
    body = v.astype("<f4").tobytes() + b"".join(b"\x03" + np.asarray(t, "<i4").tobytes() for t in f)
    return head + body


def gltf_doc(nodes, roots, positions=None, uri=None, faces=None):
    """A glTF document of one triangle mesh placed by ``nodes``, and its binary buffer: a
    triangle, or ``positions`` and ``faces`` (default: the positions in threes)."""
    pos = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32) if positions is None else positions
    pos = np.asarray(pos, np.float32)
    index = np.arange(3, dtype="<u4") if faces is None else np.asarray(faces, "<u4").reshape(-1)
    binary = pos.tobytes() + index.tobytes()
    with np.errstate(all="ignore"):
        lo, hi = np.nan_to_num(pos.min(0)).tolist(), np.nan_to_num(pos.max(0)).tolist()
    buffer = {"byteLength": len(binary), **({"uri": uri} if uri else {})}
    doc = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": roots}],
        "nodes": nodes,
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "buffers": [buffer],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": pos.nbytes},
            {"buffer": 0, "byteOffset": pos.nbytes, "byteLength": index.nbytes},
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": len(pos), "type": "VEC3", "min": lo, "max": hi},
            {"bufferView": 1, "componentType": 5125, "count": len(index), "type": "SCALAR"},
        ],
    }
    return doc, binary


def glb(nodes, roots, positions=None, json_length=None, faces=None) -> bytes:
    return glb_of(*gltf_doc(nodes, roots, positions, faces=faces), json_length)


def glb_of(doc, binary: bytes, json_length=None) -> bytes:
    """A GLB file of the document ``doc`` (any JSON value) and its binary buffer."""
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    binary += b"\0" * (-len(binary) % 4)
    length = len(text) if json_length is None else json_length
    body = (
        struct.pack("<II", length, 0x4E4F534A) + text + struct.pack("<II", len(binary), 0x004E4942) + binary
    )
    return struct.pack("<III", 0x46546C67, 2, 12 + len(body)) + body


def threemf(components: int = 0) -> bytes:
    """A 3MF of a box, or of a chain of ``components`` objects each holding the next."""
    v, f = box_arrays()
    verts = "".join(f'<vertex x="{a}" y="{b}" z="{c}"/>' for a, b, c in v)
    tris = "".join(f'<triangle v1="{a}" v2="{b}" v3="{c}"/>' for a, b, c in f)
    objects = [
        f'<object id="1" type="model"><mesh><vertices>{verts}</vertices>'
        f"<triangles>{tris}</triangles></mesh></object>"
    ]
    for k in range(2, components + 2):
        objects.append(
            f'<object id="{k}" type="model"><components><component objectid="{k - 1}"/></components></object>'
        )
    top = components + 1
    model = (
        '<?xml version="1.0" encoding="UTF-8"?><model unit="millimeter" '
        'xmlns="http://schemas.microsoft.com/3dmanufacturing/core/2015/02">'
        f'<resources>{"".join(objects)}</resources><build><item objectid="{top}"/></build></model>'
    )
    return _zip_bytes({"[Content_Types].xml": b"<Types/>", "3D/3dmodel.model": model.encode()})


def _zip_bytes(files: dict) -> bytes:
    import io

    out = io.BytesIO()
    with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as archive:
        for name, data in files.items():
            archive.writestr(name, data)
    return out.getvalue()


def encrypted(data: bytes) -> bytes:
    """A zip archive with every member flagged as encrypted (its bytes left as they are), as
    Python's zipfile cannot write one."""
    import io

    out = bytearray(data)
    with zipfile.ZipFile(io.BytesIO(data)) as archive:
        at = archive.start_dir
        for info in archive.infolist():
            out[info.header_offset + 6] |= 1  # the flags of the member's local header
            out[at + 8] |= 1  # and of its entry in the central directory
            name, extra, comment = struct.unpack_from("<HHH", out, at + 28)
            at += 46 + name + extra + comment
    return bytes(out)


def png_header(width: int, height: int) -> bytes:
    import zlib

    def chunk(kind: bytes, body: bytes) -> bytes:
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))

    ihdr = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return (
        b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(b"")) + chunk(b"IEND", b"")
    )


def small_png() -> bytes:
    import io

    from PIL import Image

    out = io.BytesIO()
    Image.new("RGB", (8, 8), (200, 40, 40)).save(out, format="PNG")
    return out.getvalue()


INVERT = (
    '[pipeline]\noutput = "out"\n[images.picture]\n[passes.out]\nop = "invert"\n'
    'inputs = { source = "picture" }\n'
)


def _zeros(size: int) -> bytes:
    return bytes(size)


# -- the corpus ----------------------------------------------------------------------------------
def _files(**contents):
    """A ``make`` that writes files (bytes, or callables of the folder)."""

    def make(folder: Path) -> None:
        for name, data in contents.items():
            target = folder / name.replace("__", "/")
            target.parent.mkdir(parents=True, exist_ok=True)
            if callable(data):
                data(target)
            else:
                target.write_bytes(data)

    return make


def _later(make, *args):
    """File contents made only when the case is run: the corpus holds large files."""
    return lambda path: path.write_bytes(make(*args))


def _boxes(count: int) -> bytes:
    return "".join(f"[[box]]\nmin = [{i}, 0, 0]\nmax = [{i + 1}, 1, 1]\n" for i in range(count)).encode()


def _fifo(path: Path) -> None:
    os.mkfifo(path)


def _sparse(size: int):
    def make(path: Path) -> None:
        with open(path, "wb") as fh:
            fh.truncate(size)

    return make


def _socket(path: Path) -> None:
    server = socket.socket(socket.AF_UNIX)
    server.bind(str(path))  # left bound: the file stays a socket after the process goes
    server.close()


RENDER = ["--size", "96", "96"]


def special_cases() -> list[Case]:
    v, f = box_arrays()
    tri = b"v 0 0 0\nv 1 0 0\nv 0 1 0\n"
    doc, _ = gltf_doc([{"mesh": 0}], [0], uri="buffer.bin")
    gltf = json.dumps(doc).encode()
    cases = []
    for suffix in ("stl", "obj", "glb", "ply"):
        cases.append(
            Case(
                "special",
                f"FIFO model .{suffix}",
                ["render", f"m.{suffix}", "-o", "out.png", *RENDER],
                _files(**{f"m.{suffix}": _fifo}),
                (f"m.{suffix}",),
            )
        )
        cases.append(
            Case(
                "special",
                f"directory model .{suffix}",
                ["info", f"m.{suffix}"],
                _files(**{f"m.{suffix}__x": b""}),
                (f"m.{suffix}",),
            )
        )
    cases += [
        Case("special", "/dev/zero model", ["info", "/dev/zero"], None, ("/dev/zero",)),
        Case("special", "/dev/null model", ["render", "/dev/null", "-o", "out.png"], None, ("/dev/null",)),
        Case("special", "socket model", ["info", "m.stl"], _files(**{"m.stl": _socket}), ("m.stl",)),
        Case(
            "special",
            "FIFO mtllib",
            ["info", "m.obj"],
            _files(**{"m.obj": b"mtllib x.mtl\n" + tri + b"f 1 2 3\n", "x.mtl": _fifo}),
            ("x.mtl",),
        ),
        Case(
            "special",
            "FIFO texture",
            ["info", "m.obj"],
            _files(
                **{
                    "m.obj": b"mtllib x.mtl\nusemtl a\nvt 0 0\nvt 1 0\nvt 0 1\n" + tri + b"f 1/1 2/2 3/3\n",
                    "x.mtl": b"newmtl a\nmap_Kd t.png\n",
                    "t.png": _fifo,
                }
            ),
            ("t.png",),
        ),
        Case(
            "special",
            "FIFO glTF buffer",
            ["info", "m.gltf"],
            _files(**{"m.gltf": gltf, "buffer.bin": _fifo}),
            ("buffer.bin",),
        ),
        Case(
            "special",
            "/dev/zero as glTF buffer",
            ["info", "m.gltf"],
            _files(**{"m.gltf": gltf.replace(b"buffer.bin", b"/dev/zero")}),
            ("m.gltf",),
        ),
        Case(
            "special",
            "FIFO glyphs",
            ["render", "box.stl", "-o", "out.png", *RENDER, "--glyphs", "g.toml"],
            _files(**{"box.stl": stl_binary(v, f), "g.toml": _fifo}),
            ("g.toml",),
        ),
        Case(
            "special",
            "FIFO style",
            ["render", "box.stl", "-o", "out.svg", "--style", "s.toml"],
            _files(**{"box.stl": stl_binary(v, f), "s.toml": _fifo}),
            ("s.toml",),
        ),
        Case(
            "special",
            "FIFO pipeline",
            ["pipeline", "run", "p.toml", "-o", "out.png"],
            _files(**{"p.toml": _fifo}),
            ("p.toml",),
        ),
        Case(
            "special",
            "FIFO pipeline image",
            ["pipeline", "run", "p.toml", "-o", "out.png", "--image", "picture=i.png"],
            _files(**{"p.toml": INVERT.encode(), "i.png": _fifo}),
            ("i.png",),
        ),
        Case(
            "special",
            "/dev/zero glyphs",
            ["render", "box.stl", "-o", "out.png", *RENDER, "--glyphs", "/dev/zero"],
            _files(**{"box.stl": stl_binary(v, f)}),
            ("/dev/zero",),
        ),
    ]
    return cases


def sparse_cases() -> list[Case]:
    v, f = box_arrays()
    big = 8 << 30
    doc, _ = gltf_doc([{"mesh": 0}], [0], uri="buffer.bin")
    return [
        Case(
            "sparse",
            "sparse 8 GiB STL",
            ["render", "m.stl", "-o", "out.png", *RENDER],
            _files(**{"m.stl": _sparse(big)}),
            ("m.stl",),
        ),
        Case("sparse", "sparse 8 GiB OBJ", ["info", "m.obj"], _files(**{"m.obj": _sparse(big)}), ("m.obj",)),
        Case(
            "sparse",
            "sparse 8 GiB mtllib",
            ["info", "m.obj"],
            _files(**{"m.obj": b"mtllib x.mtl\n" + obj_text(v, f), "x.mtl": _sparse(big)}),
            ("x.mtl",),
        ),
        Case(
            "sparse",
            "sparse 8 GiB glTF buffer",
            ["info", "m.gltf"],
            _files(**{"m.gltf": json.dumps(doc).encode(), "buffer.bin": _sparse(big)}),
            ("buffer.bin",),
        ),
        Case(
            "sparse",
            "sparse 8 GiB glyphs",
            ["render", "box.stl", "-o", "out.png", *RENDER, "--glyphs", "g.toml"],
            _files(**{"box.stl": stl_binary(v, f), "g.toml": _sparse(big)}),
            ("g.toml",),
        ),
        Case(
            "sparse",
            "sparse 8 GiB style",
            ["render", "box.stl", "-o", "out.svg", "--style", "s.json"],
            _files(**{"box.stl": stl_binary(v, f), "s.json": _sparse(big)}),
            ("s.json",),
        ),
        Case(
            "sparse",
            "sparse 8 GiB pipeline",
            ["pipeline", "run", "p.toml", "-o", "out.png"],
            _files(**{"p.toml": _sparse(big)}),
            ("p.toml",),
        ),
        Case(
            "sparse",
            "sparse 8 GiB image",
            ["pipeline", "run", "p.toml", "-o", "out.png", "--image", "picture=i.png"],
            _files(**{"p.toml": INVERT.encode(), "i.png": _sparse(big)}),
            ("i.png",),
        ),
    ]


_BOMB_CACHE: dict = {}


def _bomb(kind: str, size: int) -> bytes:
    key = (kind, size)
    if key not in _BOMB_CACHE:
        zeros = _zeros(size)
        if kind == "gz":
            _BOMB_CACHE[key] = gzip.compress(zeros, 9)
        elif kind == "bz2":
            _BOMB_CACHE[key] = bz2.compress(zeros, 9)
        elif kind == "xz":
            _BOMB_CACHE[key] = lzma.compress(zeros, preset=1)
        else:
            _BOMB_CACHE[key] = _zip_bytes({"[Content_Types].xml": b"<Types/>", "3D/3dmodel.model": zeros})
    return _BOMB_CACHE[key]


def bomb_cases(rng: random.Random) -> list[Case]:
    v, f = box_arrays()
    cases = []
    for suffix, inner in (
        ("3mf", "zip"),
        ("3dxml", "zip"),
        ("zip", "zip"),
        ("stl.gz", "gz"),
        ("obj.bz2", "bz2"),
        ("ply.xz", "xz"),
    ):
        for size in (64 << 20, 256 << 20):
            cases.append(
                Case(
                    "bomb",
                    f"{suffix} expanding to {size >> 20} MiB",
                    ["render", f"b.{suffix}", "-o", "out.png", *RENDER],
                    _files(**{f"b.{suffix}": _later(_bomb, inner, size)}),
                    (f"b.{suffix}",),
                )
            )
    good = {
        "stl.gz": gzip.compress(stl_binary(v, f)),
        "obj.bz2": bz2.compress(obj_text(v, f)),
        "off.xz": lzma.compress(off_text(v, f)),
        "zip": _zip_bytes({"a.stl": stl_binary(v, f), "b.obj": obj_text(v, f)}),
        "tar.gz": None,
    }
    import io
    import tarfile

    tar = io.BytesIO()
    with tarfile.open(fileobj=tar, mode="w") as archive:
        data = stl_binary(v, f)
        info = tarfile.TarInfo("inner/box.stl")
        info.size = len(data)
        archive.addfile(info, io.BytesIO(data))
    good["tar.gz"] = gzip.compress(tar.getvalue())
    for suffix, data in good.items():
        cases.append(
            Case(
                "bomb",
                f"valid .{suffix}",
                ["render", f"m.{suffix}", "-o", "out.png", *RENDER],
                _files(**{f"m.{suffix}": data}),
                valid=True,
            )
        )
        cut = data[: rng.randrange(1, len(data))]
        cases.append(
            Case(
                "bomb",
                f"truncated .{suffix}",
                ["info", f"m.{suffix}"],
                _files(**{f"m.{suffix}": cut}),
                (f"m.{suffix}",),
                valid=True,
            )
        )
    cases.append(
        Case(
            "bomb",
            "zip of no model",
            ["info", "m.zip"],
            _files(**{"m.zip": _zip_bytes({"a.txt": b"hello"})}),
            ("m.zip",),
        )
    )
    cases.append(
        Case(
            "bomb",
            "gz of garbage",
            ["info", "m.stl.gz"],
            _files(**{"m.stl.gz": b"\x1f\x8b" + bytes(rng.randrange(256) for _ in range(200))}),
            ("m.stl.gz",),
        )
    )
    for suffix, data in (
        ("3mf", threemf()),
        ("3dxml", threemf()),
        ("zip", _zip_bytes({"a.stl": stl_binary(v, f)})),
    ):
        cases.append(
            Case(
                "bomb",
                f"encrypted .{suffix}",
                ["info", f"m.{suffix}"],
                _files(**{f"m.{suffix}": encrypted(data)}),
                (f"m.{suffix}",),
            )
        )
    return cases


def header_cases() -> list[Case]:
    v, f = box_arrays()
    return [
        Case(
            "header",
            "ASCII PLY declaring 10^12 faces",
            ["render", "m.ply", "-o", "out.png", *RENDER],
            _files(**{"m.ply": ply_ascii(v, f, 10**12)}),
            ("m.ply",),
        ),
        Case(
            "header",
            "binary PLY declaring 10^9 faces",
            ["info", "m.ply"],
            _files(**{"m.ply": ply_binary(v, f, 10**9)}),
            ("m.ply",),
        ),
        Case(
            "header",
            "PLY with a negative count",
            ["info", "m.ply"],
            _files(**{"m.ply": ply_ascii(v, f, -5)}),
            ("m.ply",),
        ),
        Case(
            "header",
            "OFF claiming ten times its faces",
            ["info", "m.off"],
            _files(**{"m.off": off_text(v, f, 120)}),
            ("m.off",),
        ),
        Case(
            "header",
            "OFF face with 10^9 corners",
            ["render", "m.off", "-o", "out.png", *RENDER],
            _files(**{"m.off": b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n1000000000 0 1 2\n"}),
            ("m.off",),
        ),
        Case(
            "header",
            "OFF face with a word for a count",
            ["info", "m.off"],
            _files(**{"m.off": b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\nthree 0 1 2\n"}),
            ("m.off",),
        ),
        Case(
            "header",
            "binary STL whose count lies",
            ["render", "m.stl", "-o", "out.png", *RENDER],
            _files(**{"m.stl": stl_binary(v, f, 10**9)}),
            ("m.stl",),
        ),
        Case(
            "header",
            "binary STL of 2^32-1 triangles",
            ["info", "m.stl"],
            _files(**{"m.stl": stl_binary(v, f, 2**32 - 1)}),
            ("m.stl",),
        ),
        Case(
            "header",
            "GLB JSON chunk longer than the file",
            ["info", "m.glb"],
            _files(**{"m.glb": glb([{"mesh": 0}], [0], json_length=10**9)}),
            ("m.glb",),
        ),
    ]


def graph_cases() -> list[Case]:
    box, box_faces = box_arrays()
    chain = lambda n: [{"mesh": 0, "children": [i + 1]} for i in range(n - 1)] + [{"mesh": 0}]  # noqa: E731
    rows = lambda n: [{"mesh": 0, "translation": [2.0 * (i % 300), 2.0 * (i // 300), 0.0]} for i in range(n)]  # noqa: E731
    return [
        Case(
            "graph",
            "GLB nodes 0 -> 1 -> 0",
            ["render", "m.glb", "-o", "out.png", *RENDER],
            _files(**{"m.glb": glb([{"mesh": 0, "children": [1]}, {"mesh": 0, "children": [0]}], [0])}),
            ("m.glb",),
        ),
        Case(
            "graph",
            "GLB node its own child",
            ["info", "m.glb"],
            _files(**{"m.glb": glb([{"mesh": 0, "children": [0]}], [0])}),
            ("m.glb",),
        ),
        Case(
            "graph",
            "GLB cycle below a root",
            ["info", "m.glb"],
            _files(
                **{"m.glb": glb([{"children": [1]}, {"children": [2]}, {"mesh": 0, "children": [1]}], [0])}
            ),
            ("m.glb",),
        ),
        Case(
            "graph",
            "GLB child that does not exist",
            ["info", "m.glb"],
            _files(**{"m.glb": glb([{"mesh": 0, "children": [7]}], [0])}),
            ("m.glb",),
        ),
        Case(
            "graph",
            "GLB child of the wrong type",
            ["info", "m.glb"],
            _files(**{"m.glb": glb([{"mesh": 0, "children": ["a"]}], [0])}),
            ("m.glb",),
        ),
        Case(
            "graph",
            "GLB 3000 nested nodes",
            ["render", "m.glb", "-o", "out.png", *RENDER],
            _files(**{"m.glb": _later(lambda: glb(chain(3000), [0]))}),
            ("m.glb",),
        ),
        Case(
            "graph",
            "GLB 10^5 nested nodes",
            ["info", "m.glb"],
            _files(**{"m.glb": _later(lambda: glb(chain(10**5), [0]))}),
            ("m.glb",),
        ),
        Case(
            "graph",
            "GLB 60 nested nodes",
            ["render", "m.glb", "-o", "out.png", *RENDER],
            _files(**{"m.glb": glb(chain(60), [0])}),
            valid=True,
        ),
        Case(
            "graph",
            "GLB 10^5 instances",
            ["render", "m.glb", "-o", "out.png", *RENDER],
            _files(**{"m.glb": _later(lambda: glb(rows(10**5), list(range(10**5))))}),
            valid=True,
        ),
        Case(
            "graph",
            "GLB 10^5 instances of a box",
            ["render", "m.glb", "-o", "out.png", *RENDER],
            _files(**{"m.glb": _later(lambda: glb(rows(10**5), list(range(10**5)), box, faces=box_faces))}),
            ("m.glb",),
            valid=True,
        ),
        Case(
            "graph",
            "GLB 87 000 instances of a box to SVG",
            ["render", "m.glb", "-o", "out.svg"],
            _files(**{"m.glb": _later(lambda: glb(rows(87_000), list(range(87_000)), box, faces=box_faces))}),
            ("m.glb",),
            valid=True,
        ),
        Case(
            "graph",
            "GLB 2^23 instances by sharing",
            ["info", "m.glb"],
            _files(**{"m.glb": glb([{"children": [i + 1, i + 1]} for i in range(23)] + [{"mesh": 0}], [0])}),
            ("m.glb",),
        ),
        Case(
            "graph",
            "3MF chain of 10^4 components",
            ["render", "m.3mf", "-o", "out.png", *RENDER],
            _files(**{"m.3mf": _later(threemf, 10**4)}),
            ("m.3mf",),
            valid=True,
        ),
        Case(
            "graph",
            "3MF chain of 50 components",
            ["render", "m.3mf", "-o", "out.png", *RENDER],
            _files(**{"m.3mf": threemf(50)}),
            valid=True,
        ),
    ]


def work_cases() -> list[Case]:
    v, f = box_arrays()
    tri = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float)
    stl = stl_binary(v, f)
    return [
        Case(
            "work",
            "10^6 identical triangles, binary STL",
            ["render", "m.stl", "-o", "out.png", *RENDER],
            _files(**{"m.stl": _later(lambda: stl_binary(tri, np.zeros((10**6, 3), int) + [0, 1, 2]))}),
            ("m.stl",),
        ),
        Case(
            "work",
            "10^6 OBJ faces on three vertices",
            ["render", "m.obj", "-o", "out.png", *RENDER],
            _files(**{"m.obj": _later(lambda: b"v 0 0 0\nv 1 0 0\nv 0 1 0\n" + b"f 1 2 3\n" * 10**6)}),
            ("m.obj",),
        ),
        Case(
            "work",
            "silhouettes --frames 10^9",
            ["silhouettes", "m.stl", "-o", "out.mp4", "--animate", "twist", "--frames", "1000000000"],
            _files(**{"m.stl": stl}),
            ("frames",),
        ),
        Case(
            "work",
            "silhouettes --frames 0",
            ["silhouettes", "m.stl", "-o", "out.mp4", "--animate", "wave", "--frames", "0"],
            _files(**{"m.stl": stl}),
            ("frames",),
        ),
        Case(
            "work",
            "turntable --frames 10^9",
            ["turntable", "m.stl", "-o", "out.mp4", "--frames", "1000000000"],
            _files(**{"m.stl": stl}),
            ("frames",),
        ),
        Case(
            "work",
            "turntable --frames -1",
            ["turntable", "m.stl", "-o", "out.mp4", "--frames", "-1"],
            _files(**{"m.stl": stl}),
            ("frames",),
        ),
        Case(
            "work",
            "10^5 glyph boxes",
            ["render", "m.stl", "-o", "out.png", *RENDER, "--glyphs", "g.toml"],
            _files(**{"m.stl": stl, "g.toml": _later(_boxes, 10**5)}),
            ("g.toml",),
        ),
        Case(
            "work",
            "glyph path of 10^6 points",
            ["render", "m.stl", "-o", "out.png", *RENDER, "--glyphs", "g.json"],
            _files(
                **{
                    "m.stl": stl,
                    "g.json": _later(
                        lambda: json.dumps({"path": [{"points": [[i, 0, 0] for i in range(10**6)]}]}).encode()
                    ),
                }
            ),
            ("g.json",),
        ),
        Case(
            "work",
            "--size 100000 100000",
            ["render", "m.stl", "-o", "out.png", "--size", "100000", "100000"],
            _files(**{"m.stl": stl}),
            ("size",),
        ),
        Case(
            "work",
            "--max-layers 10^9",
            ["render", "m.stl", "-o", "out.png", *RENDER, "--max-layers", "1000000000"],
            _files(**{"m.stl": stl}),
            ("layers",),
        ),
    ]


def settings_cases(rng: random.Random) -> list[Case]:
    v, f = box_arrays()
    stl = stl_binary(v, f)
    texts = {
        "digits.toml": "a = " + "7" * 5000,
        "digits.json": '{"box": [{"min": [' + "7" * 5000 + ', 0, 0], "max": [1, 1, 1]}]}',
        "deep.toml": "a = " + "[" * 10**4 + "]" * 10**4,
        "deep.json": "[" * 10**5 + "]" * 10**5,
        "e400.json": '{"box": [{"min": [1' + "0" * 400 + ', 0, 0], "max": [1, 1, 1]}]}',
        "float.json": '{"box": [{"min": [1e400, 0, 0], "max": [1, 1, 1]}]}',
        "nan.toml": "[[box]]\nmin = [nan, 0, 0]\nmax = [1, 1, 1]\n",
        "huge.toml": "[[box]]\nmin = [0, 0, 0]\nmax = [1e300, 1e308, 1]\n",
        "type.toml": "box = 3\n",
        "key.toml": "[[box]]\nmin = [0, 0, 0]\nmax = [1, 1, 1]\nsize = 3\n",
        "string.json": '"just a string"',
        "bad.toml": "[[box]\nmin = ",
        "bad.json": '{"box": [',
        "latin1.toml": "# caf\xe9\n",
        "wrong.yaml": "box: []\n",
    }
    cases = []
    for name, text in texts.items():
        data = text.encode("latin-1") if name.startswith("latin1") else text.encode()
        for flag, out in (("--glyphs", "out.png"), ("--style", "out.svg")):
            extra = RENDER if out.endswith(".png") else []
            cases.append(
                Case(
                    "settings",
                    f"{flag} {name}",
                    ["render", "m.stl", "-o", out, *extra, flag, name],
                    _files(**{"m.stl": stl, name: data}),
                    (name,),
                )
            )
    pipelines = {
        "digits.toml": "[variables]\nn = " + "7" * 5000 + "\n" + INVERT,
        "deep.toml": "[variables]\nn = " + "[" * 10**4 + "]" * 10**4 + "\n" + INVERT,
        "e400.toml": "[variables]\nn = 1" + "0" * 400 + "\n" + INVERT,
        "neg.toml": INVERT.replace('op = "invert"', 'op = "invert"\nparams = { amount = "= -s" }')
        + '[variables]\ns = "text"\n',
        "max1.toml": INVERT.replace('op = "invert"', 'op = "threshold"\nparams = { level = "= max(1)" }'),
        "mixed.toml": INVERT.replace('op = "invert"', 'op = "threshold"\nparams = { level = "= min(1, s)" }')
        + '[variables]\ns = "a"\n',
        "long.toml": INVERT.replace(
            'op = "invert"', 'op = "threshold"\nparams = { level = "= ' + "-" * 5000 + '1" }'
        ),
        "unknown.toml": INVERT.replace('op = "invert"', 'op = "no-such-op"'),
        "cycle.toml": (
            '[pipeline]\noutput = "a"\n[passes.a]\nop = "invert"\ninputs = { source = "b" }\n'
            '[passes.b]\nop = "invert"\ninputs = { source = "a" }\n'
        ),
        "binary.toml": bytes(rng.randrange(256) for _ in range(300)).decode("latin-1"),
    }
    for name, text in pipelines.items():
        cases.append(
            Case(
                "settings",
                f"pipeline {name}",
                ["pipeline", "run", name, "-o", "out.png", "--image", "picture=i.png"],
                _files(**{name: text.encode("latin-1"), "i.png": small_png()}),
                (name,),
            )
        )
    return cases


def pipeline_cases() -> list[Case]:
    return [
        Case(
            "pipeline",
            "image claiming 100000 x 100000",
            ["pipeline", "run", "p.toml", "-o", "out.png", "--image", "picture=i.png"],
            _files(**{"p.toml": INVERT.encode(), "i.png": png_header(100_000, 100_000)}),
            ("i.png",),
        ),
        Case(
            "pipeline",
            "image claiming 20000 x 20000",
            ["pipeline", "run", "p.toml", "-o", "out.png", "--image", "picture=i.png"],
            _files(**{"p.toml": INVERT.encode(), "i.png": png_header(20_000, 20_000)}),
            ("i.png",),
        ),
        Case(
            "pipeline",
            "image that is not one",
            ["pipeline", "run", "p.toml", "-o", "out.png", "--image", "picture=i.png"],
            _files(**{"p.toml": INVERT.encode(), "i.png": b"not a picture at all"}),
            ("i.png",),
        ),
        Case(
            "pipeline",
            "image cut short",
            ["pipeline", "run", "p.toml", "-o", "out.png", "--image", "picture=i.png"],
            _files(**{"p.toml": INVERT.encode(), "i.png": small_png()[:60]}),
            ("i.png",),
            valid=True,
        ),
        Case(
            "pipeline",
            "missing image",
            ["pipeline", "run", "p.toml", "-o", "out.png", "--image", "picture=none.png"],
            _files(**{"p.toml": INVERT.encode()}),
            ("none.png",),
        ),
        Case(
            "pipeline",
            "dump name a directory",
            ["pipeline", "run", "p.toml", "-o", "out.png", "--image", "picture=i.png", "--dump", "out"],
            _files(**{"p.toml": INVERT.encode(), "i.png": small_png(), "out.out.png__keep": b""}),
            ("out.out.png",),
        ),
        Case(
            "pipeline",
            "dump name unknown",
            ["pipeline", "run", "p.toml", "-o", "out.png", "--image", "picture=i.png", "--dump", "x/../y"],
            _files(**{"p.toml": INVERT.encode(), "i.png": small_png()}),
            ("p.toml",),
        ),
        Case(
            "pipeline",
            "valid pipeline",
            ["pipeline", "run", "p.toml", "-o", "out.png", "--image", "picture=i.png"],
            _files(**{"p.toml": INVERT.encode(), "i.png": small_png()}),
            valid=True,
        ),
    ]


def name_cases() -> list[Case]:
    v, f = box_arrays()
    stl = stl_binary(v, f)
    long = "a" * 300
    return [
        Case(
            "names",
            "model name not UTF-8",
            ["render", b"bad\xff.stl", "-o", "out.png", *RENDER],
            _files(**{os.fsdecode(b"bad\xff.stl"): stl}),
            valid=True,
        ),
        Case(
            "names",
            "bad model name not UTF-8",
            ["info", b"bad\xfe.obj"],
            _files(**{os.fsdecode(b"bad\xfe.obj"): b"v 0 0 0\n"}),
            ("bad\\xfe.obj",),
        ),
        Case(
            "names",
            "model name with a newline",
            ["info", "two\nlines.obj"],
            _files(**{"two\nlines.obj": b"v 0 0 0\n"}),
            ("two\\nlines.obj",),
        ),
        Case(
            "names",
            "model name with an escape",
            ["info", "a\x1b[2Jb.obj"],
            _files(**{"a\x1b[2Jb.obj": b"v 0 0 0\n"}),
            ("a\\x1b[2Jb.obj",),
        ),
        Case("names", "300-character model name", ["render", long + ".stl", "-o", "out.png"], None, (long,)),
        Case(
            "names",
            "300-character output name",
            ["render", "m.stl", "-o", long + ".png", *RENDER],
            _files(**{"m.stl": stl}),
            (long,),
        ),
        Case(
            "names",
            "output in /proc",
            ["turntable", "m.stl", "-o", "/proc/out.mp4", *RENDER],
            _files(**{"m.stl": stl}),
            ("/proc/out.mp4",),
        ),
        Case(
            "names",
            "output in /dev/null/x",
            ["render", "m.stl", "-o", "/dev/null/x.png"],
            _files(**{"m.stl": stl}),
            ("/dev/null/x.png",),
        ),
        Case(
            "names",
            "output a directory",
            ["render", "m.stl", "-o", "d.png", *RENDER],
            _files(**{"m.stl": stl, "d.png__x": b""}),
            ("d.png",),
        ),
        Case(
            "names",
            "output in a missing folder",
            ["render", "m.stl", "-o", "no/x.png"],
            _files(**{"m.stl": stl}),
            ("no/x.png",),
        ),
        Case(
            "names",
            "output of an unknown suffix",
            ["render", "m.stl", "-o", "x.gif"],
            _files(**{"m.stl": stl}),
            ("x.gif",),
        ),
        Case(
            "names",
            "model of an unknown suffix",
            ["info", "m.xyzzy"],
            _files(**{"m.xyzzy": stl}),
            ("m.xyzzy",),
        ),
        Case("names", "missing model", ["info", "none.stl"], None, ("none.stl",)),
        Case("names", "empty model", ["info", "m.obj"], _files(**{"m.obj": b""}), ("m.obj",)),
    ]


def _short_vertex_obj() -> bytes:
    """A box whose fourth vertex has a number replaced by ``nan`` and its last one dropped:
    trimesh cuts every vertex to the shortest vertex line."""
    lines = obj_text(*box_arrays()).split(b"\n")
    lines[3] = b"v 0.0 nan"
    return b"\n".join(lines)


def number_cases() -> list[Case]:
    tri = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]
    return [
        Case(
            "numbers",
            "GLB NaN and inf vertices",
            ["render", "m.glb", "-o", "out.png", *RENDER],
            _files(**{"m.glb": glb([{"mesh": 0}], [0], [[0, 0, 0], [np.nan, 0, 0], [0, np.inf, 0]])}),
            ("m.glb",),
        ),
        Case(
            "numbers",
            "GLB 1e30 vertices",
            ["render", "m.glb", "-o", "out.png", *RENDER],
            _files(**{"m.glb": glb([{"mesh": 0}], [0], [[0, 0, 0], [1e30, 0, 0], [0, 1e30, 0]])}),
            ("m.glb",),
        ),
        Case(
            "numbers",
            "GLB node scale 1e300",
            ["render", "m.glb", "-o", "out.png", *RENDER],
            _files(**{"m.glb": glb([{"mesh": 0, "scale": [1e300, 1e300, 1e300]}], [0], tri)}),
            ("m.glb",),
        ),
        Case(
            "numbers",
            "OBJ nan vertex",
            ["info", "m.obj"],
            _files(**{"m.obj": b"v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"}),
            ("m.obj",),
        ),
        Case(
            "numbers",
            "OBJ 1e308 vertices",
            ["render", "m.obj", "-o", "out.png", *RENDER],
            _files(**{"m.obj": b"v 1e308 0 0\nv -1e308 0 0\nv 0 1e308 0\nf 1 2 3\n"}),
            ("m.obj",),
        ),
        Case(
            "numbers",
            "OBJ vertex of two numbers",
            ["info", "m.obj"],
            _files(**{"m.obj": _short_vertex_obj()}),
            ("m.obj",),
        ),
        Case(
            "numbers",
            "OBJ vertices cut to two numbers",
            ["render", "m.obj", "-o", "out.png", *RENDER],
            _files(**{"m.obj": b"vn 0 0 1\n" + _short_vertex_obj().replace(b" 0.0\n", b"\n")}),
            ("m.obj",),
        ),
        Case(
            "numbers",
            "OBJ faces out of range",
            ["info", "m.obj"],
            _files(**{"m.obj": b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99\n"}),
            ("m.obj",),
            valid=True,
        ),
        Case(
            "numbers",
            "OBJ degenerate only",
            ["info", "m.obj"],
            _files(**{"m.obj": b"v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n"}),
            ("m.obj",),
        ),
        Case(
            "numbers",
            "STL all zeros",
            ["render", "m.stl", "-o", "out.png", *RENDER],
            _files(**{"m.stl": stl_binary(np.zeros((3, 3)), np.array([[0, 1, 2]] * 50))}),
            ("m.stl",),
        ),
    ]


def argument_cases() -> list[Case]:
    v, f = box_arrays()
    stl = stl_binary(v, f)
    m = _files(**{"m.stl": stl})
    return [
        Case(
            "arguments", "--size 0 0", ["render", "m.stl", "-o", "out.png", "--size", "0", "0"], m, ("size",)
        ),
        Case(
            "arguments",
            "--size -5 10",
            ["render", "m.stl", "-o", "out.png", "--size", "-5", "10"],
            m,
            ("size",),
        ),
        Case(
            "arguments",
            "--view nowhere",
            ["render", "m.stl", "-o", "out.png", "--view", "nowhere"],
            m,
            ("nowhere",),
        ),
        Case(
            "arguments",
            "--fov 0",
            ["render", "m.stl", "-o", "out.png", *RENDER, "--fov", "0"],
            m,
            ("field of view",),
        ),
        Case(
            "arguments",
            "--fov nan",
            ["render", "m.stl", "-o", "out.png", *RENDER, "--fov", "nan"],
            m,
            ("field of view",),
        ),
        Case(
            "arguments",
            "--azimuth inf",
            ["render", "m.stl", "-o", "out.png", *RENDER, "--azimuth", "inf"],
            m,
            ("azimuth",),
        ),
        Case(
            "arguments",
            "--layers 10^9",
            ["silhouettes", "m.stl", "-o", "out.png", *RENDER, "--layers", "1000000000"],
            m,
            ("layers",),
        ),
        Case(
            "arguments",
            "--fps 0",
            ["turntable", "m.stl", "-o", "out.mp4", *RENDER, "--fps", "0"],
            m,
            ("fps",),
        ),
        Case(
            "arguments",
            "--include nothing",
            ["render", "m.stl", "-o", "out.png", *RENDER, "--include", "nothing*"],
            m,
            ("nothing",),
        ),
        Case(
            "arguments",
            "--set of nothing",
            ["turntable", "m.stl", "-o", "out.mp4", *RENDER, "--set", "x"],
            m,
            ("x",),
        ),
    ]


def _set(path, value):
    """A change of a glTF document: the value at ``path`` (keys and indices) set to ``value``."""

    def change(doc):
        target = doc
        for key in path[:-1]:
            target = target[key]
        target[path[-1]] = value
        return doc

    return change


def shape_cases() -> list[Case]:
    nodes = [{"mesh": 0, "children": [1]}, {"mesh": 0, "translation": [2, 0, 0]}]
    doc, binary = gltf_doc(nodes, [0])
    linked, _ = gltf_doc(nodes, [0], uri="buffer.bin")  # a .gltf's buffer is a file of its own
    changes = {
        "document a list": lambda d: [d],
        "document a string": lambda d: "glTF",
        "document a number": lambda d: 2.0,
        "nodes an object": lambda d: {**d, "nodes": dict(enumerate(d["nodes"]))},
        "scenes a number": _set(("scenes",), 0),
        "meshes a number": _set(("meshes",), 3),
        "an accessor a number": _set(("accessors", 0), 7),
        "componentType a list": _set(("accessors", 0, "componentType"), [5126]),
        "count a string": _set(("accessors", 1, "count"), "3"),
        "mesh index a string": _set(("nodes", 1, "mesh"), "0"),
        "mesh index -1": _set(("nodes", 1, "mesh"), -1),
        "scene -1": _set(("scene",), -1),
        "children an object": _set(("nodes", 0, "children"), {"1": 1}),
        "translation of booleans": _set(("nodes", 1, "translation"), [True, False, False]),
        "attributes a list": _set(("meshes", 0, "primitives", 0, "attributes"), [0]),
        "primitives of numbers": _set(("meshes", 0, "primitives"), [0]),
        "indices past the accessors": _set(("meshes", 0, "primitives", 0, "indices"), 9),
    }
    cases = []
    for label, change in changes.items():
        text = json.dumps(change(copy.deepcopy(linked))).encode()
        cases.append(
            Case(
                "shape",
                f"glTF {label}",
                ["info", "m.gltf"],
                _files(**{"m.gltf": text, "buffer.bin": binary}),
                ("m.gltf",),
            )
        )
        cases.append(
            Case(
                "shape",
                f"GLB {label}",
                ["render", "m.glb", "-o", "out.png", *RENDER],
                _files(**{"m.glb": glb_of(change(copy.deepcopy(doc)), binary)}),
                ("m.glb",),
            )
        )
    return cases


_MUTATIONS = ("flip", "cut", "repeat", "insert", "zero", "digits")


def _mutate(data: bytes, rng: random.Random) -> bytes:
    data = bytearray(data)
    how = rng.choice(_MUTATIONS)
    at = rng.randrange(len(data))
    if how == "flip":
        for _ in range(rng.randint(1, 8)):
            data[rng.randrange(len(data))] ^= 1 << rng.randrange(8)
    elif how == "cut":
        del data[at:]
    elif how == "repeat":
        end = min(len(data), at + rng.randint(1, 64))
        data[at:at] = data[at:end] * rng.randint(2, 50)
    elif how == "insert":
        data[at:at] = bytes(rng.randrange(256) for _ in range(rng.randint(1, 32)))
    elif how == "zero":
        end = min(len(data), at + rng.randint(1, 256))
        data[at:end] = bytes(end - at)
    else:  # a number made huge, or negative
        digits = rng.choice([b"9" * rng.randint(10, 400), b"-1", b"1e308", b"nan", b"-0"])
        data[at:at] = digits
    return bytes(data or b"\0")


def mutated_cases(rng: random.Random, count: int) -> list[Case]:
    v, f = box_arrays()
    pyramid_v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    pyramid_f = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    doc, binary = gltf_doc([{"mesh": 0, "translation": [1, 2, 3]}], [0], uri="buffer.bin")
    bases = {
        "stl": stl_binary(v, f),
        "stl ascii": stl_ascii(v, f),
        "obj": obj_text(v, f),
        "off": off_text(pyramid_v, pyramid_f),
        "ply": ply_ascii(v, f),
        "ply binary": ply_binary(v, f),
        "glb": glb([{"mesh": 0, "children": [1]}, {"mesh": 0, "translation": [2, 0, 0]}], [0]),
        "gltf": json.dumps(doc).encode(),
        "3mf": threemf(2),
    }
    cases = []
    kinds = sorted(bases)
    for k in range(count):
        base = kinds[k % len(kinds)]
        suffix = base.split()[0]
        data = _mutate(bases[base], rng)
        files = {f"m.{suffix}": data}
        if base == "gltf":
            files["buffer.bin"] = _mutate(binary, rng) if rng.random() < 0.5 else binary
        command = ["info", f"m.{suffix}"] if k % 3 else ["render", f"m.{suffix}", "-o", "out.png", *RENDER]
        cases.append(Case("mutated", f"{base} #{k}", command, _files(**files), (f"m.{suffix}",), valid=True))
    return cases


KINDS = {
    "special": lambda rng, n: special_cases(),
    "sparse": lambda rng, n: sparse_cases(),
    "bomb": lambda rng, n: bomb_cases(rng),
    "header": lambda rng, n: header_cases(),
    "graph": lambda rng, n: graph_cases(),
    "work": lambda rng, n: work_cases(),
    "settings": lambda rng, n: settings_cases(rng),
    "pipeline": lambda rng, n: pipeline_cases(),
    "names": lambda rng, n: name_cases(),
    "numbers": lambda rng, n: number_cases(),
    "arguments": lambda rng, n: argument_cases(),
    "mutated": mutated_cases,
    "shape": lambda rng, n: shape_cases(),
}


def generate(seed: int = 17, mutations: int = 160, kinds=None) -> list[Case]:
    """The corpus, the same for the same ``seed``: the cases of every kind of ``KINDS`` (or of
    those named in ``kinds``), ``mutations`` of them mutated files. Each kind draws from a
    generator of its own, so a subset holds the same cases as the whole."""
    cases = []
    for k, (kind, make) in enumerate(KINDS.items()):
        if kinds is None or kind in kinds:
            cases += make(random.Random(seed * 1000 + k), mutations)
    return cases


# -- running -------------------------------------------------------------------------------------
def _limits(memory: int):
    def apply() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (memory, memory))
        resource.setrlimit(resource.RLIMIT_CORE, (0, 0))

    return apply


def _shown(name) -> str:
    from blueprint.errors import printable

    return printable(os.fsdecode(name) if isinstance(name, bytes) else name)


def run_case(case: Case, folder: Path, timeout: float = 60.0, memory: int = 4 << 30) -> Outcome:
    """Make the case's files in ``folder`` (empty), run the command there and judge it."""
    folder.mkdir(parents=True, exist_ok=True)
    if case.make is not None:
        case.make(folder)
    before = sorted(os.listdir(folder))
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src"), **case.env}
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        start = time.perf_counter()
        proc = subprocess.Popen(
            [sys.executable, "-m", "blueprint", *case.args],
            cwd=folder,
            env=env,
            stdin=subprocess.DEVNULL,
            stdout=out,
            stderr=err,
            preexec_fn=_limits(memory),
            start_new_session=True,
        )
        timer = threading.Timer(timeout, lambda: _kill(proc.pid))
        timer.start()
        _, status, usage = os.wait4(proc.pid, 0)
        timer.cancel()
        seconds = time.perf_counter() - start
        proc.returncode = os.waitstatus_to_exitcode(status)
        _kill(proc.pid)  # whatever the command started in its session (ffmpeg) goes too
        out.seek(0)
        err.seek(0)
        stdout, stderr = out.read(), err.read()
    peak = usage.ru_maxrss / 1024
    code = proc.returncode
    after = sorted(os.listdir(folder))
    clean, reason = _judge(case, code, stdout, stderr, before, after, seconds >= timeout)
    return Outcome(case, clean, code, reason, seconds, peak)


def _kill(pid: int) -> None:
    try:
        os.killpg(pid, signal.SIGKILL)
    except (ProcessLookupError, PermissionError):
        pass


def _judge(case: Case, code: int, stdout: bytes, stderr: bytes, before, after, timed_out: bool):
    try:
        text = stderr.decode("utf-8")
    except UnicodeDecodeError:
        return False, "stderr is not UTF-8"
    first = text.splitlines()[0] if text else ""
    if timed_out:
        return False, "hang (killed at the time limit)"
    if "Traceback" in text:
        return False, f"traceback: {text.strip().splitlines()[-1][:160]}"
    if code < 0 or code in (-9, 137):
        return False, f"killed by signal {-code} (memory?)"
    if code == 0 and case.valid:
        return True, "valid"
    if code != 2:
        return False, f"exit {code}: {first[:160]}"
    if b"Traceback" in stdout:
        return False, "traceback on stdout"
    if text.count("\n") != 1 or not text.endswith("\n"):
        return False, f"{text.count(chr(10))} lines on stderr: {first[:160]}"
    if not first.startswith("blueprint: error: "):
        return False, f"not an error line: {first[:160]}"
    if case.names and not any(_shown(n) in first for n in case.names):
        return False, f"does not name {_shown(case.names[0])!r}: {first[:160]}"
    left = sorted(set(after) - set(before))
    if left:
        return False, f"left behind: {', '.join(map(_shown, left))[:160]}"
    return True, "refused"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seed", type=int, default=17)
    parser.add_argument("--mutations", type=int, default=160)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--timeout", type=float, default=60.0)
    parser.add_argument("--memory", default="4G", help="address-space limit of each run (K, M or G)")
    parser.add_argument("--kinds", default=None, help="comma-separated kinds to run (default: all)")
    parser.add_argument("--keep", default=None, help="folder to keep the cases' folders in")
    args = parser.parse_args()
    memory = int(args.memory[:-1]) * {"K": 1 << 10, "M": 1 << 20, "G": 1 << 30}[args.memory[-1].upper()]
    cases = generate(args.seed, args.mutations, args.kinds.split(",") if args.kinds else None)
    scratch = Path(args.keep) if args.keep else Path(tempfile.mkdtemp(prefix="hostile-"))
    start = time.perf_counter()
    with ThreadPoolExecutor(args.jobs) as pool:
        outcomes = list(
            pool.map(
                lambda ic: run_case(ic[1], scratch / f"{ic[0]:04d}", args.timeout, memory), enumerate(cases)
            )
        )
    wall = time.perf_counter() - start
    if not args.keep:
        shutil.rmtree(scratch, ignore_errors=True)
    by_kind: dict = collections.defaultdict(lambda: [0, 0])
    for o in outcomes:
        by_kind[o.case.kind][0] += o.clean
        by_kind[o.case.kind][1] += 1
    for o in outcomes:
        if not o.clean:
            print(f"NOT CLEAN [{o.case.kind}] {o.case.label}: {o.reason}")
    clean = sum(o.clean for o in outcomes)
    print(f"{clean}/{len(outcomes)} clean")
    for kind, (good, total) in by_kind.items():
        print(f"  {kind:10s} {good}/{total}")
    slowest = max(outcomes, key=lambda o: o.seconds)
    biggest = max(outcomes, key=lambda o: o.peak_mib)
    print(
        f"peak memory {biggest.peak_mib:.0f} MiB ({biggest.case.label}); "
        f"slowest {slowest.seconds:.1f} s ({slowest.case.label})"
    )
    info = subprocess.run(
        [sys.executable, "-m", "blueprint", "info", "--json"],
        capture_output=True,
        text=True,
        env={**os.environ, "PYTHONPATH": str(ROOT / "src")},
    )
    record = {
        "benchmark": "hostile",
        "seed": args.seed,
        "cases": len(outcomes),
        "clean": clean,
        "by_kind": {k: {"clean": g, "cases": t} for k, (g, t) in by_kind.items()},
        "peak_mib": round(biggest.peak_mib, 1),
        "peak_case": biggest.case.label,
        "slowest_s": round(slowest.seconds, 2),
        "slowest_case": slowest.case.label,
        "median_s": round(float(np.median([o.seconds for o in outcomes])), 3),
        "wall_s": round(wall, 1),
        "timeout_s": args.timeout,
        "memory_limit": args.memory,
        "renderer": json.loads(info.stdout)["renderer"] if info.returncode == 0 else "unknown",
        "cpus": os.cpu_count(),
        "not_clean": [f"[{o.case.kind}] {o.case.label}: {o.reason}" for o in outcomes if not o.clean],
    }
    print(json.dumps(record))


if __name__ == "__main__":
    main()
