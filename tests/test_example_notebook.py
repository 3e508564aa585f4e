"""examples/audit_story.ipynb runs top to bottom (demo -> audit -> replay with the corrected model) in
under a minute, and its figures are in the output."""

from __future__ import annotations

import time
from pathlib import Path

import pytest

nbformat = pytest.importorskip("nbformat")
nbclient = pytest.importorskip("nbclient")
pytest.importorskip("ipykernel")

NOTEBOOK = Path(__file__).resolve().parents[1] / "examples" / "audit_story.ipynb"


def test_the_example_notebook_tells_its_story_with_figures(tmp_path):
    nb = nbformat.read(NOTEBOOK, as_version=4)
    assert all(not cell.get("outputs") for cell in nb.cells if cell.cell_type == "code"), "commit it without outputs"
    start = time.perf_counter()
    nbclient.NotebookClient(nb, timeout=120, kernel_name="python3",
                            resources={"metadata": {"path": str(tmp_path)}}).execute()
    wall = time.perf_counter() - start
    assert wall < 60, f"the notebook took {wall:.0f} s"
    outputs = [out for cell in nb.cells if cell.cell_type == "code" for out in cell.outputs]
    assert not [out for out in outputs if out.output_type == "error"]
    pngs = [out for out in outputs if "image/png" in out.get("data", {})]
    assert len(pngs) >= 2  # corrected.plot() and the side-by-side figure
    html = [out["data"]["text/html"] for out in outputs if "text/html" in out.get("data", {})]
    assert any("probecommit audit" in page and "data:image/png;base64," in page for page in html)
    assert (tmp_path / "runs/demo/manifest.json").is_file() and (tmp_path / "runs/demo-corrected/manifest.json").is_file()
