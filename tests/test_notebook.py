"""The example notebook runs in a real Jupyter kernel and shows its drawings inline."""

from __future__ import annotations

from pathlib import Path

import nbformat
from nbclient import NotebookClient

NOTEBOOK = Path(__file__).resolve().parents[1] / "examples" / "blueprint.ipynb"


def test_notebook_is_stored_without_outputs():
    nb = nbformat.read(NOTEBOOK, as_version=4)
    code = [c for c in nb.cells if c.cell_type == "code"]
    assert code and all(c.outputs == [] and c.execution_count is None for c in code)


def test_notebook_runs_and_shows_drawings(tmp_path):
    nb = nbformat.read(NOTEBOOK, as_version=4)
    NotebookClient(
        nb, timeout=300, kernel_name="python3", resources={"metadata": {"path": str(tmp_path)}}
    ).execute()
    shown = [
        mime
        for cell in nb.cells
        if cell.cell_type == "code"
        for out in cell.outputs
        if out.output_type in ("execute_result", "display_data")
        for mime in out.data
        if mime in ("image/png", "image/svg+xml")
    ]
    # three raster drawings (the drawing, the plan sheet, the highlighted part) and one vector one
    assert shown.count("image/png") == 3 and shown.count("image/svg+xml") == 1
    errors = [o for c in nb.cells if c.cell_type == "code" for o in c.outputs if o.output_type == "error"]
    assert errors == []
    last = nb.cells[-1].outputs[0].data["text/plain"]
    assert last == "['scene.svg', 'scene.pdf', 'scene.dxf', 'scene.png']"
