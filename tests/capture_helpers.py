"""Helpers the layer-capture tests share: models with many depth layers a ray, the cases every
way of capturing is compared on, and the comparison of a way switched on and off (the k-buffer,
the A-buffer, the compute rasteriser against the peel that draws the model once a layer)."""

from __future__ import annotations

import contextlib
from dataclasses import replace

import numpy as np
import pytest
import trimesh

import blueprint
from blueprint import examples
from blueprint.render.table import ABufferRow, CaptureTable, PeelRow, capture_table


# -- one way of capturing ----------------------------------------------------------------------
@contextlib.contextmanager
def one_way(renderer, way: str, abuffer=None, peel=None):
    """``renderer`` capturing every frame ``way`` (``peel``, ``k-buffer`` or ``a-buffer``)
    alone: a capture table of that way whatever its thresholds, the peel (``peel``, a
    ``PeelRow``) taking what it cannot. ``abuffer(default)`` makes the A-buffer's row from the
    device's own (None where it has none). A way the driver lacks skips the test: those are
    capabilities, and the same cases run by the other ways."""
    default = capture_table(renderer)
    peel = peel or PeelRow()
    if way == "k-buffer":
        if default.row("k-buffer") is None:
            pytest.skip(
                "this driver has neither framebuffer fetch nor fragment shader interlock: no k-buffer"
            )
        rows = (replace(default.row("k-buffer"), min_density=0.0, whole_frames=False), peel)
    elif way == "a-buffer":
        if renderer.ctx.version_code < 430:
            pytest.skip("the A-buffer needs OpenGL 4.3")
        rows = (abuffer(default.row("A-buffer")), peel)
    else:
        rows = (peel,)
    with captured_by(renderer, CaptureTable(rows, default.exact_depth)):
        yield


# every way of capturing, the A-buffer's with slim fragments and the compute rasteriser or not
WAYS = ["peel", "k-buffer", "a-buffer", "a-buffer-slim", "a-buffer-compute", "a-buffer-compute-slim"]
# the A-buffer's ways that read faces by their ID through the faces table (GpuMesh.bind_faces):
# (slim fragments, the compute rasteriser lists them)
FACES_TABLE = {
    "a-buffer-slim": (True, False),
    "a-buffer-compute": (False, True),
    "a-buffer-compute-slim": (True, True),
}
# one step of the 24-bit depth buffer: the peel reads its depths back from one, the A-buffer
# keeps them whole (abuffer_resolve.comp)
DEPTH_STEP = 1.0 / (1 << 24) * 1.01


def abuffer_row(way: str) -> ABufferRow:
    """The A-buffer row of ``way`` (an ``a-buffer`` entry of ``WAYS``), on every frame."""
    slim, compute = FACES_TABLE.get(way, (False, False))
    return ABufferRow(1 << 30, min_layers=1, slim=slim, compute_from=0 if compute else None)


def captured_way(renderer, way: str):
    """``one_way`` of an entry of ``WAYS``."""
    base = "a-buffer" if way.startswith("a-buffer") else way
    return one_way(renderer, base, abuffer=lambda _: abuffer_row(way))


# -- models ------------------------------------------------------------------------------------
def nested_boxes() -> blueprint.Model:
    """Three concentric boxes: six surfaces along every ray through the middle."""
    return examples.assemble(
        {
            "outer": examples.box((-3, -2.5, -2), (3, 2.5, 2)),
            "middle": examples.box((-2, -1.5, -1.2), (2, 1.5, 1.2)),
            "inner": examples.box((-1, -0.8, -0.5), (1, 0.8, 0.5)),
        }
    )


def nested_round() -> blueprint.Model:
    """A star prism inside a tube inside a box, on one axis: up to ten surfaces a ray."""
    return examples.assemble(
        {
            "box": examples.box((-3, -3, -3), (3, 3, 3)),
            "tube": examples.tube(1.6, 2.5, 5.0, 40),
            "star": examples.prism([1.2, 0.7], 4.0, 16),
        }
    )


def sphere_in_cube() -> blueprint.Model:
    sphere = trimesh.creation.icosphere(subdivisions=3, radius=0.8)
    return examples.assemble(
        {
            "cube": examples.box((-1, -1, -1), (1, 1, 1)),
            "sphere": (np.asarray(sphere.vertices), np.asarray(sphere.faces)),
        }
    )


def tab_in_slot(clearance: float = 1e-3) -> blueprint.Model:
    """A square tab through the square slot of a plate (both squares turned 45 degrees about
    the vertical), ``clearance`` times the bounding diagonal (6) between the tab's sides and the
    slot's walls: parts that nearly touch."""
    gap = clearance * 6.0
    return examples.assemble(
        {
            "plate": examples.tube(0.5, 2.0, 0.5, 4, axis=1),
            # a square's sides lie its corner radius over sqrt 2 from the middle
            "tab": examples.prism([0.5 - gap * np.sqrt(2.0)], 2.0, 4, axis=1),
        }
    )


def touching_blocks(step: float = 1e-3) -> blueprint.Model:
    """Two blocks side by side, touching along x = 0, their fronts flush (one plane), the left
    one's top ``step`` times the bounding diagonal lower than the right one's."""
    diag = float(np.linalg.norm([4.0, 1.0, 1.0]))
    return examples.assemble(
        {
            "left": examples.box((-2.0, -0.5, -0.5), (0.0, 0.5 - step * diag, 0.5)),
            "right": examples.box((0.0, -0.5, -0.5), (2.0, 0.5, 0.5)),
        }
    )


def planes(order: list[int]) -> blueprint.Model:
    """Squares at z = 0, -1, -2 facing the viewer, drawn in ``order``."""
    positions, faces = [], []
    for z in order:
        b = len(positions)
        positions += [(-1, -1, -z), (1, -1, -z), (1, 1, -z), (-1, 1, -z)]
        faces += [(b, b + 1, b + 2), (b, b + 2, b + 3)]
    return blueprint.Model.from_arrays(np.array(positions, np.float32), np.array(faces, np.int32))


# name: (function making the model, camera options)
CASES = {
    "nested-boxes": (nested_boxes, {}),
    "nested-round": (nested_round, dict(azimuth=20.0, elevation=35.0)),
    "sphere-in-cube": (sphere_in_cube, {}),
    "gearbox": (examples.gearbox, {}),
    "gearbox-ortho": (examples.gearbox, dict(view="front", ortho=True)),
}


# -- a way of capturing against the peel ----------------------------------------------------------
def peel_both_ways(renderer, switch, model, **options):
    """``blueprint.peel`` of ``model`` with ``switch(True)`` (a way of capturing switched on),
    then with ``switch(False)``: (on, off)."""
    switch(True)
    on = blueprint.peel(model, renderer=renderer, **options)
    switch(False)
    off = blueprint.peel(model, renderer=renderer, **options)
    return on, off


def assert_front_to_back(renderer, order: list[int]) -> None:
    """The squares of ``planes(order)`` peel nearest first, each layer one square's faces, with
    the capture the renderer is set to."""
    model = planes(order)
    camera = blueprint.Camera.fit(model.positions, "front", aspect=1.0, ortho=True)
    layers = renderer.peel(model, camera, size=(32, 32), max_layers=4)
    assert len(layers.depth) == 3
    for k, z in enumerate((0, 1, 2)):
        first_face = 2 * order.index(z)
        assert set(np.unique(layers.triangle[k])) - {-1} == {first_face, first_face + 1}
    inside = layers.depth[0] < 1.0
    assert (np.diff(layers.depth[:, inside], axis=0) > 0).all()


def normal_tolerance(renderer) -> float:
    """Normals pass through halves either way: kbuffer.glsl rounds them toward zero as
    llvmpipe's half-float targets do (the same bits there); another driver may round to
    nearest, a last-place difference."""
    return 0.0 if "llvmpipe" in renderer.info["renderer"] else 1e-3


def slim_normal_tolerance(renderer) -> float:
    """How far a slim fragment's normal (``ABufferRow.slim``: the resolve's sum of the
    corners' at the pixel centre) may lie from the rasteriser's: a half's last place (2^-11
    for a unit vector's component); where the driver snaps corners (the H200) the
    rasteriser's is taken at the snapped sample, up to 1/256 px away, which on a face seen
    edge-on moves it by more (corners snapped in the vertex shader on llvmpipe: up to 8e-3 on
    the gearbox)."""
    return 1e-2 if renderer.snapped_depth else max(2.0**-11, normal_tolerance(renderer))


def assert_same_layers(whole, split, renderer) -> None:
    """The layers of a mesh uploaded whole and drawn in chunks: depths, faces and parts to the
    bit, normals too, but where the capture table's A-buffer lists slim fragments, which a
    mesh drawn in chunks does not (its faces are not all on the GPU when the resolve would
    read them): there within ``slim_normal_tolerance``."""
    for field in ("depth", "triangle", "part"):
        assert np.array_equal(getattr(whole, field), getattr(split, field)), field
    assert (whole.normal is None) == (split.normal is None)
    if whole.normal is not None:
        row = renderer.capture_table.row("A-buffer")
        tolerance = slim_normal_tolerance(renderer) if row is not None and row.slim else 0.0
        assert np.abs(whole.normal - split.normal).max(initial=0.0) <= tolerance


@contextlib.contextmanager
def whole_fragments(renderer):
    """``renderer``'s own capture table, its A-buffer listing whole fragments (not slim):
    those a mesh drawn in chunks lists."""
    table = renderer.capture_table
    rows = tuple(replace(row, slim=False) if row.way == "A-buffer" else row for row in table.rows)
    with captured_by(renderer, CaptureTable(rows, table.exact_depth)):
        yield


@contextlib.contextmanager
def captured_by(renderer, table: CaptureTable):
    """``renderer`` capturing by ``table``, its own table again after."""
    saved = renderer.capture_table
    renderer.capture_table = table
    try:
        yield
    finally:
        renderer.capture_table = saved


def drawing_difference(use, style: str, supersample: int) -> np.ndarray:
    """(H, W): the largest channel difference between the gearbox drawn with ``use(True)`` and
    with ``use(False)`` (a capture switched on and off)."""
    images = []
    for on in (True, False):
        use(on)
        options = dict(size=(200, 150), style=style, max_layers=6, supersample=supersample)
        images.append(blueprint.render(examples.gearbox(), **options).astype(int))
    return np.abs(images[0] - images[1]).max(axis=-1)
