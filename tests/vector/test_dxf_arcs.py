"""DXF circles and arcs: a round rim seen square on becomes ARC / CIRCLE entities on the true
circle; a hexagon stays a polyline."""

import numpy as np
import pytest
from helpers import project

from blueprint.examples import assemble, prism
from blueprint.scene.camera import Camera
from blueprint.vector import draw_vector, save_drawing
from blueprint.vector.dxf import fit_arc

SIZE = (256, 256)


def _dxf(renderer, tmp_path, sides):
    import ezdxf

    model = assemble({"can": prism([1.0], 2.0, sides, axis=1)})
    camera = Camera.fit(model.positions, "top", aspect=1.0, ortho=True)
    drawing = draw_vector(model, camera, SIZE, renderer=renderer)
    doc = ezdxf.readfile(save_drawing(tmp_path / f"can{sides}.dxf", drawing))
    # the rim's projected radius and centre, in the DXF's y-up pixels
    rim = project(np.array([[0.0, 1.0, 0.0], [1.0, 1.0, 0.0]]), camera, size=SIZE)
    centre = np.array([rim[0, 0], SIZE[1] - rim[0, 1]])
    return doc.modelspace(), centre, float(np.linalg.norm(rim[1] - rim[0]))


def test_a_fine_round_rim_seen_square_on_is_arcs_on_the_true_circle(renderer, tmp_path):
    entities, centre, radius = _dxf(renderer, tmp_path, 96)
    arcs = list(entities.query("ARC CIRCLE"))
    assert arcs and not list(entities.query("LWPOLYLINE"))
    covered = 0.0
    for arc in arcs:
        assert np.asarray(arc.dxf.center)[:2] == pytest.approx(centre, abs=0.1)
        # the polygon's vertices lie on the rim: the arc is the circle through them
        assert arc.dxf.radius == pytest.approx(radius, abs=0.1)
        covered += 360.0 if arc.dxftype() == "CIRCLE" else (arc.dxf.end_angle - arc.dxf.start_angle) % 360
    assert covered == pytest.approx(360.0, abs=2.0)


def test_a_hexagon_stays_a_polyline(renderer, tmp_path):
    entities, _, _ = _dxf(renderer, tmp_path, 6)
    assert not list(entities.query("ARC CIRCLE")) and list(entities.query("LWPOLYLINE"))


def test_fit_arc_on_hand_made_points():
    angle = np.radians(np.linspace(30, 120, 20))
    points = np.column_stack([5 + 40 * np.cos(angle), -3 + 40 * np.sin(angle)])
    cx, cy, r, start, end = fit_arc(points, 0.1, 0.5)
    assert (cx, cy, r, start, end) == pytest.approx((5, -3, 40, 30, 120))
    # walked the other way round, the ARC (always counterclockwise) is the same
    assert fit_arc(points[::-1], 0.1, 0.5) == pytest.approx((5, -3, 40, 30, 120))
    # a bump of 0.3 px off the circle, or a zigzag, is no arc
    bumped = points.copy()
    bumped[10] = (5, -3) + (bumped[10] - (5, -3)) * (1 + 0.3 / 40)
    assert fit_arc(bumped, 0.1, 0.5) is None
    assert fit_arc(np.array([[0, 0], [1, 1], [2, 0], [3, 1], [4, 0], [5, 1]], float), 0.1, 0.5) is None
    ring = (
        np.column_stack([np.cos(np.linspace(0, 2 * np.pi, 65)), np.sin(np.linspace(0, 2 * np.pi, 65))]) * 30
    )
    assert fit_arc(ring, 0.1, 0.5) == pytest.approx((0, 0, 30, None, None))
