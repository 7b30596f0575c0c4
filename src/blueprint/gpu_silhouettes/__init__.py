"""Silhouettes on the GPU: object-space edges drawn as lines, and triangle-ID silhouettes (paper
002), silhouettes straight from a triangle-ID buffer.

``"edges"`` (the default) finds the CPU method's silhouette and border edges on the GPU: a
vertex shader tests both faces of every edge record (:mod:`blueprint.silhouette.edgerecords`,
built once per topology) for facing from the corner positions the geometry pass draws, a
geometry shader turns the edges between a front and a back face into quads, and the fragment
shader draws them anti-aliased, one pixel wide, as ``draw_segments`` does, each into the layer
of the surfaces it lies on (compared with the peeled depth layers, 3x3 pixels around). So the
lines are the CPU method's, continuous wherever its edges join, hidden ones included.

Why it is the default: the triangle-ID test below decides per pixel whether two neighbouring
triangles share a vertex, which is not the CPU method's test (an edge between a front and a back
face). Where triangles fall under a pixel (scans) or are long and thin (CAD chamfers, fans),
neighbouring pixels show triangles two apart on one smooth, front-facing surface and mark
(specks, dotted chamfers); where the triangles on both sides of a true silhouette share a
corner, the test cannot see it (gaps); and its lines are aliased, two pixels wide.

The triangle-ID methods: each depth layer is drawn by the renderer's G-buffer pass, whose ID
target holds the face index of every pixel. A second pass looks at each pixel and its four
neighbours: where a neighbour shows a triangle that shares no vertex with the pixel's
triangle, or coverage changes, the pixel is on a silhouette. Adjacency is decided in one of two ways:

``"vertex"`` (vertex storage, the paper's choice)
    The three corner positions of every face, 3 RGB32F entries per face in rows of 4096, are
    compared with a small tolerance. No preprocessing: soups, inconsistent winding, non-manifold
    edges and deforming meshes that change topology all work, and a deforming mesh uploads its
    new positions and nothing else (:class:`SoupMesh`). On the compute path the pass reads the
    very buffer the ID pass draws from (a storage buffer); on the fragment path that buffer is
    copied into a texture on the GPU.
``"idlist"`` (ID-list storage, for static meshes)
    Vertex-to-triangle lists precomputed on the CPU (welding included), packed into a list
    texture and a pointer table (:mod:`blueprint.silhouette.idlist`); the pass binary-searches
    the lists of the pixel's three vertices. Same result as ``"vertex"``, at the price of the
    preprocessing whenever the topology changes.

Edge images are float32 (L, H, W), one per layer, row 0 at the top: line coverage in [0, 1]
(``"edges"``), or {0, 1} with lines two pixels wide, centred on the boundary (both pixels of a
pair mark). Layer 0 holds the visible
silhouettes; deeper layers the hidden ones (where a surface in front ends, its outline shows in
the layers behind as well, under the visible line). :func:`composite` turns them into a picture.

The modules, bottom up: ``ops`` (the two pass descriptors), ``context`` (the renderer's context
made current around GL work), ``tables`` (corner and ID-list tables as GPU buffers and
textures), ``lines`` (edge records on the GPU and the line pass), ``cache`` (those tables per
static model), ``soup`` (a deforming mesh), ``passes``
(the silhouette pass as compute or fragment work), ``draw`` (:class:`GpuSilhouettes`, peeling
and the pass per layer) and ``images`` (still and animated pictures).
"""

from .draw import DRAW_METHODS, MAX_LAYERS, GpuSilhouettes
from .images import (
    DEFAULT_LAYERS,
    DEFAULT_METHOD,
    STILL_METHODS,
    animate_silhouettes,
    composite,
    render_silhouettes,
)
from .ops import IDSIL_LIST, IDSIL_VERTEX, METHODS
from .soup import SoupMesh

__all__ = [
    "DEFAULT_LAYERS",
    "DEFAULT_METHOD",
    "DRAW_METHODS",
    "IDSIL_LIST",
    "IDSIL_VERTEX",
    "MAX_LAYERS",
    "METHODS",
    "STILL_METHODS",
    "GpuSilhouettes",
    "SoupMesh",
    "animate_silhouettes",
    "composite",
    "render_silhouettes",
]
