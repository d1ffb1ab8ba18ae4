"""What calling through Python costs: the hemisphere example run by the command line and by
`thermostamp.run`, alternately, with the same output files, on the same machine.

    python3 python/benches/overhead.py [--pairs 3] [--exe target/release/thermostamp]

Prints each pair's wall times, the medians and the difference (the command line's time includes
starting its process; Python's includes loading the scenario and handing over the arrays). Run from the repository's root after
`cargo build --release` and `pip install ./python`.
"""

import argparse
import statistics
import subprocess
import tempfile
import time

import thermostamp as ts


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--pairs", type=int, default=3)
    parser.add_argument("--exe", default="target/release/thermostamp")
    parser.add_argument("--scenario", default="examples/hemisphere.toml")
    args = parser.parse_args()
    cli, python = [], []
    with tempfile.TemporaryDirectory() as scratch:
        for k in range(args.pairs):
            start = time.perf_counter()
            subprocess.run(
                [args.exe, "run", args.scenario, "--output", f"{scratch}/cli"],
                check=True,
                capture_output=True,
            )
            cli.append(time.perf_counter() - start)
            start = time.perf_counter()
            result = ts.run(ts.Scenario.load(args.scenario), output=f"{scratch}/python")
            python.append(time.perf_counter() - start)
            print(f"pair {k + 1}: command line {cli[-1]:.2f} s, Python {python[-1]:.2f} s")
    a, b = statistics.median(cli), statistics.median(python)
    print(f"median: command line {a:.2f} s, Python {b:.2f} s, difference {100 * (b - a) / a:+.1f} %")
    print(f"records {len(result.history['time'])}, cells {len(result.frame.cell_types)}")


if __name__ == "__main__":
    main()
