"""Compares two forming runs of the same scenario (same mesh), e.g. the implicit solver
against a slow explicit reference, as docs/solver.md reports them.

Usage: python3 compare_forming.py REFERENCE_FOLDER OTHER_FOLDER

Each folder is what `thermostamp run ... --output FOLDER` wrote. Printed, one `key value`
line each:

- `shear_max_deg`, `shear_rms_deg`: largest and root-mean-square difference of the cells'
  shear angle (cell data `shear_angle_deg`) in the last frame of each forming.pvd;
- `punch_force_end`, `punch_force_peak`: the relative difference of the punch force at the
  end of the stroke and of its peak (forming.csv), and `punch_force_curve`: the largest
  relative difference along the stroke where the reference's force is above a tenth of its
  peak, the other run interpolated at the reference's strokes;
- `draw_in_mm`: the difference of the edge's draw-in at the end of the stroke.

Only the Python standard library: the .vtu frames are decoded as thermostamp writes them
(appended to nothing, base64 "binary" arrays with a UInt64 byte count in front).
"""

import base64
import csv
import math
import struct
import sys
import xml.etree.ElementTree as ET
from pathlib import Path


def last_frame(folder):
    pvd = ET.parse(folder / "forming.pvd").getroot()
    files = [d.get("file") for d in pvd.iter("DataSet")]
    return folder / files[-1]


def cell_array(vtu, name):
    root = ET.parse(vtu).getroot()
    for array in root.iter("DataArray"):
        if array.get("Name") == name:
            raw = base64.b64decode("".join(array.text.split()))
            (length,) = struct.unpack("<Q", raw[:8])
            return list(struct.unpack(f"<{length // 8}d", raw[8 : 8 + length]))
    raise SystemExit(f"{vtu}: no array {name}")


def history(folder):
    with open(folder / "forming.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    return [{k: float(v) for k, v in row.items()} for row in rows]


def interpolate(rows, stroke, key):
    for a, b in zip(rows, rows[1:]):
        if a["stroke"] <= stroke <= b["stroke"] and b["stroke"] > a["stroke"]:
            w = (stroke - a["stroke"]) / (b["stroke"] - a["stroke"])
            return a[key] + w * (b[key] - a[key])
    return None


def main():
    if len(sys.argv) != 3:
        raise SystemExit(__doc__)
    reference, other = Path(sys.argv[1]), Path(sys.argv[2])
    a = cell_array(last_frame(reference), "shear_angle_deg")
    b = cell_array(last_frame(other), "shear_angle_deg")
    if len(a) != len(b):
        raise SystemExit(f"different meshes: {len(a)} and {len(b)} cells")
    diff = [abs(x - y) for x, y in zip(a, b)]
    print(f"cells {len(a)}")
    print(f"shear_largest_deg {max(map(abs, a)):.3f} {max(map(abs, b)):.3f}")
    print(f"shear_max_deg {max(diff):.3f}")
    print(f"shear_rms_deg {math.sqrt(sum(d * d for d in diff) / len(diff)):.3f}")
    ra, rb = history(reference), history(other)
    end_a, end_b = ra[-1], rb[-1]
    print(f"stroke_end_mm {end_a['stroke']:.3f} {end_b['stroke']:.3f}")
    fa, fb = end_a["punch_force"], end_b["punch_force"]
    print(f"punch_force_end {fa:.3f} {fb:.3f} {(fb - fa) / fa:+.4f}")
    pa = max(r["punch_force"] for r in ra)
    pb = max(r["punch_force"] for r in rb)
    print(f"punch_force_peak {pa:.3f} {pb:.3f} {(pb - pa) / pa:+.4f}")
    worst = 0.0
    for r in ra:
        if r["punch_force"] <= 0.1 * pa:
            continue
        f = interpolate(rb, r["stroke"], "punch_force")
        if f is not None:
            worst = max(worst, abs(f - r["punch_force"]) / r["punch_force"])
    print(f"punch_force_curve {worst:.4f}")
    da, db = end_a["draw_in"], end_b["draw_in"]
    print(f"draw_in_mm {da:.3f} {db:.3f} {db - da:+.3f}")


if __name__ == "__main__":
    main()
