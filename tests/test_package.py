"""The package as pip builds it: the wheel carries every file of the package's data folders, the
wheel's requirements name every package the code imports, and an install missing a shader says
so in one line. (.ci/wheel.sh installs the wheel and runs every command from it.)"""

from __future__ import annotations

import ast
import importlib.metadata
import os
import re
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest
from helpers import no_output, one_error

from blueprint import examples

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "src" / "blueprint"
DATA_FOLDERS = {"glsl", "presets", "data"}


def _normal(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> zipfile.ZipFile:
    """The wheel pip builds from a copy of the project (setuptools writes its build folders into
    the tree it builds, and a stale build/lib would lend the wheel files the tree no longer has)."""
    work = tmp_path_factory.mktemp("wheel")
    project = work / "project"
    project.mkdir()
    for name in ("pyproject.toml", "README.md", "LICENSE"):
        shutil.copy(ROOT / name, project / name)
    shutil.copytree(ROOT / "src", project / "src", ignore=shutil.ignore_patterns("__pycache__", "*.egg-info"))
    proc = subprocess.run(
        [sys.executable, "-m", "pip", "wheel", str(project), "--no-deps", "--no-build-isolation", "-q"]
        + ["-w", str(work / "dist")],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    (built,) = (work / "dist").glob("blueprint_drawings-*.whl")
    with zipfile.ZipFile(built) as archive:
        yield archive


def test_wheel_carries_every_file_of_the_data_folders(wheel):
    want = {
        path.relative_to(PACKAGE.parent).as_posix(): path
        for path in PACKAGE.rglob("*")
        if path.is_file()
        and "__pycache__" not in path.parts
        and DATA_FOLDERS & set(path.relative_to(PACKAGE).parts[:-1])
    }
    # every kind of file the package ships, so a new kind cannot be left out unnoticed
    assert {".geom", ".vert", ".frag", ".comp", ".glsl", ".toml", ".glb"} <= {p.suffix for p in want.values()}
    missing = sorted(set(want) - set(wheel.namelist()))
    assert missing == []
    changed = [name for name, path in want.items() if wheel.read(name) != path.read_bytes()]
    assert changed == []


def test_wheel_carries_every_module(wheel):
    modules = {p.relative_to(PACKAGE.parent).as_posix() for p in PACKAGE.rglob("*.py")}
    assert sorted(modules - set(wheel.namelist())) == []


def test_wheel_requires_every_package_the_code_imports(wheel):
    (metadata,) = [n for n in wheel.namelist() if n.endswith(".dist-info/METADATA")]
    required = {
        _normal(re.match(r"[A-Za-z0-9._-]+", line.split(":", 1)[1].strip()).group(0))
        for line in wheel.read(metadata).decode().splitlines()
        if line.startswith("Requires-Dist:") and "extra ==" not in line
    }
    imported = set()
    for path in PACKAGE.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                imported |= {alias.name.split(".")[0] for alias in node.names}
            elif isinstance(node, ast.ImportFrom) and node.level == 0:
                imported.add(node.module.split(".")[0])
    third_party = imported - set(sys.stdlib_module_names) - {"blueprint"}
    distributions = importlib.metadata.packages_distributions()
    undeclared = {
        module: names
        for module in sorted(third_party)
        if not (names := {_normal(d) for d in distributions.get(module, [])}) & required
    }
    assert undeclared == {}
    assert "rtree" in required  # imported by trimesh, not by blueprint: sections need it


def test_console_script_is_declared(wheel):
    (entry_points,) = [n for n in wheel.namelist() if n.endswith(".dist-info/entry_points.txt")]
    assert "blueprint = blueprint.cli:main" in wheel.read(entry_points).decode().splitlines()


def broken_install(tmp_path: Path, missing: str, command: str) -> tuple[subprocess.CompletedProcess, Path]:
    """``blueprint COMMAND`` of the example model to a PNG, run from a copy of the package
    without the file ``missing`` (relative to the package): the process and the output
    folder."""
    copy = tmp_path / "site"
    shutil.copytree(PACKAGE, copy / "blueprint", ignore=shutil.ignore_patterns("__pycache__"))
    (copy / "blueprint" / missing).unlink()
    out = tmp_path / "out"
    out.mkdir()
    args = [command, str(examples.example_path()), "-o", str(out / "r.png"), "--size", "64", "48"]
    proc = subprocess.run(
        [sys.executable, "-m", "blueprint", *args],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        env={**os.environ, "PYTHONPATH": str(copy)},
        timeout=120,
    )
    return proc, out


def test_a_missing_shader_file_is_one_line(tmp_path):
    """A broken install (a shader left out of the wheel): exit 2 and the file named, no traceback."""
    proc, out = broken_install(tmp_path, "gpu_silhouettes/glsl/idsil_lines.geom", "silhouettes")
    one_error(proc, "shader file", "gpu_silhouettes/glsl/idsil_lines.geom", "not found")
    no_output(out)


def test_a_missing_module_says_the_install_is_broken(tmp_path):
    """A module of the package left out (or a package it requires missing): one line naming
    the module and saying the installation is incomplete, exit 2, no traceback."""
    proc, out = broken_install(tmp_path, "export/writers.py", "render")
    one_error(proc, "no module named 'blueprint.export.writers'", "installation is incomplete")
    no_output(out)


def test_a_missing_core_preset_says_the_install_is_broken(tmp_path):
    """Without presets/blueprint.toml no picture can be drawn: the line names the file and says
    the installation is incomplete, rather than reading like a mistyped preset name."""
    proc, out = broken_install(tmp_path, "pipeline/presets/blueprint.toml", "render")
    one_error(proc, "presets/blueprint.toml is missing", "installation is incomplete")
    no_output(out)
