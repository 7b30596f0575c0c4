"""Specks on scans (issue 39, point 2), with the issue's measure (``scan_helpers.specks``: an
8-connected blob of at most 12 px of ink, ink more than 60 off the paper in summed RGB) at
1024 x 1024, and the features that must stay."""

from __future__ import annotations

import numpy as np
import pytest
from scan_helpers import ink, noisy_bust, noisy_sphere, specks, stanford_bunny
from scipy import ndimage

import blueprint
from blueprint.scene.camera import Camera, clip_to_pixels, transform

SIZE = (1024, 1024)


def test_stanford_bunny_specks(renderer, shared_models):
    """The mesh's own outline (``smooth_contours=False``; the default picture draws contour lines
    there, ``test_smooth_contour_pictures``): 42 specks when a crease was every edge but a lone
    one past the crease angle; 24 since a run of crease edges of fewer than 8 edges and 5 % of
    the model, touching no border, is noise (llvmpipe). Most of those left are faint: hidden
    contours of the noise's folds."""
    image = blueprint.render(stanford_bunny(shared_models), size=SIZE, smooth_contours=False)
    assert specks(np.asarray(image)) <= 24


# the noisy sphere's specks as measured: 34 on llvmpipe, 35 where the image passes run in
# compute (the H100's), whose sums round apart from the fragment passes' in the last place
SPHERE_SPECKS = 35


@pytest.mark.parametrize(("name", "most"), [("noisy sphere", SPHERE_SPECKS), ("noisy bust", 19)])
def test_generated_scan_specks(renderer, name, most):
    """The generated scans' specks with the mesh's outline, as measured: the sphere's are all
    along its outline (the depth jump's band broken by the noise), as before the crease runs;
    the bust had 20."""
    model = noisy_sphere(0.006) if name == "noisy sphere" else noisy_bust()[0]
    assert specks(np.asarray(blueprint.render(model, size=SIZE, smooth_contours=False))) <= most


def test_noisy_sphere_specks_lie_along_its_outline(renderer):
    """With the mesh's outline, the noisy sphere's specks are all the noise's folds at the outline: inside its
    silhouette (layer 0's coverage, peeled on its own) and within 6 % of its radius of the
    edge, where the surface is within some 20 degrees of grazing (measured: 34, the deepest
    25 px in from a 460 px radius, llvmpipe); none on the face, where no crease may be."""
    model = noisy_sphere(0.006)
    image = np.asarray(blueprint.render(model, size=SIZE, smooth_contours=False))
    covered = blueprint.peel(model, size=SIZE, max_layers=1, normals=False).depth[0] < 1
    radius = np.sqrt(covered.sum() / np.pi)
    inside = ndimage.distance_transform_edt(covered)  # pixels in from the outline
    labels, _ = ndimage.label(ink(image), np.ones((3, 3)))
    small = np.nonzero(np.bincount(labels.ravel())[1:] <= 12)[0] + 1
    assert len(small) <= SPHERE_SPECKS
    nearest = np.asarray(ndimage.minimum(inside, labels, small))
    deepest = np.asarray(ndimage.maximum(inside, labels, small))
    assert (nearest > 0).all(), "a speck outside the silhouette"
    assert (deepest <= 0.06 * radius).all(), np.sort(deepest) / radius


def test_bust_ridge_is_inked(renderer):
    """The bust's ridge, seen from the front, is a crease run of about 60 edges: inked along
    its crest (every crest vertex within 1 px of ink) while runs of noise are not."""
    model, crest = noisy_bust()
    camera = Camera.fit(model.positions, "front", aspect=1.0)
    image = np.asarray(blueprint.render(model, size=SIZE, camera=camera))
    view = np.asarray(camera.view_matrix(), float)
    projection = np.asarray(camera.projection_matrix(), float)
    crest_px = np.floor(clip_to_pixels(transform(crest, projection @ view), SIZE)).astype(int)
    inked = ink(image)
    near = np.zeros(len(crest_px), bool)
    for dx in (-1, 0, 1):
        for dy in (-1, 0, 1):
            near |= inked[crest_px[:, 1] + dy, crest_px[:, 0] + dx]
    assert near.all(), crest_px[~near]
