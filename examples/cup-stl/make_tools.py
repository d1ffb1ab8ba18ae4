#!/usr/bin/env python3
"""Writes the tools of examples/cup-stl.toml as binary STL files, as a CAD program exports
them: a flat punch of radius 35 mm with an 8 mm corner fillet, a die whose opening of radius
37 mm ends in a 5 mm fillet, and a flat blank holder around the opening.

Each tool is a profile (r, z) swept around the z axis, cut as a CAD export cuts it: a flat
face is a fan of long thin triangles from its rim (or the axis), a fillet is a strip of
quadrilaterals (SEGMENTS_PER_QUARTER steps along its quarter circle, AROUND steps around the
axis) each cut into two triangles. Surfaces face the blank (the punch and holder up, the die
down) and touch its faces: a ply of THICKNESS mm whose mid-plane is z = 0.

    python3 make_tools.py [FOLDER]    (default: this script's folder)
"""

import math
import os
import struct
import sys

THICKNESS = 0.31          # mm, the ply of materials/t300-5hs-pps.toml
AROUND = 72               # steps around the axis (5°)
SEGMENTS_PER_QUARTER = 10 # steps along a fillet's quarter circle (9°)


def profile_points(pieces):
    """The profile's points: lines kept as their two ends (a CAD face is flat), arcs cut into
    steps of at most 90 / SEGMENTS_PER_QUARTER degrees."""
    points = []
    for piece in pieces:
        if piece[0] == "line":
            _, a, b = piece
            run = [a, b]
        else:
            _, (cr, cz), radius, start, end = piece
            steps = max(1, round(abs(end - start) / (math.pi / 2) * SEGMENTS_PER_QUARTER))
            run = [(cr + radius * math.cos(start + (end - start) * i / steps),
                    cz + radius * math.sin(start + (end - start) * i / steps))
                   for i in range(steps + 1)]
        if points:
            run = run[1:]
        points.extend(run)
    return points


def swept(points):
    """Triangles of the profile swept around z, counter-clockwise seen from the profile's left
    side (walking the profile from its first point)."""
    triangles = []
    ring = lambda r, z, k: (r * math.cos(2 * math.pi * k / AROUND),
                            r * math.sin(2 * math.pi * k / AROUND), z)
    for (r0, z0), (r1, z1) in zip(points, points[1:]):
        for k in range(AROUND):
            a, b = ring(r0, z0, k), ring(r0, z0, k + 1)
            c, d = ring(r1, z1, k), ring(r1, z1, k + 1)
            if r0 == 0.0:
                triangles.append((a, c, d))
            elif r1 == 0.0:
                triangles.append((a, c, b))
            else:
                triangles.append((a, d, b))
                triangles.append((a, c, d))
    return triangles


def write_stl(path, triangles):
    with open(path, "wb") as f:
        f.write(b"thermostamp examples/cup-stl".ljust(80, b" "))
        f.write(struct.pack("<I", len(triangles)))
        for t in triangles:
            f.write(struct.pack("<3f", 0.0, 0.0, 0.0))
            for p in t:
                f.write(struct.pack("<3f", *p))
            f.write(b"\0\0")


def main():
    folder = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.abspath(__file__))
    half = 0.5 * THICKNESS
    q = math.pi / 2
    # punch: top at z = -half from the axis to r = 27, fillet of 8 about (27, -half - 8),
    # wall at r = 35 down 40 mm; walked outward its left side is up and out
    punch = profile_points([
        ("line", (0.0, -half), (27.0, -half)),
        ("arc", (27.0, -half - 8.0), 8.0, q, 0.0),
        ("line", (35.0, -half - 8.0), (35.0, -half - 40.0)),
    ])
    # die: underside at z = +half from r = 90 in to 42, fillet of 5 about (42, half + 5),
    # wall at r = 37 up 40 mm; walked inward its left side faces the blank (down, inward)
    die = profile_points([
        ("line", (90.0, half), (42.0, half)),
        ("arc", (42.0, half + 5.0), 5.0, -q, -2 * q),
        ("line", (37.0, half + 5.0), (37.0, half + 40.0)),
    ])
    # holder: a flat ring at z = -half from r = 42 out to 90, facing up
    holder = profile_points([("line", (42.0, -half), (90.0, -half))])
    for name, points in [("punch", punch), ("die", die), ("holder", holder)]:
        write_stl(os.path.join(folder, f"{name}.stl"), swept(points))


if __name__ == "__main__":
    main()
