"""Every route that uploads a model sizes its frame first (``Capturer.check_memory``): under a
``BLUEPRINT_GPU_MEMORY`` that holds the route's other buffers and a third of the mesh, the vector
drawings (from the faces k-buffer, the layers copied a pass a layer, or the faces read back at
the probed pixels), the layers read back (``blueprint.peel``) and the GPU silhouettes draw the
mesh in chunks and give what one upload gives, to the byte; under one that does not hold those
buffers they are refused in one line before anything is uploaded; and the commands ``render
x.svg``, ``layers`` and ``silhouettes`` do the same, exit 2 and no file where refused."""

from __future__ import annotations

import os
import subprocess
from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest
import trimesh
from capture_helpers import assert_same_layers, one_way
from helpers import BLUEPRINT, needs_cli, one_error

import blueprint
from blueprint.errors import InputError
from blueprint.examples import assemble, box
from blueprint.gpu_silhouettes import GpuSilhouettes
from blueprint.gpu_silhouettes.draw import LINES
from blueprint.pipeline import load_pipeline
from blueprint.render import budget
from blueprint.scene.camera import fit_camera
from blueprint.scene.model import Model

SIZE = (120, 96)
CAMERA = {"view": "iso", "azimuth": 35.0, "elevation": 25.0}


def ball_and_bar() -> Model:
    """A sphere of 20 480 faces pierced by a bar (12): four layers through the middle, creases,
    silhouettes and the lines where the parts cut each other; a third of its faces is more than
    ``budget.MIN_CHUNK_FACES``."""
    sphere = trimesh.creation.icosphere(subdivisions=5, radius=1.0)
    return assemble(
        {
            "ball": (np.asarray(sphere.vertices), np.asarray(sphere.faces)),
            "bar": box((-1.4, -0.3, -0.25), (1.4, 0.3, 0.25)),
        }
    )


def room(
    renderer, model: Model, pixels: int, max_layers: int | None, mesh_faces: int, extra=None, lists=True
) -> int:
    """Bytes of GPU memory that hold a frame's buffers (``budget.frame_bytes`` as the frame
    sizes them, under the renderer's capture table; the A-buffer's lists left out unless
    ``lists``) and ``mesh_faces`` faces of its mesh."""
    row = renderer.capture_table.row("A-buffer")
    need = budget.frame_bytes(
        model.triangle_count,
        pixels,
        max_layers,
        row.max_bytes if row else None,
        extra=extra,
        slim=bool(row and row.slim),
    )
    held = sum(need.values()) - need["mesh"] - (0 if lists else need["lists"])
    return held + budget.MESH_BYTES * mesh_faces


def occlusion(model: Model, size, max_layers: int | None) -> dict[str, int]:
    """What a vector drawing's occlusion allocates beside the capture: its table of face
    planes (four float32 a face and one for none, in rows of 4 096) and, with a layer cap, a
    copy of each layer's faces (int32 a pixel)."""
    planes = {"planes": 16 * 4096 * -(-(model.triangle_count + 1) // 4096)}
    return planes if max_layers is None else {**planes, "copies": 4 * size[0] * size[1] * max_layers}


def third(model: Model) -> int:
    return -(-model.triangle_count // 3)


@pytest.fixture
def uploads(renderer, monkeypatch):
    """The models ``renderer`` is asked to upload from now on (``Capturer.mesh``)."""
    asked = []
    capturer = renderer.capturer
    upload = type(capturer).mesh

    def recorded(self, model, crease_angle):
        asked.append(model)
        return upload(self, model, crease_angle)

    monkeypatch.setattr(type(capturer), "mesh", recorded)
    return asked


@pytest.fixture(params=["peel", "k-buffer", "A-buffer"])
def way(request, renderer):
    """The renderer capturing every frame one way (a capture table of that way alone)."""
    with one_way(renderer, request.param.lower(), abuffer=lambda row: replace(row, min_layers=1)):
        yield request.param


def routes_taken(renderer, monkeypatch) -> list[str]:
    """The renderer's layer routes a vector drawing calls from now on, by name."""
    taken = []
    kind = type(renderer)
    for name in ("face_kbuffer", "each_face_layer", "triangles_at"):
        original = getattr(kind, name)

        def recorded(self, *args, _name=name, _original=original, **kwargs):
            taken.append(_name)
            return _original(self, *args, **kwargs)

        monkeypatch.setattr(kind, name, recorded)
    return taken


def drawn(renderer, make, draw, free: int | None, monkeypatch):
    """``draw(model)`` of a new ``make()`` (a model no frame has checked) under ``free`` bytes
    of GPU memory (None: the device's own), and the chunks its mesh was drawn in."""
    model = make()
    if free is None:
        monkeypatch.delenv(budget.GPU_MEMORY_ENV, raising=False)
    else:
        monkeypatch.setenv(budget.GPU_MEMORY_ENV, str(free))
    try:
        return draw(model), renderer.capturer.chunks(model)
    finally:
        monkeypatch.delenv(budget.GPU_MEMORY_ENV, raising=False)
        renderer.forget(model)


@pytest.mark.parametrize("max_layers", [None, 4])
def test_an_svg_drawn_in_chunks_is_one_uploads(way, renderer, max_layers, monkeypatch):
    """The SVG's bytes, by every capture way: the faces k-buffer, the layers copied a pass a
    layer, the faces read back at the probed pixels; levels behind three surfaces drawn."""
    taken = routes_taken(renderer, monkeypatch)

    def svg(model):
        drawing = blueprint.draw(model, size=SIZE, max_layers=max_layers, vector=True, **CAMERA)
        return drawing.svg(), drawing.lines.lines_per_level()

    (whole, levels), none = drawn(renderer, ball_and_bar, svg, None, monkeypatch)
    routes = sorted(set(taken))
    taken.clear()
    model = ball_and_bar()
    free = room(
        renderer, model, SIZE[0] * SIZE[1], max_layers, third(model), occlusion(model, SIZE, max_layers)
    )
    (split, _), chunks = drawn(renderer, ball_and_bar, svg, free, monkeypatch)
    assert none == 0 and chunks == 3
    assert sorted(set(taken)) == routes
    assert split == whole and max(levels) >= 3
    # the faces k-buffer is asked first; where it draws none (a capture that is no k-buffer,
    # one through fragment shader interlock, or one pass that does not find every layer) the
    # layers' faces are read back at the probed pixels without a cap, and copied on the GPU a
    # layer a pass with one
    row = renderer.capture_table.row("k-buffer")
    kbuffer = way == "k-buffer" and max_layers is not None and not row.interlock
    expected = (
        ["face_kbuffer"]
        if kbuffer
        else sorted(["face_kbuffer", "triangles_at" if max_layers is None else "each_face_layer"])
    )
    assert routes == expected


@pytest.mark.parametrize("normals", [True, False])
def test_layers_read_back_in_chunks_are_one_uploads(renderer, normals, monkeypatch):
    """``blueprint.peel``'s depths, normals, faces and parts, to the bit (normals within a
    half's last place where the whole mesh's A-buffer lists slim fragments)."""

    def peel(model):
        return blueprint.peel(model, size=SIZE, max_layers=None, normals=normals, **CAMERA)

    whole, none = drawn(renderer, ball_and_bar, peel, None, monkeypatch)
    model = ball_and_bar()
    split, chunks = drawn(
        renderer,
        ball_and_bar,
        peel,
        room(renderer, model, SIZE[0] * SIZE[1], None, third(model)),
        monkeypatch,
    )
    assert none == 0 and chunks == 3 and len(whole.depth) >= 4
    assert_same_layers(whole, split, renderer)
    assert (whole.normal is None) == (not normals)


@pytest.mark.parametrize("method", [LINES, "vertex", "idlist"])
def test_silhouettes_drawn_in_chunks_are_one_uploads(renderer, method, monkeypatch):
    """The silhouette images of 2 layers, each method, to the bit; the room counts the
    silhouettes' own tables and targets, which are not drawn in chunks."""
    layers = 2
    camera = fit_camera(ball_and_bar(), SIZE, "iso")

    def images(model):
        with GpuSilhouettes(renderer) as sil:
            return sil.render(model, camera, SIZE, layers, method)

    whole, none = drawn(renderer, ball_and_bar, images, None, monkeypatch)
    model = ball_and_bar()
    with GpuSilhouettes(renderer) as sil:
        tables = sil._tables.to_upload(model, lists=method == "idlist", edges=method == LINES)
    extra = {"targets": SIZE[0] * SIZE[1] * layers, **tables}
    free = room(renderer, model, SIZE[0] * SIZE[1], 1, third(model), extra)
    split, chunks = drawn(renderer, ball_and_bar, images, free, monkeypatch)
    assert none == 0 and chunks == 3
    assert whole.shape == (layers, SIZE[1], SIZE[0]) and whole[0].sum() > 0 and whole[1].sum() > 0
    assert np.array_equal(whole, split)


def test_the_silhouettes_tables_are_sized_by_what_is_not_held_yet(renderer):
    """Corners (a buffer and its texture, padded rows of 4 096 entries of 12 bytes), edge
    records (at most three a face, 16 bytes each), ID lists; none of those held already."""
    model = ball_and_bar()
    faces = model.triangle_count
    rows = -(-3 * faces // 4096)
    with GpuSilhouettes(renderer) as sil:
        tables = sil._tables
        assert tables.to_upload(model, lists=False, edges=False) == {"corners": 2 * rows * 4096 * 12}
        assert tables.to_upload(model, lists=True, edges=True) == {
            "corners": 2 * rows * 4096 * 12,
            "edge records": 3 * faces * 16,
            "ID lists": 4096 * (12 * -(-faces // 4096) + 12 * rows),
        }
        sil.render(model, None, (32, 32), 1, LINES)
        assert tables.to_upload(model, lists=True, edges=True) == {
            "ID lists": 4096 * (12 * -(-faces // 4096) + 12 * rows)
        }
        renderer.forget(model)


@pytest.mark.parametrize(
    "route",
    ["svg", "peel", "silhouettes", "picture"],
)
def test_a_route_whose_buffers_do_not_fit_is_refused_before_any_upload(renderer, route, uploads, monkeypatch):
    """Room for the mesh whole but not for the route's other buffers (G-buffers, lists, the
    silhouettes' tables): one line naming the model and the bytes needed and free, nothing
    uploaded."""
    model = replace(ball_and_bar(), source="ball-and-bar.ply")
    pixels = SIZE[0] * SIZE[1]
    monkeypatch.setenv(budget.GPU_MEMORY_ENV, str(budget.MESH_BYTES * model.triangle_count + pixels))
    draws = {
        "svg": lambda: blueprint.draw(model, size=SIZE, max_layers=4, vector=True, **CAMERA).svg(),
        "peel": lambda: blueprint.peel(model, size=SIZE, **CAMERA),
        "silhouettes": lambda: GpuSilhouettes(renderer).render(model, None, SIZE, 2, LINES),
        "picture": lambda: blueprint.draw(model, size=SIZE, supersample=1, **CAMERA).png(),
    }
    with pytest.raises(InputError) as caught:
        draws[route]()
    message = str(caught.value)
    assert message.startswith("ball-and-bar.ply: the frame needs about ") and "\n" not in message
    assert "of GPU memory (mesh " in message and "free on " in message
    assert uploads == [] and renderer.capturer.chunks(model) == 0


TWO_SCALES = """
[pipeline]
output = "mark"
layers = 3
[attributes]
depth = { scale = 2 }
triangle = {}
[passes.mark]
op = "id_edges"
inputs = { ids = "triangle" }
per_layer = true
"""


def test_a_pipelines_run_is_sized_by_its_g_buffers(renderer, tmp_path, uploads, monkeypatch):
    """A pipeline of attributes at two scales (a G-buffer each), run by the executor alone:
    drawn in the chunks the room left beside both G-buffers allows, its output and dumps one
    upload's to the bit; refused before any upload where the G-buffers do not fit."""
    path = tmp_path / "two.toml"
    path.write_text(TWO_SCALES, encoding="utf-8")
    spec = load_pipeline(str(path))
    w, h = SIZE
    camera = fit_camera(ball_and_bar(), SIZE, "iso")

    def run(model):
        result = renderer.executor.run(spec, model, camera, size=SIZE, dumps=("depth", "triangle"))
        return result.output, result.dumps

    (whole, dumps), none = drawn(renderer, ball_and_bar, run, None, monkeypatch)
    model = ball_and_bar()
    free = room(renderer, model, 4 * w * h + w * h, 3, third(model))
    (split, split_dumps), chunks = drawn(renderer, ball_and_bar, run, free, monkeypatch)
    assert none == 0 and chunks == 3
    assert whole.shape[0] == 3 and whole.any() and np.array_equal(whole, split)
    assert dumps["depth"].shape[1:3] == (2 * h, 2 * w)
    for name in dumps:
        assert np.array_equal(dumps[name], split_dumps[name]), name
    uploads.clear()
    # too little for the G-buffers beside a chunk of the fewest faces, the lists given way
    least = room(renderer, model, 4 * w * h + w * h, 3, budget.MIN_CHUNK_FACES, lists=False)
    monkeypatch.setenv(budget.GPU_MEMORY_ENV, str(least - 1))
    with pytest.raises(InputError, match="the frame needs about .* of GPU memory"):
        run(ball_and_bar())
    assert uploads == []


def test_a_frame_checked_once_is_not_asked_again(renderer, monkeypatch):
    """The picture's own check and its run's size the same frame: the device is asked once a
    frame, not again for the next frame like it (a picture without contour lines: their passes,
    which run before the frame, size their own memory)."""
    asked = []
    free = budget.free_gpu_memory
    monkeypatch.setattr(budget, "free_gpu_memory", lambda device: asked.append(1) or free(device))
    model = ball_and_bar()
    try:
        for _ in range(2):
            blueprint.draw(model, size=(64, 48), supersample=2, smooth_contours=False, **CAMERA).png()
        assert len(asked) == 1
    finally:
        renderer.forget(model)


@needs_cli
@pytest.mark.parametrize("command", ["svg", "layers", "silhouettes"])
def test_the_commands_draw_in_chunks_or_refuse_in_one_line(renderer, tmp_path, command):
    """``render x.svg``, ``layers`` and ``silhouettes`` under a ``BLUEPRINT_GPU_MEMORY`` that
    leaves room for a quarter of the mesh (beside the frame's buffers as the device's capture
    table sizes them): the same file as under the device's own memory; under one that leaves
    none for the G-buffers: one line, exit 2, nothing written."""
    model = ball_and_bar()
    path = tmp_path / "ball.ply"
    trimesh.Trimesh(model.positions, model.faces, process=False).export(path)
    size, layers, triangles = 128, 4, model.triangle_count
    pixels = size * size
    if command == "silhouettes":
        edges = 2 * -(-3 * triangles // 4096) * 4096 * 12 + 3 * triangles * 16
        sized, extra = 1, {"other": pixels * layers + edges}
    else:
        sized, extra = layers, occlusion(model, (size, size), layers) if command == "svg" else None
    quarter = room(renderer, model, pixels, sized, triangles // 4, extra=extra)
    gbuffers = budget.frame_bytes(triangles, pixels, sized, None)["gbuffers"]
    suffix = {"svg": "svg", "layers": "npz", "silhouettes": "png"}[command]
    arguments = {
        "svg": ["render", "--max-layers", str(layers)],
        "layers": ["layers", "--max-layers", str(layers)],
        "silhouettes": ["silhouettes", "--layers", str(layers), "--method", "gpu-edges"],
    }[command]

    def run(out: str, gpu_memory: int | None) -> subprocess.CompletedProcess:
        env = {k: v for k, v in os.environ.items() if k != budget.GPU_MEMORY_ENV}
        if gpu_memory is not None:
            env[budget.GPU_MEMORY_ENV] = str(gpu_memory)
        target = tmp_path / f"{out}.{suffix}"
        line = [str(BLUEPRINT), arguments[0], str(path), "-o", str(target), "--size", str(size), str(size)]
        return subprocess.run(line + arguments[1:], capture_output=True, text=True, env=env, timeout=300)

    whole, split = run("whole", None), run("split", quarter)
    assert whole.returncode == 0 and split.returncode == 0, (whole.stderr, split.stderr)
    assert "drawn in" not in whole.stdout and ", drawn in 4 chunks" in split.stdout
    whole_file, split_file = (tmp_path / f"{name}.{suffix}" for name in ("whole", "split"))
    if command == "layers":
        # the normals within a half's last place where the device's A-buffer lists slim
        # fragments, which a mesh drawn in chunks does not
        with np.load(whole_file) as ours, np.load(split_file) as theirs:
            assert_same_layers(SimpleNamespace(**ours), SimpleNamespace(**theirs), renderer)
    else:
        assert whole_file.read_bytes() == split_file.read_bytes()
    proc = run("refused", gbuffers // 2)
    one_error(proc, f"{path}: the frame needs about", "of GPU memory", "free on")
    assert not (tmp_path / f"refused.{suffix}").exists()
