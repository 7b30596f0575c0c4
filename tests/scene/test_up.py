"""The up axis of OBJ, PLY and OFF models, guessed from the shape (``blueprint.scene.up``).

A statue on a plinth made Z-up and saved as OBJ used to load Y-up (on its side); now its flat
base at the bottom of Z decides. A model without a base keeps Y; ``--up`` wins over the guess;
formats with an axis of their own are not guessed. Also the other small things of the command
line: ``render --help`` names every output, ``--scale`` on an iso view says it goes orthographic.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import trimesh
from helpers import run_cli

from blueprint import load_model
from blueprint.scene.up import base_fraction, guess_up


def statue(up: int) -> trimesh.Trimesh:
    """A plinth (a 2 x 0.4 x 2 box on its base) with a sphere on it, standing along axis `up`."""
    plinth = trimesh.creation.box((2.0, 0.4, 2.0))
    plinth.apply_translation((0, 0.2, 0))
    head = trimesh.creation.icosphere(subdivisions=3, radius=0.8)
    head.apply_translation((0, 1.2, 0))
    mesh = trimesh.util.concatenate([plinth, head])
    if up == 2:  # Y-up to Z-up: +y goes to +z
        mesh.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, (1, 0, 0)))
    return mesh


def test_base_fraction_is_the_base_over_the_cross_section():
    # the plinth's base is 2 x 2 and the bounding box's cross-section 2 x 2
    mesh = statue(2)
    assert base_fraction(mesh.vertices, mesh.faces, 2) == pytest.approx(1.0)
    # the side of the plinth, 2 x 0.4, lies flat at the bottom of y: 0.8 of 2 x 2
    assert base_fraction(mesh.vertices, mesh.faces, 1) == pytest.approx(0.2)


@pytest.mark.parametrize("up", [1, 2])
def test_a_statue_stands_on_its_base(tmp_path, up):
    path = tmp_path / "statue.obj"
    statue(up).export(path)
    model = load_model(path)
    assert model.up == "yz"[up - 1]
    assert model.up_reason == f"guessed from a flat base at the bottom of {model.up}"


def test_up_given_wins_and_other_formats_keep_their_own(tmp_path):
    statue(2).export(tmp_path / "statue.obj")
    statue(1).export(tmp_path / "statue.stl")
    given = load_model(tmp_path / "statue.obj", up="y")
    assert (given.up, given.up_reason) == ("y", "given")
    stl = load_model(tmp_path / "statue.stl")
    assert (stl.up, stl.up_reason) == ("z", "by the format")


def test_a_shape_without_a_base_keeps_y():
    ball = trimesh.creation.icosphere(subdivisions=3)
    assert guess_up(ball.vertices, ball.faces).axis == "y"
    # a cube has a base at the bottom of both: the shape does not decide
    cube = trimesh.creation.box()
    assert guess_up(cube.vertices, cube.faces, default="y").axis == "y"


@pytest.mark.parametrize("name", ["common-3d-test-models/stanford-bunny.obj", "Euclid/dragon.ply"])
def test_y_up_scans_stay_y_up(shared_models, name):
    assert load_model(shared_models / name).up == "y"


def test_info_and_render_report_the_guess(tmp_path):
    path = tmp_path / "statue.obj"
    statue(2).export(path)
    info = run_cli("info", path)
    assert info.returncode == 0, info.stderr
    assert info.stdout.splitlines()[0].endswith("up z (guessed from a flat base at the bottom of z)")
    assert json.loads(run_cli("info", path, "--json").stdout)["up_reason"].startswith("guessed")
    out = run_cli("render", path, "-o", tmp_path / "s.png", "--size", "64", "64")
    assert out.returncode == 0, out.stderr
    assert ", up z guessed from a flat base at the bottom of z, " in out.stdout
    given = run_cli("render", path, "-o", tmp_path / "s.png", "--size", "64", "64", "--up", "z")
    assert given.returncode == 0 and "guessed" not in given.stdout


def test_bad_up_is_one_line(tmp_path):
    path = tmp_path / "statue.obj"
    statue(2).export(path)
    proc = run_cli("render", path, "-o", tmp_path / "s.png", "--up", "x")
    assert proc.returncode == 2 and proc.stdout == ""
    assert len(proc.stderr.strip().splitlines()) == 1 and "'x'" in proc.stderr


def test_render_help_names_every_output():
    text = " ".join(run_cli("render", "--help").stdout.split())
    for suffix in (".png", ".svg", ".pdf", ".dxf", ".npz"):
        assert suffix in text


def test_scale_on_an_iso_view_says_it_goes_orthographic(tmp_path):
    path = tmp_path / "statue.stl"
    statue(2).export(path)
    proc = run_cli(
        "render", path, "-o", tmp_path / "s.svg", "--size", "64", "64", "--scale", "1:10", "--units", "m"
    )
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == (
        "blueprint: warning: --scale 1:10 draws the iso view orthographic "
        "(a drawing to scale has no perspective)\n"
    )
    quiet = run_cli(
        "render",
        path,
        "-o",
        tmp_path / "t.svg",
        "--size",
        "64",
        "64",
        "--scale",
        "1:10",
        "--units",
        "m",
        "--ortho",
    )
    assert quiet.returncode == 0 and quiet.stderr == ""
