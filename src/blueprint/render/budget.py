"""The GPU memory a frame will allocate, sized from the model's triangles and the frame's size
and layers before anything is allocated, against what the device has free: a frame that would
not fit is refused in one line instead of failing in the driver."""

from __future__ import annotations

import numpy as np

from blueprint import settings
from blueprint.errors import InputError
from blueprint.gpu.device import CURRENT_AVAILABLE_NVX, nvx_memory
from blueprint.render.kbuffer import KBUFFER_MAX
from blueprint.render.mesh import INSTANCE, PLACEMENT
from blueprint.scene.prepare import VERTEX

__all__ = [
    "GBUFFER_BYTES",
    "MESH_BYTES",
    "NODE_BYTES",
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
# an A-buffer fragment as llvmpipe lists it whole (a GPU's slim ones take half)
NODE_BYTES = 16


def free_gpu_memory(device) -> int | None:
    """Bytes the device has free now: NVIDIA's ``GL_NVX_gpu_memory_info`` (current available
    memory), the host's available memory on a software rasteriser (its textures are host
    memory), else None (the driver does not tell)."""
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
    triangles: int, pixels: int, max_layers: int | None, list_bytes: int | None, instances: int = 0
) -> dict[str, int]:
    """The GPU memory a frame allocates at most, by kind: ``mesh`` (vertex and index buffers
    of ``triangles`` not yet uploaded, and the records of their ``instances``: ``uploaded``),
    ``gbuffers`` (a G-buffer of ``pixels`` supersampled
    pixels a layer a pass holds: up to ``KBUFFER_MAX``) and ``lists`` (an A-buffer's fragments,
    a node a pixel a layer, at most ``list_bytes``, its row's cap; None: no A-buffer)."""
    layers = KBUFFER_MAX if not max_layers else min(max_layers, KBUFFER_MAX)
    lists = 0 if list_bytes is None else min(list_bytes, NODE_BYTES * pixels * layers)
    mesh = MESH_BYTES * triangles + RECORD_BYTES * instances
    return {"mesh": mesh, "gbuffers": GBUFFER_BYTES * pixels * layers, "lists": lists}


def check_frame_memory(device, name: str, need: dict[str, int]) -> None:
    """Raise ``InputError`` naming ``name`` where the frame's GPU memory ``need``
    (``frame_bytes``) is more than the device has free (``free_gpu_memory``)."""
    free = free_gpu_memory(device)
    total = sum(need.values())
    if free is None or total <= free:
        return
    parts = ", ".join(f"{kind} {settings.human_size(n)}" for kind, n in need.items() if n)
    raise InputError(
        f"{name}: the frame needs about {settings.human_size(total)} of GPU memory ({parts}), more than "
        f"the {settings.human_size(free)} free on {device.info['renderer']} (try a smaller --size, "
        "--supersample or --max-layers)"
    )
