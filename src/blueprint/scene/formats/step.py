"""STEP: Z-up by the convention of CAD; meshed by OpenCASCADE in metres, whatever unit the file
is written in.

STEP files are meshed by OpenCASCADE (through ``cascadio``) in a child process.

OpenCASCADE is native code: it prints its parse errors straight to the process's own stdout and
stderr, and nothing bounds the time a hostile file can keep it busy. In a child process its
output is captured (the first line of it goes into the one-line error) and a time limit can end
it; the child writes a GLB that is read like any glTF binary.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

from blueprint.errors import InputError
from blueprint.scene.formats.base import Converted
from blueprint.settings import read_file

__all__ = ["STEP_FILE_LIMIT", "STEP_TIME_LIMIT", "read_step", "step_to_glb"]

# A STEP file is text of about a hundred bytes an entity; meshing takes OpenCASCADE far longer
# per byte than any mesh format takes to parse, so its limits are much lower than a mesh's.
STEP_FILE_LIMIT = 256 << 20
STEP_TIME_LIMIT = 300.0  # seconds

_COLOUR = re.compile("\x1b\\[[0-9;]*m")
_CHILD = """
import sys
import cascadio
sys.exit(0 if cascadio.step_to_glb(sys.argv[1], sys.argv[2]) == 0 else 3)
"""


def step_to_glb(path: Path, data: bytes, time_limit: float | None = None) -> bytes:
    """Mesh a STEP file's contents and return them as GLB bytes.

    Parameters
    ----------
    path : Path
        The file's name, for messages.
    data : bytes
        The STEP file's contents (already read within ``STEP_FILE_LIMIT``).
    time_limit : float, optional
        Seconds the meshing may take; ``STEP_TIME_LIMIT`` if not given.

    Raises
    ------
    InputError
        ``cascadio`` is not installed, OpenCASCADE cannot read the file, or meshing it takes
        longer than the limit.
    """
    limit = STEP_TIME_LIMIT if time_limit is None else time_limit
    with tempfile.TemporaryDirectory(prefix="blueprint-step-") as folder:
        source = os.path.join(folder, "model.step")
        target = os.path.join(folder, "model.glb")
        with open(source, "wb") as fh:
            fh.write(data)
        try:
            done = subprocess.run(
                [sys.executable, "-c", _CHILD, source, target],
                capture_output=True,
                timeout=limit,
                stdin=subprocess.DEVNULL,
                check=False,
            )
        except subprocess.TimeoutExpired:
            raise InputError(f"{path}: meshing the STEP file took longer than {limit:g} s") from None
        output = (done.stderr + done.stdout).decode("utf-8", "replace")
        if "No module named 'cascadio'" in output:
            raise InputError(f"{path}: reading this file needs the Python package 'cascadio'")
        if done.returncode != 0 or not os.path.isfile(target) or os.path.getsize(target) == 0:
            raise InputError(f"{path}: cannot read as STEP: {_first_problem(output)}")
        with open(target, "rb") as fh:
            return fh.read()


def _first_problem(output: str) -> str:
    """OpenCASCADE's first parse error (it names the line), else cascadio's first message,
    without colour codes and asterisks."""
    lines = [
        "".join(c for c in _COLOUR.sub("", line) if c.isprintable()).strip(" *")
        for line in output.splitlines()
    ]
    parse = [line.split(":", 1)[1].strip() for line in lines if line.startswith("ERR StepFile")]
    other = [line.removeprefix("Error:").strip() for line in lines if line]
    return (parse or other or ["OpenCASCADE found no shapes in it"])[0]


def read_step(path: Path, size: int) -> Converted:
    """The file meshed into GLB bytes (``step_to_glb``), for the GLB reader."""
    glb = step_to_glb(path, read_file(path, STEP_FILE_LIMIT, "a STEP file"))
    return Converted(glb, "glb", f"{path}: cannot read the mesh OpenCASCADE made of it")
