"""A mesh drawn in chunks (``render.mesh.ChunkedMesh``): the faces each chunk draws are the
one upload's, with their IDs, corners and instances; the layers and pictures of flattened and
instanced models drawn in several chunks are those of one upload, bit for bit, by every capture
way; a frame whose mesh does not fit the GPU's free memory beside its other buffers is drawn in
chunks sized from it (``BLUEPRINT_GPU_MEMORY`` standing in for a small GPU), and one whose other
buffers do not fit is refused in one line; the drawing's phases tell each chunk drawn."""

from __future__ import annotations

import os
import subprocess
from dataclasses import replace

import numpy as np
import pytest
import trimesh
from capture_helpers import assert_same_layers, one_way, whole_fragments
from helpers import BLUEPRINT, needs_cli, one_error
from instanced_scenes import exact_scene, mixed_scene

import blueprint
from blueprint.api import stages
from blueprint.errors import InputError
from blueprint.examples import assemble, gearbox
from blueprint.render import budget
from blueprint.render.mesh import ChunkedMesh, GpuMesh, _chunks, _used, draw_groups, joined
from blueprint.scene.model import Model

SIZE = (120, 96)
CAMERA = {"view": "iso", "azimuth": 35.0, "elevation": 25.0}


def chunked_mixed_scene() -> Model:
    """The mixed scene with its meshes used once side by side: three draw groups, each split
    by small chunks."""
    return mixed_scene(("l", "w1", "w2", "l", "wedge", "l", "wedge"))


def dense_model() -> Model:
    """Two nested spheres of 20 480 faces each (four layers through the middle), two parts."""
    parts = {}
    for k, radius in enumerate((1.0, 0.6)):
        sphere = trimesh.creation.icosphere(subdivisions=5, radius=radius)
        parts[f"shell{k}"] = (np.asarray(sphere.vertices), np.asarray(sphere.faces))
    return assemble(parts)


MODELS = {"flat": (gearbox, 500), "instanced": (exact_scene, 7), "mixed": (chunked_mixed_scene, 9)}


def drawn_faces(draws) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(face IDs (T,), corner vertices (T, 3) ``VERTEX``, transform rows (T, 3, 4)) of every
    face the ``draws`` draw, ordered by ID; ``draws`` gives (vertices, indices, instance records,
    first index, index count) a draw, each face's ID its instance's first face plus its place
    in the draw (``gl_PrimitiveID``)."""
    ids, corners, rows = [], [], []
    for vertices, indices, records, first, count in draws:
        faces = indices[first : first + count].reshape(-1, 3)
        ids.append((records["face"][:, None] + np.arange(len(faces))).ravel())
        corners.append(np.broadcast_to(vertices[faces], (len(records), *faces.shape)).reshape(-1, 3))
        placing = np.stack([records["x"], records["y"], records["z"]], axis=1)
        rows.append(np.repeat(placing, len(faces), axis=0))
    ids, corners, rows = np.concatenate(ids), np.concatenate(corners), np.concatenate(rows)
    order = np.argsort(ids, kind="stable")
    return ids[order], corners[order], rows[order]


@pytest.mark.parametrize("name", list(MODELS))
@pytest.mark.parametrize("limit", [None, 4])
def test_the_chunks_draw_the_one_uploads_faces(name, limit):
    """Every face the model draws, each once, by its ID: the same corners (positions, normals,
    parts) at the same instance's transform as one upload's draws, with chunks of consecutive
    faces that hold only the vertices they use and cross the groups' borders; with a piece
    limit, no draw of more faces than it."""
    make, chunk_faces = MODELS[name]
    model = make()
    groups = draw_groups(model, 30.0)
    vertices, indices, base, count = joined(groups)
    whole = drawn_faces(
        (vertices, indices, records, int(b), int(c))
        for (_, _, records), b, c in zip(groups, base, count, strict=True)
    )
    records = [r for _, _, r in groups]
    chunks = _chunks(vertices, indices, base // 3, count // 3, records, chunk_faces, limit)
    total = len(indices) // 3
    assert len(chunks) == -(-total // chunk_faces) >= 4
    ours = drawn_faces((v, i, piece, first, n) for v, i, draws in chunks for piece, first, n, _ in draws)
    assert np.array_equal(ours[0], np.arange(model.triangle_count))
    assert np.array_equal(whole[0], ours[0])
    assert np.array_equal(whole[1], ours[1]) and np.array_equal(whole[2], ours[2])
    for v, i, draws in chunks:
        assert len(i) <= 3 * chunk_faces and len(v) == len(np.unique(i)) and i.max() == len(v) - 1
        assert sum(n for _, _, n, _ in draws) == len(i)
        if limit is not None:
            assert max(n for _, _, n, _ in draws) <= 3 * limit
    if name != "flat":
        assert any(len(draws) > 1 for _, _, draws in chunks)  # a chunk crossing groups


@pytest.mark.parametrize("vertices", [50, 100_000])
def test_a_chunks_vertices_are_those_its_corners_use(vertices):
    """By flags over the vertices (few vertices) or by sorting (many): what ``np.unique``
    finds, the corners renumbered into them."""
    corners = np.random.default_rng(7).integers(0, vertices, 3000).astype(np.uint32)
    used, local = _used(corners, vertices)
    expected, inverse = np.unique(corners, return_inverse=True)
    assert np.array_equal(used, expected) and np.array_equal(local, inverse)
    assert local.dtype == np.uint32 and np.array_equal(used[local], corners)


@pytest.fixture(params=["peel", "k-buffer", "A-buffer"])
def way(request, renderer):
    """The renderer capturing every frame one way (a capture table of that way alone)."""
    with one_way(renderer, request.param.lower(), abuffer=lambda row: replace(row, min_layers=1)):
        yield request.param


def chunked(renderer, model: Model, chunk_faces: int | None, draw):
    """``draw(model)`` with ``model`` uploaded a chunk of ``chunk_faces`` faces at a time
    (None: whole), and the chunks it was drawn in."""
    renderer.forget(model)
    renderer.chunk_faces = chunk_faces
    try:
        out = draw(model)
        return out, renderer.capturer.chunks(model)
    finally:
        renderer.chunk_faces = None
        renderer.forget(model)


@pytest.mark.parametrize("name", list(MODELS))
def test_layers_drawn_in_chunks_are_one_uploads(way, renderer, name):
    """Depths, normals, faces and parts of every layer, to the bit (normals within a half's
    last place where the whole mesh's A-buffer lists slim fragments: ``assert_same_layers``)."""
    make, chunk_faces = MODELS[name]
    model = make()

    def peel(m):
        return blueprint.peel(m, size=SIZE, renderer=renderer, max_layers=None, **CAMERA)

    whole, none = chunked(renderer, model, None, peel)
    split, chunks = chunked(renderer, model, chunk_faces, peel)
    assert none == 0 and chunks == -(-len(joined(draw_groups(model, None))[1]) // (3 * chunk_faces)) >= 4
    assert whole.depth.shape == split.depth.shape and whole.depth.shape[0] >= 3
    assert_same_layers(whole, split, renderer)
    assert set(np.unique(split.part[split.part >= 0])) == set(range(len(model.part_names)))


@pytest.mark.parametrize("name", list(MODELS))
def test_a_picture_drawn_in_chunks_is_one_uploads(renderer, name):
    """The PNG of the device's own capture (on llvmpipe the A-buffer, all layers), byte for
    byte, its A-buffer listing whole fragments as it does a chunked mesh's (its slim nodes and
    compute rasteriser read the mesh after the geometry pass; a slim node's normal may lie a
    half's last place from the rasteriser's, and tip an edge: test_layers_drawn_in_chunks_...)."""
    make, chunk_faces = MODELS[name]
    model = make()

    def png(m):
        return blueprint.draw(m, size=(160, 120), max_layers=0, **CAMERA).png()

    with whole_fragments(renderer):
        whole, _ = chunked(renderer, model, None, png)
        split, chunks = chunked(renderer, model, chunk_faces, png)
    assert chunks >= 4 and split == whole


def test_a_frame_is_chunked_to_the_gpus_free_memory(renderer, monkeypatch):
    """Free memory for the G-buffers, the lists and a third of the mesh: the mesh is drawn in
    three chunks of the faces that fit, the picture that of the whole mesh; the drawing's
    phases tell each chunk drawn (``stages.watch``)."""
    model = dense_model()
    triangles = model.triangle_count
    pixels, layers = 96 * 96, 8
    row = renderer.capture_table.row("A-buffer")
    need = budget.frame_bytes(triangles, pixels, layers, row.max_bytes, slim=row.slim)
    assert need["mesh"] == budget.MESH_BYTES * triangles
    third = -(-triangles // 3)
    free = need["gbuffers"] + need["lists"] + budget.MESH_BYTES * third
    # the mesh's outline: its smooth contour lines need it whole (a mesh drawn in chunks keeps
    # its outline, test_contour_gpu)
    options = {"size": (96, 96), "supersample": 1, "max_layers": layers, "smooth_contours": False, **CAMERA}
    whole = np.asarray(blueprint.draw(model, **options).image)
    assert renderer.capturer.chunks(model) == 0
    renderer.forget(model)
    model = dense_model()  # a frame like the last one checked is not checked again
    monkeypatch.setenv(budget.GPU_MEMORY_ENV, str(free))
    told = []
    try:
        with stages.listen(lambda name, detail=None: told.append((name, detail))):
            stages.watch(renderer)
            frame = blueprint.draw(model, **options)
        mesh = renderer.mesh(model, 30.0)
        assert isinstance(mesh, ChunkedMesh) and mesh.chunk_faces == third
        assert renderer.capturer.chunks(model) == 3
        assert np.array_equal(np.asarray(frame.image), whole)
        assert ("capture_edges", None) in told
        assert [d for n, d in told if d] == [f"chunk {k} of 3" for k in (1, 2, 3)]
        # a smaller frame of the same model fits whole: the chunks uploaded serve it
        monkeypatch.delenv(budget.GPU_MEMORY_ENV)
        blueprint.draw(model, **{**options, "size": (64, 64)})
        assert renderer.mesh(model, 30.0) is mesh
    finally:
        vars(renderer.capturer).pop("mesh", None)  # stages.watch's timing of uploads
        renderer.forget(model)
    # too little for the G-buffers beside a chunk of the fewest faces, the lists given way:
    # refused
    least = need["gbuffers"] + budget.MESH_BYTES * budget.MIN_CHUNK_FACES
    monkeypatch.setenv(budget.GPU_MEMORY_ENV, str(least - 1))
    with pytest.raises(InputError, match="the frame needs about .* of GPU memory"):
        blueprint.draw(dense_model(), **options)
    monkeypatch.setenv(budget.GPU_MEMORY_ENV, "lots")
    with pytest.raises(InputError, match="BLUEPRINT_GPU_MEMORY='lots' is not a size"):
        blueprint.draw(dense_model(), **options)


def test_the_chunk_setting_takes_positive_face_counts(renderer):
    for bad in (0, -5, 2.5, True, "100"):
        with pytest.raises(InputError, match="chunk_faces must be a positive whole number"):
            renderer.chunk_faces = bad
    assert renderer.chunk_faces is None
    model = gearbox()
    renderer.chunk_faces = 1000
    try:
        assert isinstance(renderer.mesh(model, None), ChunkedMesh)
        assert renderer.capturer.chunks(model) == 3
        renderer.chunk_faces = None
        # chunks uploaded before serve until the model is forgotten
        assert isinstance(renderer.mesh(model, None), ChunkedMesh)
        renderer.forget(model)
        assert type(renderer.mesh(model, None)) is GpuMesh
    finally:
        renderer.chunk_faces = None
        renderer.forget(model)


@needs_cli
def test_the_cli_draws_in_chunks_or_refuses_in_one_line(renderer, tmp_path):
    """``blueprint render`` under a ``BLUEPRINT_GPU_MEMORY`` that leaves room for a quarter of
    the mesh: the same PNG, drawn in four chunks, as it says; under one that leaves none for
    the G-buffers: one line, exit 2, nothing written."""
    model = dense_model()
    path = tmp_path / "shells.ply"
    trimesh.Trimesh(model.positions, model.faces, process=False).export(path)
    triangles = model.triangle_count
    pixels = 128 * 128
    # the lists' cap (the A-buffer row's) is far above a 128² frame's on every device; the
    # command opens the device this process has, with its table
    row = renderer.capture_table.row("A-buffer")
    need = budget.frame_bytes(triangles, pixels, 8, 1 << 30 if row else None, slim=bool(row and row.slim))
    free = need["gbuffers"] + need["lists"] + budget.MESH_BYTES * (triangles // 4)

    def render(out: str, gpu_memory: int | None) -> subprocess.CompletedProcess:
        env = {k: v for k, v in os.environ.items() if k != budget.GPU_MEMORY_ENV}
        if gpu_memory is not None:
            env[budget.GPU_MEMORY_ENV] = str(gpu_memory)
        # (the mesh's outline: a mesh drawn in chunks keeps it where its lines would be)
        options = ["--size", "128", "128", "--supersample", "1", "--max-layers", "8", "--no-smooth-contours"]
        command = [str(BLUEPRINT), "render", str(path), "-o", str(tmp_path / out), *options]
        return subprocess.run(command, capture_output=True, text=True, env=env, timeout=300)

    whole, split = render("whole.png", None), render("split.png", free)
    assert whole.returncode == 0 and split.returncode == 0, (whole.stderr, split.stderr)
    assert "drawn in" not in whole.stdout and ", 4 layers, drawn in 4 chunks, " in split.stdout
    assert (tmp_path / "whole.png").read_bytes() == (tmp_path / "split.png").read_bytes()
    proc = render("refused.png", need["gbuffers"])
    one_error(proc, f"{path}: the frame needs about", "of GPU memory", "free on")
    assert not (tmp_path / "refused.png").exists()
