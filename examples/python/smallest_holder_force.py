"""The smallest blank-holder force that keeps the flange flat, at each temperature.

An optimisation loop over a scenario: for each temperature, SciPy's Brent root finder
(`scipy.optimize.brentq`) looks for the holder force at which the flange's waviness crosses the
wrinkle threshold (half the ply's thickness, 0.155 mm for the T300/PPS card), between a force
too small to hold the flange and one that holds it. Each evaluation is a forming run
(`thermostamp.run`); results are cached, so the loop never runs the same force twice.

    python3 smallest_holder_force.py            # 280, 300, 320 °C on the hemisphere, 8 mm cells
    python3 smallest_holder_force.py --quick    # one temperature, coarse: the form CI runs

Prints one line per run and, per temperature, the force found. Needs SciPy.
"""

import argparse
import functools
import pathlib

from scipy.optimize import brentq

import thermostamp as ts

HERE = pathlib.Path(__file__).resolve().parent
BASE = HERE.parent / "hemisphere.toml"
THRESHOLD = 0.155  # mm: half the ply's thickness, the studies' default wrinkle threshold


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="one temperature, 10 mm cells")
    args = parser.parse_args()
    temperatures = [300.0] if args.quick else [280.0, 300.0, 320.0]
    cells = 10.0 if args.quick else 8.0
    low, high = (6.0, 10.0) if args.quick else (2.0, 60.0)
    tolerance = 2.0 if args.quick else 1.0  # N
    for temperature in temperatures:
        base = ts.Scenario.load(
            BASE,
            set={
                "process.temperature": temperature,
                "blank.element_size": cells,
                "output.frames": 0,
            },
        )
        force = smallest_force(base, low, high, tolerance)
        print(f"{temperature:.0f} °C: smallest holder force keeping the flange flat {force}")


def smallest_force(base, low, high, tolerance):
    """The holder force (N) in [low, high] where the waviness crosses THRESHOLD, to within
    ``tolerance``; a text saying so when the whole bracket is on one side."""

    @functools.lru_cache(maxsize=None)
    def excess_waviness(force):
        result = ts.run(base.with_set({"process.blank_holder_force": force}))
        result.raise_for_status()
        waviness = result.summary["waviness"]
        print(f"  {force:7.2f} N: waviness {waviness:.3f} mm ({result.summary['wall_seconds']:.1f} s)")
        return waviness - THRESHOLD

    if excess_waviness(low) <= 0:
        return f"at most {low:.1f} N (flat already)"
    if excess_waviness(high) > 0:
        return f"above {high:.1f} N (still wavy)"
    force = brentq(excess_waviness, low, high, xtol=tolerance)
    return f"{force:.1f} N (to within {tolerance:.0f} N)"


if __name__ == "__main__":
    main()
