"""Depth masking and highlighted parts: where peeling stops, against a ray-casting oracle."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import project, run_cli
from oracle import raycast_layers

from blueprint import InputError, load_model
from blueprint.api import designated_parts, render_frame
from blueprint.examples import assemble, box, gearbox
from blueprint.scene.camera import fit_camera
from blueprint.scene.model import Model
from blueprint.scene.parts import select_parts, select_parts_like

SIZE = (80, 80)


def predicted_layers(model, camera, selected, fraction):
    """Layers the masking rule must draw, from ray casting: at each pixel the designated parts
    cover, their front surface is surface k (0 = nearest); peeling layer i uncovers the pixels
    with k <= i, and stops at the first i where the uncovered share reaches ``fraction``.
    Returns (layers, share uncovered per layer)."""
    view, projection = camera.view_matrix(), camera.projection_matrix()
    depth, face = raycast_layers(model.positions, model.faces, view, projection, *SIZE)
    hit = face >= 0
    designated = np.zeros(face.shape, bool)
    designated[hit] = selected[model.face_part[face[hit]]]
    covered = designated.any(axis=0)
    first = np.argmax(designated, axis=0)[covered]
    shares = np.array([(first <= i).mean() for i in range(len(depth))])
    return int(np.argmax(shares >= fraction)) + 1, shares


def check_stop(renderer, model, pattern, fractions):
    selected = select_parts(model, pattern)
    camera = fit_camera(model, SIZE)
    checked = 0
    for fraction in fractions:
        expected, shares = predicted_layers(model, camera, selected, fraction)
        # a share within a pixel's worth of the threshold could go either way at silhouettes
        if np.min(np.abs(shares - fraction)) < 0.02:
            continue
        frame = renderer.render(
            model, camera, size=SIZE, supersample=1, highlight=selected, reveal=fraction, max_layers=None
        )
        assert frame.layers == expected, (pattern, fraction, shares, frame.layer_pixels)
        assert frame.revealed == pytest.approx(shares[expected - 1], abs=0.02)
        assert frame.revealed >= fraction
        checked += 1
    assert checked >= 2, "every fraction was ambiguous: pick others"


def test_masking_stops_where_ray_casting_says_on_the_gearbox(renderer):
    check_stop(renderer, gearbox(), "gear,hub", [0.3, 0.6, 0.9, 1.0])


@pytest.mark.parametrize(
    ("path", "pattern"),
    [
        ("glTF-Sample-Models/2CylinderEngine.glb", "Piston*"),
        ("trimesh/converted/cycloidal.glb", "camshaft*"),
        ("trimesh/converted/FM1_satellite.glb", "xtion_pro*"),
    ],
)
def test_masking_stops_where_ray_casting_says_on_assemblies(renderer, shared_models, path, pattern):
    check_stop(renderer, load_model(shared_models / path), pattern, [0.25, 0.5, 0.75, 0.95])


def test_highlight_outlines_hidden_part_in_its_ink(renderer):
    """A box inside a closed box: outlined in the highlight ink, over the outer box's faces."""
    inner = box((-1, -1, -1), (1, 1, 1))
    outer = box((-3, -3, -3), (3, 3, 3))
    model = assemble({"outer": outer, "inner": inner})
    plain = renderer.render(model, size=(128, 128), style="paper").image
    lit = renderer.render(model, size=(128, 128), style="paper", highlight=np.array([False, True])).image
    orange = (lit[..., 0] > 200) & (lit[..., 1] > 80) & (lit[..., 1] < 200) & (lit[..., 2] < 100)
    assert orange.sum() > 100
    assert not ((plain[..., 0] > 200) & (plain[..., 2] < 100)).any()
    # the outline sits where the inner box projects, not on the outer box's silhouette
    rows, cols = np.nonzero(orange)
    assert 30 < rows.min() and rows.max() < 98 and 30 < cols.min() and cols.max() < 98


def test_reveal_draws_fewer_layers_than_full_peel(renderer):
    model = gearbox()
    full = renderer.render(model, size=SIZE, supersample=1, max_layers=None)
    masked = renderer.render(
        model, size=SIZE, supersample=1, max_layers=None, highlight=select_parts(model, "gear"), reveal=0.5
    )
    assert masked.layers < full.layers


def test_part_selection_by_pattern_index_and_model():
    model = gearbox()
    assert select_parts(model, "bolt_*").sum() == 4
    assert select_parts(model, "BEARING_LEFT").tolist() == [n == "bearing_left" for n in model.part_names]
    assert select_parts(model, "0, shaft")[[0, 5]].all() and select_parts(model, "0, shaft").sum() == 2
    gear_only = assemble({"gear": tuple(_part_mesh(model, "gear"))})
    assert select_parts_like(model, gear_only).tolist() == [n == "gear" for n in model.part_names]
    flags = np.zeros(len(model.part_names), bool)
    assert designated_parts(model, flags) is flags


def _part_mesh(model, name):
    index = model.part_names.index(name)
    faces = model.faces[model.face_part == index]
    used = np.unique(faces)
    remap = np.full(len(model.positions), -1)
    remap[used] = np.arange(len(used))
    return model.positions[used], remap[faces]


def test_bad_part_patterns_name_the_closest_parts():
    model = gearbox()
    with pytest.raises(InputError, match="no part matches 'gera'; closest: gear"):
        select_parts(model, "gera")
    with pytest.raises(InputError, match="out of range"):
        select_parts(model, "99")
    with pytest.raises(InputError, match="reveal needs"):
        render_frame(model, size=(32, 32), reveal=0.5)
    with pytest.raises(InputError, match=r"reveal must be in \(0, 1\]"):
        render_frame(model, size=(32, 32), highlight="gear", reveal=1.5)


def test_cli_highlight_and_reveal(tmp_path):
    from blueprint.examples import example_path

    out = tmp_path / "hl.png"
    done = run_cli(
        "render", example_path(), "-o", out, "--size", 96, 64, "--highlight", "gear", "--reveal", 0.8
    )
    assert done.returncode == 0, done.stderr
    assert "of the highlighted parts shown" in done.stdout and out.exists()
    bad = run_cli("render", example_path(), "-o", tmp_path / "x.png", "--highlight", "gera")
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "closest: gear" in bad.stderr
    assert not (tmp_path / "x.png").exists()


def test_shaded_part_hides_what_is_behind_it_and_keeps_edges_in_front(renderer):
    """Front view, orthographic: a plate behind a larger box. Opaque shading of the box hides
    the plate's outline, keeps the box's own outline on top; translucent shading lets it through."""
    from blueprint import Camera

    plate = box((-1, -1, -3.1), (1, 1, -2.9))
    near = box((-1.5, -1.5, 3.5), (1.5, 1.5, 4.5))
    model = assemble({"plate": plate, "near": near})
    camera = Camera.fit(model.positions, "front", ortho=True, aspect=1.0)
    size = (128, 128)

    def draw(**kw):
        return renderer.render(model, camera, size=size, style="paper", **kw).image.astype(int)

    plain, opaque = draw(), draw(shade=np.array([False, True]))
    glass = draw(shade=np.array([False, True]), shade_opacity=0.4)

    def pixel(x, y, z):
        column, row = project([x, y, z], camera, size=size)
        return int(row), int(column)

    row, plate_col = pixel(1.0, 0.0, -3.0)
    _, box_col = pixel(1.5, 0.0, 4.5)
    ink = lambda image, col: image[row, col - 1 : col + 2, :3].min()  # noqa: E731
    assert ink(plain, plate_col) < 200, "the plate's hidden outline shows in the plain drawing"
    centre = opaque[row, (plate_col + 64) // 2, :3]
    assert (centre < 250).all(), "the box is shaded"
    assert np.abs(opaque[row, plate_col - 1 : plate_col + 2, :3] - centre).max() <= 3, "outline hidden"
    assert ink(opaque, box_col) < ink(plain, box_col) + 40 < 200, "the box's outline stays on top"
    assert ink(glass, plate_col) < ink(opaque, plate_col) - 10, "translucent shading shows it"


def test_parts_like_another_model_are_those_most_of_whose_vertices_it_holds():
    """100 cubes; a second model holding three cubes whole, five of another's eight corners
    and four of a fifth's: those three and the one with five are chosen, the one with half not."""
    model = assemble({f"cube{k}": box((2 * k, 0, 0), (2 * k + 1, 1, 1)) for k in range(100)})
    corners = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], np.float64)
    held = [corners + (2 * k, 0, 0) for k in (7, 40, 99)]
    held += [corners[:5] + (2 * 12, 0, 0), corners[:4] + (2 * 60, 0, 0)]
    points = np.concatenate(held)
    other = Model.from_arrays(points, np.arange(len(points) - len(points) % 3).reshape(-1, 3))
    chosen = select_parts_like(model, other)
    assert np.flatnonzero(chosen).tolist() == [7, 12, 40, 99]
