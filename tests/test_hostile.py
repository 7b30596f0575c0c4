"""Hostile input (issue 17): every failure is one line whatever the file's name holds.

The CLI runs in a subprocess with a timeout, so that input that makes it hang fails its test
instead of hanging the suite.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import blueprint
from blueprint.errors import printable

TIMEOUT = 30  # seconds: a refusal takes well under one; only a hang reaches this

# the package under test, whatever the folder the command runs in (a relative PYTHONPATH would not)
ENV = {
    **os.environ,
    "PYTHONPATH": os.pathsep.join(
        [str(Path(blueprint.__file__).parents[1]), os.environ.get("PYTHONPATH", "")]
    ),
}


def run(*args, cwd: Path) -> subprocess.CompletedProcess:
    """The blueprint command in a subprocess; arguments may be bytes (names that are not UTF-8)."""
    return subprocess.run(
        [sys.executable, "-m", "blueprint.cli", *args],
        capture_output=True,
        cwd=cwd,
        env=ENV,
        timeout=TIMEOUT,
    )


def one_line(proc: subprocess.CompletedProcess) -> str:
    """The one error line of a failed run: exit 2, nothing on stdout, one line on stderr."""
    stderr = proc.stderr.decode("utf-8")  # strict: the line must be valid UTF-8 too
    assert proc.returncode == 2, (proc.returncode, stderr)
    assert proc.stdout == b"", proc.stdout
    assert stderr.endswith("\n") and stderr.count("\n") == 1, f"not one line: {stderr!r}"
    assert stderr.startswith("blueprint: error: "), stderr
    return stderr[len("blueprint: error: ") : -1]


# -- names that would break the line -------------------------------------------------------------------
def test_a_name_with_a_newline_stays_on_one_line(tmp_path):
    (tmp_path / "two\nlines.obj").write_bytes(b"v 0 0 0\n")
    line = one_line(run("info", "two\nlines.obj", cwd=tmp_path))
    assert line == "two\\nlines.obj: no triangles in the file"


def test_printable_escapes_what_would_break_a_line():
    name = os.fsdecode(b"a\xfe\n\r\tb\x1b[2J\xe2\x80\xa8c")  # U+2028 separates lines too
    assert printable(name + " é") == "a\\xfe\\n\\r\\tb\\x1b[2J\\u2028c é"
