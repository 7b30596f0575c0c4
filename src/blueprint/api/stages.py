"""Stage timings of one command, for benchmarks (``benchmarks/scale.py``): with
``BLUEPRINT_STAGES=1`` in its environment, ``blueprint render`` prints, as it ends, one JSON
line on stderr: ``{"stages": {name: seconds}, "gpu_memory": {...} or null}``.

A picture's stages: ``read`` (the model file to a ``Model``), ``prepare_upload`` (the mesh
made ready for the GPU and uploaded: normals, welding, buffers), ``contours`` (its smooth
contour lines found, with their levels), ``capture_edges`` (the peel or capture of layers and
their edges), ``compose``, ``read_back`` and ``write``, the GPU ones synchronised after each
(``DrawOptions.profile``). A vector drawing's are those its workflow measures (``read``,
``lines``, ``peel``, ``occlusion``, ``simplify``, ``write``). A stage timed within another
(the mesh prepared as the contour lines are found) counts to itself alone. Nothing is
timed or synchronised without the variable.

The same boundaries mark the phases a progress display shows (``listen``): each stage's start
is told to the listener, by name, as it begins; ``capture_edges`` begins when the mesh is on the
GPU (``watch``), and where the mesh is drawn in chunks (``render.mesh.ChunkedMesh``) each chunk
drawn is told as its progress (``progress``). Nothing is told without a listener.
"""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager

__all__ = [
    "ENV",
    "add",
    "add_frame",
    "begin",
    "enabled",
    "gpu_memory",
    "listen",
    "listening",
    "progress",
    "report",
    "timed",
    "watch",
]

ENV = "BLUEPRINT_STAGES"

_SECONDS: dict[str, float] = {}
_LISTENERS: list[Callable[[str], None]] = []
# the stages open now, innermost last: (name, seconds of the stages timed within it)
_OPEN: list[list] = []
# seconds of each stage timed within no other
_OUTERMOST: dict[str, float] = {}


def enabled() -> bool:
    """Whether stage timings are asked for (``BLUEPRINT_STAGES`` set to 1)."""
    return os.environ.get(ENV, "") == "1"


def add(name: str, seconds: float) -> None:
    """Count ``seconds`` to the stage ``name``."""
    _SECONDS[name] = _SECONDS.get(name, 0.0) + seconds


@contextmanager
def listen(told: Callable[..., None]) -> Iterator[None]:
    """Within the block, call ``told(name)`` as each stage begins (``begin``), and
    ``told(name, detail)`` as it makes progress (``progress``)."""
    _LISTENERS.append(told)
    try:
        yield
    finally:
        _LISTENERS.remove(told)


def listening() -> bool:
    """Whether a listener is told the stages (``listen``)."""
    return bool(_LISTENERS)


def begin(name: str) -> None:
    """Tell the listeners that the stage ``name`` begins."""
    for told in _LISTENERS:
        told(name)


def progress(name: str, detail: str) -> None:
    """Tell the listeners how far the stage ``name`` has come, in words (``"chunk 2 of 5"``)."""
    for told in _LISTENERS:
        told(name, detail)


@contextmanager
def timed(name: str) -> Iterator[None]:
    """Count the block's wall time to the stage ``name``, its start told (``begin``), less
    that of the stages timed within it; where it is within another stage, that stage's start
    is told again as it ends."""
    begin(name)
    start = time.perf_counter()
    _OPEN.append([name, 0.0])
    try:
        yield
    finally:
        inner = _OPEN.pop()[1]
        seconds = time.perf_counter() - start
        add(name, seconds - inner)
        if _OPEN:
            _OPEN[-1][1] += seconds
            begin(_OPEN[-1][0])
        else:
            _OUTERMOST[name] = _OUTERMOST.get(name, 0.0) + seconds


def watch(renderer) -> None:
    """Time ``renderer``'s mesh preparation and upload (``Capturer.mesh``, which the frame
    calls) as the stage ``prepare_upload``; the capture (``capture_edges``) begins after it,
    and a mesh drawn in chunks tells each chunk drawn as its progress."""
    capturer = renderer.capturer
    mesh = capturer.mesh
    if getattr(mesh, "watched", False):
        return

    def timed_mesh(*args, **kwargs):
        with timed("prepare_upload"):
            held = mesh(*args, **kwargs)
        if not _OPEN:
            begin("capture_edges")
        if held.chunk_faces is not None:
            held.on_chunk = _chunk_drawn
        return held

    timed_mesh.watched = True

    capturer.mesh = timed_mesh


def _chunk_drawn(done: int, total: int) -> None:
    progress("capture_edges", f"chunk {done} of {total}")


def add_frame(stages_ms: dict[str, float]) -> None:
    """Count a profiled frame's stages (``Frame.stages``, ms): its capture and edges less the
    mesh preparation timed within them (``watch``; within no other stage), its composition,
    its read-back."""
    capture = stages_ms.get("peel_edges", 0.0) / 1e3 - _OUTERMOST.get("prepare_upload", 0.0)
    add("prepare_upload", stages_ms.get("upload", 0.0) / 1e3)  # the pipeline's images, if any
    add("capture_edges", max(capture, 0.0))
    add("compose", stages_ms.get("compose", 0.0) / 1e3)
    add("read_back", stages_ms.get("read", 0.0) / 1e3)


def gpu_memory(renderer) -> dict | None:
    """The GPU's memory in bytes where the driver tells it (NVIDIA's GL_NVX_gpu_memory_info):
    ``total`` and ``used`` now (by every process), else None."""
    if "GL_NVX_gpu_memory_info" not in renderer.ctx.extensions:
        return None
    import ctypes

    try:
        gl = ctypes.CDLL("libOpenGL.so.0")
        total, available = ctypes.c_int(0), ctypes.c_int(0)
        gl.glGetIntegerv(0x9048, ctypes.byref(total))  # GPU_MEMORY_INFO_TOTAL_AVAILABLE_MEMORY_NVX, KiB
        gl.glGetIntegerv(0x9049, ctypes.byref(available))  # ..._CURRENT_AVAILABLE_VIDMEM_NVX, KiB
    except (OSError, AttributeError):
        return None
    return {"total": total.value * 1024, "used": (total.value - available.value) * 1024}


def report(renderer=None) -> None:
    """Print the stages counted, and the GPU memory of ``renderer`` where given, as one JSON
    line on stderr."""
    import json  # the runs that time their stages alone write JSON

    memory = gpu_memory(renderer) if renderer is not None else None
    print(json.dumps({"stages": _SECONDS, "gpu_memory": memory}), file=sys.stderr, flush=True)
