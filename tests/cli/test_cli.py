"""Happy paths of the command line, through the installed console script, and file formats.

``info`` (GL and model), ``render`` (PNG of the requested size), ``layers`` (the NPZ contract,
checked by casting rays through the written matrices), ``bench`` (JSON lines); every format
trimesh can write here loads with its triangle count and bounds; glTF node transforms apply.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
import time

import numpy as np
import pytest
import trimesh
from helpers import needs_cli, run_cli
from PIL import Image

from blueprint import examples, load_model

EXAMPLE = examples.example_path()
PAPER = (0x12, 0x45, 0x7A, 255)  # the blueprint style's paper colour

pytestmark = needs_cli


def ok(proc: subprocess.CompletedProcess) -> str:
    """stdout of a run that must succeed quietly."""
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == "", proc.stderr
    return proc.stdout


@pytest.fixture(scope="module")
def gearbox_parts() -> dict[str, int]:
    model = examples.gearbox()
    return dict(zip(model.part_names, model.part_triangle_counts().tolist(), strict=True))


@pytest.fixture(scope="module")
def gl() -> dict:
    return json.loads(ok(run_cli("info", "--json")))


# -- info ---------------------------------------------------------------------------------------


def test_info_prints_renderer_and_gl_version(gl):
    lines = ok(run_cli("info")).splitlines()
    assert lines[0] == f"renderer: {gl['renderer']}"
    assert lines[1] == f"vendor: {gl['vendor']}"
    assert lines[2] == f"OpenGL: {gl['version']}"
    major, minor = (int(v) for v in re.match(r"(\d+)\.(\d+)", gl["version"]).groups())
    assert (major, minor) >= (3, 3)
    assert int(gl["max_texture_size"]) >= 1024
    # the ways it draws, as the renderer's capture table holds them for this driver
    from blueprint.api.renderer import Renderer

    with Renderer() as r:
        passes = "compute shaders" if r.use_compute else "fragment passes"
        table, old_gl = r.capture_table, r.ctx.version_code < 430
    kbuffer, listed = table.row("k-buffer"), table.row("A-buffer")
    way = "fragment shader interlock" if kbuffer and kbuffer.interlock else "framebuffer fetch"
    held = f"{way}, from {kbuffer.min_density:g} triangles per pixel" if kbuffer else "none"
    assert lines[3] == f"image passes: {passes}" and gl["image_passes"] == passes
    assert lines[4].startswith(f"k-buffer: {held}") and gl["kbuffer"].startswith(held)
    if listed:
        least = listed.min_layers
        abuffer = "every frame" if least <= 1 else f"from {least} layers a frame"
    else:
        abuffer = "none" if old_gl else "off on this driver"
    assert abuffer in lines[5] and lines[5].startswith("A-buffer: ") and abuffer in gl["abuffer"]
    depth = "exact planes" if table.exact_depth else "as rasterised"
    assert lines[6].startswith(f"depth: {depth} (") and gl["depth"].startswith(depth)


def test_info_model_lists_parts(gearbox_parts):
    assert sum(gearbox_parts.values()) == 2144 and len(gearbox_parts) == 13
    lines = ok(run_cli("info", EXAMPLE)).splitlines()
    assert lines[0] == f"{EXAMPLE}: 2144 triangles, 13 parts, up y (by the format)"
    assert lines[1] == "bounds: [-70, 0, -35] - [70, 73.5, 35]"
    # glTF is in metres by its specification
    assert lines[2] == "unit: m, from the file (glTF is in metres by its specification)"
    assert lines[3] == "size: 140 x 73.5 x 70 m = 140000 x 73500 x 70000 mm"
    rows = [re.fullmatch(r"\s*(\d+)\s+(\d+)\s+(\S+)", line) for line in lines[4:]]
    assert all(rows), lines[4:]
    assert [int(r.group(1)) for r in rows] == list(range(13))
    assert {r.group(3): int(r.group(2)) for r in rows} == gearbox_parts


def test_info_model_json(gearbox_parts):
    data = json.loads(ok(run_cli("info", EXAMPLE, "--json")))
    assert data["file"] == str(EXAMPLE)
    assert data["triangles"] == 2144 and data["up"] == "y"
    assert data["bounds"] == [[-70.0, 0.0, -35.0], [70.0, 73.5, 35.0]]
    assert (data["unit"], data["unit_assumed"]) == ("m", False)
    assert data["size"] == [140.0, 73.5, 70.0] and data["size_mm"] == [140000.0, 73500.0, 70000.0]
    assert [p["index"] for p in data["parts"]] == list(range(13))
    assert {p["name"]: p["triangles"] for p in data["parts"]} == gearbox_parts


# -- render ---------------------------------------------------------------------------------------

RENDER_LINE = re.compile(
    r"(?P<file>.+): (?P<w>\d+)x(?P<h>\d+), (?P<tri>\d+) triangles, "
    r"(?P<layers>\d+)(?: of (?P<total>\d+))? layers, "
    r"(?P<ms>\d+\.\d) ms on (?P<renderer>.+)"
)


def test_render_writes_png_of_requested_size(tmp_path, gl):
    out = tmp_path / "out"
    out.mkdir()
    target = out / "gear.png"
    target.write_bytes(b"an older file that must be replaced")
    stdout = ok(run_cli("render", EXAMPLE, "-o", target, "--size", 96, 64))
    match = RENDER_LINE.fullmatch(stdout.strip())
    assert match, stdout
    assert match["file"] == str(target) and (match["w"], match["h"]) == ("96", "64")
    assert int(match["tri"]) == 2144 and match["renderer"] == gl["renderer"]
    assert int(match["layers"]) == 8 and float(match["ms"]) > 0
    # the default cap of 8 says what it left: at least as many as a peel without the cap draws
    # (the count takes the touching faces of two parts, which the peel merges, as two)
    every = RENDER_LINE.fullmatch(
        ok(run_cli("render", EXAMPLE, "-o", target, "--size", 96, 64, "--max-layers", 0)).strip()
    )
    assert every["total"] is None and int(every["layers"]) <= int(match["total"]) <= int(every["layers"]) + 1
    assert sorted(p.name for p in out.iterdir()) == ["gear.png"]  # no temporary file left
    with Image.open(target) as picture:
        assert picture.format == "PNG" and picture.size == (96, 64) and picture.mode == "RGBA"
        image = np.asarray(picture)
    for corner in (image[0, 0], image[0, -1], image[-1, 0], image[-1, -1]):
        assert tuple(corner) == PAPER
    # white ink on the visible edges
    assert (image[..., :3].min(axis=-1) > 200).sum() > 50


def test_render_accepts_every_option(tmp_path):
    target = tmp_path / "all.png"
    stdout = ok(
        run_cli(
            "render",
            EXAMPLE,
            "-o",
            target,
            "--size",
            40,
            30,
            "--view",
            "front",
            "--azimuth",
            10,
            "--elevation",
            20,
            "--fov",
            40,
            "--ortho",
            "--up",
            "z",
            "--style",
            "paper",
            "--grid",
            8,
            "--max-layers",
            3,
            "--min-fraction",
            0.01,
            "--crease-angle",
            40,
            "--line-width",
            1.5,
            "--supersample",
            1,
        )  # fmt: skip
    )
    match = RENDER_LINE.fullmatch(stdout.strip())
    assert match and int(match["layers"]) <= 3, stdout
    with Image.open(target) as picture:
        assert picture.size == (40, 30)


# -- layers ---------------------------------------------------------------------------------------


def test_layers_npz_contract_by_ray_casting(tmp_path):
    vertices, faces = examples.box((0, 0, 0), (1, 2, 3))
    source = tmp_path / "box.obj"
    trimesh.Trimesh(vertices, faces, process=False).export(source)
    model = load_model(source)
    target = tmp_path / "box.npz"
    stdout = ok(run_cli("layers", source, "-o", target, "--size", 64, 48))
    assert stdout.strip() == f"{target}: 2 layers of 64x48"
    with np.load(target) as npz:
        data = {k: npz[k] for k in npz.files}
    assert {"depth", "triangle", "part", "view", "projection"} <= set(data)
    assert data["depth"].dtype == np.float32 and data["depth"].shape == (2, 48, 64)
    assert data["triangle"].dtype == np.int32 and data["triangle"].shape == (2, 48, 64)
    assert data["part"].dtype == np.int32 and data["part"].shape == (2, 48, 64)
    assert data["view"].dtype == np.float64 and data["view"].shape == (4, 4)
    assert data["projection"].dtype == np.float64 and data["projection"].shape == (4, 4)

    tri, depth, part = data["triangle"], data["depth"], data["part"]
    empty = tri < 0
    assert (tri[~empty] < 12).all()
    np.testing.assert_array_equal(depth[empty], 1.0)
    np.testing.assert_array_equal(part[empty], -1)
    np.testing.assert_array_equal(part[~empty], 0)
    assert ((depth[~empty] > 0) & (depth[~empty] < 1)).all()
    both = ~empty[0] & ~empty[1]
    assert both.sum() > 100 and (depth[1][both] > depth[0][both]).all()
    np.testing.assert_array_equal(~empty[0], ~empty[1])  # a closed box: every ray enters and leaves

    # cast a ray through each pixel centre (row 0 at the top) with the written matrices: the
    # point at the written depth lies on the plane of the written triangle
    inverse = np.linalg.inv(data["projection"] @ data["view"])
    rows, cols = np.indices((48, 64))
    ndc_x, ndc_y = (cols + 0.5) / 64 * 2 - 1, 1 - (rows + 0.5) / 48 * 2
    eye = np.linalg.inv(data["view"])[:3, 3]
    tri_vertices = model.positions[model.faces].astype(np.float64)
    normals = np.cross(tri_vertices[:, 1] - tri_vertices[:, 0], tri_vertices[:, 2] - tri_vertices[:, 0])
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    for layer in range(2):
        m = ~empty[layer]
        clip = np.stack([ndc_x[m], ndc_y[m], 2.0 * depth[layer][m] - 1, np.ones(m.sum())])
        world = inverse @ clip
        world = (world[:3] / world[3]).T
        t = tri[layer][m]
        distance = np.abs(np.einsum("ij,ij->i", world - tri_vertices[t, 0], normals[t]))
        assert distance.max() < 1e-3, f"layer {layer}: {distance.max()}"
        assert (world > -1e-3).all() and (world < np.array([1, 2, 3]) + 1e-3).all()
        facing = np.einsum("ij,ij->i", eye - tri_vertices[t, 0], normals[t])
        # layer 0 sees the faces turned to the eye, layer 1 the ones turned away
        assert ((facing > 0) if layer == 0 else (facing < 0)).all()


# -- bench ----------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def bench_run() -> subprocess.CompletedProcess:
    args = ("--size", 64, 64, "--max-layers", 2, "--frames", 2, "--warmup", 1)
    return run_cli("bench", EXAMPLE, *args)


def test_bench_prints_one_record_per_configuration(bench_run, gl):
    assert bench_run.returncode == 0, bench_run.stderr
    records = [json.loads(line) for line in bench_run.stdout.splitlines() if line.strip()]
    assert len(records) == 1
    record = records[0]
    assert record["renderer"] == gl["renderer"] and record["model"] == "gearbox.glb"
    assert record["triangles"] == 2144
    assert (record["width"], record["height"]) == (64, 64)
    assert record["layers"] == 2 and record["ms"] > 0
    assert isinstance(record["stages"], dict) and record["stages"]
    assert all(isinstance(v, int | float) and v >= 0 for v in record["stages"].values())
    assert record["capture"] in ("peel", "k-buffer", "A-buffer", "A-buffer, compute rasteriser")


def test_bench_stdout_is_pure_json_lines(bench_run):
    """Every line of stdout is one JSON object: rich's transient Progress bar (bench.py) draws
    on stdout and leaves an empty line after the records when stdout is not a terminal."""
    assert bench_run.returncode == 0, bench_run.stderr
    for line in bench_run.stdout.split("\n")[:-1]:
        assert isinstance(json.loads(line), dict), repr(line)
    assert bench_run.stdout.endswith("}\n")


# -- file formats -----------------------------------------------------------------------------------

FORMATS = [
    ("obj", "obj", "y"),
    ("stl", "stl", "z"),
    ("stl_ascii", "stl", "z"),
    ("ply", "ply", "y"),
    ("off", "off", "y"),
    ("glb", "glb", "y"),
    ("3mf", "3mf", "z"),
]


@pytest.mark.parametrize("shape", ["gearbox", "box"])
@pytest.mark.parametrize("file_type, suffix, up", FORMATS, ids=[f[0] for f in FORMATS])
def test_format_keeps_triangles_and_bounds(tmp_path, shape, file_type, suffix, up):
    if shape == "gearbox":
        model = examples.gearbox()
        vertices, faces = model.positions, model.faces
    else:
        vertices, faces = examples.box((-1, 0, 2), (1, 2, 5))
    mesh = trimesh.Trimesh(vertices, faces, process=False)
    # every format's exporter comes with the project's own dependencies (networkx and lxml for
    # 3MF): one that fails is a broken install, not a reason to skip
    data = mesh.export(file_type=file_type)
    path = tmp_path / f"{shape}.{suffix}"
    path.write_bytes(data if isinstance(data, bytes) else data.encode())
    loaded = load_model(path)
    assert loaded.triangle_count == len(faces)
    expected = np.array([vertices.min(axis=0), vertices.max(axis=0)], np.float64)
    np.testing.assert_allclose(loaded.bounds, expected, rtol=1e-6, atol=1e-5)
    assert loaded.up == up
    assert loaded.part_names == (shape,)
    assert not loaded.degenerate_faces().any()


def test_scene_formats_keep_parts(tmp_path, gearbox_parts):
    scene = trimesh.load_scene(str(EXAMPLE))
    for file_type in ("glb", "3mf"):
        path = tmp_path / f"gearbox.{file_type}"
        path.write_bytes(scene.export(file_type=file_type))
        loaded = load_model(path)
        counts = dict(zip(loaded.part_names, loaded.part_triangle_counts().tolist(), strict=True))
        assert counts == gearbox_parts, file_type


def test_non_utf8_obj_loads(tmp_path):
    """An OBJ with a Latin-1 comment (common from Windows CAD exporters) is a valid file; trimesh
    falls back to charset_normalizer for non-UTF-8 text, which is not installed, so it failed with
    "cannot read as OBJ: No module named 'charset_normalizer'"."""
    path = tmp_path / "latin1.obj"
    path.write_bytes("# modèle café\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n".encode("latin-1"))
    assert load_model(path).triangle_count == 1


def _instances_scene() -> trimesh.Scene:
    """One box mesh used by two nodes: translated, and rotated about Z after a lift."""
    vertices, faces = examples.box((0, 0, 0), (1, 2, 3))
    scene = trimesh.Scene()
    moved = trimesh.transformations.translation_matrix([10, 0, 0])
    turned = trimesh.transformations.rotation_matrix(np.pi / 2, [0, 0, 1]) @ (
        trimesh.transformations.translation_matrix([0, 0, 5])
    )
    scene.add_geometry(trimesh.Trimesh(vertices, faces, process=False), "a", "boxgeom", transform=moved)
    scene.graph.update(frame_to="b", frame_from=scene.graph.base_frame, geometry="boxgeom", matrix=turned)
    return scene


@pytest.mark.parametrize("file_type", ["glb", "gltf"])
def test_gltf_instances_become_parts_with_transforms(tmp_path, file_type):
    scene = _instances_scene()
    assert len(scene.geometry) == 1  # really one mesh, two instances
    if file_type == "glb":
        path = tmp_path / "inst.glb"
        path.write_bytes(scene.export(file_type="glb"))
    else:
        for name, data in scene.export(file_type="gltf").items():
            (tmp_path / name).write_bytes(data)
        path = tmp_path / "model.gltf"
    model = load_model(path)
    assert model.triangle_count == 24 and len(model.part_names) == 2
    assert sorted(model.part_names) == ["boxgeom", "boxgeom[2]"]
    np.testing.assert_array_equal(model.part_triangle_counts(), [12, 12])
    bounds = set()
    for part in range(2):
        used = model.positions[model.faces[model.face_part == part].reshape(-1)].astype(np.float64)
        bounds.add(tuple(np.round(np.r_[used.min(axis=0), used.max(axis=0)], 5) + 0.0))
    # translated by +10 in x; rotated 90 degrees about z: (x, y) -> (-y, x), lifted to z 5..8
    assert bounds == {(10, 0, 0, 11, 2, 3), (-2, 0, 5, 0, 1, 8)}


def test_nested_node_transforms_compose(tmp_path):
    vertices, faces = examples.box((0, 0, 0), (1, 2, 3))
    scene = trimesh.Scene()
    scene.graph.update(
        frame_to="parent",
        frame_from=scene.graph.base_frame,
        matrix=trimesh.transformations.scale_matrix(2.0),
    )
    scene.add_geometry(
        trimesh.Trimesh(vertices, faces, process=False),
        node_name="child",
        geom_name="box",
        parent_node_name="parent",
        transform=trimesh.transformations.translation_matrix([10, 0, 0]),
    )
    path = tmp_path / "nested.glb"
    path.write_bytes(scene.export(file_type="glb"))
    model = load_model(path)
    np.testing.assert_allclose(model.bounds, [[20, 0, 0], [22, 4, 6]], atol=1e-5)


def test_render_svg_reports_its_own_time(tmp_path, gl):
    """The seconds printed are the drawing's, not the sum of its stages and their total."""
    target = tmp_path / "gear.svg"
    start = time.perf_counter()
    stdout = ok(run_cli("render", EXAMPLE, "-o", target, "--size", 96, 64))
    wall = time.perf_counter() - start
    match = re.fullmatch(r".+: (\d+) bytes, polylines .+, (\d+\.\d+) s on .+", stdout.strip())
    assert match, stdout
    assert int(match[1]) == target.stat().st_size
    assert 0 < float(match[2]) <= wall


def test_render_plan_sheet_as_vectors(tmp_path, gl):
    out = tmp_path / "sheet.dxf"
    stdout = ok(run_cli("render", EXAMPLE, "-o", out, "--size", 160, 120, "--view", "plan"))
    assert stdout.startswith(f"{out}: ") and "polylines level 0" in stdout
    assert out.stat().st_size > 1000


def test_help_lists_every_command_without_importing_them():
    """``blueprint --help`` lists the commands from ``COMMANDS``, whose short helps are the
    commands' own, and imports none of their modules (nor the renderer)."""
    import importlib

    from blueprint.cli import COMMANDS, cli

    for name, (module, attribute, short) in COMMANDS.items():
        command = getattr(importlib.import_module(module), attribute)
        assert command.name == name
        assert command.get_short_help_str(limit=10_000) == short
    assert sorted(COMMANDS) == cli.list_commands(None)
    probe = (
        "import sys\nfrom blueprint.cli import main\n"
        "try:\n    main(['--help'])\nexcept SystemExit:\n    pass\n"
        "heavy = ('blueprint.cli.', 'blueprint.render', 'numpy')\n"
        "print(sorted(m for m in sys.modules if m.startswith(heavy)))"
    )
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines()[-1] == "['blueprint.cli.shell']"
    assert all(name in done.stdout for name in COMMANDS)


def test_success_lines_print_names_safely(tmp_path):
    """A file name holding a newline is one line on stdout too, the newline shown as ``\\n``."""
    model = tmp_path / "two\nlines.stl"
    trimesh.creation.box((1.0, 2.0, 3.0)).export(model)
    lines = ok(run_cli("info", model)).splitlines()
    assert lines[0].startswith(str(tmp_path / "two\\nlines.stl") + ": 12 triangles, 1 parts")
    assert len(lines) == 5  # the model, its bounds, unit and size, its one part
    out = tmp_path / "out\nfile.png"
    lines = ok(run_cli("render", model, "-o", out, "--size", "64", "48")).splitlines()
    assert len(lines) == 1 and lines[0].startswith(str(tmp_path / "out\\nfile.png") + ": 64x48")
    assert out.exists()
