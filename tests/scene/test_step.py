"""STEP input: meshed by OpenCASCADE in a child process, parts named from the file, broken files
one line, a time limit on the meshing."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import no_output, one_error, run_cli

import blueprint
from blueprint.errors import InputError
from blueprint.scene.formats import step


@pytest.fixture(scope="module")
def trimesh_models(shared_models):
    return shared_models / "trimesh"


def test_step_is_the_same_part_as_its_stl(trimesh_models):
    mesh = blueprint.load_model(trimesh_models / "featuretype.STEP")
    stl = blueprint.load_model(trimesh_models / "featuretype.STL")
    assert mesh.part_names == ("featuretype",)
    assert mesh.up == "z"
    # OpenCASCADE writes metres, the STL is in inches: 5 x 2.5 x 1.375 in
    np.testing.assert_allclose(mesh.bounds, stl.bounds * 0.0254, atol=1e-6)


def test_step_parts_are_named_from_the_file(trimesh_models):
    model = blueprint.load_model(trimesh_models / "box_sides.STEP")
    assert sorted(model.part_names) == sorted(
        ["box_top", "box_base", "side_long", "side_long_1", "side_short", "side_short_B"]
        + ["gusset", "gusset_1", "gusset_2", "gusset_3"]
    )
    assert (model.part_triangle_counts() > 0).all()


def test_step_renders_from_the_command_line(trimesh_models, tmp_path):
    proc = run_cli("render", trimesh_models / "featuretype.STEP", "-o", tmp_path / "f.png", "--size", 64, 64)
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "f.png").stat().st_size > 0


@pytest.mark.parametrize(
    "name, data, mentions",
    [
        ("garbage.step", b"garbage, not a STEP file\n", ["Line 2", "Incorrect syntax"]),
        ("empty.stp", b"ISO-10303-21;\nHEADER;\nENDSEC;\nDATA;\nENDSEC;\nEND-ISO-10303-21;\n", []),
        ("cut.step", None, ["unexpected end of file"]),
    ],
)
def test_broken_step_is_one_line(trimesh_models, tmp_path, name, data, mentions):
    if data is None:
        data = (trimesh_models / "featuretype.STEP").read_bytes()[:50_000]
    model = tmp_path / name
    model.write_bytes(data)
    folder = tmp_path / "out"
    folder.mkdir()
    proc = run_cli("render", model, "-o", folder / "x.png", "--size", 64, 64)
    one_error(proc, name, "cannot read as STEP", *mentions)
    no_output(folder)


def test_meshing_has_a_time_limit(trimesh_models):
    data = (trimesh_models / "featuretype.STEP").read_bytes()
    with pytest.raises(InputError, match="took longer than 0.01 s"):
        step.step_to_glb(trimesh_models / "featuretype.STEP", data, time_limit=0.01)


def test_step_size_limit(tmp_path, monkeypatch):
    model = tmp_path / "big.step"
    model.write_bytes(b"ISO-10303-21;\n" + b" " * 4096)
    monkeypatch.setattr("blueprint.scene.formats.step.STEP_FILE_LIMIT", 1024)
    with pytest.raises(InputError, match="over the limit of 1 KiB for a STEP file"):
        blueprint.load_model(model)
