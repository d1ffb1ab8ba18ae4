#!/usr/bin/env python3
"""Writes the blank of examples/hemisphere.toml (160 x 160 mm, centred on the punch axis, in
z = 0) as 10 mm quadrilaterals in the two mesh formats thermostamp reads, for
tests/forming_mesh_files.rs:

- hemisphere-blank-10mm.msh: Gmsh MSH 4.1 ASCII, one surface entity, physical surface "blank" and
  physical curve "edge" (the boundary as line elements); node tags numbered column by column
  from 101, so that the reader's renumbering is exercised.
- hemisphere-blank-10mm.inp: Abaqus, S4R elements with sparse labels (from 5001, step 2), node
  labels row by row from 1, NSET EDGE, and the ply's reference direction through *ORIENTATION
  (local 1-axis along x) and *SHELL SECTION.

Run from this folder: python3 make_hemisphere_blanks.py
"""

N = 16  # cells per side
SIDE = 160.0
H = SIDE / N


def xy(i, j):
    return -0.5 * SIDE + i * H, -0.5 * SIDE + j * H


def boundary_loop():
    """Grid points (i, j) round the boundary, counter-clockwise from the lower-left corner."""
    loop = [(i, 0) for i in range(N)]
    loop += [(N, j) for j in range(N)]
    loop += [(i, N) for i in range(N, 0, -1)]
    loop += [(0, j) for j in range(N, 0, -1)]
    return loop


def write_msh(path):
    tag = {}
    order = []
    for i in range(N + 1):
        for j in range(N + 1):
            tag[(i, j)] = 101 + len(order)
            order.append((i, j))
    quads = [
        (tag[(i, j)], tag[(i + 1, j)], tag[(i + 1, j + 1)], tag[(i, j + 1)])
        for j in range(N)
        for i in range(N)
    ]
    loop = boundary_loop()
    lines = [(tag[loop[k]], tag[loop[(k + 1) % len(loop)]]) for k in range(len(loop))]
    lo, hi = -0.5 * SIDE, 0.5 * SIDE
    out = [
        "$MeshFormat", "4.1 0 8", "$EndMeshFormat",
        "$PhysicalNames", "2", '1 2 "edge"', '2 1 "blank"', "$EndPhysicalNames",
        "$Entities", "0 1 1 0",
        f"1 {lo} {lo} 0 {hi} {hi} 0 1 2 0",
        f"1 {lo} {lo} 0 {hi} {hi} 0 1 1 1 1",
        "$EndEntities",
        "$Nodes", f"1 {len(order)} 101 {100 + len(order)}", f"2 1 0 {len(order)}",
    ]
    out += [str(tag[p]) for p in order]
    out += [f"{xy(*p)[0]} {xy(*p)[1]} 0" for p in order]
    out.append("$EndNodes")
    total = len(lines) + len(quads)
    out += ["$Elements", f"2 {total} 1 {total}", f"1 1 1 {len(lines)}"]
    out += [f"{k + 1} {a} {b}" for k, (a, b) in enumerate(lines)]
    out.append(f"2 1 3 {len(quads)}")
    out += [f"{len(lines) + k + 1} {a} {b} {c} {d}" for k, (a, b, c, d) in enumerate(quads)]
    out.append("$EndElements")
    with open(path, "w") as f:
        f.write("\n".join(out) + "\n")


def write_inp(path):
    label = {}
    for j in range(N + 1):
        for i in range(N + 1):
            label[(i, j)] = len(label) + 1
    out = [
        "*HEADING",
        "Blank of examples/hemisphere.toml: 160 x 160 mm, 10 mm S4R (tests/data/meshes/make_hemisphere_blanks.py)",
        "*NODE",
    ]
    for (i, j), n in sorted(label.items(), key=lambda kv: kv[1]):
        x, y = xy(i, j)
        out.append(f"{n}, {x}, {y}, 0.")
    out.append("*ELEMENT, TYPE=S4R, ELSET=BLANK")
    e = 5001
    for j in range(N):
        for i in range(N):
            out.append(
                f"{e}, {label[(i, j)]}, {label[(i + 1, j)]}, {label[(i + 1, j + 1)]}, {label[(i, j + 1)]}"
            )
            e += 2
    out.append("*NSET, NSET=EDGE")
    edge = sorted(label[p] for p in boundary_loop())
    for k in range(0, len(edge), 16):
        out.append(", ".join(str(n) for n in edge[k:k + 16]))
    out += [
        "*ORIENTATION, NAME=PLY, SYSTEM=RECTANGULAR",
        "1., 0., 0., 0., 1., 0.",
        "3, 0.",
        "*SHELL SECTION, ELSET=BLANK, MATERIAL=PREPREG, ORIENTATION=PLY",
        "0.31",
    ]
    with open(path, "w") as f:
        f.write("\n".join(out) + "\n")


write_msh("hemisphere-blank-10mm.msh")
write_inp("hemisphere-blank-10mm.inp")
