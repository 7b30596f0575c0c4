"""Triangle-ID silhouettes on the GPU (paper 002): silhouettes straight from a triangle-ID buffer.

Each depth layer is drawn by the renderer's G-buffer pass, whose ID target holds the face index
of every pixel. A second pass looks at each pixel and its four neighbours: where a neighbour
shows a triangle that shares no vertex with the pixel's triangle, or coverage changes, the pixel
is on a silhouette. Adjacency is decided in one of two ways:

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

Edge images are float32 (L, H, W) in {0, 1}, one per layer, row 0 at the top; lines are two
pixels wide, centred on the boundary (both pixels of a pair mark). Layer 0 holds the visible
silhouettes; deeper layers the hidden ones (where a surface in front ends, its outline shows in
the layers behind as well, under the visible line). :func:`composite` turns them into a picture.

The modules, bottom up: ``ops`` (the two pass descriptors), ``context`` (the renderer's context
made current around GL work), ``tables`` (corner and ID-list tables as GPU buffers and
textures), ``cache`` (those tables per static model), ``soup`` (a deforming mesh), ``passes``
(the silhouette pass as compute or fragment work), ``draw`` (:class:`GpuSilhouettes`, peeling
and the pass per layer) and ``images`` (still and animated pictures).
"""

from .draw import MAX_LAYERS, GpuSilhouettes
from .images import STILL_METHODS, animate_silhouettes, composite, render_silhouettes
from .ops import IDSIL_LIST, IDSIL_VERTEX, METHODS
from .soup import SoupMesh

__all__ = [
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
