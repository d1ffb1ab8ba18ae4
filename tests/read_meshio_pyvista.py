"""Reads ParaView files with meshio and with pyvista, as users' scripts do, and prints what
each found.

Usage: python3 read_meshio_pyvista.py FILE...   (.vtu or .pvd)

For each .vtu, one line per reader:

    meshio FILE points N cells M point_data A,B,... cell_data C,D,...
    pyvista FILE points N cells M point_data A,B,... cell_data C,D,...

and, where there is a `displacement`, the heights of the points as written and as warped by it:

    z FILE points ZMIN ZMAX warped ZMIN ZMAX

For a .pvd (pyvista only; meshio reads no collections), one line per time:

    pvd FILE time T blocks B points P0,P1,...

A file that a reader cannot read ends the script with exit code 1 and the reader's error on
standard error. Exit code 3: meshio or pyvista is not installed.
"""

import sys
from pathlib import Path

try:
    import meshio
    import pyvista
except ImportError as e:
    print(f"meshio and pyvista are needed (pip install meshio pyvista): {e}", file=sys.stderr)
    sys.exit(3)


def names(data):
    return ",".join(sorted(data.keys())) or "-"


def read_vtu(path):
    try:
        mesh = meshio.read(path)
    except Exception as e:  # any failure of the reader is the file's
        print(f"{path}: meshio: {e}", file=sys.stderr)
        sys.exit(1)
    cells = sum(len(block.data) for block in mesh.cells)
    print(
        f"meshio {path.name} points {len(mesh.points)} cells {cells} "
        f"point_data {names(mesh.point_data)} cell_data {names(mesh.cell_data)}"
    )
    if "displacement" in mesh.point_data:
        z = mesh.points[:, 2]
        warped = z + mesh.point_data["displacement"][:, 2]
        print(f"z {path.name} points {z.min()} {z.max()} warped {warped.min()} {warped.max()}")
    try:
        grid = pyvista.read(path)
    except Exception as e:
        print(f"{path}: pyvista: {e}", file=sys.stderr)
        sys.exit(1)
    print(
        f"pyvista {path.name} points {grid.n_points} cells {grid.n_cells} "
        f"point_data {names(grid.point_data)} cell_data {names(grid.cell_data)}"
    )


def read_pvd(path):
    try:
        reader = pyvista.get_reader(str(path))
        for time in reader.time_values:
            reader.set_active_time_value(time)
            blocks = reader.read()
            points = ",".join(str(b.n_points) for b in blocks)
            print(f"pvd {path.name} time {time} blocks {len(blocks)} points {points}")
    except Exception as e:
        print(f"{path}: pyvista: {e}", file=sys.stderr)
        sys.exit(1)


def main():
    for name in sys.argv[1:]:
        path = Path(name)
        if path.suffix == ".pvd":
            read_pvd(path)
        else:
            read_vtu(path)


main()
