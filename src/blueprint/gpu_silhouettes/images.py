"""Pictures of silhouettes: edge layers composed in ink on paper, for a still model and, frame
by frame, for a deforming one, by the GPU methods or the CPU object-space method."""

from __future__ import annotations

import time
from collections.abc import Iterator

import numpy as np

from blueprint.errors import InputError
from blueprint.gpu.device import check_size
from blueprint.render.renderer import LayerRenderer
from blueprint.scene.camera import Camera, fit_camera
from blueprint.scene.model import Model
from blueprint.silhouette import BORDER, SILHOUETTE, build_adjacency, classify_edges, draw_segments
from blueprint.silhouette.deform import Animation

from .draw import GpuSilhouettes
from .soup import box_corners

PAPER = (250, 250, 245)
INK = (20, 40, 90)


def composite(edges: np.ndarray, hidden: float = 0.35) -> np.ndarray:
    """Edge layers, (L, H, W) in [0, 1], as an RGB picture: layer 0 in full ink on paper,
    deeper layers at `hidden` strength, fading by a quarter per layer.

    Returns
    -------
    np.ndarray
        (H, W, 3) uint8.
    """
    edges = np.asarray(edges, dtype=np.float32)
    strength = np.array([1.0] + [hidden * 0.75**k for k in range(len(edges) - 1)], np.float32)
    alpha = (edges * strength[:, None, None]).max(axis=0)[..., None]
    paper, ink = np.array(PAPER, np.float32), np.array(INK, np.float32)
    return np.clip(paper + alpha * (ink - paper) + 0.5, 0, 255).astype(np.uint8)


STILL_METHODS = ("gpu-edges", "gpu-vertex", "gpu-idlist", "cpu")
DEFAULT_METHOD = "gpu-edges"
# Visible silhouettes and, in the second layer, every hidden one: the set the CPU method draws.
DEFAULT_LAYERS = 2
# GPU methods that draw from a topology, rebuilt when an animation changes it
_TOPOLOGY_METHODS = ("gpu-edges", "gpu-idlist")


def _cpu_image(positions, faces, camera: Camera, size) -> np.ndarray:
    w, h = size
    edge_set = classify_edges(
        build_adjacency(positions, faces), camera.view_matrix(), camera.projection_matrix(), w, h
    )
    chosen = np.isin(edge_set.kind, (SILHOUETTE, BORDER))
    return draw_segments(edge_set.segments2d[chosen], w, h)[None]


def render_silhouettes(
    model: Model,
    *,
    method: str = DEFAULT_METHOD,
    layers: int = DEFAULT_LAYERS,
    size: tuple[int, int] = (800, 600),
    view: str = "iso",
    azimuth: float | None = None,
    elevation: float | None = None,
    fov: float = 30.0,
    ortho: bool = False,
    camera: Camera | None = None,
    renderer: LayerRenderer,
) -> np.ndarray:
    """A picture of a model's silhouettes (see :func:`composite`), (H, W, 3) uint8.

    ``method`` is ``gpu-edges`` (the object-space silhouette and border edges, classified and
    drawn anti-aliased on the GPU, each in the layer of the surfaces it lies on: with the default
    2 layers, the visible ones in full ink and every hidden one fainter), ``gpu-vertex`` or
    ``gpu-idlist`` (the triangle-ID test per pixel, layer by layer) or ``cpu`` (the object-space
    method: weld, connect, orient, classify, draw; it has no visibility, so it draws hidden
    silhouettes in full ink and ignores `layers`). The camera is `camera`, or one fitted from `view`,
    `azimuth`, `elevation` (degrees), `fov` and `ortho` as ``fit_camera`` does. `renderer`
    draws them (``blueprint.api.files.render_silhouettes_file`` defaults to the shared one).
    """
    if method not in STILL_METHODS:
        raise InputError(f"unknown method {method!r} (choose {', '.join(STILL_METHODS)})")
    w, h = check_size(size, 1, renderer.max_texture)
    camera = camera or fit_camera(
        model, (w, h), view, azimuth=azimuth, elevation=elevation, fov=fov, ortho=ortho
    )
    if method == "cpu":
        return composite(_cpu_image(model.positions, model.faces, camera, (w, h)))
    with GpuSilhouettes(renderer) as sil:
        edges = sil.render(model, camera, (w, h), layers, method.removeprefix("gpu-"))
    return composite(edges)


def animate_silhouettes(
    model: Model,
    *,
    animate: str = "twist",
    frames: int = 60,
    split_at: float = 0.5,
    method: str = DEFAULT_METHOD,
    layers: int = DEFAULT_LAYERS,
    size: tuple[int, int] = (800, 600),
    camera: Camera | None = None,
    renderer: LayerRenderer,
    **placement,
) -> Iterator[tuple[np.ndarray, float]]:
    """Pictures of a deforming model's silhouettes, frame by frame: ``(image, ms)`` pairs, the
    image (H, W, 3) uint8 and `ms` the time to get its silhouettes from the frame's positions.

    ``gpu-vertex`` uploads the new positions and does nothing else per frame; ``gpu-edges``
    and ``gpu-idlist`` upload them too and rebuild their edge records or lists when the topology
    changes (once, at the split); ``cpu`` redoes the whole
    object-space preprocessing every frame, as the paper's comparison does. `renderer` draws
    them, as for :func:`render_silhouettes`. The camera is `camera`, or one fitted to every
    pose of the animation from `placement`: ``fit_camera``'s `view` and its `azimuth`,
    `elevation`, `fov` and `ortho` keywords.
    """
    if method not in STILL_METHODS:
        raise InputError(f"unknown method {method!r} (choose {', '.join(STILL_METHODS)})")
    anim = Animation(model, animate, frames, split_at)
    w, h = check_size(size, 1, renderer.max_texture)
    if camera is None:
        camera = fit_camera(box_corners(anim.bounds()), (w, h), up=model.up, **placement)
    if method == "cpu":
        for i in range(anim.frames):
            pose = anim.pose(i)
            t0 = time.perf_counter()
            image = _cpu_image(pose.positions, pose.faces, camera, (w, h))
            yield composite(image), (time.perf_counter() - t0) * 1e3
        return
    with GpuSilhouettes(renderer) as sil:
        pose = anim.pose(0)
        soup = sil.soup(pose.corners(), model.face_part, (pose.faces, len(pose.positions)))
        topology = pose.topology
        try:
            for i in range(anim.frames):
                pose = anim.pose(i)
                corners = pose.corners()
                t0 = time.perf_counter()
                changed = pose.topology != topology and method in _TOPOLOGY_METHODS
                soup.update(corners, (pose.faces, len(pose.positions)) if changed else None)
                topology = pose.topology
                edges = sil.render(soup, camera, (w, h), layers, method.removeprefix("gpu-"))
                yield composite(edges), (time.perf_counter() - t0) * 1e3
        finally:
            soup.release()
