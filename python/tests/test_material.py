"""thermostamp.material_point, the virtual tests and the fits against the command line: the
same inputs give the same numbers (the CLI's CSV writes each number so that it reads back to
the same double: the arrays equal its columns), and bad input the same messages."""

import csv
import io
import subprocess
import tomllib
from pathlib import Path

import numpy as np
import pytest

import thermostamp as ts
from thermostamp import _core
from thermostamp.errors import InputError

ROOT = Path(__file__).resolve().parents[2]
CLI = ROOT / "target" / "release" / "thermostamp"
CARD = ROOT / "materials" / "t300-5hs-pps.toml"
STIFF = ROOT / "tests" / "data" / "stiff-yarn-fabric.toml"
POINT = ROOT / "examples" / "material-point"

# the coarse bias extension of the Rust tests (tests/common/mod.rs, QUICK_BIAS_EXTENSION)
QUICK_BIAS = dict(
    element_size=37.5,
    end_displacement=20.0,
    speed=200.0,
    time_scaling=1.0,
    target_step=0.0,
    frames=3,
    history_points=12,
)
QUICK_BIAS_ARGS = [
    "--element-size", "37.5", "--end-displacement", "20", "--speed", "200",
    "--time-scaling", "1", "--target-step", "0", "--frames", "3", "--history-points", "12",
]  # fmt: skip


def cli(*args, check=True):
    """Runs the command-line binary from the repository root."""
    if not CLI.exists():
        pytest.skip(f"{CLI} is not built (cargo build --release)")
    done = subprocess.run(
        [str(CLI), *map(str, args)], cwd=ROOT, capture_output=True, text=True
    )
    if check:
        assert done.returncode == 0, done.stderr
    return done


def read_csv(text):
    """Column name to array of a CSV text."""
    lines = [l for l in text.splitlines() if l.strip() and not l.lstrip().startswith("#")]
    rows = list(csv.reader(io.StringIO("\n".join(lines))))
    rows = [[cell.strip() for cell in row] for row in rows]
    header, data = rows[0], np.array(rows[1:], dtype=float)
    return {name: data[:, j] for j, name in enumerate(header)}


def assert_same_columns(ours, theirs):
    assert list(ours) == list(theirs)
    for name in theirs:
        np.testing.assert_allclose(
            ours[name], theirs[name], rtol=1e-12, atol=0, err_msg=name
        )


def history_of(path):
    """A CSV history file as column name to array (all columns)."""
    return read_csv(Path(path).read_text())


# --- material point -------------------------------------------------------------------------


@pytest.mark.parametrize(
    "layer, history",
    [
        ("laminate", "laminate-shear-300C.csv"),
        ("fabric", "fabric-warp-tension.csv"),
        ("matrix", "matrix-uniaxial-300C.csv"),
    ],
)
def test_material_point_equals_the_cli(layer, history):
    path = POINT / history
    expected = read_csv(
        cli("material-point", "--card", CARD, "--layer", layer, "--history", path,
            "--angle", "10").stdout
    )  # fmt: skip
    columns = history_of(path)
    ours = ts.material_point(CARD, layer, columns, angle=10.0)
    assert_same_columns(ours, expected)
    # a 2-D array with the columns in order gives the same
    order = _core.point_history_columns(layer)
    table = np.column_stack([columns[c] for c in order])
    again = ts.material_point(str(CARD), layer, table, angle=10.0)
    for name in ours:
        np.testing.assert_array_equal(again[name], ours[name])


def laminate_history():
    return history_of(POINT / "laminate-shear-300C.csv")


def test_material_point_names_the_row_of_a_time_that_does_not_increase():
    h = laminate_history()
    h["t"][2] = h["t"][1]
    with pytest.raises(InputError, match=r"history: row 3: t = .* does not increase"):
        ts.material_point(CARD, "laminate", h)


def test_material_point_names_the_row_of_a_crushed_element():
    h = laminate_history()
    h["F11"][4] = -1.0
    with pytest.raises(InputError, match=r"history: row 5: det F = .* <= 0"):
        ts.material_point(CARD, "laminate", h)


def test_material_point_names_a_missing_column_and_a_nan():
    h = laminate_history()
    del h["F21"]
    with pytest.raises(InputError, match=r"missing column 'F21'"):
        ts.material_point(CARD, "laminate", h)
    h = laminate_history()
    h["T"][6] = np.nan
    with pytest.raises(InputError, match=r"history: row 7: column 'T': 'nan' is not a finite"):
        ts.material_point(CARD, "laminate", h)
    with pytest.raises(InputError, match=r"unexpected column 'F13'"):
        ts.material_point(CARD, "laminate", {**laminate_history(), "F13": h["t"]})


def test_material_point_refuses_what_the_cli_refuses():
    with pytest.raises(InputError, match=r"layer 'skin'"):
        ts.material_point(CARD, "skin", laminate_history())
    with pytest.raises(InputError, match=r"^angle"):
        ts.material_point(CARD, "laminate", laminate_history(), angle=1e9)
    with pytest.raises(InputError, match=r"no-such-card.toml"):
        ts.material_point("no-such-card.toml", "laminate", laminate_history())
    dry = cli("material-point", "--card", STIFF, "--layer", "matrix", "--history",
              POINT / "matrix-uniaxial-300C.csv", check=False)  # fmt: skip
    assert dry.returncode != 0
    with pytest.raises(InputError) as e:
        ts.material_point(STIFF, "matrix", history_of(POINT / "matrix-uniaxial-300C.csv"))
    assert "the card has no [matrix] section" in str(e.value)
    assert "the card has no [matrix] section" in dry.stderr


# --- virtual tests --------------------------------------------------------------------------


def test_bias_extension_equals_the_cli_and_writes_its_files(tmp_path):
    cli_dir, py_dir = tmp_path / "cli", tmp_path / "py"
    cli("test", "bias-extension", "--card", STIFF, *QUICK_BIAS_ARGS, "--threads", "1",
        "--output", cli_dir)  # fmt: skip
    expected = history_of(cli_dir / "bias-extension.csv")
    result = ts.bias_extension_test(STIFF, **QUICK_BIAS, threads=1, output=py_dir)
    assert result.ok and result.status == "finished"
    assert_same_columns(result.history, expected)
    # the files the CLI writes, with the same history
    names = sorted(p.name for p in cli_dir.iterdir() if not p.name.startswith("."))
    assert sorted(p.name for p in py_dir.iterdir() if not p.name.startswith(".")) == names
    assert_same_columns(history_of(py_dir / "bias-extension.csv"), expected)
    assert {Path(f).name for f in result.files} >= {"bias-extension.csv", "bias-extension.pvd"}
    assert result.summary["steps"] > 0 and result.summary["elements"] > 0
    assert all(c.status for c in result.checks)
    # without a folder nothing is written, and the numbers are the same
    bare = ts.bias_extension_test(STIFF, **QUICK_BIAS, threads=1)
    assert bare.files == []
    for name in expected:
        np.testing.assert_array_equal(bare.history[name], result.history[name])


# the coarse uniaxial and picture-frame tests of tests/cli_virtual_tests_more.rs
@pytest.mark.parametrize(
    "kind, call, options, args",
    [
        ("uniaxial", ts.uniaxial_test,
         dict(ply_angle=-90.0, end_displacement=1.5, speed=200.0),
         ["--ply-angle", "-90", "--end-displacement", "1.5", "--speed", "200"]),
        ("picture-frame", ts.picture_frame_test,
         dict(element_size=75.0, end_displacement=20.0, speed=200.0, target_step=5e-5),
         ["--element-size", "75", "--end-displacement", "20", "--speed", "200",
          "--target-step", "5e-5"]),
    ],
)  # fmt: skip
def test_uniaxial_and_picture_frame_equal_the_cli(tmp_path, kind, call, options, args):
    cli("test", kind, "--card", STIFF, *args, "--time-scaling", "1", "--frames", "0",
        "--history-points", "12", "--threads", "1", "--output", tmp_path)  # fmt: skip
    expected = history_of(tmp_path / f"{kind}.csv")
    result = call(STIFF, **options, time_scaling=1.0, history_points=12, threads=1)
    assert result.ok
    assert_same_columns(result.history, expected)


def test_virtual_test_options_are_checked_as_the_cli_checks_them():
    with pytest.raises(TypeError, match="element_sise"):
        ts.bias_extension_test(STIFF, element_sise=10.0)
    # the CLI's message, the option spelled as in Python
    done = cli("test", "uniaxial", "--card", STIFF, "--time-scaling", "0.5", check=False)
    assert done.returncode != 0 and "--time-scaling" in done.stderr
    with pytest.raises(InputError) as e:
        ts.uniaxial_test(STIFF, time_scaling=0.5)
    message = str(e.value)
    assert message.startswith("time_scaling = 0.5 is out of range")
    assert message.split("out of range")[1] == done.stderr.strip().split("out of range")[1]
    with pytest.raises(InputError, match=r"^temperature is required"):
        ts.uniaxial_test(CARD)
    with pytest.raises(InputError, match=r"^side"):
        ts.picture_frame_test(STIFF, side=-5.0)
    with pytest.raises(InputError, match=r"pattern 'hex'"):
        ts.uniaxial_test(STIFF, pattern="hex")


def test_ctrl_c_keeps_the_records_so_far():
    calls = []

    def progress(fraction, step, time):
        calls.append(fraction)
        raise KeyboardInterrupt

    options = dict(QUICK_BIAS, history_points=40, element_size=25.0)
    with pytest.raises(KeyboardInterrupt) as e:
        ts.bias_extension_test(STIFF, **options, threads=1, progress=progress)
    result = e.value.result
    assert result.outcome == "interrupted" and not result.ok
    assert len(result.history["time"]) >= 1
    assert len(result.history["time"]) < 41


# --- fits -----------------------------------------------------------------------------------

TENSION = "examples/fit-fabric-tension"
SHEAR_DATA = "examples/fit-shear/bias_extension_glass_pp_plain_150x450.csv"
TWINTEX = "materials/twintex-plain-weave.toml"
PPS = "materials/t300-5hs-pps.toml"


def columns_of(relative):
    """A CSV file of the repository as a dict of column to array (comments skipped)."""
    return read_csv((ROOT / relative).read_text())


def assert_as_written(ours, theirs):
    """Fitted values against a card's, which has them to 6 significant digits (toml_float)."""
    rounded = [float(f"{v:.5e}") for v in np.atleast_1d(ours)]
    np.testing.assert_allclose(rounded, np.atleast_1d(theirs), rtol=1e-12, atol=0)


def test_fit_fabric_tension_equals_the_cli(tmp_path, monkeypatch):
    monkeypatch.chdir(ROOT)
    out = tmp_path / "cli.toml"
    cli("fit", "fabric-tension", "--warp", f"{TENSION}/warp.csv", "--weft",
        f"{TENSION}/weft.csv", "--width", "25", "--card", PPS, "--output", out)  # fmt: skip
    fitted = ts.fit_fabric_tension(
        PPS, warp=f"{TENSION}/warp.csv", weft=f"{TENSION}/weft.csv", width=25,
        output=tmp_path / "py.toml",
    )  # fmt: skip
    assert fitted.card == out.read_text() == (tmp_path / "py.toml").read_text()
    fabric = tomllib.loads(fitted.card)["fabric"]
    for direction in ("warp", "weft"):
        ours = [v for k, v in fitted.parameters.items() if k.startswith(direction)]
        assert_as_written(ours, fabric[f"{direction}_tension"])
        assert fitted.quality[f"{direction}_points"] > 0
    # the same curves as arrays give the same coefficients
    arrays = ts.fit_fabric_tension(
        PPS, warp=columns_of(f"{TENSION}/warp.csv"), weft=columns_of(f"{TENSION}/weft.csv"),
        width=25,
    )  # fmt: skip
    assert arrays.parameters == fitted.parameters
    assert arrays.files == []


def test_fit_fabric_tension_names_the_row_and_the_option():
    warp = columns_of(f"{TENSION}/warp.csv")
    warp["strain"][3] = warp["strain"][2] - 1e-3
    with pytest.raises(InputError, match=r"^warp: row 4: strain = .* does not increase"):
        ts.fit_fabric_tension(ROOT / PPS, warp=warp)
    with pytest.raises(InputError, match=r"^terms 0: "):
        ts.fit_fabric_tension(ROOT / PPS, warp=columns_of(f"{TENSION}/warp.csv"), terms=0)
    with pytest.raises(TypeError, match="term"):
        ts.fit_fabric_tension(ROOT / PPS, warp=columns_of(f"{TENSION}/warp.csv"), term=2)


def test_fit_matrix_equals_the_cli(tmp_path, monkeypatch):
    monkeypatch.chdir(ROOT)
    manifest = "examples/fit-matrix/manifest.toml"
    out = tmp_path / "cli.toml"
    cli("fit", "matrix", "--manifest", manifest, "--card", PPS, "--bulk-modulus", "1500",
        "--output", out)  # fmt: skip
    fitted = ts.fit_matrix(manifest, card=PPS, bulk_modulus=1500.0)
    assert fitted.card == out.read_text()
    matrix = tomllib.loads(fitted.card)["matrix"]
    assert_as_written(fitted.parameters["c10"], matrix["c10"])
    assert_as_written(fitted.parameters["temperature"], [280.0, 300.0, 320.0])
    # the manifest's curves as a list of dicts, with arrays
    entries = tomllib.loads((ROOT / manifest).read_text())["curve"]
    curves = [
        {**{k: v for k, v in e.items() if k != "file"},
         "curve": columns_of(f"examples/fit-matrix/{e['file']}")}
        for e in entries
    ]  # fmt: skip
    arrays = ts.fit_matrix(curves, card=PPS, bulk_modulus=1500.0)
    for name in ("c10", "eta1", "d1"):
        np.testing.assert_array_equal(arrays.parameters[name], fitted.parameters[name])
    with pytest.raises(InputError, match=r"curves: \[\[curve\]\] #1 .*give strain_rate"):
        ts.fit_matrix([{"curve": curves[0]["curve"], "temperature": 280.0}], bulk_modulus=1500.0)
    with pytest.raises(InputError, match=r"^D1 needs bulk_modulus K or poisson nu"):
        ts.fit_matrix(manifest)


def test_fit_shear_equals_the_cli(tmp_path, monkeypatch):
    monkeypatch.chdir(ROOT)
    out = tmp_path / "cli.toml"
    options = ["--width", "150", "--length", "450", "--terms", "friction,1,3",
               "--friction-onset", "3", "--max-shear", "35"]  # fmt: skip
    cli("fit", "shear", "--data", SHEAR_DATA, "--card", TWINTEX, "--output", out, *options)
    fitted = ts.fit_shear(
        TWINTEX, SHEAR_DATA, width=150, length=450, terms="friction,1,3", friction_onset=3,
        max_shear=35, plot=tmp_path / "fit.png",
    )  # fmt: skip
    assert fitted.card == out.read_text()
    assert (tmp_path / "fit.png").read_bytes()[:4] == b"\x89PNG"
    fabric = tomllib.loads(fitted.card)["fabric"]
    assert_as_written(fitted.parameters["friction"], fabric["shear_friction"])
    assert_as_written([fitted.parameters["c1"], fitted.parameters["c3"]],
                 [fabric["shear"][0], fabric["shear"][2]])  # fmt: skip
    assert fitted.quality["points"] == len(fitted.quality["fitted"]["model"]) > 0
    arrays = ts.fit_shear(
        TWINTEX, columns_of(SHEAR_DATA), width=150, length=450, terms=["friction", "1", "3"],
        friction_onset=3, max_shear=35,
    )  # fmt: skip
    assert arrays.parameters == fitted.parameters
    with pytest.raises(InputError, match=r"^a bias-extension curve needs width and length"):
        ts.fit_shear(TWINTEX, SHEAR_DATA)
    with pytest.raises(InputError, match=r"^terms friction,12,1: power 12 is beyond"):
        ts.fit_shear(TWINTEX, SHEAR_DATA, width=150, length=450, terms="friction,12,1")
    bad = columns_of(SHEAR_DATA)
    bad["force_N"][5] = -1.0
    with pytest.raises(InputError, match=r"^data: row 6: force_N = -1"):
        ts.fit_shear(TWINTEX, bad, width=150, length=450)
