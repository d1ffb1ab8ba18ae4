#!/usr/bin/env python3
"""Writes hemisphere-quarter.msh (Gmsh MSH 4.1 ASCII): the quarter x >= 0, y >= 0 of the
160 x 160 mm blank of examples/hemisphere.toml, as 8 mm quadrilaterals (10 x 10), with the
physical surface "blank" and the physical curves "symmetry_x" (the edge on x = 0) and
"symmetry_y" (the edge on y = 0) that examples/hemisphere-quarter.toml holds.

In Gmsh itself the same mesh comes from a square surface with transfinite 11-point curves,
recombined into quadrangles, and the three physical groups. Run from this folder:
python3 make_quarter_blank.py
"""

N = 10
SIDE = 80.0
H = SIDE / N

tag = {}
for j in range(N + 1):
    for i in range(N + 1):
        tag[(i, j)] = len(tag) + 1
quads = [
    (tag[(i, j)], tag[(i + 1, j)], tag[(i + 1, j + 1)], tag[(i, j + 1)])
    for j in range(N)
    for i in range(N)
]
on_x0 = [(tag[(0, j)], tag[(0, j + 1)]) for j in range(N)]
on_y0 = [(tag[(i, 0)], tag[(i + 1, 0)]) for i in range(N)]

out = [
    "$MeshFormat", "4.1 0 8", "$EndMeshFormat",
    "$PhysicalNames", "3", '1 1 "symmetry_x"', '1 2 "symmetry_y"', '2 3 "blank"',
    "$EndPhysicalNames",
    "$Entities", "0 2 1 0",
    f"1 0 0 0 0 {SIDE} 0 1 1 0",
    f"2 0 0 0 {SIDE} 0 0 1 2 0",
    f"1 0 0 0 {SIDE} {SIDE} 0 1 3 2 1 2",
    "$EndEntities",
    "$Nodes", f"1 {len(tag)} 1 {len(tag)}", f"2 1 0 {len(tag)}",
]
ordered = sorted(tag.items(), key=lambda kv: kv[1])
out += [str(n) for _, n in ordered]
out += [f"{i * H} {j * H} 0" for (i, j), _ in ordered]
out.append("$EndNodes")
total = len(on_x0) + len(on_y0) + len(quads)
out += ["$Elements", f"3 {total} 1 {total}"]
k = 1
for entity, lines in ((1, on_x0), (2, on_y0)):
    out.append(f"1 {entity} 1 {len(lines)}")
    for a, b in lines:
        out.append(f"{k} {a} {b}")
        k += 1
out.append(f"2 1 3 {len(quads)}")
for q in quads:
    out.append(f"{k} " + " ".join(str(n) for n in q))
    k += 1
out.append("$EndElements")
with open("hemisphere-quarter.msh", "w") as f:
    f.write("\n".join(out) + "\n")
