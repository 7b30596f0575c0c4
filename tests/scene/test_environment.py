"""Environment meshes (``blueprint.scene.environment``): a city inside a skybox, on a ground.

The generated city: a 4 x 4 grid of buildings, inside an inward-facing skybox 40 times its size
and on a ground plane 20 times as wide. Loaded, the skybox and the ground are left out with a
warning naming them, so the camera fits the city and the skybox hides nothing; ``include``
keeps them, ``exclude`` drops parts by name, and patterns that match nothing are one line.
"""

from __future__ import annotations

import json
import logging
from pathlib import Path

import numpy as np
import pytest
import trimesh
from helpers import run_cli

from blueprint import load_model
from blueprint.api.files import render_vector_file
from blueprint.errors import InputError
from blueprint.scene.camera import fit_camera
from blueprint.scene.environment import environment_parts

BUILDINGS = [f"building{i}" for i in range(16)]


def city(path: Path, skybox: bool = True, ground: bool = True) -> Path:
    scene = trimesh.Scene()
    for i, name in enumerate(BUILDINGS):
        height = 1.0 + (i * 7 % 5)
        box = trimesh.creation.box((0.8, height, 0.8))
        box.apply_translation((i % 4 - 1.5, height / 2, i // 4 - 1.5))
        scene.add_geometry(box, node_name=name, geom_name=name)
    if skybox:
        sky = trimesh.creation.box((160.0, 160.0, 160.0))
        sky.invert()  # seen from inside: its faces turn inwards
        scene.add_geometry(sky, node_name="Skybox", geom_name="Skybox")
    if ground:
        plane = trimesh.Trimesh(
            [[-40, 0, -40], [40, 0, -40], [40, 0, 40], [-40, 0, 40]], [[0, 2, 1], [0, 3, 2]]
        )
        scene.add_geometry(plane, node_name="Ground", geom_name="Ground")
    scene.export(path)
    return path


@pytest.fixture
def city_file(tmp_path) -> Path:
    return city(tmp_path / "city.glb")


def test_the_skybox_and_the_ground_are_environment(city_file):
    everything = load_model(city_file, include="*")
    found = {everything.part_names[i] for i in np.flatnonzero(environment_parts(everything))}
    assert found == {"Skybox", "Ground"}


def test_a_city_alone_has_no_environment(tmp_path):
    alone = load_model(city(tmp_path / "alone.glb", skybox=False, ground=False))
    assert sorted(alone.part_names) == sorted(BUILDINGS)
    assert not environment_parts(alone).any()


def test_loading_leaves_them_out_and_says_so(city_file, caplog):
    with caplog.at_level(logging.WARNING, logger="blueprint"):
        model = load_model(city_file)
    assert sorted(model.part_names) == sorted(BUILDINGS)
    assert [r.getMessage() for r in caplog.records] == [
        f"{city_file}: left out Ground, Skybox, which surround the scene (--include to keep)"
    ]
    # the camera fits the city, as it fits the city alone
    alone = load_model(city(city_file.with_name("alone.glb"), skybox=False, ground=False))
    assert np.allclose(model.bounds, alone.bounds)
    assert np.allclose(fit_camera(model, (64, 64)).view_matrix(), fit_camera(alone, (64, 64)).view_matrix())


def test_include_keeps_them_and_exclude_drops_by_name(city_file):
    everything = load_model(city_file, include="*")
    assert len(everything.part_names) == 18
    assert np.allclose(everything.bounds, [[-80, -80, -80], [80, 80, 80]])
    fewer = load_model(city_file, exclude="building1*")
    assert sorted(fewer.part_names) == sorted(n for n in BUILDINGS if not n.startswith("building1"))
    assert fewer.triangle_count == 12 * len(fewer.part_names)


def test_the_skybox_no_longer_hides_the_city(city_file, renderer):
    # every building's outline is visible: the vector drawing's visible lines outnumber the
    # hidden ones, where inside the skybox everything was behind it
    kept = render_vector_file(city_file, city_file.with_suffix(".svg"), size=(160, 120), renderer=renderer)
    boxed = render_vector_file(
        city_file, city_file.with_name("boxed.svg"), size=(160, 120), include="*", renderer=renderer
    )
    # (here 110 visible polylines against the skybox's 9)
    assert kept["lines"][0] > 5 * boxed["lines"][0]
    assert kept["parts"] == 16 and boxed["parts"] == 18


@pytest.mark.parametrize("option", ["--exclude", "--include"])
def test_patterns_matching_nothing_are_one_line(city_file, tmp_path, option):
    proc = run_cli("render", city_file, "-o", tmp_path / "c.png", option, "tower*")
    assert proc.returncode == 2 and proc.stdout == "" and not (tmp_path / "c.png").exists()
    assert proc.stderr.startswith(f"blueprint: error: {city_file}: {option}: no part matches 'tower*'")
    assert len(proc.stderr.splitlines()) == 1


def test_nothing_left_is_an_error(city_file):
    with pytest.raises(InputError, match="leave no part to draw"):
        load_model(city_file, exclude="*")


def test_info_marks_the_environment_and_render_warns(city_file, tmp_path):
    info = run_cli("info", city_file, "--json")
    parts = {p["name"]: p["environment"] for p in json.loads(info.stdout)["parts"]}
    assert parts == {**dict.fromkeys(BUILDINGS, False), "Skybox": True, "Ground": True}
    proc = run_cli("layers", city_file, "-o", tmp_path / "c.npz", "--size", "32", "32")
    assert proc.returncode == 0
    warning = f"{city_file}: left out Ground, Skybox, which surround the scene (--include to keep)"
    assert proc.stderr == f"blueprint: warning: {warning}\n"
    with np.load(tmp_path / "c.npz") as data:
        assert set(np.unique(data["part"])) <= set(range(-1, 16))
