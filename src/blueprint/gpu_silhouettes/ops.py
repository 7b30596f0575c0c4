"""The two silhouette passes as operation descriptors: the textures each reads, what it writes,
its parameters, and its GLSL in fragment and compute form."""

from __future__ import annotations

from blueprint.ops import Op, Param

IDSIL_VERTEX = Op(
    name="idsil_vertex",
    shader="blueprint.gpu_silhouettes:glsl/idsil_vertex.frag",
    inputs={"depth": "depth", "ids": "rg32i", "corners": "rgb32f"},
    output="r8",
    params=(
        Param(
            "tolerance2", 0.0, 0.0, None, "squared model-space distance under which corners are one vertex"
        ),
    ),
    doc="triangle-ID silhouettes, adjacency from per-face corner positions (no preprocessing)",
    compute="blueprint.gpu_silhouettes:glsl/idsil_vertex.comp",
)
IDSIL_LIST = Op(
    name="idsil_list",
    shader="blueprint.gpu_silhouettes:glsl/idsil_list.frag",
    inputs={
        "depth": "depth",
        "ids": "rg32i",
        "face_vertices": "rgb32i",
        "pointers": "rg32i",
        "lists": "r32i",
    },
    output="r8",
    doc="triangle-ID silhouettes, adjacency from precomputed vertex-to-triangle lists",
    compute="blueprint.gpu_silhouettes:glsl/idsil_list.comp",
)
METHODS = {"vertex": IDSIL_VERTEX, "idlist": IDSIL_LIST}
