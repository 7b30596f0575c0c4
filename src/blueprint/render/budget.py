"""The GPU memory a frame will allocate, sized from the model's triangles and the frame's size
and layers before anything is allocated, against what the device has free: a frame whose mesh
does not fit beside its G-buffers and A-buffer lists is drawn with its mesh uploaded a chunk of
faces at a time (``render.mesh.ChunkedMesh``), and one whose buffers would not fit even with a
small chunk is refused in one line instead of failing in the driver."""

from __future__ import annotations

import os

import numpy as np

from blueprint import settings
from blueprint.errors import InputError
from blueprint.gpu.device import CURRENT_AVAILABLE_NVX, nvx_memory
from blueprint.render.abuffer import NODE_BYTES, SLIM_BYTES
from blueprint.render.kbuffer import KBUFFER_MAX
from blueprint.render.mesh import INSTANCE, PLACEMENT
from blueprint.scene.prepare import VERTEX

__all__ = [
    "GBUFFER_BYTES",
    "GPU_MEMORY_ENV",
    "MESH_BYTES",
    "MIN_CHUNK_FACES",
    "RECORD_BYTES",
    "check_frame_memory",
    "frame_bytes",
    "free_gpu_memory",
    "uploaded",
]

# at most three vertex records (a soup's corners) and three uint32 indices a triangle
MESH_BYTES = 3 * VERTEX.itemsize + 3 * 4
# an instance's record (its draw's) and its row of the faces table (render.mesh)
RECORD_BYTES = INSTANCE.itemsize + PLACEMENT.itemsize
# a G-buffer's pixel: two depth textures, the rgba16f normal and the rg32i IDs
GBUFFER_BYTES = 4 + 4 + 8 + 8
# the fewest faces a chunk of a mesh drawn in chunks uploads: below it the draws' and uploads'
# overhead would be all of a chunk's cost, and a frame is refused instead
MIN_CHUNK_FACES = 1 << 12
# bytes (or with a suffix K, M or G) taken as the GPU's free memory in place of what the device
# says: to draw as a smaller GPU would, in chunks or refused
GPU_MEMORY_ENV = "BLUEPRINT_GPU_MEMORY"


def free_gpu_memory(device) -> int | None:
    """Bytes the device has free now: ``BLUEPRINT_GPU_MEMORY`` where set (``GPU_MEMORY_ENV``),
    else NVIDIA's ``GL_NVX_gpu_memory_info`` (current available memory), the host's available
    memory on a software rasteriser (its textures are host memory), else None (the driver does
    not tell)."""
    text = os.environ.get(GPU_MEMORY_ENV, "").strip()
    if text:
        size = settings.parse_size(text)
        if size is None:
            raise InputError(
                f"{GPU_MEMORY_ENV}={text!r} is not a size in bytes (a number, or with K, M or G)"
            )
        return size
    if device.software:
        return settings.available_memory()
    return nvx_memory(device.ctx, CURRENT_AVAILABLE_NVX)


def uploaded(model) -> tuple[int, int]:
    """(triangles, instances) ``render.mesh.GpuMesh`` uploads of ``model``: a flattened
    model's triangles and no instance; of a model kept as instances, the triangles of each
    mesh it places, once, and its instances."""
    inst = model.instances
    if inst is None:
        return model.triangle_count, 0
    return int(inst.mesh_faces()[np.unique(inst.mesh)].sum()), len(inst.mesh)


def frame_bytes(
    triangles: int,
    pixels: int,
    max_layers: int | None,
    list_bytes: int | None,
    instances: int = 0,
    extra: dict[str, int] | None = None,
    slim: bool = False,
) -> dict[str, int]:
    """The GPU memory a frame allocates, by kind: ``mesh`` (vertex and index buffers of
    ``triangles`` not yet uploaded, and the records of their ``instances``: ``uploaded``),
    ``gbuffers`` (a G-buffer of ``pixels`` supersampled pixels a layer a pass holds: up to
    ``KBUFFER_MAX``) and ``lists`` (an A-buffer's fragments, ``slim`` or not
    (``abuffer.NODE_BYTES``), a fragment a pixel a layer, at most ``list_bytes``, its row's cap;
    None: no A-buffer); then the kinds of ``extra``, what the frame's own passes allocate beside
    the capture (tables read by face, targets a layer), none of which a mesh drawn in chunks
    makes smaller. The lists are what a frame of that many layers takes: a deeper model's
    A-buffer takes no more than ``check_frame_memory`` leaves it, and peels where that is
    too little."""
    layers = KBUFFER_MAX if not max_layers else min(max_layers, KBUFFER_MAX)
    node = NODE_BYTES + (SLIM_BYTES if slim else 0)
    lists = 0 if list_bytes is None else min(list_bytes, node * pixels * layers)
    mesh = MESH_BYTES * triangles + RECORD_BYTES * instances
    need = {"mesh": mesh, "gbuffers": GBUFFER_BYTES * pixels * layers, "lists": lists}
    for kind, size in (extra or {}).items():
        if kind in need:
            raise ValueError(f"a frame's extra GPU memory cannot be called {kind!r}")
        need[kind] = int(size)
    return need


def check_frame_memory(
    device, name: str, need: dict[str, int], instances: int = 0
) -> tuple[int | None, int | None]:
    """(faces, lists) of a frame whose GPU memory is ``need`` (``frame_bytes``, its mesh of
    ``instances`` instance records), against what the device has free (``free_gpu_memory``):
    ``faces`` a chunk of the mesh uploads, None where the mesh fits whole; ``lists`` the bytes
    its A-buffer's lists may take (None where the driver does not tell). Where the whole frame
    fits, the lists take all that the rest leaves; where it does not, the mesh is drawn in
    chunks that fit beside everything else; where not even a small chunk does
    (``MIN_CHUNK_FACES``), the A-buffer gives way, its frame peeled instead (the lists are the
    one kind a frame can do without). Raise ``InputError`` naming ``name`` where even that
    would not fit."""
    free = free_gpu_memory(device)
    if free is None:
        return None, None
    total = sum(need.values())
    records = RECORD_BYTES * instances
    for lists in (need["lists"], 0):
        rest = total - need["lists"] + lists
        if rest <= free:
            return None, free - rest + lists
        left = free - (rest - need["mesh"]) - records
        if left >= MESH_BYTES * MIN_CHUNK_FACES:
            return left // MESH_BYTES, lists
    least = {kind: n for kind, n in need.items() if kind != "lists"}
    parts = ", ".join(f"{kind} {settings.human_size(n)}" for kind, n in least.items() if n)
    raise InputError(
        f"{name}: the frame needs about {settings.human_size(sum(least.values()))} of GPU memory ({parts}), "
        f"more than the {settings.human_size(free)} free on {device.info['renderer']} (try a smaller --size, "
        "--supersample or --max-layers)"
    )
