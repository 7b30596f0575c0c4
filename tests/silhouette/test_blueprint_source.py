"""Triangle-ID silhouettes as an edge source of the blueprint itself (every layer's edge pass)."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from blueprint import Camera, Model
from blueprint.gpu_silhouettes import GpuSilhouettes

SIZE = (160, 120)


def two_spheres() -> Model:
    """A sphere in front of a larger one, one part: the front sphere's outline over the back
    one is a silhouette that neither depth (threshold raised) nor normal edges (crease angle
    180) mark, so only the ID test can draw it."""
    front = trimesh.creation.icosphere(subdivisions=3, radius=0.6)
    back = trimesh.creation.icosphere(subdivisions=3, radius=1.5)
    positions = np.vstack([front.vertices + [0, 0, 1.0], back.vertices + [0, 0, -1.5]])
    faces = np.vstack([front.faces, back.faces + len(front.vertices)])
    return Model.from_arrays(positions, faces)


@pytest.mark.parametrize("compute", [False, True])
def test_id_silhouettes_in_the_edge_pass_match_the_silhouette_op(renderer, compute):
    if compute and renderer.ctx.version_code < 430:
        pytest.skip("compute shaders need OpenGL 4.3")
    saved = renderer.use_compute
    renderer.use_compute = compute
    try:
        model = two_spheres()
        camera = Camera.fit(model.positions, "front", aspect=SIZE[0] / SIZE[1])
        options = dict(
            size=SIZE,
            supersample=1,
            max_layers=1,
            style="paper",
            depth_threshold=1000.0,
            crease_angle=180.0,
            part_edges=False,
        )
        plain = renderer.render(model, camera, **options).image[..., 0] < 200
        with_ids = renderer.render(model, camera, id_silhouettes=True, **options).image[..., 0] < 200
        reference = GpuSilhouettes(renderer).render(model, camera, size=SIZE, layers=1)[0] > 0.5
    finally:
        renderer.use_compute = saved
    # the front sphere's outline over the back sphere: ID silhouette pixels not on the image's
    # coverage outline (which every source draws)
    inner = reference & ~plain
    assert inner.sum() > 100, "the scene has silhouette pixels only the ID test finds"
    assert with_ids[inner].mean() > 0.95
    # the option adds ink and removes none
    assert with_ids[plain].all()
