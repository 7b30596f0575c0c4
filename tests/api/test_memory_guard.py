"""The memory guard: a model whose peak memory, foretold from its header's counts, passes the
budget is refused in one line before its body is read; a frame whose GPU buffers would pass the
memory the device has free is refused before any is allocated (``render.budget``)."""

import os
import re
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest
import trimesh
from helpers import BLUEPRINT, hostile_corpus, needs_cli, one_error

from blueprint import settings
from blueprint.api.frames import render_frame
from blueprint.errors import InputError
from blueprint.examples import assemble, box, example_path, prism
from blueprint.render import budget
from blueprint.scene.headers import peak_estimate, pictures_only
from blueprint.scene.loader import load_model
from blueprint.vector import drawing

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
@pytest.mark.parametrize(
    ("suffix", "each"), [(".png", settings.PICTURE_TRIANGLE_BYTES), (".svg", settings.TRIANGLE_BYTES)]
)
def test_a_model_over_the_budget_is_refused_from_its_header(tmp_path, suffix, each):
    """Refused at the header's count, at a picture's bytes a triangle for a PNG and at a
    vector drawing's for an SVG."""
    model, out = tmp_path / "big.ply", tmp_path / "out"
    out.mkdir()
    _ply_of_garbage(model, FACES)
    budget_bytes = 64 << 20  # holds the file (a quarter of it is the file limit), not its triangles
    start = time.monotonic()
    proc = subprocess.run(
        [str(BLUEPRINT), "render", str(model), "-o", str(out / f"big{suffix}")],
        capture_output=True,
        text=True,
        env={**os.environ, "BLUEPRINT_MEMORY_LIMIT": str(budget_bytes)},
    )
    took = time.monotonic() - start
    estimate = FACES * each
    one_error(
        proc,
        f"{model}: {FACES} triangles to draw need about {estimate / 2**20:.3g} MiB of memory at "
        f"{each} bytes a triangle, more than the memory budget of 64 MiB",
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
    # a model drawn only as pictures holds no lines' adjacency: its triangles weigh less
    assert settings.PICTURE_TRIANGLE_BYTES < settings.TRIANGLE_BYTES
    with pictures_only():
        assert peak_estimate(5_242_880) == 5_242_880 * settings.PICTURE_TRIANGLE_BYTES
        assert peak_estimate(1_200_000, 12, 100_000) == (
            12 * settings.PICTURE_TRIANGLE_BYTES + 100_000 * settings.INSTANCE_BYTES
        )
        parts = 300 * settings.PICTURE_TRIANGLE_BYTES + 100 * settings.PART_BYTES
        assert peak_estimate(300, 300, 100) == parts
    assert peak_estimate(5_242_880) == 5_242_880 * settings.TRIANGLE_BYTES
    # a scene kept as instances (drawn at least twice its unique triangles): its unique
    # triangles and its instances; one drawn less than twice over is flattened
    kept = 12 * settings.TRIANGLE_BYTES + 100_000 * settings.INSTANCE_BYTES
    assert peak_estimate(1_200_000, 12, 100_000) == kept
    assert peak_estimate(24, 12, 2) == 12 * settings.TRIANGLE_BYTES + 2 * settings.INSTANCE_BYTES
    assert peak_estimate(23, 12, 2) == 23 * settings.TRIANGLE_BYTES + 2 * settings.PART_BYTES
    # a scene of distinct parts, flattened: each part weighs beside its triangles
    assert peak_estimate(300, 300, 100) == 300 * settings.TRIANGLE_BYTES + 100 * settings.PART_BYTES


def _distinct_parts(path: Path, count: int) -> Path:
    """A GLB of ``count`` distinct one-triangle meshes, each placed once by a node of its own
    (a building's elements, in small)."""
    corners = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32)
    positions = (corners[None] * (1.0 + np.arange(count))[:, None, None]).astype(np.float32)
    indices = np.arange(3, dtype="<u4")
    accessors, meshes = [], []
    for k in range(count):
        accessors.append(
            {"bufferView": 0, "byteOffset": 36 * k, "componentType": 5126, "count": 3, "type": "VEC3"}
            | {"min": positions[k].min(0).tolist(), "max": positions[k].max(0).tolist()}
        )
        meshes.append({"primitives": [{"attributes": {"POSITION": k}, "indices": count}]})
    accessors.append({"bufferView": 1, "componentType": 5125, "count": 3, "type": "SCALAR"})
    doc = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": list(range(count))}],
        "nodes": [{"mesh": k} for k in range(count)],
        "meshes": meshes,
        "buffers": [{"byteLength": positions.nbytes + indices.nbytes}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": positions.nbytes},
            {"buffer": 0, "byteOffset": positions.nbytes, "byteLength": indices.nbytes},
        ],
        "accessors": accessors,
    }
    path.write_bytes(hostile_corpus().glb_of(doc, positions.tobytes() + indices.tobytes()))
    return path


def test_a_scene_of_distinct_parts_weighs_each_part(tmp_path, monkeypatch):
    """A scene of many small distinct parts is flattened into one mesh, each part with its
    name and its mesh as the file holds it: the estimate weighs the parts beside their
    triangles, refused over the budget in one line before the meshes are read, drawn within."""
    path = _distinct_parts(tmp_path / "parts.glb", 200)
    estimate = 200 * settings.TRIANGLE_BYTES + 200 * settings.PART_BYTES
    monkeypatch.setattr(settings, "MEMORY_BUDGET", estimate - 1)
    with pytest.raises(InputError) as caught:
        load_model(path)
    assert str(caught.value) == (
        f"{path}: 200 triangles to draw (200 mesh instances) need about {settings.human_size(estimate)} "
        f"of memory at 896 bytes a triangle and {settings.PART_BYTES} an instance, more than the memory "
        f"budget of {settings.human_size(estimate - 1)} (BLUEPRINT_MEMORY_LIMIT sets the budget)"
    )
    monkeypatch.setattr(settings, "MEMORY_BUDGET", estimate)
    model = load_model(path)
    assert model.instances is None and len(model.part_names) == 200 and model.triangle_count == 200


def _prism_stl(path: Path) -> int:
    """A binary STL of a prism of 20 000 sides at ``path``; its triangles."""
    vertices, faces = prism(1.0, 1.0, 20_000)
    trimesh.Trimesh(vertices, faces, process=False).export(path)
    return len(faces)


@needs_cli
def test_a_model_drawn_only_as_pictures_is_weighed_as_a_picture(tmp_path):
    """Under a budget that holds a model's picture (``PICTURE_TRIANGLE_BYTES`` a triangle) but
    not its vector drawing (``TRIANGLE_BYTES``), its PNG and its layers are drawn, ``info`` lists
    it, and its SVG is refused in one line, exit 2, no file."""
    path = tmp_path / "prism.stl"
    faces = _prism_stl(path)
    budget_bytes = faces * (settings.PICTURE_TRIANGLE_BYTES + settings.TRIANGLE_BYTES) // 2
    env = {**os.environ, "BLUEPRINT_MEMORY_LIMIT": str(budget_bytes)}

    def run(command: str, out: str, *options: str) -> subprocess.CompletedProcess:
        argv = [str(BLUEPRINT), command, str(path), "-o", str(tmp_path / out), "--size", "64", "64", *options]
        return subprocess.run(argv, capture_output=True, text=True, env=env, timeout=300)

    proc = run("render", "prism.png", "--max-layers", "2")
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "prism.png").stat().st_size > 0
    proc = run("layers", "prism.npz", "--max-layers", "2")
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "prism.npz").stat().st_size > 0
    listed = [str(BLUEPRINT), "info", str(path)]
    proc = subprocess.run(listed, capture_output=True, text=True, env=env, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.startswith(f"{path}: {faces} triangles"), proc.stdout
    proc = run("render", "prism.svg")
    estimate = settings.human_size(faces * settings.TRIANGLE_BYTES)
    one_error(
        proc,
        f"{path}: {faces} triangles to draw need about {estimate} of memory at {settings.TRIANGLE_BYTES} "
        f"bytes a triangle, more than the memory budget of {settings.human_size(budget_bytes)}",
    )
    assert not (tmp_path / "prism.svg").exists()


def test_the_picture_api_weighs_a_model_file_as_a_picture(tmp_path, monkeypatch, renderer):
    """``render_frame`` of a model file loads it as a picture's; ``load_model``, whose model
    may become a vector drawing, as a vector drawing's."""
    path = tmp_path / "prism.stl"
    faces = _prism_stl(path)
    monkeypatch.setattr(settings, "MEMORY_BUDGET", faces * settings.TRIANGLE_BYTES - 1)
    frame = render_frame(path, renderer=renderer, size=(32, 32), max_layers=1)
    assert frame.image.shape == (32, 32, 4) and frame.layers == 1
    with pytest.raises(InputError, match=f"at {settings.TRIANGLE_BYTES} bytes a triangle"):
        load_model(path)
    monkeypatch.setattr(settings, "MEMORY_BUDGET", faces * settings.PICTURE_TRIANGLE_BYTES - 1)
    with pytest.raises(InputError, match=f"at {settings.PICTURE_TRIANGLE_BYTES} bytes a triangle"):
        render_frame(path, renderer=renderer, size=(32, 32), max_layers=1)


@needs_cli
def test_the_instances_a_scene_may_place_follow_the_memory_budget(tmp_path):
    """The mesh instances a scene may place are as many as the memory budget holds at the
    least an instance takes: a scene placing a box 4 096 times is refused in one line under a
    budget that holds one instance fewer, and read under one that holds them, as
    ``BLUEPRINT_MEMORY_LIMIT`` sets it."""
    path = tmp_path / "rows.glb"
    count = 4096
    corners, faces = hostile_corpus().box_arrays()
    nodes = [{"mesh": 0, "translation": [2.0 * (k % 64), 3.0 * (k // 64), 0.0]} for k in range(count)]
    path.write_bytes(hostile_corpus().glb(nodes, list(range(count)), corners, faces=faces))

    def info(budget: int) -> subprocess.CompletedProcess:
        env = {**os.environ, "BLUEPRINT_MEMORY_LIMIT": str(budget)}
        return subprocess.run(
            [str(BLUEPRINT), "info", str(path)], capture_output=True, text=True, env=env, timeout=120
        )

    short = (count - 1) * settings.INSTANCE_BYTES
    one_error(
        info(short),
        f"{path}: its scene holds more than {count - 1} mesh instances, the most the memory budget of "
        f"{settings.human_size(short)} holds at {settings.INSTANCE_BYTES} bytes an instance "
        "(BLUEPRINT_MEMORY_LIMIT sets the budget)",
    )
    proc = info(count * settings.INSTANCE_BYTES + 12 * settings.TRIANGLE_BYTES)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.startswith(f"{path}: {12 * count} triangles, {count} parts"), proc.stdout


COPIES = 100_000


def _box_moves() -> np.ndarray:
    """(COPIES, 3) float64 translations of the boxes: a grid of 400 a row."""
    side = 400
    return np.c_[2.0 * (np.arange(COPIES) % side), 3.0 * (np.arange(COPIES) // side), np.zeros(COPIES)]


def _box_grid(path: Path, copies: int) -> Path:
    """A GLB of ``copies`` instances of one box at ``path``, on the grid of ``_box_moves``."""
    hostile = hostile_corpus()
    corners, faces = hostile.box_arrays()
    nodes = [{"mesh": 0, "translation": move} for move in _box_moves()[:copies].tolist()]
    path.write_bytes(hostile.glb(nodes, list(range(copies)), corners, faces=faces))
    return path


@needs_cli
def test_instances_are_weighed_by_their_unique_geometry(tmp_path):
    """A GLB of 10^5 instances of a box is drawn under a memory budget that refuses the same
    triangles flattened into one mesh (its unique triangles and instance records weigh far
    less than 1.2 M drawn ones). Its vector drawing, whose lines are placed instance by instance,
    is weighed by its drawn triangles and the segments placed so far, and refused in one line
    as they pass the budget. (It keeps the instances too: the tests of ``vector.instanced``
    hold that it never flattens them.)"""
    hostile = hostile_corpus()
    corners, faces = hostile.box_arrays()
    moves = _box_moves()
    kept, flat = _box_grid(tmp_path / "kept.glb", COPIES), tmp_path / "flat.glb"
    positions = (corners[None] + moves[:, None]).reshape(-1, 3)
    flat_faces = (faces[None] + 8 * np.arange(COPIES)[:, None, None]).reshape(-1, 3)
    flat.write_bytes(hostile.glb([{"mesh": 0}], [0], positions, faces=flat_faces))
    drawn = 12 * COPIES
    budget_bytes = 512 << 20
    assert 12 * settings.TRIANGLE_BYTES + COPIES * settings.INSTANCE_BYTES <= budget_bytes
    assert drawn * settings.TRIANGLE_BYTES > budget_bytes
    env = {**os.environ, "BLUEPRINT_MEMORY_LIMIT": "512M"}
    options = ["--size", "64", "64", "--max-layers", "1"]

    def render(model: Path, out: str) -> subprocess.CompletedProcess:
        command = [str(BLUEPRINT), "render", str(model), "-o", str(tmp_path / out), *options]
        return subprocess.run(command, capture_output=True, text=True, env=env, timeout=300)

    proc = render(flat, "flat.png")
    picture = drawn * settings.PICTURE_TRIANGLE_BYTES + settings.PART_BYTES
    assert picture > budget_bytes
    one_error(
        proc,
        f"{flat}: {drawn} triangles to draw (1 mesh instances) need about "
        f"{settings.human_size(picture)} of memory at {settings.PICTURE_TRIANGLE_BYTES} "
        f"bytes a triangle and {settings.PART_BYTES} an instance, more than the memory budget of 512 MiB",
    )
    proc = render(kept, "kept.png")
    assert proc.returncode == 0, proc.stderr
    assert f"{drawn} triangles" in proc.stdout
    assert (tmp_path / "kept.png").stat().st_size > 0
    # a vector drawing places, samples and occludes every instance's lines: the 12 edges of
    # each box (1.2 M) pass the budget as they are placed, and it is refused then
    proc = render(kept, "kept.svg")
    line = one_error(proc, f"{kept} as a vector drawing of 64 x 64 pixels: {drawn} triangles and ")
    placed = int(re.search(r"and (\d+) line segments placed so far need", line).group(1))
    assert placed <= 12 * COPIES
    assert drawn * settings.PLACED_TRIANGLE_BYTES + placed * settings.SEGMENT_BYTES > budget_bytes
    assert line.endswith(
        f"at {settings.PLACED_TRIANGLE_BYTES} bytes a triangle and {settings.SEGMENT_BYTES} a segment, "
        "more than the memory budget of 512 MiB (BLUEPRINT_MEMORY_LIMIT sets the budget)"
    )
    assert not (tmp_path / "kept.svg").exists()


def _instanced_prisms(path: Path, copies: int) -> int:
    """A GLB of ``copies`` instances of a round prism (smooth sides, few lines a triangle) at
    ``path``; its drawn triangles."""
    hostile = hostile_corpus()
    vertices, faces = prism(1.0, 2.0, 256)
    nodes = [{"mesh": 0, "translation": [3.0 * (k % 8), 3.0 * (k // 8), 0.0]} for k in range(copies)]
    path.write_bytes(hostile.glb(nodes, list(range(copies)), vertices, faces=faces))
    return len(faces) * copies


@needs_cli
def test_an_instanced_svg_is_weighed_by_its_placed_lines_not_its_triangles_alone(tmp_path):
    """An instanced assembly whose drawn triangles at a flat model's bytes pass the budget, but
    whose lines, placed instance by instance, are few: its SVG is drawn. Under a budget that
    its drawn triangles alone pass, it is refused in one line before any line is found."""
    model = tmp_path / "prisms.glb"
    drawn = _instanced_prisms(model, 64)
    budget_bytes = 32 << 20
    assert drawn * settings.TRIANGLE_BYTES > budget_bytes > 2 * drawn * settings.PLACED_TRIANGLE_BYTES

    def render(budget: int, out: str) -> subprocess.CompletedProcess:
        command = [str(BLUEPRINT), "render", str(model), "-o", str(tmp_path / out), "--size", "128", "128"]
        env = {**os.environ, "BLUEPRINT_MEMORY_LIMIT": str(budget)}
        return subprocess.run(command, capture_output=True, text=True, env=env, timeout=120)

    proc = render(budget_bytes, "drawn.svg")
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "drawn.svg").read_text().count(' d="M') > 64
    small = drawn * settings.PLACED_TRIANGLE_BYTES - 1
    proc = render(small, "refused.svg")
    one_error(
        proc,
        f"{model} as a vector drawing of 128 x 128 pixels: {drawn} triangles need about "
        f"{settings.human_size(drawn * settings.PLACED_TRIANGLE_BYTES)} of memory at "
        f"{settings.PLACED_TRIANGLE_BYTES} bytes a triangle, more than the memory budget of "
        f"{settings.human_size(small)} (BLUEPRINT_MEMORY_LIMIT sets the budget)",
    )
    assert not (tmp_path / "refused.svg").exists()


def test_placed_segments_are_weighed_as_each_block_is_placed(tmp_path, monkeypatch, renderer):
    """The running count of an instanced drawing's placed segments is told as each block of
    instances is placed: refused at the first count the budget does not hold, with the count
    so far, on one thread and from the pool's."""
    from blueprint import parallel
    from blueprint.vector import instanced

    model = load_model(_box_grid(tmp_path / "boxes.glb", 300))
    told = []
    placing_weighed = instanced.placing_weighed

    def counting(weigh):
        return placing_weighed(lambda count: (told.append(count), weigh(count)))

    monkeypatch.setattr(drawing, "placing_weighed", counting)
    monkeypatch.setattr(instanced, "_ROWS", 24)  # a box a block
    monkeypatch.setattr(settings, "THREADS", 1)
    options = {"size": (64, 64), "renderer": renderer, "max_layers": 1}
    drawing.draw_vector(model, **options)
    assert told == list(range(12, 12 * 300 + 1, 12))  # a box's twelve edges a block
    triangles = model.triangle_count * settings.PLACED_TRIANGLE_BYTES
    cut = told[150]
    monkeypatch.setattr(settings, "MEMORY_BUDGET", triangles + cut * settings.SEGMENT_BYTES - 1)
    told.clear()
    with pytest.raises(InputError, match=f": 3600 triangles and {cut} line segments placed so far need"):
        drawing.draw_vector(model, **options)
    assert told[-1] == cut and len(told) == 151
    monkeypatch.setattr(settings, "THREADS", 3)
    monkeypatch.setattr(parallel, "MIN_BLOCK", 1)
    with pytest.raises(InputError) as refused:
        drawing.draw_vector(model, **options)
    placed = int(re.search(r"and (\d+) line segments placed so far", str(refused.value)).group(1))
    assert cut <= placed <= 12 * 300


def test_a_vector_drawing_is_weighed_by_its_line_samples(monkeypatch, renderer):
    """The samples of a drawing's lines follow their length in pixels, not the triangles: once
    the lines are joined, their count is weighed beside the triangles and the drawing refused
    in one line, before any sample is made, where the two pass the budget; at the budget it is
    drawn. The count the error names is the count the drawing makes."""
    model = load_model(example_path())
    made = []

    def counted(*args, **kwargs):
        samples = sample_polylines(*args, **kwargs)
        made.append(len(samples.eye))
        return samples

    sample_polylines = drawing.sample_polylines
    monkeypatch.setattr(drawing, "sample_polylines", counted)
    options = {"size": (256, 256), "renderer": renderer, "spacing": 0.1, "max_layers": 2}
    drawing.draw_vector(model, **options)
    samples = made[-1]
    estimate = model.triangle_count * settings.TRIANGLE_BYTES + samples * settings.SAMPLE_BYTES
    # the samples, not the triangles, are what the budget does not hold
    assert model.triangle_count * settings.TRIANGLE_BYTES < estimate // 8
    monkeypatch.setattr(settings, "MEMORY_BUDGET", estimate)
    drawing.draw_vector(model, **options)
    assert made[-1] == samples
    monkeypatch.setattr(settings, "MEMORY_BUDGET", estimate - 1)
    with pytest.raises(InputError) as refused:
        drawing.draw_vector(model, **options)
    assert len(made) == 2  # refused before the samples were made
    assert str(refused.value) == (
        f"{model.source} as a vector drawing of 256 x 256 pixels: {model.triangle_count} triangles and "
        f"{samples} line samples need about {settings.human_size(estimate)} of memory at "
        f"{settings.TRIANGLE_BYTES} bytes a triangle and {settings.SAMPLE_BYTES} a sample, more than the "
        f"memory budget of {settings.human_size(estimate - 1)} (a smaller size takes fewer samples; "
        "BLUEPRINT_MEMORY_LIMIT sets the budget)"
    )


@needs_cli
def test_an_svg_whose_samples_pass_the_budget_is_refused_in_one_line(tmp_path):
    """A field of 20 000 boxes, whose triangles the budget holds, has more line samples than it
    holds: ``render`` to an SVG exits 2 with the one line and writes nothing."""
    copies = 20_000
    model = _box_grid(tmp_path / "boxes.glb", copies)
    budget_bytes = 256 << 20
    assert 12 * copies * (settings.PLACED_TRIANGLE_BYTES + settings.SEGMENT_BYTES) < budget_bytes
    out = tmp_path / "boxes.svg"
    proc = subprocess.run(
        [str(BLUEPRINT), "render", str(model), "-o", str(out), "--size", "256", "256", "--max-layers", "1"],
        capture_output=True,
        text=True,
        env={**os.environ, "BLUEPRINT_MEMORY_LIMIT": str(budget_bytes)},
        timeout=120,
    )
    one_error(
        proc,
        f"{model} as a vector drawing of 256 x 256 pixels: {12 * copies} triangles and ",
        "a sample, more than the memory budget of 256 MiB (a smaller size takes fewer samples",
    )
    assert list(tmp_path.iterdir()) == [model]


@needs_cli
def test_a_crowd_of_instances_in_a_few_pixels_draws_its_svg(tmp_path):
    """10^5 boxes drawn into 64 x 64 pixels, thousands of their lines' stretches in a pixel: the
    search for coincident lines looks at a bounded number each, so the SVG is written (it was
    quadratic in a pixel's crowd) and holds the lines that stay."""
    out = tmp_path / "boxes.svg"
    command = [str(BLUEPRINT), "render", str(_box_grid(tmp_path / "boxes.glb", COPIES)), "-o", str(out)]
    proc = subprocess.run(
        [*command, "--size", "64", "64", "--max-layers", "1"], capture_output=True, text=True, timeout=120
    )
    assert proc.returncode == 0, proc.stderr
    assert "polylines level 0: " in proc.stdout
    assert out.read_text().count(' d="M') >= 1


def test_an_instanced_upload_is_weighed_by_its_unique_meshes(tmp_path):
    """``budget.uploaded``: a model kept as instances uploads each mesh it places once and a
    record an instance; a flattened one its triangles."""
    hostile = hostile_corpus()
    corners, faces = hostile.box_arrays()
    nodes = [{"mesh": 0, "translation": [2.0 * k, 0.0, 0.0]} for k in range(50)]
    path = tmp_path / "rows.glb"
    path.write_bytes(hostile.glb(nodes, list(range(50)), corners, faces=faces))
    model = load_model(path)
    assert model.instances is not None
    assert budget.uploaded(model) == (12, 50)
    need = budget.frame_bytes(12, 100, 1, None, instances=50)
    assert need["mesh"] == 12 * budget.MESH_BYTES + 50 * (92 + 112)
    flat = assemble({"box": box((0, 0, 0), (1, 2, 3))})
    assert budget.uploaded(flat) == (12, 0)


def test_a_frames_gpu_memory_is_sized_by_kind():
    # 28-byte vertex records (position, normal: 3 float32 each, part: int32), three a
    # triangle at most, and three uint32 indices
    need = budget.frame_bytes(1000, 64 * 64, 2, 1 << 30)
    # a fragment of the lists: its surface, its links in the pixel's list and layers (24), and
    # where the nodes are slim its depth and face as the geometry pass writes them (8 more)
    assert need == {"mesh": 96_000, "gbuffers": 24 * 4096 * 2, "lists": 24 * 4096 * 2}
    assert budget.frame_bytes(1000, 64 * 64, 2, 1 << 30, slim=True)["lists"] == 32 * 4096 * 2
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
    # what the frame cannot do without: the mesh and the G-buffers (the A-buffer's lists give
    # way to a peel)
    need = 96 * model.triangle_count + 24 * pixels * 4
    message = str(caught.value)
    assert message.startswith(f"{model.source or 'the model'}: the frame needs about {need / 2**20:.3g} MiB")
    assert "more than the 1 MiB free on " in message
    assert drawn == []
    monkeypatch.undo()
    frame = renderer.render(model, size=(64, 64))
    assert np.asarray(frame.image).shape == (64, 64, 4)
