"""What the tests of the Python package share: the repository's files and the command line
they are compared with (``target/release/thermostamp``, built by ``cargo build --release``;
``THERMOSTAMP_EXE`` names another)."""

import os
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
HEMISPHERE = ROOT / "examples" / "hemisphere.toml"
# A hemisphere that forms in about a second: coarse cells, a third of the stroke.
QUICK = {"blank.element_size": 10.0, "process.stroke": 10.0}


def cli_exe():
    exe = pathlib.Path(os.environ.get("THERMOSTAMP_EXE", ROOT / "target" / "release" / "thermostamp"))
    if not exe.exists():
        pytest.fail(f"{exe} is missing: build the command line with `cargo build --release`")
    return exe


def run_cli(*args, cwd=ROOT, check=True):
    """Runs the command line; its completed process."""
    done = subprocess.run([str(cli_exe()), *map(str, args)], cwd=cwd, capture_output=True, text=True)
    if check and done.returncode != 0:
        pytest.fail(f"thermostamp {' '.join(map(str, args))} failed:\n{done.stderr}")
    return done


def quick_set(extra=None):
    """The ``--set`` arguments of :data:`QUICK` (and ``extra``)."""
    out = []
    for key, value in {**QUICK, **(extra or {})}.items():
        out += ["--set", f"{key}={value}"]
    return out
