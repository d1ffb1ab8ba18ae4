"""The formed blank's deck with a non-orthogonal material per shear-angle band.

thermostamp writes `formed-blank.inp` with one orientation per element: its local 1-axis is the
formed warp, its second point the formed weft, and every shell section names one material,
PREPREG. A sheared fabric is stiff along both of its yarns, which no longer cross at 90
degrees, so an orthotropic material in the element's axes misses the weft. This script reads
the deck, finds each element's shear angle (90 degrees less the angle between warp and weft),
groups the elements in bands of that angle, and writes a copy of the deck whose sections name
one material per band, `PREPREG_SHEAR_P27_0` for +27.0 degrees (`M` for negative angles), each
defined at the end as an anisotropic elastic material in the element's axes:

    C = C_iso(E_m, nu_m) + E_warp a (x) a (x) a (x) a + E_weft b (x) b (x) b (x) b

with a = (1, 0, 0) the warp and b = (sin g, cos g, 0) the weft at the band's shear angle g:
an isotropic matrix plus the stiffness each yarn family adds along itself (docs/forming.md,
"The formed blank in the next analysis").

Usage:
    python3 band_materials.py formed-blank.inp --warp-modulus 40000 --weft-modulus 40000 \
        --matrix-modulus 3800 --matrix-poisson 0.35 [--band 2] [--output formed-blank-bands.inp]

Moduli in MPa, as the deck's lengths are in mm. Only the Python standard library.
"""

import argparse
import math
import re
import sys

ORIENTATION = re.compile(r"^\*ORIENTATION,\s*NAME=(\S+)\s*$", re.IGNORECASE)
SECTION = re.compile(r"^(\*SHELL SECTION,.*MATERIAL=)PREPREG(\b.*ORIENTATION=(\S+?))\s*$", re.IGNORECASE)


def shear_angle(numbers):
    """Degrees: 90 less the angle between the warp a and the weft b of an orientation line."""
    a, b = numbers[:3], numbers[3:6]
    dot = sum(x * y for x, y in zip(a, b))
    norm = math.sqrt(sum(x * x for x in a) * sum(y * y for y in b))
    return 90.0 - math.degrees(math.acos(max(-1.0, min(1.0, dot / norm))))


def band_name(angle):
    sign = "M" if angle < 0 else "P"
    return "PREPREG_SHEAR_" + sign + f"{abs(angle):.1f}".replace(".", "_")


def stiffness(e_warp, e_weft, e_m, nu_m, gamma_deg):
    """The 3 x 3 x 3 x 3 stiffness of the recipe in the element's axes."""
    lam = e_m * nu_m / ((1 + nu_m) * (1 - 2 * nu_m))
    mu = e_m / (2 * (1 + nu_m))
    g = math.radians(gamma_deg)
    a, b = (1.0, 0.0, 0.0), (math.sin(g), math.cos(g), 0.0)
    delta = lambda i, j: 1.0 if i == j else 0.0

    def c(i, j, k, l):
        iso = lam * delta(i, j) * delta(k, l) + mu * (delta(i, k) * delta(j, l) + delta(i, l) * delta(j, k))
        return iso + e_warp * a[i] * a[j] * a[k] * a[l] + e_weft * b[i] * b[j] * b[k] * b[l]

    return c


# the 21 constants of *ELASTIC, TYPE=ANISO in Abaqus's (and CalculiX's) order, axes from 1
ANISO_ORDER = [
    "1111", "1122", "2222", "1133", "2233", "3333", "1112", "2212",
    "3312", "1212", "1113", "2213", "3313", "1213", "1313", "1123",
    "2223", "3323", "1223", "1323", "2323",
]


def material(name, c):
    values = [c(*(int(d) - 1 for d in ijkl)) for ijkl in ANISO_ORDER]
    lines = [values[0:8], values[8:16], values[16:21]]
    text = [f"*MATERIAL, NAME={name}", "*ELASTIC, TYPE=ANISO"]
    text += [", ".join(f"{v:.9g}" for v in line) for line in lines]
    return "\n".join(text)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("deck")
    p.add_argument("--warp-modulus", type=float, required=True, help="MPa, added along the warp")
    p.add_argument("--weft-modulus", type=float, required=True, help="MPa, added along the weft")
    p.add_argument("--matrix-modulus", type=float, required=True, help="MPa, isotropic part")
    p.add_argument("--matrix-poisson", type=float, required=True)
    p.add_argument("--band", type=float, default=2.0, help="degrees of shear angle a band")
    p.add_argument("--output", default="formed-blank-bands.inp")
    args = p.parse_args()
    if not (args.band > 0 and args.matrix_modulus > 0 and -1 < args.matrix_poisson < 0.5
            and args.warp_modulus >= 0 and args.weft_modulus >= 0):
        sys.exit("band_materials: moduli must be positive, the band too, the Poisson ratio in (-1, 0.5)")

    lines = open(args.deck).read().splitlines()
    angles = {}
    for k, line in enumerate(lines):
        m = ORIENTATION.match(line)
        if m:
            numbers = [float(x) for x in lines[k + 1].split(",")[:6]]
            angles[m.group(1).upper()] = shear_angle(numbers)
    if not angles:
        sys.exit(f"band_materials: {args.deck} has no orientations (a deck of thermostamp's formed blank?)")
    bands = {}
    out = []
    for line in lines:
        m = SECTION.match(line)
        if m:
            angle = args.band * round(angles[m.group(3).upper()] / args.band)
            name = band_name(angle)
            bands[name] = angle
            line = m.group(1) + name + m.group(2)
        out.append(line)
    out.append(f"** Materials per band of {args.band:g} degrees of shear (band_materials.py)")
    for name, angle in sorted(bands.items(), key=lambda item: item[1]):
        c = stiffness(args.warp_modulus, args.weft_modulus, args.matrix_modulus, args.matrix_poisson, angle)
        out.append(material(name, c))
    with open(args.output, "w") as f:
        f.write("\n".join(out) + "\n")
    print(f"wrote {args.output}: {len(angles)} elements in {len(bands)} bands of shear angle "
          f"from {min(bands.values()):g} to {max(bands.values()):g} degrees")


main()
