"""Every notebook of docs/notebooks runs headless (nbclient), start to end."""

import pathlib

import nbformat
import pytest
from nbclient import NotebookClient

from conftest import ROOT, SHARED

NOTEBOOKS = sorted((ROOT / "docs" / "notebooks").glob("*.ipynb"))


def test_there_are_the_three_notebooks():
    assert {n.stem for n in NOTEBOOKS} >= {"paper001_guided_experiment", "your_own_log",
                                           "doa_on_a_cluster"}


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_the_notebook_runs(path, monkeypatch):
    nb = nbformat.read(path, as_version=4)
    assert all(not c.get("outputs") for c in nb.cells if c.cell_type == "code"), \
        f"{path.name} is committed with outputs"
    monkeypatch.setenv("LOCUS_SHARED", str(SHARED))
    monkeypatch.setenv("MPLBACKEND", "Agg")
    NotebookClient(nb, timeout=600, kernel_name="python3",
                   resources={"metadata": {"path": str(path.parent)}}).execute()
