"""Environments in pieces (``blueprint.scene.environment``): groups of parts that together
enclose the rest, or lie under it as a ground.

A small town (nine boxes 0.8 wide on a 3 x 3 grid, 1 to 3 tall) inside generated environments
of separate parts: a skybox of six inward-facing panels, an octagonal ring of walls with a lid,
a dome of eight gores, a ground of 20 x 20 tiles, and mixes of these with one-mesh ones. Each
is found, left out with a warning naming it, and the camera and the drawing are then those of
the town alone. A room around furniture of its own size, a walled town whose solid walls face
both ways, the gearbox with its cover as five parts and the shared assemblies have none.
"""

from __future__ import annotations

import logging
import math

import numpy as np
import pytest
from helpers import run_cli

from blueprint import load_model
from blueprint.api.files import render_vector_file
from blueprint.examples import assemble, box, gearbox, write_glb
from blueprint.scene.camera import fit_camera
from blueprint.scene.environment import environment_parts

Part = tuple[np.ndarray, np.ndarray]


def town() -> dict[str, Part]:
    return {
        f"house{i}": box((i % 3 - 1.4, 0, i // 3 - 1.4), (i % 3 - 0.6, 1 + i % 3, i // 3 - 0.6))
        for i in range(9)
    }


def panel(corners, towards) -> Part:
    """A one-sided convex polygon (fanned into triangles) facing the point ``towards``."""
    corners = np.asarray(corners, float)
    n = len(corners)
    faces = np.column_stack([np.zeros(n - 2, int), np.arange(1, n - 1), np.arange(2, n)])
    normal = np.cross(corners[1] - corners[0], corners[2] - corners[0])
    if normal @ (np.asarray(towards, float) - corners.mean(axis=0)) < 0:
        faces = faces[:, ::-1]
    return corners, faces


def skybox(half: float = 80.0) -> dict[str, Part]:
    """Six panels of a cube around the origin, each facing in."""
    parts = {}
    for axis, name in enumerate("xyz"):
        for sign, side in ((1, "p"), (-1, "n")):
            square = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], float) * half
            corners = np.insert(square, axis, sign * half, axis=1)
            parts[f"sky_{side}{name}"] = panel(corners, (0, 0, 0))
    return parts


def ring(radius: float = 80.0, height: float = 40.0, sides: int = 8) -> dict[str, Part]:
    """A ring of ``sides`` walls standing on y = 0 and a lid over it, all facing in."""
    angles = (np.arange(sides) + 0.5) * 2 * math.pi / sides
    rim = np.column_stack([radius * np.cos(angles), np.zeros(sides), radius * np.sin(angles)])
    centre = (0, height / 2, 0)
    parts = {}
    for k in range(sides):
        a, b = rim[k], rim[(k + 1) % sides]
        parts[f"wall{k}"] = panel([a, b, b + (0, height, 0), a + (0, height, 0)], centre)
    parts["lid"] = panel(rim + (0, height, 0), centre)
    return parts


def dome(radius: float = 60.0, gores: int = 8, rows: int = 6, columns: int = 4) -> dict[str, Part]:
    """A hemisphere over y = 0 in ``gores`` segments from the rim to the top, facing in."""
    parts = {}
    for g in range(gores):
        azimuth = (g + np.linspace(0, 1, columns + 1)) * 2 * math.pi / gores
        elevation = np.linspace(0, math.pi / 2, rows + 1)
        el, az = np.meshgrid(elevation, azimuth, indexing="ij")
        points = radius * np.stack([np.cos(el) * np.cos(az), np.sin(el), np.cos(el) * np.sin(az)], -1)
        index = np.arange(points.shape[0] * points.shape[1]).reshape(points.shape[:2])
        a, b, c, d = index[:-1, :-1], index[:-1, 1:], index[1:, 1:], index[1:, :-1]
        faces = np.concatenate(
            [np.stack([a, c, b], -1).reshape(-1, 3), np.stack([a, d, c], -1).reshape(-1, 3)]
        )
        vertices = points.reshape(-1, 3)
        # inward: the normal of each face turned towards the centre
        normal = np.cross(
            vertices[faces[:, 1]] - vertices[faces[:, 0]], vertices[faces[:, 2]] - vertices[faces[:, 0]]
        )
        outward = np.einsum("ij,ij->i", normal, vertices[faces].mean(axis=1)) > 0
        faces[outward] = faces[outward][:, ::-1]
        # the faces that meet at the top are slivers of no area
        parts[f"gore{g}"] = (vertices, faces[np.linalg.norm(normal, axis=1) > 1e-6 * radius**2])
    return parts


def tiles(width: float = 80.0, count: int = 20) -> dict[str, Part]:
    """A ground of ``count`` x ``count`` square tiles on y = 0, facing up."""
    step = width / count
    parts = {}
    for i in range(count):
        for j in range(count):
            x, z = -width / 2 + i * step, -width / 2 + j * step
            corners = [(x, 0, z), (x + step, 0, z), (x + step, 0, z + step), (x, 0, z + step)]
            parts[f"tile{i}_{j}"] = panel(corners, (0, 1, 0))
    return parts


def ground_plane(width: float = 80.0) -> dict[str, Part]:
    return {
        "ground": panel(
            [
                (-width / 2, 0, -width / 2),
                (width / 2, 0, -width / 2),
                (width / 2, 0, width / 2),
                (-width / 2, 0, width / 2),
            ],
            (0, 1, 0),
        )
    }


def one_mesh_skybox(half: float = 80.0) -> dict[str, Part]:
    vertices, faces = box((-half,) * 3, (half,) * 3)
    return {"skybox": (vertices, faces[:, ::-1])}


ENVIRONMENTS = {
    "skybox": skybox,
    "ring": ring,
    "dome": dome,
    "tiles": tiles,
    "skybox+ground": lambda: {**skybox(), **ground_plane()},
    "one-mesh skybox+tiles": lambda: {**one_mesh_skybox(), **tiles()},
    "ring+tiles": lambda: {**ring(), **tiles(200.0, 10)},
}


def found(model) -> set[str]:
    return {model.part_names[i] for i in np.flatnonzero(environment_parts(model))}


def room() -> dict[str, Part]:
    """A room 6 x 3 x 5 of one-sided inward panels (4 walls, floor, ceiling) and furniture across it."""
    lo, hi = np.array([-3.0, 0.0, -2.5]), np.array([3.0, 3.0, 2.5])
    parts = {}
    for axis, name in enumerate("xyz"):
        for value, side in ((lo[axis], "n"), (hi[axis], "p")):
            others = [a for a in range(3) if a != axis]
            square = np.array(
                [
                    [lo[others[0]], lo[others[1]]],
                    [hi[others[0]], lo[others[1]]],
                    [hi[others[0]], hi[others[1]]],
                    [lo[others[0]], hi[others[1]]],
                ]
            )
            parts[f"room_{side}{name}"] = panel(np.insert(square, axis, value, axis=1), (lo + hi) / 2)
    parts |= {
        "bed": box((-2.9, 0, -2.4), (-0.9, 0.5, 0.4)),
        "wardrobe": box((1.9, 0, -2.4), (2.9, 2.2, -0.9)),
        "table": box((0.0, 0.7, 0.5), (1.6, 0.75, 1.5)),
        "chair": box((-0.6, 0, 0.8), (-0.1, 0.9, 1.3)),
        "shelf": box((2.5, 1.2, 0.5), (2.9, 1.6, 2.4)),
    }
    return parts


def walled_town(radius: float = 40.0, height: float = 6.0, sides: int = 8) -> dict[str, Part]:
    """Solid walls (boxes, turned about the up axis) in a ring around the town, far wider than it."""
    parts = {}
    for k in range(sides):
        angle = (k + 0.5) * 2 * math.pi / sides
        length = 2 * radius * math.tan(math.pi / sides) + 2
        vertices, faces = box((-length / 2, 0, radius), (length / 2, height, radius + 2))
        c, s = math.cos(angle), math.sin(angle)
        turn = np.array([[c, 0, -s], [0, 1, 0], [s, 0, c]])
        parts[f"rampart{k}"] = (vertices @ turn.T, faces)
    return parts


def gearbox_of_walls():
    """The gearbox with its cover's five boxes (four walls and a lid) as five parts."""
    model = gearbox()
    cover = model.part_names.index("cover")
    faces = np.flatnonzero(model.face_part == cover)
    face_part = model.face_part.copy()
    # the cover's boxes come one after another, 12 faces each
    face_part[faces[12:]] = len(model.part_names) + (np.arange(12, len(faces)) // 12 - 1)
    names = model.part_names + tuple(f"cover{k}" for k in range(1, 5))
    return type(model).from_arrays(model.positions, model.faces, face_part, names)


@pytest.mark.parametrize("kind", ENVIRONMENTS)
def test_the_group_is_found_and_nothing_else(kind):
    environment = ENVIRONMENTS[kind]()
    model = assemble({**environment, **town()})
    assert found(model) == set(environment)
    # the same whatever the order of the faces
    mixed = np.random.default_rng(0).permutation(model.triangle_count)
    shuffled = type(model).from_arrays(
        model.positions, model.faces[mixed], model.face_part[mixed], model.part_names
    )
    assert found(shuffled) == set(environment)


@pytest.mark.parametrize("kind", ["skybox", "ring", "dome", "tiles"])
def test_loading_leaves_the_group_out_and_names_it(kind, tmp_path, caplog):
    path = tmp_path / f"{kind}.glb"
    write_glb(assemble({**ENVIRONMENTS[kind](), **town()}), path)
    write_glb(assemble(town()), tmp_path / "town.glb")
    everything = load_model(path, include="*")
    names = [everything.part_names[i] for i in np.flatnonzero(environment_parts(everything))]
    with caplog.at_level(logging.WARNING, logger="blueprint"):
        model = load_model(path)
    alone = load_model(tmp_path / "town.glb")
    assert sorted(model.part_names) == sorted(alone.part_names) == sorted(town())
    listed = ", ".join(names) if len(names) <= 10 else ", ".join(names[:10]) + f" and {len(names) - 10} more"
    plural = "s" if len(names) == 1 else ""
    assert [r.getMessage() for r in caplog.records] == [
        f"{path}: left out {listed}, which surround{plural} the scene (--include to keep)"
    ]
    # the camera frames the town, as it frames the town alone
    assert np.array_equal(model.bounds, alone.bounds)
    assert np.allclose(fit_camera(model, (64, 48)).view_matrix(), fit_camera(alone, (64, 48)).view_matrix())
    # kept on request
    assert len(load_model(path, include="*").part_names) == len(names) + 9


@pytest.mark.parametrize("kind", ["skybox", "ring", "tiles"])
def test_the_drawing_is_the_towns(kind, tmp_path, renderer):
    """The SVG of the town in its environment is byte for byte the SVG of the town alone (files
    of one name, so the title matches); with the environment kept, the panels hide the town."""
    (tmp_path / "in").mkdir()
    (tmp_path / "alone").mkdir()
    write_glb(assemble({**ENVIRONMENTS[kind](), **town()}), tmp_path / "in" / "town.glb")
    write_glb(assemble(town()), tmp_path / "alone" / "town.glb")
    drawn = render_vector_file(tmp_path / "in" / "town.glb", tmp_path / "in.svg", size=(160, 120))
    alone = render_vector_file(tmp_path / "alone" / "town.glb", tmp_path / "alone.svg", size=(160, 120))
    assert (tmp_path / "in.svg").read_bytes() == (tmp_path / "alone.svg").read_bytes()
    assert drawn["lines"] == alone["lines"] and drawn["parts"] == 9
    kept = render_vector_file(
        tmp_path / "in" / "town.glb", tmp_path / "kept.svg", size=(160, 120), include="*"
    )
    if kind != "tiles":
        # inside walls and a lid, most of the town's lines are hidden
        assert kept["lines"][0] < alone["lines"][0]


def test_the_command_line_on_the_ring(tmp_path):
    """``blueprint render`` to PNG and SVG: one warning naming the lid and walls, and the files
    are those of the town alone."""
    (tmp_path / "in").mkdir()
    (tmp_path / "alone").mkdir()
    write_glb(assemble({**ring(), **town()}), tmp_path / "in" / "town.glb")
    write_glb(assemble(town()), tmp_path / "alone" / "town.glb")
    names = load_model(tmp_path / "in" / "town.glb", include="*").part_names
    walls = ", ".join(n for n in names if n == "lid" or n.startswith("wall"))
    for suffix in ("png", "svg"):
        outputs = []
        for folder in ("in", "alone"):
            out = tmp_path / f"{folder}.{suffix}"
            proc = run_cli("render", tmp_path / folder / "town.glb", "-o", out, "--size", "160", "120")
            assert proc.returncode == 0, proc.stderr
            outputs.append(out.read_bytes())
            if folder == "in":
                warning = f"{tmp_path / 'in' / 'town.glb'}: left out {walls}, which surround the scene"
                assert proc.stderr == f"blueprint: warning: {warning} (--include to keep)\n"
            else:
                assert proc.stderr == ""
        assert outputs[0] == outputs[1]


def test_a_room_around_its_furniture_is_no_environment():
    assert found(assemble(room())) == set()


def test_scale_is_what_sets_a_skybox_apart_from_a_room():
    """The room's panels around one stool a tenth of its size pass every test: they are taken."""
    panels = {name: part for name, part in room().items() if name.startswith("room_")}
    stool = {"stool": box((-0.2, 0, -0.2), (0.2, 0.45, 0.2))}
    assert found(assemble({**panels, **stool})) == set(panels)


def test_solid_walls_face_both_ways():
    """Solid walls around a town 50 times narrower are drawn; one-sided walls facing in, laid out
    alike, are taken."""
    assert found(assemble({**walled_town(), **town()})) == set()
    one_sided = {name: part for name, part in ring(41.0, 6.0).items() if name != "lid"}
    assert found(assemble({**one_sided, **town()})) == set(one_sided)


def test_generated_assemblies_have_none():
    assert found(gearbox()) == set()
    walls = gearbox_of_walls()
    assert len(walls.part_names) == len(gearbox().part_names) + 4
    assert found(walls) == set()


@pytest.mark.parametrize(
    "name", ["glTF-Sample-Models/2CylinderEngine.glb", "trimesh/converted/cycloidal.glb"]
)
def test_shared_assemblies_have_none(shared_models, name):
    model = load_model(shared_models / name, include="*")
    assert len(model.part_names) > 50
    assert found(model) == set()


def test_a_hundred_thousand_buildings_in_a_skybox():
    """Bounds and sorting per part, faces read only for the groups tried: the six panels found
    among 10^5 buildings."""
    count = 100_000
    side = int(math.ceil(math.sqrt(count)))
    vertices, faces = box((0, 0, 0), (0.8, 1, 0.8))
    i = np.arange(count)
    stretch = np.column_stack([np.ones(count), 1 + i * 7 % 5, np.ones(count)])
    offset = np.column_stack([i % side - side / 2, np.zeros(count), i // side - side / 2])
    sky = assemble(skybox(3000.0))
    model = type(sky).from_arrays(
        np.concatenate([(vertices * stretch[:, None] + offset[:, None]).reshape(-1, 3), sky.positions]),
        np.concatenate([(faces + 8 * i[:, None, None]).reshape(-1, 3), sky.faces + 8 * count]),
        np.concatenate([np.repeat(i, 12), sky.face_part + count]),
        tuple(f"building{k}" for k in range(count)) + sky.part_names,
    )
    environment = environment_parts(model)
    assert np.flatnonzero(environment).tolist() == list(range(count, count + 6))
