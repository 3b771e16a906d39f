"""The example notebook runs from top to bottom (nbclient, Debian's python3-nbclient and
python3-ipykernel) from an empty folder, as a Jupyter user starts it: every cell's assertions
hold and its figures are drawn inline (no backend forced from outside). Run from ctest
(python_notebook)."""
import os
from pathlib import Path

import nbformat
import pytest

nbclient = pytest.importorskip("nbclient", reason="python3-nbclient is not installed")

SOURCE = Path(os.environ["RTHS_SOURCE_DIR"])


def test_example_notebook_runs_clean_from_any_folder_and_draws_inline(tmp_path, monkeypatch):
    monkeypatch.delenv("MPLBACKEND", raising=False)  # Jupyter's own inline backend, as a user has
    notebook = nbformat.read(SOURCE / "examples/rths_in_jupyter.ipynb", as_version=4)
    client = nbclient.NotebookClient(notebook, timeout=300, kernel_name="python3",
                                     resources={"metadata": {"path": str(tmp_path)}})
    client.execute()
    outputs = [out for cell in notebook.cells if cell.cell_type == "code"
               for out in cell.get("outputs", [])]
    printed = "".join(out.get("text", "") for out in outputs)
    assert "completed: peak" in printed
    # The paper frame's 14 ms lag reads as `rths run` reads it (README): E_rms 57.50 %.
    assert "E_rms 57.5 %" in printed, printed
    assert "NRMSE" not in printed
    assert "DIVERGED" in printed
    figures = [out for out in outputs if "image/png" in out.get("data", {})]
    assert len(figures) >= 2, "the notebook's figures were not drawn inline"
