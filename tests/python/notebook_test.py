"""The example notebook runs from top to bottom (nbclient, Debian's python3-nbclient and
python3-ipykernel): every cell's assertions hold. Run from ctest (python_notebook)."""
import os
from pathlib import Path

import nbformat
import pytest

nbclient = pytest.importorskip("nbclient", reason="python3-nbclient is not installed")

SOURCE = Path(os.environ["RTHS_SOURCE_DIR"])


def test_example_notebook_runs_clean(tmp_path):
    notebook = nbformat.read(SOURCE / "examples/rths_in_jupyter.ipynb", as_version=4)
    client = nbclient.NotebookClient(notebook, timeout=300, kernel_name="python3",
                                     resources={"metadata": {"path": str(tmp_path)}})
    client.execute()
    printed = "".join(out.get("text", "") for cell in notebook.cells if cell.cell_type == "code"
                      for out in cell.get("outputs", []))
    assert "completed: peak" in printed
    assert "DIVERGED" in printed
