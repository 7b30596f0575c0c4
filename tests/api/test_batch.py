"""``blueprint batch`` on a 2-worker Dask LocalCluster sharing llvmpipe's one EGL device: inputs
from folders and globs, outputs equal to ``draw``'s, a manifest, reruns that keep what is up to
date, broken files reported and not fatal; EGL device selection and its one-line errors."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest
import trimesh
from helpers import needs_cli, run_cli
from PIL import Image

import blueprint
from blueprint import InputError
from blueprint.api.batch import MANIFEST, MODEL_SUFFIXES, batch, choose_devices, collect_inputs, outputs_for
from blueprint.gpu.context import create_context, egl_device_count, egl_devices

SIZE = (72, 64)


def _models(root: Path) -> dict[str, Path]:
    (root / "sub").mkdir(parents=True)
    paths = {
        "box": root / "box.stl",
        "ball": root / "sub" / "ball.obj",
        "broken": root / "sub" / "broken.obj",
    }
    trimesh.creation.box(extents=(1, 2, 3)).export(paths["box"])
    trimesh.creation.icosphere(subdivisions=1).export(paths["ball"])
    paths["broken"].write_text("v 0 0 0\nthis is not an OBJ\n")
    (root / "notes.txt").write_text("not a model")
    return paths


@pytest.fixture(scope="module")
def ran(tmp_path_factory):
    """One batch of three inputs (one broken) on two workers sharing device 0."""
    root = tmp_path_factory.mktemp("models")
    paths = _models(root)
    out = tmp_path_factory.mktemp("out")
    manifest = batch(
        [root], out, views=["iso", "top"], formats=["png", "svg"], workers=2, gpus="0,", size=SIZE
    )
    return root, paths, out, manifest


def test_inputs_from_folders_globs_and_files(tmp_path):
    paths = _models(tmp_path)
    assert collect_inputs([tmp_path]) == [paths["box"], paths["ball"], paths["broken"]]
    assert collect_inputs([tmp_path / "sub" / "*.obj", paths["ball"]]) == [paths["ball"], paths["broken"]]
    for bad, message in [
        (tmp_path / "missing.stl", "missing.stl: no such file or folder"),
        (tmp_path / "*.ply", r"\*.ply: no files match this pattern"),
        (tmp_path / "sub" / "empty", "empty: no model files in this folder"),
    ]:
        if bad.name == "empty":
            bad.mkdir()
        with pytest.raises(InputError, match=message):
            collect_inputs([bad])


def test_a_folder_yields_every_format_the_loader_reads(tmp_path):
    # every suffix a folder is searched for is one the loader reads (STEP through its
    # tessellator), and none it cannot
    from blueprint.scene.loader import supported_formats

    readable = {f".{ext}" for ext in supported_formats()}
    assert set(MODEL_SUFFIXES) <= readable
    for suffix in (".step", ".stp", ".3mf", ".gltf"):
        (tmp_path / f"part{suffix.upper()}").write_bytes(b"x")
    (tmp_path / "notes.txt").write_text("not a model")
    found = {p.name for p in collect_inputs([tmp_path])}
    assert found == {"part.STEP", "part.STP", "part.3MF", "part.GLTF"}


def test_outputs_keep_the_folders_below_the_common_one(tmp_path):
    out = tmp_path / "out"
    ball = tmp_path / "a" / "sub" / "ball.obj"
    assert outputs_for(ball, tmp_path / "a", out, ["iso", "top"], ["png"]) == [
        out / "sub" / "ball.iso.png",
        out / "sub" / "ball.top.png",
    ]


def test_manifest_lists_each_input(ran):
    root, paths, out, manifest = ran
    assert json.loads((out / MANIFEST).read_text()) == manifest
    assert [r["input"] for r in manifest["inputs"]] == [str(paths[k]) for k in ("box", "ball", "broken")]
    assert (manifest["drawn"], manifest["skipped"], manifest["failed"], manifest["workers"]) == (2, 0, 1, 2)
    assert manifest["devices"] == [0]
    box, ball, broken = manifest["inputs"]
    assert box["outputs"] == [str(out / f"box.{v}.{f}") for v in ("iso", "top") for f in ("png", "svg")]
    assert ball["outputs"][0] == str(out / "sub" / "ball.iso.png")
    assert box["layers"] == {"iso": 2, "top": 2} and box["error"] is None and box["ms"] > 0
    assert broken["outputs"] == [] and broken["error"].startswith(f"{paths['broken']}: ")
    assert "\n" not in broken["error"]
    assert {box["device"], ball["device"]} == {0}


def test_outputs_equal_what_draw_draws(ran, renderer):
    _, paths, out, _ = ran
    for view in ("iso", "top"):
        drawing = blueprint.draw(paths["box"], size=SIZE, view=view)
        np.testing.assert_array_equal(np.asarray(Image.open(out / f"box.{view}.png")), drawing.image)
        vector = blueprint.draw(paths["ball"], size=SIZE, view=view, vector=True)
        assert (out / "sub" / f"ball.{view}.svg").read_text(encoding="utf-8") == vector.svg()
    assert sorted(p.name for p in out.rglob("*") if p.is_file()) == sorted(
        [MANIFEST] + [f"{m}.{v}.{f}" for m in ("box", "ball") for v in ("iso", "top") for f in ("png", "svg")]
    )


def test_a_rerun_keeps_outputs_newer_than_their_input(ran):
    _, paths, out, first = ran
    stamps = {p: p.stat().st_mtime_ns for p in out.rglob("*.png")}
    again = batch([paths["box"], paths["ball"]], out, views=["iso", "top"], formats=["png", "svg"], size=SIZE)
    assert (again["drawn"], again["skipped"], again["workers"]) == (0, 2, 0)
    assert {p: p.stat().st_mtime_ns for p in out.rglob("*.png")} == stamps
    assert [r["layers"] for r in again["inputs"]] == [r["layers"] for r in first["inputs"][:2]]
    # an input changed after its drawings is drawn again, and only it
    later = max(stamps.values()) / 1e9 + 5
    os.utime(paths["box"], (later, later))
    third = batch([paths["box"], paths["ball"]], out, views=["iso", "top"], formats=["png", "svg"], size=SIZE)
    assert (third["drawn"], third["skipped"]) == (1, 1)
    assert (out / "box.iso.png").stat().st_mtime_ns > stamps[out / "box.iso.png"]
    assert (out / "sub" / "ball.iso.png").stat().st_mtime_ns == stamps[out / "sub" / "ball.iso.png"]


def test_devices_are_chosen_by_index_or_count():
    devices = egl_devices()
    count = egl_device_count()
    assert count is not None and len(devices) == count >= 1
    usable = [d["index"] for d in devices if d["gpu"]] or [d["index"] for d in devices]
    assert choose_devices("all") == usable
    assert choose_devices(1) == usable[:1] == choose_devices("1")
    assert choose_devices("0,") == [0]
    assert choose_devices(None) is None
    for bad, message in [
        (f"{count},", f"EGL device {count} does not exist"),
        (str(len(usable) + 1), f"this machine has {len(usable)} usable EGL devices"),
        ("0,0", "device indices repeat"),
        ("many", "give all, a count N, or device indices"),
        ("0", "--gpus 0: this machine has"),
    ]:
        with pytest.raises(InputError, match=message):
            choose_devices(bad)


def test_a_context_on_a_device_that_does_not_exist_is_one_line():
    count = egl_device_count()
    with pytest.raises(InputError) as caught:
        create_context(device=count)
    assert str(caught.value).startswith(f"EGL device {count} does not exist: this machine has ")
    ctx = create_context(device=0)
    assert ctx.info["GL_RENDERER"] == egl_devices()[0]["renderer"]
    ctx.release()


@needs_cli
def test_command_line_exit_codes(tmp_path):
    paths = _models(tmp_path / "models")
    out = tmp_path / "out"
    failed = run_cli("batch", paths["box"], paths["broken"], "-o", out, "--size", *SIZE)
    assert failed.returncode == 1, failed.stderr
    assert failed.stderr.splitlines() == [f"blueprint: failed: {paths['broken']}: no triangles in the file"]
    assert failed.stdout.startswith(f"{out / MANIFEST}: 1 drawn, 0 up to date, 1 failed")
    assert (out / "box.iso.png").is_file()
    for args, message in [
        (("--formats", "gif"), "blueprint: error: unknown format 'gif' (choose png, svg, pdf, dxf)"),
        (("--views", "sideways"), "blueprint: error: unknown view 'sideways'"),
        (("--gpus", "9,"), "blueprint: error: --gpus: EGL device 9 does not exist"),
        (("--workers", "0"), "blueprint: error: --workers must be at least 1, got 0"),
    ]:
        bad = run_cli("batch", paths["box"], "-o", tmp_path / "bad", *args)
        assert bad.returncode == 2 and len(bad.stderr.splitlines()) == 1, bad.stderr
        assert bad.stderr.startswith(message)
        assert not (tmp_path / "bad" / "box.iso.png").exists()
    device = run_cli("render", paths["box"], "-o", tmp_path / "x.png", env={"BLUEPRINT_GL_DEVICE": "9"})
    assert device.returncode == 2 and device.stderr.startswith(
        "blueprint: error: EGL device 9 does not exist"
    )
    assert not (tmp_path / "x.png").exists()
