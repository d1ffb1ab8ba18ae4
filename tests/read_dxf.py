"""Reads DXF drawings with ezdxf, as a CAD program would, and prints what it found.

Usage: python3 read_dxf.py FILE...

For each file one line:

    dxf FILE version V errors E polylines N layer L closed C vertices K area A

then one line `vertex X Y` per vertex of the first polyline. E is the number of errors ezdxf's
audit found. With no files it only imports ezdxf. Exit code 3: ezdxf is not installed; a file
ezdxf cannot read ends the script with exit code 1 and its error on standard error.
"""

import sys

try:
    import ezdxf
except ImportError:
    print("ezdxf (the ezdxf Python package) is not installed", file=sys.stderr)
    sys.exit(3)


def area(points):
    """The shoelace area of a closed polygon."""
    n = len(points)
    return 0.5 * sum(
        points[k][0] * points[(k + 1) % n][1] - points[(k + 1) % n][0] * points[k][1]
        for k in range(n)
    )


for path in sys.argv[1:]:
    doc = ezdxf.readfile(path)
    auditor = doc.audit()
    polylines = [e for e in doc.modelspace() if e.dxftype() in ("POLYLINE", "LWPOLYLINE")]
    first = polylines[0]
    if first.dxftype() == "POLYLINE":
        points = [(v.dxf.location.x, v.dxf.location.y) for v in first.vertices]
    else:
        points = [(x, y) for x, y, *_ in first.get_points()]
    print(
        f"dxf {path} version {doc.dxfversion} errors {len(auditor.errors)} "
        f"polylines {len(polylines)} layer {first.dxf.layer} closed {int(first.is_closed)} "
        f"vertices {len(points)} area {area(points)!r}"
    )
    for x, y in points:
        print(f"vertex {x!r} {y!r}")
