"""Reads ParaView files with VTK itself, as ParaView does, and prints what it found.

Usage: python3 read_vtk.py FILE...   (.vtu or .pvd)

For a .pvd: one line `pvd FILE times T0 T1 ...` (each time once, whatever the parts listed
under it), then each data set it lists, read by vtkXMLUnstructuredGridReader. For each .vtu:

    vtu FILE points N cells M types T1,T2 shared_points S
    point|cell NAME components K names C0,C1 nan COUNT
    field NAME values V0|V1|...

`shared_points` is how many points more than one cell uses. A file that VTK cannot read ends
the script with exit code 1 and its error on standard error. Exit code 3: VTK is not installed.
"""

import math
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

try:
    from vtkmodules.vtkCommonCore import vtkOutputWindow, vtkFileOutputWindow
    from vtkmodules.vtkIOXML import vtkXMLUnstructuredGridReader
except ImportError:
    print("VTK (the vtk Python package) is not installed", file=sys.stderr)
    sys.exit(3)


class Errors:
    """VTK reports read errors through its output window, not through exceptions."""

    def __init__(self):
        self.log = Path("vtk-errors.log").resolve()
        self.log.unlink(missing_ok=True)
        window = vtkFileOutputWindow()
        window.SetFileName(str(self.log))
        vtkOutputWindow.SetInstance(window)

    def check(self, file):
        if self.log.exists() and self.log.read_text().strip():
            text = self.log.read_text()
            print(f"{file}: VTK reported: {text}", file=sys.stderr)
            sys.exit(1)


def array_line(kind, array):
    k = array.GetNumberOfComponents()
    names = [array.GetComponentName(c) or "" for c in range(k)] if k > 1 else []
    nan = 0
    for t in range(array.GetNumberOfTuples()):
        for c in range(k):
            if not math.isfinite(array.GetComponent(t, c)):
                nan += 1
    return f"{kind} {array.GetName()} components {k} names {','.join(names) or '-'} nan {nan}"


def read_vtu(path, errors):
    reader = vtkXMLUnstructuredGridReader()
    reader.SetFileName(str(path))
    reader.Update()
    errors.check(path)
    grid = reader.GetOutput()
    if grid is None or grid.GetNumberOfPoints() == 0:
        print(f"{path}: VTK read no points", file=sys.stderr)
        sys.exit(1)
    types = sorted({grid.GetCellType(c) for c in range(grid.GetNumberOfCells())})
    uses = [0] * grid.GetNumberOfPoints()
    for c in range(grid.GetNumberOfCells()):
        ids = grid.GetCell(c).GetPointIds()
        for k in range(ids.GetNumberOfIds()):
            uses[ids.GetId(k)] += 1
    shared = sum(1 for u in uses if u > 1)
    print(
        f"vtu {path.name} points {grid.GetNumberOfPoints()} cells {grid.GetNumberOfCells()} "
        f"types {','.join(map(str, types))} shared_points {shared}"
    )
    for kind, data in (("point", grid.GetPointData()), ("cell", grid.GetCellData())):
        for a in range(data.GetNumberOfArrays()):
            print(array_line(kind, data.GetArray(a)))
    fields = grid.GetFieldData()
    for a in range(fields.GetNumberOfArrays()):
        array = fields.GetAbstractArray(a)
        values = [array.GetValue(v) for v in range(array.GetNumberOfValues())]
        print(f"field {array.GetName()} values {'|'.join(map(str, values))}")


def read_pvd(path, errors):
    root = ET.parse(path).getroot()
    sets = root.find("Collection").findall("DataSet")
    times = list(dict.fromkeys(s.get("timestep") for s in sets))
    print(f"pvd {path.name} times {' '.join(times)}")
    for s in sets:
        read_vtu(path.parent / s.get("file"), errors)


def main():
    errors = Errors()
    for name in sys.argv[1:]:
        path = Path(name)
        if path.suffix == ".pvd":
            read_pvd(path, errors)
        else:
            read_vtu(path, errors)


main()
