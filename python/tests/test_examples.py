"""The Python examples run as a user runs them: the notebook top to bottom (nbclient), the
optimisation loop in its quick form."""

import shutil
import subprocess
import sys

import pytest

from conftest import ROOT

EXAMPLES = ROOT / "examples" / "python"


def test_the_notebook_runs_top_to_bottom():
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    notebook = nbformat.read(EXAMPLES / "tutorial.ipynb", as_version=4)
    study = EXAMPLES / "tutorial-study"
    shutil.rmtree(study, ignore_errors=True)
    try:
        client = nbclient.NotebookClient(
            notebook, timeout=600, kernel_name="python3", resources={"metadata": {"path": str(EXAMPLES)}}
        )
        client.execute()  # raises CellExecutionError naming the cell that failed
    finally:
        shutil.rmtree(study, ignore_errors=True)
    outputs = [o for cell in notebook.cells if cell.cell_type == "code" for o in cell.outputs]
    text = "".join(o.get("text", "") for o in outputs if o.output_type == "stream")
    assert "finished" in text
    assert any("image/png" in o.get("data", {}) for o in outputs), "no picture came out"
    assert "largest shear" in text


def test_the_optimisation_example_finds_a_force_in_its_quick_form():
    done = subprocess.run(
        [sys.executable, "smallest_holder_force.py", "--quick"],
        cwd=EXAMPLES,
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert done.returncode == 0, done.stderr
    assert "300 °C: smallest holder force keeping the flange flat" in done.stdout
    assert " N (to within " in done.stdout, done.stdout
