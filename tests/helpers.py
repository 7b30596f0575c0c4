"""Helpers the tests share: the project's paths, the command line in a subprocess and its
one-line errors, a model loaded in a fresh process, and model points to pixels.

Importable from every test folder as ``helpers`` (pytest puts this folder, the conftest's, on
``sys.path``).
"""

from __future__ import annotations

import importlib.util
import os
import resource
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import blueprint

# the repository's root, whichever folder of tests/ a test lies in
ROOT = Path(__file__).resolve().parents[1]
TESTS = ROOT / "tests"
# the shared test models beside the repository (present in CI; the ``shared_models`` fixture skips)
SHARED_MODELS = ROOT.parent / "shared" / "models"
# the geometry vertex shader with corners snapped to 1/256 px, as the H200's rasteriser snaps them
SNAPPED_GEOMETRY = TESTS / "glsl" / "snapped_geometry.vert"
# the console script of the environment running the tests
BLUEPRINT = Path(sys.executable).parent / "blueprint"
needs_cli = pytest.mark.skipif(not BLUEPRINT.exists(), reason=f"console script not found at {BLUEPRINT}")


def hostile_corpus():
    """benchmarks/hostile.py, the corpus of hostile inputs (and its GLB writer), as a module."""
    path = Path(__file__).resolve().parents[1] / "benchmarks" / "hostile.py"
    spec = importlib.util.spec_from_file_location("hostile_corpus", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up by name
    spec.loader.exec_module(module)
    return module


def run_cli(*args, cwd=None, env=None, limits=None, timeout: float = 300) -> subprocess.CompletedProcess:
    """The ``blueprint`` command with ``args`` (made strings) in a subprocess, its output
    captured as text. ``env`` entries are laid over this process's environment; ``limits`` maps
    ``resource.RLIMIT_*`` to a soft and hard limit of the child."""

    def apply_limits() -> None:
        for which, value in (limits or {}).items():
            resource.setrlimit(which, (value, value))

    return subprocess.run(
        [str(BLUEPRINT), *map(str, args)],
        capture_output=True,
        text=True,
        cwd=cwd,
        env={**os.environ, **(env or {})},
        timeout=timeout,
        preexec_fn=apply_limits if limits else None,
    )


def one_error(proc: subprocess.CompletedProcess, *mentions: str, blank_stdout: bool = False) -> str:
    """The single error line of a failed run, checked; ``mentions`` must appear in it.
    ``blank_stdout`` tolerates whitespace on stdout (bench's progress bar, see test_cli)."""
    assert "Traceback" not in proc.stderr, proc.stderr
    assert proc.returncode == 2, (proc.returncode, proc.stderr)
    assert (proc.stdout.strip() if blank_stdout else proc.stdout) == "", proc.stdout
    assert proc.stderr.endswith("\n") and proc.stderr.count("\n") == 1, f"not one line: {proc.stderr!r}"
    line = proc.stderr.rstrip("\n")
    assert line.startswith("blueprint: error: "), line
    for text in mentions:
        assert text.lower() in line.lower(), f"{text!r} not in {line!r}"
    return line


def loaded_in_a_process(path: Path, what: str) -> list[str]:
    """``what`` (an expression of the model ``m``) of ``path`` loaded in a fresh process, and
    whether that process imported trimesh."""
    code = (
        "import sys; from blueprint.scene.loader import load_model; "
        f"m = load_model({str(path)!r}); print({what}, 'trimesh' in sys.modules)"
    )
    env = {**os.environ, "PYTHONPATH": str(Path(blueprint.__file__).parents[1])}
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=120)
    assert done.returncode == 0, done.stderr
    return done.stdout.split()


def no_output(folder: Path) -> None:
    """Nothing left in ``folder`` (by a run that failed)."""
    left = sorted(p.name for p in folder.iterdir())
    assert left == [], f"left in the output folder: {left}"


def project(points, view, projection=None, size=None) -> np.ndarray:
    """Model points (..., 3) through ``view`` and ``projection`` ((4, 4), OpenGL conventions,
    column vectors; or a ``Camera`` as ``view`` and its matrices): (..., 3) normalised device
    coordinates, or with ``size`` (width, height) (..., 2) float64 pixels, x right and y down
    from the top-left corner of the picture. Every point must lie in front of the eye.

    Written out here, apart from the package's ``Camera.to_pixels``, so that the tests check the
    package's projection rather than repeat it."""
    if projection is None:
        view, projection = view.view_matrix(), view.projection_matrix()
    points = np.asarray(points, np.float64)
    homogeneous = np.concatenate([points, np.ones((*points.shape[:-1], 1))], axis=-1)
    matrix = np.asarray(projection, np.float64) @ np.asarray(view, np.float64)
    clip = np.einsum("ij,...j->...i", matrix, homogeneous)
    assert (clip[..., 3] > 0).all(), "a point lies behind the camera"
    ndc = clip[..., :3] / clip[..., 3:]
    if size is None:
        return ndc
    return np.stack([(ndc[..., 0] + 1) / 2 * size[0], (1 - ndc[..., 1]) / 2 * size[1]], axis=-1)
