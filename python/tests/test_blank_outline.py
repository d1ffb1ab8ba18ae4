"""`thermostamp blank-outline` as a CAD user meets it: the outline's DXF drawing, read by ezdxf,
is one closed polyline on the layer OUTLINE with the vertices of `outline.csv`."""

import csv

import pytest

from conftest import HEMISPHERE, run_cli, quick_set

ezdxf = pytest.importorskip("ezdxf")


def test_the_outline_dxf_reads_in_ezdxf_as_the_csv_outline(tmp_path):
    out = tmp_path / "outline"
    run_cli("blank-outline", HEMISPHERE, "--trim-circle", 45, "--margin", 5, "--iterations", 1,
            *quick_set({"output.frames": 0}), "--output", out)
    with open(out / "outline.csv", newline="") as f:
        rows = [(float(r["x"]), float(r["y"])) for r in csv.DictReader(f)]
    assert rows[0] == rows[-1], "the CSV closes the outline"
    doc = ezdxf.readfile(out / "outline.dxf")
    assert doc.dxfversion == "AC1009"
    assert not doc.audit().has_errors
    assert "OUTLINE" in doc.layers
    polylines = [e for e in doc.modelspace() if e.dxftype() in ("POLYLINE", "LWPOLYLINE")]
    assert len(polylines) == 1
    outline = polylines[0]
    assert outline.dxf.layer == "OUTLINE"
    assert outline.is_closed
    vertices = [(v.dxf.location.x, v.dxf.location.y) for v in outline.vertices]
    assert vertices == rows[:-1]
