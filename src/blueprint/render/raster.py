"""The A-buffer's geometry pass in compute: triangles binned to tiles, each tile rasterised by a
workgroup (glsl/abuffer_raster.comp), every fragment listed as the fragment shader lists it.

Where the graphics pipeline runs on a few of the GPU's cores and compute on all of them, the
geometry pass is bound by what its fragments write from those few
(``benchmarks/capture_cost.py``); the same fragments listed from compute cost less
(``benchmarks/compute_capture.py``). Coverage follows the rasteriser's rules (corners
snapped to 1/256 pixel, pixel centres, the top-left rule, exact edge tests) and a fragment's
depth is the plane through the projected corners at the pixel centre: the true plane's, as
``fragment_depth.glsl`` takes it where the driver snaps depths. The faces are drawn a chunk at a
time, the set-up and bins sized for one (``chunk``: ``CHUNK_BYTES`` of set-up, or what a
binding holds where that is less, ``Device.storage_bytes``). There is no clipping: a view is
drawn this way only where the model's bounds lie wholly in front of the eye and project within
a range whose edge tests stay exact (``sees``); depths outside [0, 1] are dropped per fragment,
as the near and far planes would clip them.
"""

from __future__ import annotations

import numpy as np

from blueprint.scene.camera import clip_to_pixels

RASTER_COMP = "blueprint.render:glsl/abuffer_raster.comp"
# pixels along a tile's side, and threads a triangle's tiles are walked by (abuffer_raster.comp)
TILE, ROWS = 16, 8
# workgroups in a row of the set-up dispatches: a dispatch's dimension holds 65535 at least
ACROSS = 32768
# storage bindings of the mesh, the triangles' set-up, the tiles' counts and starts, the bins
# and the edge equations (abuffer_raster.comp)
VERTICES, INDICES, SETUP, COUNT, START, BINS, EDGES = 5, 6, 11, 12, 13, 14, 15
# bytes a triangle's set-up and edge equations take, and a bin entry
SETUP_BYTES, EDGE_BYTES, BIN_BYTES = 80, 72, 4
# bytes of set-up a chunk of faces takes at most (where a binding holds more): a GPU maps the
# memory of new buffers as they are first written, at some 20 GB a second (the H100), which a
# single drawing pays where a chunk's buffers are gigabytes
CHUNK_BYTES = 1 << 28
# window positions (pixels) within which snapped corners' edge equations stay exact in double
# precision (products of two coordinates in 1/256 pixel below 2^53)
REACH = 1 << 17


class ComputeRaster:
    """The four dispatches of abuffer_raster.comp for one renderer ``r``: set-up (each
    triangle's snapped corners, edge equations and the tiles it reaches, counted), a scan of the
    counts, binning, and a workgroup a tile listing its pixels' fragments, over ``chunk`` faces
    at a time (the set-up of a chunk fills a storage binding at most). The bins' room grows from
    what a frame of each size listed (``pairs``: the most of any chunk), as the lists' room does."""

    def __init__(self, r) -> None:
        self.r = r
        self.rooms: dict[tuple[int, int], int] = {}
        self.binding = r.storage_bytes
        self.chunk = max(1, min(self.binding, CHUNK_BYTES) // SETUP_BYTES)

    def stages(self, defines: dict, mesh) -> list:
        defines = {**defines, **mesh.placement_defines}
        return [self.r.compute(RASTER_COMP, {"STAGE": k, **defines}) for k in range(4)]

    def sees(self, bounds: np.ndarray, uniforms: dict, size) -> bool:
        """Whether a mesh within ``bounds`` (2, 3) is drawn this way in the view of the camera's
        ``uniforms`` (an A-buffer's) at ``size``: every corner of the bounds in front of the eye,
        their window positions within ``REACH`` (a perspective projection of a box in front of
        the eye takes its extremes at the box's corners)."""
        grid = np.meshgrid(*zip(bounds[0], bounds[1], strict=True), indexing="ij")
        corners = np.c_[np.stack(grid, -1).reshape(8, 3), np.ones(8)]
        view = np.frombuffer(uniforms["u_view"], np.float32).reshape(4, 4)
        projection = np.frombuffer(uniforms["u_projection"], np.float32).reshape(4, 4)
        # (the matrices' bytes are column-major: as read, each is its transpose)
        clip = corners @ (view.astype(np.float64) @ projection)
        w = clip[:, 3]
        if not (w > 0.0).all():
            return False
        window = clip_to_pixels(clip, size, origin="bottom")
        return bool(np.abs(window).max() < REACH)

    def room(self, size: tuple[int, int], triangles: int) -> int:
        """Bin entries a frame of ``size`` starts with (a chunk's)."""
        return self.rooms.get(size, max(4 * min(triangles, self.chunk), 1 << 16))

    def holds(self, size: tuple[int, int], triangles: int) -> bool:
        """Whether the bins of a frame of ``size`` fit a storage binding."""
        return BIN_BYTES * self.room(size, triangles) <= self.binding

    def pairs(self, size: tuple[int, int], listed: int, room: int) -> bool:
        """Note ``listed`` triangle-tile pairs of a frame of ``size`` that had ``room``: whether
        they fitted (a frame that listed more drew too few fragments, and is drawn again)."""
        if listed > room or size not in self.rooms:
            self.rooms[size] = int(listed * 1.25) + 1024
        return listed <= room

    def bytes(self, size: tuple[int, int], triangles: int) -> int:
        """Memory its buffers take for a frame of ``size``: a chunk's set-up and bins."""
        tiles = -(-size[0] // TILE) * -(-size[1] // TILE)
        set_up = (SETUP_BYTES + EDGE_BYTES) * min(triangles, self.chunk)
        return set_up + 8 * (tiles + 1) + BIN_BYTES * self.room(size, triangles)

    def fragments(self, ab, size: tuple[int, int], uniforms: dict) -> int:
        """Every fragment of ``ab``'s mesh listed into its lists (bound, and emptied) at
        ``size``, the camera's ``uniforms`` as the A-buffer holds them; the bins' room it had."""
        r, pool, mesh = self.r, self.r.pool, ab.mesh
        w, h = size
        triangles = mesh.triangles
        chunk = min(triangles, self.chunk)
        columns, rows = -(-w // TILE), -(-h // TILE)
        tiles = columns * rows
        room = self.room(size, triangles)
        count = pool.buffer("raster.count", 4 * tiles)
        mesh.bind_faces(VERTICES, INDICES)
        for binding, name, nbytes in (
            (SETUP, "setup", SETUP_BYTES * chunk),
            (START, "start", 4 * (tiles + 1)),
            (BINS, "bins", BIN_BYTES * room),
            (EDGES, "edges", EDGE_BYTES * chunk),
        ):
            pool.buffer(f"raster.{name}", nbytes).bind_to_storage_buffer(binding)
        count.bind_to_storage_buffer(COUNT)
        stages = self.stages(ab.capture_defines, mesh)

        def put(values: dict) -> None:
            for prog in stages:
                for name, value in values.items():
                    if name in prog:
                        r.uniforms.set(prog, name, value)

        put(
            {
                "u_size": (w, h),
                "u_tile_columns": columns,
                "u_tiles": tiles,
                "u_bin_room": room,
                **{k: uniforms[k] for k in ("u_view", "u_projection", "u_ortho")},
            }
        )
        ctx = r.ctx
        for first in range(0, triangles, chunk):
            these = min(chunk, triangles - first)
            put({"u_first": first, "u_triangles": these})
            groups = -(-these * ROWS // 64)
            across = min(groups, ACROSS)
            down = -(-groups // across)
            if first:
                # the chunk before still reads the set-up and bins this one writes
                ctx.memory_barrier()
            count.clear()
            stages[0].run(across, down)
            ctx.memory_barrier()
            stages[1].run(1)
            ctx.memory_barrier()
            stages[2].run(across, down)
            ctx.memory_barrier()
            stages[3].run(columns, rows)
        return room
