"""What a frame holds on the GPU: the G-buffer's targets are made when first used, so a capture
that leaves its layers where it found them (an A-buffer's lists, a k-buffer's surfaces read in
place) holds none of them, nor the A-buffer's depth targets; its readers' second cursor is the
lists' heads; the memory guard (``budget.frame_bytes``) counts at least what each way of
capturing holds, summed from the pool's own record of every target and buffer; and the first
lists of a scene kept as instances are sized by the fragments its placed faces foretell."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from capture_helpers import one_way
from instanced_scenes import flattened, mixed_scene

import blueprint
from blueprint import settings
from blueprint.examples import gearbox
from blueprint.gpu.targets import FORMATS, INTERNAL_FORMATS
from blueprint.render import abuffer, budget
from blueprint.render import renderer as renderer_module
from blueprint.render.abuffer import placed_fragments, projected_fragments
from blueprint.render.gbuffer import gbuffer
from blueprint.scene.camera import fit_camera
from blueprint.scene.loader import model_from_object

CAMERA = {"view": "iso", "azimuth": 35.0, "elevation": 25.0}


def target_bytes(key: tuple) -> int:
    """Bytes of a pool texture from its key (size (with slices), format): depth textures are
    four bytes a texel."""
    size, fmt = key[0], key[1]
    if fmt == "depth":
        per = 4
    else:
        components, dtype = {**FORMATS, **INTERNAL_FORMATS}[fmt]
        per = components * int(dtype[1:])
    return per * int(np.prod(size))


def frame_targets(pool, size: tuple[int, int]) -> dict[str, tuple]:
    """The pool's textures at ``size`` and those named by it (the A-buffer's lists, kept in rows
    of their own), name -> key."""
    named = f"{size[0]}x{size[1]}"
    return {
        name: key
        for name, (key, _) in pool._textures.items()
        if tuple(key[0][:2]) == tuple(size) or named in name
    }


def frame_buffers(pool, size: tuple[int, int]) -> dict[str, int]:
    named = f"{size[0]}x{size[1]}"
    return {name: nbytes for name, (nbytes, _) in pool._buffers.items() if named in name}


def test_a_gbuffers_targets_are_made_when_first_used(renderer):
    pool = renderer.pool
    gb = gbuffer(pool, (40, 30), "test.lazy")
    assert gb.size == (40, 30)
    assert not [name for name in pool._textures if name.startswith("test.lazy.")]
    assert gb.ids.size == (40, 30)
    assert [name for name in pool._textures if name.startswith("test.lazy.")] == ["test.lazy.ids"]
    assert pool._textures["test.lazy.ids"][0] == ((40, 30), "rg32i")
    first, second = gb.depth
    assert first.size == second.size == (40, 30) and first is not second
    assert gb.layer_depth(3) is second
    gb.fbos  # noqa: B018 (the framebuffers take the normal target too)
    made = sorted(name for name in pool._textures if name.startswith("test.lazy."))
    assert made == ["test.lazy.depth0", "test.lazy.depth1", "test.lazy.ids", "test.lazy.normal"]
    assert pool._textures["test.lazy.normal"][0] == ((40, 30), "rgba16f")
    # the A-buffer's depth targets stand in where it unpacked its layers: made when first read
    made_flat = []
    gb.flat = lambda: made_flat.append(1) or ("flat0", "flat1")
    assert gb.layer_depth(2) == "flat0" and gb.layer_depth(1) == "flat1" and made_flat == [1]
    ids_only = gbuffer(pool, (40, 30), "test.lazy.idb", normals=False)
    assert ids_only.normal is None and ids_only.ids is not None
    assert pool._textures["test.lazy.idb.ids"][0] == ((40, 30), "r32i")
    assert "test.lazy.idb.normal" not in pool._textures


@pytest.mark.parametrize(
    ("way", "max_layers", "size", "holds"),
    [
        # llvmpipe's own table: every layer from the A-buffer, read from its lists
        (None, 0, (136, 104), "abuffer.136x104.nodes"),
        # ...and a capped frame from one k-buffer pass, read from its surfaces
        (None, 4, (138, 104), "kbuffer.138x104"),
        ("peel", 8, (140, 104), None),
        ("k-buffer", 8, (142, 104), "kbuffer.142x104.0"),
    ],
)
def test_a_frame_holds_its_ways_targets_alone(renderer, way, max_layers, size, holds):
    """Each way's frame at a size no other frame takes (so that the pool's targets at it are
    this frame's): the targets it holds, and the memory guard's count of the frame (G-buffers
    and lists) no less than their bytes."""
    if renderer.ctx.version_code < 430 or not renderer.device.software:
        pytest.skip("the ways chosen here are llvmpipe's (framebuffer fetch, the A-buffer)")
    model = gearbox()
    options = {"size": size, "supersample": 1, "max_layers": max_layers, **CAMERA}
    if way is None:
        blueprint.draw(model, **options)
    else:
        with one_way(renderer, way):
            blueprint.draw(model, **options)
    pool = renderer.pool
    held = frame_targets(pool, size)
    gbuffer_targets = {"gb.depth0", "gb.depth1", "gb.normal", "gb.ids"}
    if holds is not None:
        assert [name for name in held if name.startswith(holds)], held
    if way == "peel" or way == "k-buffer":
        # layers unpacked into the G-buffer, a layer at a time
        assert gbuffer_targets <= set(held)
    else:
        assert not gbuffer_targets & set(held)
        named = f"abuffer.{size[0]}x{size[1]}"
        assert not {f"{named}.depth0", f"{named}.depth1", f"{named}.cursor.next"} & set(held)
    table = renderer.capture_table.row("A-buffer")
    need = budget.frame_bytes(0, size[0] * size[1], max_layers, table.max_bytes if table else None)
    holding = sum(target_bytes(key) for key in held.values()) + sum(frame_buffers(pool, size).values())
    assert 0 < holding <= need["gbuffers"] + need["lists"]


def test_placed_fragments_are_the_flattened_scenes(monkeypatch):
    """The fragments foretold of a scene kept as instances are those of its flattened twin,
    whatever the block of faces placed at a time (one block, and blocks that cut instances
    apart, on one thread or side by side); None where a corner lies behind the eye."""
    model = mixed_scene()
    twin = flattened(mixed_scene())
    size = (160, 120)
    camera = fit_camera(twin, size)
    expected = projected_fragments(twin.positions, twin.faces, camera, size)
    assert expected > 0
    assert placed_fragments(model.instances, camera, size) == pytest.approx(expected, rel=1e-5)
    monkeypatch.setattr(abuffer, "PLACED_BLOCK", 7)
    assert len(twin.faces) > 7 * 3
    monkeypatch.setattr(settings, "THREADS", 1)
    one_thread = placed_fragments(model.instances, camera, size)
    assert one_thread == pytest.approx(expected, rel=1e-5)
    # the blocks side by side: the same sum, bit for bit
    monkeypatch.setattr(settings, "THREADS", 3)
    assert placed_fragments(model.instances, camera, size) == one_thread
    inside = blueprint.Camera(eye=(0, 0, 0), target=(0, 0, -1), up=(0, 1, 0), near=0.01, far=9)
    assert placed_fragments(model.instances, inside, size) is None
    assert not model.is_flat


def test_a_scene_kept_as_instances_starts_with_the_room_its_fragments_foretell(renderer, monkeypatch):
    """On a software rasteriser the first lists of a scene kept as instances hold the
    fragments foretold (``placed_fragments``) with a counted room's spare, the scene never
    flattened; one geometry pass holds them."""
    if renderer.ctx.version_code < 430 or not renderer.device.software:
        pytest.skip("the lists live in the host's memory on a software rasteriser alone")
    model = mixed_scene()
    size = (144, 104)
    camera = fit_camera(model, size)
    renderer.abuffer_room.pop(size, None)
    foretold = placed_fragments(model.instances, camera, size)
    assert foretold < abuffer.FIRST_ROOM * size[0] * size[1]
    rooms = []
    buffers = abuffer.ABufferSource._buffers

    def listed(self, name, room=None):
        rooms.append(room)
        return buffers(self, name, room)

    monkeypatch.setattr(abuffer.ABufferSource, "_buffers", listed)
    with one_way(renderer, "a-buffer", abuffer=lambda row: row):
        renderer.peel(model, camera, size=size, max_layers=None)
    assert [r for r in rooms if r is not None] == [abuffer.spare_room(foretold)]
    drawn = (renderer.abuffer_room[size] - 1024) / 1.25
    assert drawn == pytest.approx(foretold, rel=0.02)
    assert not model.is_flat


def nested_boxes(count: int = 40) -> blueprint.Model:
    """Boxes one inside the next, each a part: 2 * ``count`` layers at the centre."""
    boxes = [trimesh.creation.box(extents=(k, 0.8 * k, 0.6 * k)) for k in range(1, count + 1)]
    return model_from_object(trimesh.Scene(boxes), name="nested boxes")


def list_bytes(pool, size: tuple[int, int]) -> int:
    """Bytes the pool holds for the A-buffer's lists at ``size``: each fragment's node, links
    and, where slim, its depth and face (abuffer.ABufferSource._buffers), in images or buffers."""
    parts = tuple(f"abuffer.{size[0]}x{size[1]}.{part}" for part in ("nodes", "links", "order", "slim"))
    images = [key for name, key in frame_targets(pool, size).items() if name in parts]
    return sum(map(target_bytes, images)) + sum(
        n for name, n in frame_buffers(pool, size).items() if name in parts
    )


@pytest.mark.parametrize("guess", ["foretold", "a GPU's"])
def test_a_deep_models_lists_take_no_more_than_the_memory_check_leaves(renderer, monkeypatch, guess):
    """Free GPU memory for the mesh, the G-buffers and a third of what the A-buffer holds for
    every layer of 40 nested boxes (80 layers at the centre; the guard counts the lists as a
    fragment a pixel a layer of the 8 a pass holds, short of that): the A-buffer of a renderer
    that starts afresh holds no more than that third, and the frame, peeled instead, draws
    what the A-buffer draws with room enough. Its first room is the fragments the faces'
    areas foretell (a software rasteriser's) or ``FIRST_ROOM`` a pixel (a GPU's), too little:
    the room it then learns is not lists it holds."""
    if renderer.capture_table.row("A-buffer") is None:
        pytest.skip("no A-buffer (OpenGL 4.3)")
    size = (146, 106)
    options = {"size": size, "supersample": 1, "max_layers": 0, **CAMERA}
    asked = []

    def spied(*args, **kwargs):
        asked.append(budget.frame_bytes(*args, **kwargs))
        return asked[-1]

    monkeypatch.setattr(renderer_module, "frame_bytes", spied)
    model = nested_boxes()
    roomy = np.asarray(blueprint.draw(model, **options).image)
    assert renderer.executor.last_run.groups[0].capture.way == "A-buffer"
    need, listed = asked[-1], list_bytes(renderer.pool, size)
    assert 0 < need["lists"] < listed
    renderer.forget(model)
    left = listed // 3
    monkeypatch.setattr(budget, "free_gpu_memory", lambda device: sum(need.values()) - need["lists"] + left)
    with blueprint.Renderer() as fresh:
        monkeypatch.setattr(blueprint.api, "_renderer", fresh)
        if guess == "a GPU's":
            fresh.abuffer_room[size] = abuffer.FIRST_ROOM * size[0] * size[1]
        model = nested_boxes()
        tight = np.asarray(blueprint.draw(model, **options).image)
        assert fresh.capturer.list_room == left
        assert fresh.executor.last_run.groups[0].capture.way == "peel"
        assert list_bytes(fresh.pool, size) <= left
        # the same frame again is not checked again: the lists it allocated came out of the
        # room, and it is drawn without the A-buffer again
        assert np.array_equal(np.asarray(blueprint.draw(model, **options).image), tight)
        assert fresh.executor.last_run.groups[0].capture.way != "A-buffer"
        assert list_bytes(fresh.pool, size) <= left
    assert np.array_equal(tight, roomy)
    # room for the lists: the A-buffer; a frame after it, checked again (another layer
    # count), sees the free memory less the lists it holds, as a GPU tells it, and takes them
    # again rather than peel
    with blueprint.Renderer() as fresh:
        monkeypatch.setattr(blueprint.api, "_renderer", fresh)
        free = sum(need.values()) - need["lists"] + listed
        monkeypatch.setattr(budget, "free_gpu_memory", lambda device: free)
        model = nested_boxes()
        blueprint.draw(model, **options)
        assert fresh.executor.last_run.groups[0].capture.way == "A-buffer"
        held = list_bytes(fresh.pool, size)
        free -= held
        again = np.asarray(blueprint.draw(model, **{**options, "max_layers": 40}).image)
        assert fresh.capturer.list_room < held
        assert fresh.executor.last_run.groups[0].capture.way == "A-buffer"
        assert list_bytes(fresh.pool, size) == held
    assert np.array_equal(again, roomy)
