"""Every depth layer from one geometry pass: an A-buffer of per-pixel fragment lists.

Depth peeling draws the whole mesh once a layer. Here one geometry pass appends every
fragment to its pixel's list (storage buffers and an atomic counter, OpenGL 4.3), a compute
pass sorts each pixel's list into the layers the peel would draw (its rules: the depth
buffer's precision, back faces pushed back, the peel's tolerance, the first drawn winning a
tie), and each layer is then unpacked into the G-buffer by a full-screen pass, so whatever
reads layers sees what the peel draws. The lists' room comes from the fragments the last frame
of that size drew; a pass that finds too little room is drawn again with enough, and one whose
fragments would not fit ``max_bytes`` says so and the caller peels instead. Where the CPU
should not wait for the capture before issuing the frame's other passes (a GPU), the counts are
read only when first asked for, and a capture that then turns out to have had too little room
raises ``Overflow``: its caller draws the frame again, with the room now known.
"""

from __future__ import annotations

import functools

import numpy as np

from blueprint import parallel
from blueprint.gpu.device import TOTAL_AVAILABLE_NVX, nvx_memory, run_over
from blueprint.render.gbuffer import BACK_BIAS, GBuffer, abuffer_uniforms, depth_tolerance
from blueprint.render.mesh import geometry_program, target_uniform
from blueprint.scene.camera import Camera

ABUFFER_FRAG = "blueprint.render:glsl/abuffer.frag"
CLEAR_COMP = "blueprint.render:glsl/abuffer_clear.comp"
RESOLVE_COMP = "blueprint.render:glsl/abuffer_resolve.comp"
UNPACK_COMP = "blueprint.render:glsl/abuffer_unpack.comp"
FACES_COMP = "blueprint.render:glsl/abuffer_faces.comp"
# the faces ``faces_at`` reads back a dispatch at most (bytes), and the invocations of its
# workgroups (abuffer_faces.comp)
FACES_BYTES = 1 << 26
FACES_GROUP = 64
# the histogram of layers a pixel has (abuffer.glsl)
MOST_LAYERS = 256
# bytes a fragment's surface takes, and all it holds: its surface, its link in the pixel's list,
# its link in the pixel's layers
SURFACE_BYTES = 16
NODE_BYTES = SURFACE_BYTES + 8
# ...and its depth and face as the geometry pass writes them where the nodes are slim
SLIM_BYTES = 8
# storage bindings of the slim fragments and of the mesh the resolve reads (abuffer.glsl,
# abuffer_resolve.comp)
SLIM_BINDING, VERTICES_BINDING, INDICES_BINDING = 7, 8, 9
# storage binding of the long lists' pixels, which the resolve's second dispatch sorts
LONG_BINDING = 11
# fragments a long list's sort takes on a software rasteriser at most: past some 1 800 (fewer in
# the worst order) its loops would run past the 65 535 turns an invocation's loops have there
# (abuffer_resolve.comp), and the frame is peeled instead
LONG_MOST = 960
# fragments a list the resolve sorts in registers (abuffer_resolve.comp); a longer one's pixel is
# listed for the second dispatch, so a room of n fragments lists at most n / SORTED pixels
SORTED = 48
# room for this many fragments a pixel before a first frame has counted them
FIRST_ROOM = 4
# faces whose areas on the picture ``projected_fragments`` sums at a time, and
# ``placed_fragments`` on each thread (a few threads' blocks hold what one of the former does)
AREA_BLOCK = 1 << 15
PLACED_BLOCK = 1 << 13
# pixels along a side of the tiles whose layers are counted, for a software rasteriser to unpack
# and draw each layer only where it has pixels (blueprint.pipeline.tiles)
TILE = 16
# groups of 8 x 8 a row of a tiled unpack's dispatch (abuffer_unpack.comp)
ROW = 32768
# entries a row of the images that hold the lists on a software rasteriser (abuffer.glsl)
AB_ROW = 4096
# the image units of the lists there (nodes, links, order; abuffer.glsl)
LIST_UNITS = (5, 6, 7)
# the pool's targets of a size's lists, after its name (``_buffers``): what a fragment's room takes
LIST_PARTS = ("nodes", "links", "order", "slim")
# storage binding of the nodes past a binding's reach (abuffer.glsl's AB_SPLIT), and the offsets a
# binding may start at: whole multiples of this many bytes (the most a driver may ask for)
NODES_HIGH_BINDING = 16
BINDING_ALIGNMENT = 256


def _lists_name(size: tuple[int, int]) -> str:
    """The name the pool holds the lists and targets of a capture at ``size`` under."""
    return f"abuffer.{size[0]}x{size[1]}"


def list_defines(r) -> dict:
    """The defines of a program that reads or writes the lists on renderer ``r`` (abuffer.glsl):
    images on a software rasteriser, storage buffers elsewhere."""
    return {"AB_IMAGES": 1} if r.software else {}


def split_node(r, max_bytes: int, node_bytes: int) -> int:
    """The first node of the lists' second binding of nodes (abuffer.glsl's AB_SPLIT) where
    lists in storage buffers of at most ``max_bytes`` (``node_bytes`` a fragment) may hold more
    nodes than one binding does (``Device.storage_bytes``): its nodes, whole multiples of
    ``BINDING_ALIGNMENT`` bytes; else 0."""
    if r.software:
        return 0
    held = r.storage_bytes // BINDING_ALIGNMENT * BINDING_ALIGNMENT // SURFACE_BYTES
    return held if 0 < held < max_bytes // node_bytes else 0


class Overflow(Exception):
    """A capture whose counts were read late found more fragments than it had room for."""


class _Prepared:
    """What an A-buffer capture of ``mesh`` by ``row`` (with ``tiles`` or not) needs whatever
    the frame: its programs, their defines and constant uniforms, made once and kept with the
    mesh (``GpuMesh.prepared``), since a stream's frames would otherwise look them up again
    before their first draw, while the GPU waits."""

    def __init__(self, capturer, row, mesh, tiles: bool) -> None:
        r = capturer.device
        self.model = capturer.model_of(mesh)
        images = r.software
        # a mesh drawn in chunks is not on the GPU whole when the resolve would read its faces
        self.slim = row.slim and mesh.chunk_faces is None
        self.node_bytes = NODE_BYTES + (SLIM_BYTES if self.slim else 0)
        self.split = split_node(r, row.max_bytes, self.node_bytes)
        self.defines = {**list_defines(r), **mesh.surface_defines, "AB_SPLIT": self.split}
        capture = self.capture_defines = {**self.defines, "SLIM": self.slim}
        # where the lists live in images (a software rasteriser) an atomic on the fragment
        # counter runs a lane at a time: the subgroup's fragments take their nodes with one
        ballot = images and not self.slim and r.subgroup_ballot
        # ...and where the driver orders a pixel's fragments (framebuffer fetch), each takes the
        # pixel's list from the last one without an atomic: the head is the pass's target
        self.fetch_head = images and r.framebuffer_fetch
        defines = {**capture, "BALLOT": ballot, "FETCH_HEAD": self.fetch_head}
        self.geometry = geometry_program(capturer, ABUFFER_FRAG, mesh, defines, modern=True)
        # with tiles the counts come from each pixel's layers read back (``_count_pixels``), and
        # the resolve runs over the tiles with fragments alone (``_resolve``)
        # a slim fragment's face is found in the mesh's faces table (GpuMesh.bind_faces)
        resolving = {**capture, **mesh.placement_defines} if self.slim else capture
        resolving = {**resolving, "LONG_BINDING": LONG_BINDING, "SORTED": SORTED}
        if tiles:
            resolving = {**resolving, "COUNTED_AFTER": 1, "TILES": TILE, "ROW": ROW}
        # the lists too long to sort in registers, in a dispatch of their own over their pixels
        self.resolve = r.compute(RESOLVE_COMP, {**resolving, "LONG": 0})
        longest = {"LONG_MOST": LONG_MOST} if r.software else {}
        self.resolve_long = r.compute(RESOLVE_COMP, {**resolving, "LONG": 1, **longest})
        self.clear = r.compute(CLEAR_COMP)
        self.unpack = r.compute(
            UNPACK_COMP, {**self.defines, "TILES": TILE, "ROW": ROW} if tiles else self.defines
        )
        for prog in (self.resolve, self.resolve_long, self.unpack):
            r.uniforms.set(prog, "u_back_bias", BACK_BIAS)
        # the compute rasteriser where the row lists fragments in compute (render.raster)
        chunked = mesh.chunk_faces is not None
        self.raster = capturer.compute_raster if row.compute_from is not None and not chunked else None


class ABufferSource:
    """The A-buffer capture of one frame's layers into ``gb`` (see the module's docstring):
    ``draw`` at layer 0 captures and sorts every layer, then unpacks layer 0; at each later
    layer it unpacks that layer. ``row`` is the capture table's (``table.ABufferRow``): the
    bytes the lists may take, and where it is ``slim`` the geometry pass writes each fragment's
    depth and face alone and the resolve makes the whole surfaces of the fragments it keeps as
    layers. The ``request`` (``table.Request``) says the rest. With its ``tiles`` the counts
    come from each pixel's layers read back, with the most layers a pixel of each ``TILE`` x
    ``TILE`` tile has (``tile_layers``), and each layer is unpacked only in the tiles that have
    it: what a software rasteriser wants, where reading back is cheap and every pixel a pass
    touches costs. With ``defer`` the counts are read when first asked for (``layer_pixels``,
    ``deepest``): every layer is unpacked until then, an unpack past a pixel's last layer
    clearing it as an empty layer's would, and a capture that had too little room raises
    ``Overflow`` there. Without ``unpack`` no layer is unpacked: readers read the sorted lists
    themselves (``reads`` "lists": ``bind``). The counts come back through a buffer of their
    own for each ``slot``: frames that stream read one frame's counts after the next is issued
    (``counts_kept``). On a software rasteriser the lists live in images, not storage buffers
    (abuffer.glsl): programs that read them take ``defines``."""

    counts_kept = True

    def __init__(self, capturer, row, mesh, camera: Camera, gb: GBuffer, request) -> None:
        r = self.r = capturer.device
        self.mesh, self.gb = mesh, gb
        self.camera = camera
        # the room of the frames before, by G-buffer size (``Capturer.abuffer_room``)
        self.rooms = capturer.abuffer_room
        self.back_bias, self.unpacks, self.slot = BACK_BIAS, request.unpack, request.slot
        self.reads = None if self.unpacks else "lists"
        tiles, defer = request.tiles, request.defer
        self.images = r.software
        p = mesh.prepared.get((ABufferSource, row, tiles))
        if p is None:
            p = mesh.prepared[(ABufferSource, row, tiles)] = _Prepared(capturer, row, mesh, tiles)
        self.model, self.defines, self.slim, self.node_bytes = p.model, p.defines, p.slim, p.node_bytes
        self.split = p.split
        self.capture_defines, self.fetch_head, self.raster = p.capture_defines, p.fetch_head, p.raster
        self.geometry, self.resolve, self.clear, self.unpack = p.geometry, p.resolve, p.clear, p.unpack
        self.resolve_long = p.resolve_long
        # the row's cap, or less where the frame's memory check left the lists less (a deep
        # model's fragments past it are peeled instead of allocated); the lists the pool held
        # at this size as it checked are taken again, not allocated, and the free memory it
        # saw was without them: what the pool held, not the room learned (a capture that ran
        # out of room learns more than it allocated) nor lists allocated since
        room = capturer.list_room
        if room is not None:
            name = _lists_name(gb.size)
            room += sum(capturer.pool_held.get(f"{name}.{part}", 0) for part in LIST_PARTS)
        self.max_bytes = row.max_bytes if room is None else min(row.max_bytes, room)
        uniforms = abuffer_uniforms(camera, depth_tolerance(camera, mesh.bounds))
        put = r.uniforms.set  # a stream's frames change only the camera's
        camera_names = ("u_view", "u_projection", "u_ortho")
        resolving = ("u_depth_range", "u_peel_eps", *(camera_names if self.slim else ()))
        for prog, names in (
            (self.geometry, camera_names),
            (self.resolve, resolving),
            (self.resolve_long, resolving),
        ):
            for name in names:
                put(prog, name, uniforms[name])
        self.uniforms = uniforms
        self.compute_from = row.compute_from
        # (its bins' room, the size) of the capture in hand where the compute rasteriser drew it
        self._binned: tuple[int, tuple[int, int]] | None = None
        self._layer_pixels: list[int] = []
        self._flat: dict[tuple, tuple] = {}  # (names carry the size: the pool keeps them)
        self._rooms: dict[str, int] = {}  # the room of the last capture, by its lists' name
        self.tiles, self.defer = tiles, defer and not tiles
        # (counts buffer, room) of a capture whose counts are not read yet
        self._unread: tuple | None = None
        # the last capture counted had a list too long for a software rasteriser's sort
        self._too_long = False
        # (rows, columns) of tiles, row 0 at the bottom: the layers of each, once layer 0 is drawn
        self.tile_layers: np.ndarray | None = None
        self._deepest_first: np.ndarray | None = None  # the tiles' layers, most first
        self._tile_list = None  # the image of the tiles with any layer, most layers first

    @classmethod
    def open(
        cls, capturer, row, mesh, camera: Camera, gb: GBuffer, request, selected=None
    ) -> ABufferSource | None:
        """The A-buffer of the frame, or None where its lists, with the fragments the last
        frame of its size drew, would pass the row's memory."""
        source = cls(capturer, row, mesh, camera, gb, request)
        return source if source.fits(gb.size) else None

    @property
    def way(self) -> str:
        """``A-buffer``, or ``A-buffer, compute rasteriser`` where its fragments were listed
        in compute (render.raster)."""
        return "A-buffer, compute rasteriser" if self.rasterised_in_compute else "A-buffer"

    @property
    def rasterised_in_compute(self) -> bool:
        """Whether the compute rasteriser listed the last capture's fragments."""
        return self._binned is not None

    @property
    def layer_pixels(self) -> list[int]:
        """Pixels covered by each layer, once layer 0 is drawn."""
        self.settle()
        return self._layer_pixels

    def settle(self) -> None:
        """Read a deferred capture's counts if they are not read yet (``Overflow`` where it
        had too little room)."""
        if self._unread is not None:
            self._count(*self._unread)

    def deepest(self) -> int:
        """The most layers any pixel has, once layer 0 is drawn."""
        return len(self.layer_pixels)

    def fits(self, size: tuple[int, int]) -> bool:
        """Whether a frame of ``size`` with the fragments of the last one there would fit."""
        return self._room(size) <= self._most_room()

    def _list_bytes(self, room: int) -> int:
        """Bytes the lists of ``room`` fragments take: images hold whole rows."""
        return (-(-room // AB_ROW) * AB_ROW if self.images else room) * self.node_bytes

    def _room(self, size: tuple[int, int]) -> int:
        held = self.rooms.get(tuple(size))
        return held if held is not None else FIRST_ROOM * size[0] * size[1]

    def _first_room(self, size: tuple[int, int]) -> int:
        """The room a capture at ``size`` starts with: the last one's there (``_room``), else,
        where the lists live in the host's memory (a software rasteriser's images), the
        fragments the faces' areas on the picture foretell, with a counted room's spare, up to
        ``FIRST_ROOM`` a pixel: a closed scan draws some two a pixel it covers; of a model kept
        as instances, each instance's faces placed a block at a time, never flattened. A deeper
        model gets the room foretold where the lists may hold it: a first pass with less would
        be drawn again (one foretold past them starts small, as lists that may be peeled)."""
        room = self._room(size)
        if tuple(size) in self.rooms or not self.images or self.model is None:
            return room
        model = self.model
        if model.is_flat:
            foretold = projected_fragments(model.positions, model.faces, self.camera, size)
        else:
            foretold = placed_fragments(model.instances, self.camera, size)
        if foretold is None:
            return room
        wanted = spare_room(foretold)
        return wanted if wanted <= max(room, self._most_room()) else room

    def _most_room(self) -> int:
        """The most fragments lists may hold within ``max_bytes`` and, in storage buffers, what
        one binding holds of their nodes (``Device.storage_bytes``), or two where they are
        split (``split_node``), and one of their slim fragments; or in images, their rows of
        ``AB_ROW`` entries each; the compute rasteriser's buffers are counted where it draws
        them (``_computes``)."""
        if not self.images:
            nodes = 2 * self.split if self.split else self.r.storage_bytes // SURFACE_BYTES
            return min(self.max_bytes // self.node_bytes, nodes, self.r.storage_bytes // SLIM_BYTES)
        return min(self.max_bytes // (AB_ROW * self.node_bytes), self.r.max_texture) * AB_ROW

    def draw(self, layer: int, query=None, guard=None) -> int | None:
        """Layer ``layer`` into the G-buffer: its depth into ``flat[layer % 2]``, two float
        targets standing in for the G-buffer's depth textures (``samples`` then tells its
        covered pixels; the query and guard are the peel's, unused); the draw calls and
        dispatches issued, or None where layer 0 found more fragments than ``max_bytes`` holds
        (nothing is drawn then)."""
        gb = self.gb
        if layer and not self.unpacks:
            return 0  # every layer was captured at layer 0, and none is unpacked
        drawn = self._draw(gb, layer)
        if drawn is not None:
            # layers left in the lists have no depth target to fill: made only where one is read
            gb.flat = self.flat(gb.size) if self.unpacks else functools.partial(self.flat, gb.size)
        return drawn

    def samples(self, layer: int, query=None) -> int:
        """Layer ``layer``'s covered pixels, as the capture counted them (0 past the deepest)."""
        pixels = self.layer_pixels
        return pixels[layer] if layer < len(pixels) else 0

    def bind(self, prog, layer: int, step: int) -> None:
        """The sorted lists bound for a reader (edges_lists.frag and .comp) of the layers from
        ``layer`` on, no layer unpacked: each pixel's chain carried from one pass to the next
        (``step`` layers on) in a pair of cursor images, and each pixel's layer count."""
        self.r.uniforms.set(prog, "u_back_bias", self.back_bias)
        batch = layer // step
        if batch:
            # a later batch reads what the batch before it left in the cursors; the lists are
            # still bound and the capture's writes visible since the first batch's full barrier
            ctx = self.r.ctx
            ctx.memory_barrier(ctx.SHADER_IMAGE_ACCESS_BARRIER_BIT)
            *cursors, layer_count = self._list_images(self.gb.size)
        else:
            *cursors, layer_count = self.lists(self.gb.size)
        cursors[batch % 2].bind_to_image(2, read=True, write=False)
        cursors[(batch + 1) % 2].bind_to_image(3, read=False, write=True)
        layer_count.bind_to_image(4, read=True, write=False)

    def faces_at(self, pixels: np.ndarray, layers: int) -> np.ndarray:
        """(layers, N) int32: the face of layers 0 to ``layers`` - 1 at ``pixels`` (N flat
        indices ``y * width + x``, OpenGL rows), -1 past a pixel's last layer: read from the
        sorted lists in place, with nothing unpacked, a block of pixels a dispatch
        (``FACES_BYTES`` of faces at most) and each block's faces read back once."""
        size = self.gb.size
        pixels = np.ascontiguousarray(pixels, np.uint32)
        out = np.empty((layers, len(pixels)), np.int32)
        if layers == 0 or len(pixels) == 0:
            return out
        ctx = self.r.ctx
        prog = self.r.compute(FACES_COMP, self.defines)
        cursor = self.lists(size)[0]
        cursor.bind_to_image(1, read=True, write=False)
        block = max(1, FACES_BYTES // (4 * layers))
        for start in range(0, len(pixels), block):
            chunk = pixels[start : start + block]
            wanted = self.r.pool.buffer("abuffer.faces_at.pixels", chunk.nbytes)
            wanted.write(chunk)
            wanted.bind_to_storage_buffer(5)
            found = self.r.pool.buffer("abuffer.faces_at.faces", 4 * layers * len(chunk))
            found.bind_to_storage_buffer(6)
            prog["u_count"].value = len(chunk)
            prog["u_layers"].value = layers
            run_over(prog, len(chunk), FACES_GROUP)
            ctx.memory_barrier()
            faces = np.frombuffer(found.read(4 * layers * len(chunk)), np.int32).reshape(layers, -1)
            np.subtract(faces, 1, out=out[:, start : start + len(chunk)])
        return out

    def release(self) -> None:
        """The lists are the pool's."""

    def _draw(self, gb, layer: int) -> int | None:
        size = gb.size
        name = _lists_name(size)
        calls = 0
        if layer == 0:
            calls = self._capture(gb, name)
            if calls is None:
                return None
        if not self.unpacks:
            return calls
        if self._unread is None and layer >= len(self._layer_pixels):
            # an empty layer, as the peel's would be
            self.r.ctx.memory_barrier()
            self.r.pool.framebuffer((self.flat(size)[layer % 2],)).clear(1.0, 1.0, 1.0, 1.0)
            return calls
        self._unpack(gb, name, layer)
        return calls + 1

    def lists(self, size: tuple[int, int]) -> tuple:
        """The captured lists at ``size`` bound to their storage blocks (abuffer.glsl), for a
        pass that reads the layers from them; returns two cursor images and the layer counts:
        the first cursor holds each pixel's layer 0 (the resolve's), the second is free for a
        pass to leave where each pixel's chain goes on; the counts image holds each pixel's
        layers. The second cursor is the lists' heads, which nothing reads once the resolve has
        sorted them, and the next capture clears."""
        self.r.ctx.memory_barrier()
        self._buffers(_lists_name(size))
        return self._list_images(size)

    def _list_images(self, size: tuple[int, int]) -> tuple:
        """The two cursor images and the layer counts of ``lists``, as they are."""
        name = _lists_name(size)
        pool = self.r.pool
        return (
            pool.texture(f"{name}.cursor", size, "r32ui"),
            pool.texture(f"{name}.head", size, "r32ui"),
            pool.texture(f"{name}.layer_count", size, "r32ui"),
        )

    def flat(self, size: tuple[int, int]) -> tuple:
        """The two float targets the layers' depths alternate in, at ``size``."""
        held = self._flat.get(size)
        if held is None:
            name = _lists_name(size)
            held = self._flat[size] = tuple(
                self.r.pool.texture(f"{name}.depth{i}", size, "r32f") for i in (0, 1)
            )
        return held

    def _buffers(self, name: str, room: int | None = None) -> tuple:
        """(totals, depths) bound to their storage blocks, and the lists with room for ``room``
        fragments (None: as the last capture had) bound to theirs or their image units
        (abuffer.glsl)."""
        pool = self.r.pool
        room = self._rooms[name] if room is None else room
        self._rooms[name] = room
        if self.images:
            size = (AB_ROW, -(-room // AB_ROW))
            parts = (("nodes", "rgba32ui"), ("links", "r32ui"), ("order", "r32ui"))
            for unit, (part, fmt) in zip(LIST_UNITS, parts, strict=True):
                pool.texture(f"{name}.{part}", size, fmt).bind_to_image(unit, read=True, write=True)
        else:
            for binding, (part, nbytes) in enumerate((("nodes", SURFACE_BYTES), ("links", 4), ("order", 4))):
                buffer = pool.buffer(f"{name}.{part}", nbytes * room)
                if part != "nodes" or not self.split:
                    buffer.bind_to_storage_buffer(binding)
                    continue
                # the nodes past the split in a second binding (where none is, the first again)
                low = min(buffer.size, SURFACE_BYTES * self.split)
                buffer.bind_to_storage_buffer(binding, size=low)
                high = (low, buffer.size - low) if buffer.size > low else (0, low)
                buffer.bind_to_storage_buffer(NODES_HIGH_BINDING, offset=high[0], size=high[1])
        held = pool.buffer(f"{name}.totals", 16), pool.buffer(f"{name}.depths", 4 * (MOST_LAYERS + 1))
        for binding, buf in enumerate(held, 3):
            buf.bind_to_storage_buffer(binding)
        if self.slim:
            pool.buffer(f"{name}.slim", SLIM_BYTES * room).bind_to_storage_buffer(SLIM_BINDING)
        return held

    def _capture(self, gb, name: str) -> int | None:
        """Every fragment into the lists and each list sorted into its layers: the geometry
        pass and the resolve, again with more room where the first found too little. The counts
        come back in one read a frame. The calls issued, or None where the fragments would take
        more than ``max_bytes``."""
        ctx, pool, size = self.r.ctx, self.r.pool, gb.size
        head = pool.texture(f"{name}.head", size, "r32ui")
        cursor = pool.texture(f"{name}.cursor", size, "r32ui")
        layer_count = pool.texture(f"{name}.layer_count", size, "r32ui")
        groups = (-(-size[0] // 8), -(-size[1] // 8))
        calls = 0
        room = self._first_room(size)
        while True:
            if room > self._most_room():
                return None
            totals, depths = self._buffers(name, room)
            head.bind_to_image(0, read=True, write=True)
            self.clear["u_capacity"].value = room
            self.clear.run(*groups)
            ctx.memory_barrier()
            self._binned = None
            self.fragments(gb, head)
            ctx.memory_barrier()
            # lists cut short by too little room hold only the fragments that had room: sorted
            # all the same, and drawn again below
            head.bind_to_image(0, read=True, write=False)
            cursor.bind_to_image(1, read=False, write=True)
            layer_count.bind_to_image(2, read=False, write=True)
            if self.slim:
                self.mesh.bind_faces(VERTICES_BINDING, INDICES_BINDING)
                target_uniform(self.r, self.resolve, size)
                target_uniform(self.r, self.resolve_long, size)
            long_lists = self._resolve(name, head, (cursor, layer_count), groups, room)
            ctx.memory_barrier()
            calls += 3
            # the counts are copied out before they are read: a buffer the CPU reads may be
            # moved where the GPU's atomics on it are slow
            nbytes = totals.size + (0 if self.tiles else depths.size)
            # on a software rasteriser the lists too long for its sort (``LONG_MOST``) too: the
            # word after the three group counts of the long lists' dispatch (abuffer_resolve.comp)
            long = 4 if self.r.software else 0
            seen = pool.buffer(f"{name}.seen{self.slot}", nbytes + long)
            ctx.copy_buffer(seen, totals, totals.size)
            if not self.tiles:
                ctx.copy_buffer(seen, depths, depths.size, write_offset=totals.size)
            if long:
                ctx.copy_buffer(seen, long_lists, long, read_offset=4 * 3, write_offset=nbytes)
            nbytes += long
            if self.defer:
                self._unread = (seen.read, nbytes, room, size, name)
                return calls
            if self._count(seen.read, nbytes, room, size, name):
                return None if self._too_long else calls
            room = self._room(size)

    def _resolve(self, name: str, head, cleared: tuple, groups: tuple[int, int], room: int):
        """The resolve's dispatches over lists of ``room`` fragments: over every group, or with
        tiles over the tiles that hold a fragment, found from the lists' heads read back, the
        ``cleared`` images (cursors and counts) zeroed everywhere first; then over the pixels of
        the lists too long to sort in registers, which the first lists, as many groups as it
        counts (an indirect dispatch: none, and no wait for the count, where no list is
        long). Returns the long lists' buffer (abuffer_resolve.comp's Long)."""
        long = self.r.pool.buffer(f"{name}.long", 4 * (4 + room // SORTED + 1))
        long.write(np.array([0, 1, 1, 0], np.uint32))
        long.bind_to_storage_buffer(LONG_BINDING)
        self._resolve_short(name, head, cleared, groups)
        self.r.ctx.memory_barrier(self.r.ctx.SHADER_STORAGE_BARRIER_BIT | self.r.ctx.COMMAND_BARRIER_BIT)
        self.resolve_long.run_indirect(long)
        return long

    def _resolve_short(self, name: str, head, cleared: tuple, groups: tuple[int, int]) -> None:
        if not self.tiles:
            self.resolve.run(*groups)
            return
        w, h = head.size
        heads = np.empty((h, w), np.uint32)
        head.read_into(heads)
        held = tile_max(heads).ravel()
        tiles = np.flatnonzero(held)
        for image in cleared:
            self.r.pool.framebuffer((image,)).clear()
        if not len(tiles):
            return
        columns = -(-w // TILE)
        self._tile_image(f"{name}.resolve_tiles", tiles, columns).bind_to_image(3, read=True, write=False)
        count = len(tiles) * (TILE // 8) ** 2
        self.resolve["u_groups"].value = count
        self.resolve.run(min(count, ROW), -(-count // ROW))

    def _tile_image(self, name: str, tiles: np.ndarray, columns: int):
        """``tiles`` (flat indices, ``columns`` tiles a row) in the image that passes over
        listed tiles read (abuffer_tiles.glsl): x | y << 16 each, ``AB_ROW`` a row."""
        rows, across = np.divmod(tiles, columns)
        packed = np.zeros(max(1, -(-len(tiles) // AB_ROW)) * AB_ROW, np.uint32)
        packed[: len(tiles)] = across | (rows << 16)
        image = self.r.pool.texture(name, (AB_ROW, len(packed) // AB_ROW), "r32ui")
        image.write(packed)
        return image

    def _computes(self, size: tuple[int, int]) -> bool:
        """Whether the compute rasteriser lists a frame of ``size`` (render.raster: where it
        sees the view too): from ``compute_from`` pixels, where its buffers (some 150 bytes a
        triangle of a chunk, and its bins) fit ``max_bytes`` beside the lists of the room kept
        for the size and its bins fit a storage binding; else the graphics pipeline lists it,
        rather than the frame be peeled a pass a layer."""
        if self.raster is None or size[0] * size[1] < self.compute_from:
            return False
        triangles = self.mesh.triangles
        if not self.raster.holds(size, triangles):
            return False
        needs = self._list_bytes(self._room(size)) + self.raster.bytes(size, triangles)
        return needs <= self.max_bytes

    def fragments(self, gb, head) -> None:
        """Every fragment of the mesh into its pixel's list (``head``: the lists' first nodes):
        by the compute rasteriser where there is one and it sees the view, else the graphics
        pipeline's (abuffer.frag)."""
        if self._computes(gb.size) and self.raster.sees(self.mesh.bounds, self.uniforms, gb.size):
            self._binned = self.raster.fragments(self, gb.size, self.uniforms), tuple(gb.size)
            return
        if self.fetch_head:
            self.r.pool.framebuffer((head,)).use()
        else:
            gb.clears[0].use()
        target_uniform(self.r, self.geometry, gb.size)
        self.mesh.vao(self.geometry).render()

    def _count(self, read, nbytes: int, room: int, size: tuple[int, int], name: str) -> bool:
        """The counts (``read`` of ``nbytes``) of a capture that had ``room``: the layers'
        pixels (and tiles) kept, or False where it had too little room (``Overflow`` where it
        was deferred)."""
        self._unread = None
        size = tuple(size)
        counts = np.frombuffer(read(size=nbytes), np.uint32).astype(np.int64)
        drawn = int(counts[0])
        self._too_long = self.r.software and bool(counts[-1])
        if drawn > room or size not in self.rooms:
            self.rooms[size] = spare_room(drawn)
        # the compute rasteriser's bins (render.raster) take the same turn where they were short
        binned = self._binned is None or self.raster.pairs(self._binned[1], int(counts[3]), self._binned[0])
        if drawn > room or not binned:
            if self.defer:
                raise Overflow(f"{drawn} fragments, room for {room}; {counts[3]} tile bins")
            return False
        histogram = self._count_pixels(name, size) if self.tiles else counts[4 : 4 + MOST_LAYERS + 1]
        # pixels with at least k + 1 layers are those layer k covers
        covered = np.cumsum(histogram[::-1])[::-1][1:]
        self._layer_pixels = covered[covered > 0].tolist()
        return True

    def _count_pixels(self, name: str, size: tuple[int, int]) -> np.ndarray:
        """The histogram of the pixels' layers (the last entry: ``MOST_LAYERS`` or more) from
        each pixel's layers read back, and the tiles' layers listed: what the resolve counts on
        a GPU, at a copy's cost where the GPU is the CPU."""
        layers = np.empty(size[::-1], np.uint32)
        self.r.pool.texture(f"{name}.layer_count", size, "r32ui").read_into(layers)
        self._list_tiles(name, tile_max(layers))
        flat = layers.ravel()
        if self.tile_layers.max(initial=0) >= MOST_LAYERS:
            flat = np.minimum(flat, MOST_LAYERS)
        return np.bincount(flat, minlength=MOST_LAYERS + 1)

    def _list_tiles(self, name: str, layers: np.ndarray) -> None:
        """Keep the tiles' layers and upload the tiles that have any, most layers first, so that
        the tiles with a layer are the first of the list at every layer."""
        self.tile_layers = layers
        flat = layers.ravel()
        order = np.argsort(-flat.astype(np.int64), kind="stable")
        order = order[flat[order] > 0]
        self._deepest_first = flat[order]
        self._tile_list = self._tile_image(f"{name}.tile_list", order, layers.shape[1])

    def _unpack(self, gb, name: str, layer: int) -> None:
        """Layer ``layer`` at each pixel's cursor into the G-buffer, the cursor moved on."""
        ctx, pool, size = self.r.ctx, self.r.pool, gb.size
        # the layer before's passes may still be reading the normal and ID targets this
        # overwrites (a GPU runs dispatches side by side; llvmpipe one after another)
        ctx.memory_barrier()
        self._buffers(name)
        pool.texture(f"{name}.cursor", size, "r32ui").bind_to_image(1, read=True, write=True)
        depth = self.flat(size)[layer % 2]
        depth.bind_to_image(2, read=False, write=True)
        gb.normal.bind_to_image(3, read=False, write=True)
        gb.ids.bind_to_image(4, read=False, write=True)
        if not self.tiles:
            self.unpack.run(-(-size[0] // 8), -(-size[1] // 8))
            ctx.memory_barrier()
            return
        pool.framebuffer((depth,)).clear(1.0, 1.0, 1.0, 1.0)
        ctx.memory_barrier()
        # the tiles with more than ``layer`` layers lead the list
        tiles = int(np.count_nonzero(self._deepest_first > layer))
        groups = tiles * (TILE // 8) ** 2
        if groups:
            self._tile_list.bind_to_image(0, read=True, write=False)
            self.unpack["u_groups"].value = groups
            self.unpack.run(min(groups, ROW), -(-groups // ROW))
        ctx.memory_barrier()


def spare_room(fragments: float) -> int:
    """The room kept for a frame of ``fragments``: some to spare for a model turning."""
    return int(fragments * 1.25) + 1024


def projected_fragments(
    positions: np.ndarray, faces: np.ndarray, camera: Camera, size: tuple[int, int]
) -> float | None:
    """About the fragments a geometry pass of ``faces`` (F, 3) of ``positions`` (V, 3) draws
    into a target of ``size`` through ``camera``: the sum of their areas in pixels, front and
    back faces alike (a pixel's centre lies in as many faces as cross it), a block of faces at
    a time; None where a corner lies on or behind the eye's plane, whose area is unbounded.
    Faces wholly off the picture are left out; those across its edge count whole: more than
    are drawn, never fewer."""
    rows = (camera.projection_matrix() @ camera.view_matrix())[[0, 1, 3]]
    turn, shift = rows[:, :3].T.astype(np.float32), rows[:, 3].astype(np.float32)
    # each vertex projected once, not once a corner: (V, 3) clip x, y and w
    clip = positions @ turn + shift
    total = 0.0
    for start in range(0, len(faces), AREA_BLOCK):
        block = faces[start : start + AREA_BLOCK]
        area = _twice_area([clip[block[:, k]] for k in range(3)])
        if area is None:
            return None
        total += area
    return _pixels(total, size)


def placed_fragments(instances, camera: Camera, size: tuple[int, int]) -> float | None:
    """``projected_fragments`` of the scene ``instances`` (``scene.instances.Instances``) place:
    each instance's faces through its transform, ``PLACED_BLOCK`` faces of the flattened scene
    at a time on each thread, so that no more than a block's corners a thread are ever placed at
    once."""
    rows = (camera.projection_matrix() @ camera.view_matrix())[[0, 1, 3]]
    # each instance's rows from its mesh's coordinates to clip x, y and w: (N, 3, 4)
    placed = np.einsum("ij,njk->nik", rows, instances.transform)
    turn = np.ascontiguousarray(placed[:, :, :3].transpose(0, 2, 1)).astype(np.float32)
    shift = placed[:, :, 3].astype(np.float32)
    counts = instances.instance_faces()
    ends = np.cumsum(counts)
    starts = ends - counts
    face_start, vertex_start = instances.face_start[instances.mesh], instances.vertex_start[instances.mesh]
    faces = int(ends[-1]) if len(ends) else 0

    def areas(first: int, last: int) -> list[float | None]:
        found = []
        for start in range(first * PLACED_BLOCK, min(last * PLACED_BLOCK, faces), PLACED_BLOCK):
            flat = np.arange(start, min(start + PLACED_BLOCK, faces))
            inst = np.searchsorted(ends, flat, side="right")
            face = face_start[inst] + (flat - starts[inst])
            corners = instances.faces[face] + vertex_start[inst][:, None]
            block_turn, block_shift = turn[inst], shift[inst]
            # a corner at a time: a block's corners placed at once would hold three times the memory
            clips = [
                np.einsum("bi,bij->bj", instances.positions[corners[:, k]].astype(np.float32), block_turn)
                + block_shift
                for k in range(3)
            ]
            found.append(_twice_area(clips))
        return found

    # the blocks side by side on the pool, their areas summed in order as one thread would
    found = [area for part in parallel.run(areas, -(-faces // PLACED_BLOCK), min_block=1) for area in part]
    if any(area is None for area in found):
        return None
    total = 0.0
    for area in found:
        total += area
    return _pixels(total, size)


def _twice_area(clips: list[np.ndarray]) -> float | None:
    """Twice the summed area on the picture, in normalised device coordinates, of triangles
    whose corners are ``clips`` (three (B, 3) arrays of clip x, y and w); None where a corner
    lies on or behind the eye's plane."""
    if not all((clip[:, 2] > 0).all() for clip in clips):
        return None
    (x0, y0), (x1, y1), (x2, y2) = ((clip[:, 0] / clip[:, 2], clip[:, 1] / clip[:, 2]) for clip in clips)
    # faces wholly beyond one side of the picture draw nothing
    shown = np.ones(len(x0), bool)
    for a, b, c in ((x0, x1, x2), (y0, y1, y2)):
        shown &= (np.minimum(np.minimum(a, b), c) <= 1) & (np.maximum(np.maximum(a, b), c) >= -1)
    twice = np.abs((x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0))
    return float(twice[shown].sum(dtype=np.float64))


def _pixels(twice_area: float, size: tuple[int, int]) -> float:
    """Twice an area in normalised device coordinates as pixels of a target of ``size``."""
    # normalised device coordinates span 2 a side: a pixel is (2 / w) by (2 / h) of them
    return twice_area / 2 * size[0] * size[1] / 4


def tile_max(values: np.ndarray) -> np.ndarray:
    """The largest of ``values`` (H, W) in each ``TILE`` x ``TILE`` tile (those at the far
    edges cut short); by reshaping, far faster than ``np.maximum.reduceat``."""
    h, w = values.shape
    th, tw = -(-h // TILE), -(-w // TILE)
    if (th * TILE, tw * TILE) != (h, w):
        padded = np.zeros((th * TILE, tw * TILE), values.dtype)
        padded[:h, :w] = values
        values = padded
    return values.reshape(th, TILE, tw * TILE).max(axis=1).reshape(th, tw, TILE).max(axis=2)


def gpu_memory_bytes(r) -> int | None:
    """The GPU's memory where the driver tells it (NVIDIA's GL_NVX_gpu_memory_info), else None."""
    return nvx_memory(r.ctx, TOTAL_AVAILABLE_NVX)
