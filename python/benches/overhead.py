"""What calling through Python costs: the hemisphere example run by the command line and by
`thermostamp.run`, alternately, with the same output files, on the same machine.

    python3 python/benches/overhead.py [--pairs 3] [--exe target/release/thermostamp]

Prints each pair's wall times, the medians and their difference (the command line's time
includes starting its process; Python's includes loading the scenario and handing over the
arrays), and the time each spends outside the solver's run (set-up, files, summary; Python:
the arrays too), which is where the two differ: the solver's run is the same code. Run from the repository's root after
`cargo build --release` and `pip install ./python`.
"""

import argparse
import statistics
import subprocess
import tempfile
import time

import thermostamp as ts


def solver_seconds(summary):
    """The run's own wall time from the command line's summary (`wall time  12.3 s on ...`)."""
    for line in summary.splitlines():
        if line.startswith("wall time"):
            return float(line.split()[2])
    raise ValueError("no wall time in the summary")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--pairs", type=int, default=3)
    parser.add_argument("--exe", default="target/release/thermostamp")
    parser.add_argument("--scenario", default="examples/hemisphere.toml")
    args = parser.parse_args()
    cli, python, cli_outside, python_outside = [], [], [], []
    with tempfile.TemporaryDirectory() as scratch:
        for k in range(args.pairs):
            start = time.perf_counter()
            done = subprocess.run(
                [args.exe, "run", args.scenario, "--output", f"{scratch}/cli"],
                check=True,
                capture_output=True,
                text=True,
            )
            cli.append(time.perf_counter() - start)
            cli_outside.append(cli[-1] - solver_seconds(done.stdout))
            start = time.perf_counter()
            result = ts.run(ts.Scenario.load(args.scenario), output=f"{scratch}/python")
            python.append(time.perf_counter() - start)
            python_outside.append(python[-1] - result.summary["wall_seconds"])
            print(
                f"pair {k + 1}: command line {cli[-1]:.2f} s ({cli_outside[-1]:.3f} s outside "
                f"the solver's run), Python {python[-1]:.2f} s ({python_outside[-1]:.3f} s)"
            )
    a, b = statistics.median(cli), statistics.median(python)
    print(f"median: command line {a:.2f} s, Python {b:.2f} s, difference {100 * (b - a) / a:+.1f} %")
    a_out, b_out = statistics.median(cli_outside), statistics.median(python_outside)
    print(
        f"median outside the solver's run: command line {a_out:.3f} s, Python {b_out:.3f} s: "
        f"Python adds {b_out - a_out:+.3f} s, {100 * (b_out - a_out) / a:+.2f} % of the run"
    )
    print(f"records {len(result.history['time'])}, cells {len(result.frame.cell_types)}")


if __name__ == "__main__":
    main()
