"""The example notebooks (examples/*.ipynb) run from top to bottom in a fresh Jupyter kernel
(nbclient, as `jupyter nbconvert --execute` would), their own asserts included: the documented
Python API works as the notebooks show it."""

from __future__ import annotations

from pathlib import Path

import nbformat
import pytest
from nbclient import NotebookClient

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


@pytest.mark.parametrize("path", sorted(EXAMPLES.glob("*.ipynb")), ids=lambda p: p.name)
def test_an_example_notebook_runs_from_top_to_bottom(path, tmp_path):
    notebook = nbformat.read(path, as_version=4)
    NotebookClient(notebook, timeout=600, kernel_name="python3", resources={"metadata": {"path": str(tmp_path)}}).execute()
    outputs = [o for cell in notebook.cells if cell.cell_type == "code" for o in cell.outputs]
    assert not [o for o in outputs if o.output_type == "error"]
    assert any("runs bit for bit like the scene" in o.get("text", "") for o in outputs) or path.stem != "quickstart"


def test_there_is_an_example_notebook():
    assert (EXAMPLES / "quickstart.ipynb").exists()
