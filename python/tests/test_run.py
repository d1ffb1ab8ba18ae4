"""thermostamp.run against the command line: the same files byte for byte and the same arrays;
progress, Ctrl-C, the interpreter left free, typed errors."""

import _thread
import threading
import time

import numpy as np
import pytest

import thermostamp as ts
from conftest import HEMISPHERE, QUICK, ROOT, quick_set, run_cli


def read_csv(path):
    header = path.read_text().splitlines()[0].split(",")
    values = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    return {name: values[:, k] for k, name in enumerate(header)}


def test_the_hemisphere_example_gives_the_command_lines_history(tmp_path):
    cli = tmp_path / "cli"
    run_cli("run", HEMISPHERE, "--output", cli)
    result = ts.run(ts.Scenario.load(HEMISPHERE), output=tmp_path / "python")
    assert result.ok, result.status
    for name in ["forming.csv", "forming-result.csv"]:
        assert (tmp_path / "python" / name).read_bytes() == (cli / name).read_bytes(), name
    history = read_csv(cli / "forming.csv")
    assert list(result.history) == list(history) == list(ts.HISTORY_COLUMNS)
    for name, column in history.items():
        np.testing.assert_allclose(result.history[name], column, rtol=1e-12, atol=0, err_msg=name)
    assert result.summary["peak_punch_force"] == pytest.approx(history["punch_force"].max(), rel=1e-12)
    written = {p.name for p in result.files}
    assert {"forming.csv", "forming-shear-map.png", "formed-blank.inp", "forming.pvd"} <= written


def test_without_an_output_folder_nothing_is_written(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    result = ts.run(ts.Scenario.load(HEMISPHERE, set=QUICK))
    assert result.ok and result.files == []
    assert list(tmp_path.iterdir()) == []
    assert len(result.history["time"]) > 10


def test_history_arrays_are_handed_over_without_a_copy():
    result = ts.run(ts.Scenario.load(HEMISPHERE, set=QUICK))
    for name, column in result.history.items():
        # the array's memory is the engine's vector, kept alive by the array's base object
        assert not column.flags.owndata and column.base is not None, name
        assert column.dtype == np.float64 and column.flags.c_contiguous


def test_a_bad_key_raises_the_typed_exception_naming_it():
    with pytest.raises(ts.ScenarioError) as caught:
        ts.Scenario.load(HEMISPHERE, set={"process.temperatur": 300})
    assert caught.value.key == "process.temperatur"
    assert "unknown field `temperatur`" in str(caught.value)
    assert isinstance(caught.value, ValueError)
    table = ts.Scenario.load(HEMISPHERE).to_dict()
    table["blank"]["widht"] = 100.0
    with pytest.raises(ts.ScenarioError) as caught:
        ts.Scenario.from_dict(table)
    assert caught.value.key == "blank.widht"
    with pytest.raises(ts.ScenarioError) as caught:
        ts.Scenario.load(HEMISPHERE, set={"process.temperature": -400})
    assert caught.value.key == "process.temperature"


def test_the_same_message_as_the_command_line():
    done = run_cli("run", HEMISPHERE, "--set", "process.punch_speed=-1", check=False)
    assert done.returncode == 2
    with pytest.raises(ts.ScenarioError) as caught:
        ts.Scenario.load(HEMISPHERE, set={"process.punch_speed": -1})
    assert str(caught.value).split("(with --set")[0].strip() in done.stderr


def test_a_scenario_round_trips_through_a_dictionary_and_toml(tmp_path):
    scenario = ts.Scenario.load(HEMISPHERE, set={"process.temperature": 310})
    again = ts.Scenario.from_dict(scenario.to_dict())
    assert again == scenario
    assert scenario["process.temperature"] == 310.0
    path = tmp_path / "standalone.toml"
    path.write_text(scenario.to_toml())
    assert ts.Scenario.load(path) == scenario


def test_progress_is_called_up_to_the_end():
    calls = []
    ts.run(ts.Scenario.load(HEMISPHERE, set=QUICK), progress=lambda *a: calls.append(a))
    assert len(calls) >= 2
    fractions = [c[0] for c in calls]
    assert fractions == sorted(fractions) and fractions[-1] == pytest.approx(1.0)
    assert all(isinstance(c[1], int) for c in calls)


@pytest.mark.parametrize("threads", [None, 1])
def test_ctrl_c_stops_the_run_and_keeps_a_valid_partial_result(tmp_path, threads):
    def interrupt_once(fraction, step, time):
        # as a Ctrl-C would: the signal is seen at the run's next look at Python
        if step > 2 and not interrupted:
            interrupted.append(step)
            _thread.interrupt_main()

    interrupted = []
    with pytest.raises(KeyboardInterrupt) as caught:
        ts.run(ts.Scenario.load(HEMISPHERE), output=tmp_path, threads=threads, progress=interrupt_once)
    result = caught.value.result
    assert result.outcome == "interrupted" and result.status.startswith("interrupted at step")
    records = len(result.history["time"])
    assert 0 < records < 61
    written = read_csv(tmp_path / "forming.csv")
    assert len(written["time"]) == records
    np.testing.assert_array_equal(written["punch_force"], result.history["punch_force"])
    assert '"interrupted at step' in (tmp_path / "forming-result.csv").read_text()
    assert result.frame is not None and len(result.frame.points) > 0


def test_an_exception_of_the_progress_callable_stops_the_run():
    def fail(fraction, step, time):
        raise RuntimeError("enough")

    with pytest.raises(RuntimeError, match="enough") as caught:
        ts.run(ts.Scenario.load(HEMISPHERE, set=QUICK), progress=fail)
    assert caught.value.result.outcome == "interrupted"


def test_the_interpreter_is_free_while_a_run_goes():
    ticks = []
    running = threading.Event()
    running.set()

    def tick():
        while running.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.002)

    thread = threading.Thread(target=tick)
    thread.start()
    start = time.perf_counter()
    ts.run(ts.Scenario.load(HEMISPHERE, set=QUICK))
    seconds = time.perf_counter() - start
    running.clear()
    thread.join()
    during = [t for t in ticks if start <= t <= start + seconds]
    # a thread that had to wait for the run's looks at Python (ten a second) would tick about
    # ten times a second; free, it ticks every few milliseconds
    assert len(during) > 50 * seconds, (len(during), seconds)


def test_results_are_the_same_on_one_and_two_threads():
    scenario = ts.Scenario.load(HEMISPHERE, set=QUICK)
    one = ts.run(scenario, threads=1)
    two = ts.run(scenario, threads=2)
    for name in ts.HISTORY_COLUMNS:
        if name not in ("solver_time",):
            np.testing.assert_array_equal(one.history[name], two.history[name], err_msg=name)


def test_the_last_frame_reaches_pandas_and_pyvista():
    result = ts.run(ts.Scenario.load(HEMISPHERE, set=QUICK))
    frame = result.frame
    assert frame.points.shape == (result.summary["nodes"], 3)
    assert len(frame.cell_types) == result.summary["elements"]
    shear = frame.cell_data["shear_angle_deg"]
    assert np.abs(shear).max() == pytest.approx(result.summary["max_shear_deg"], rel=1e-9)
    pandas = pytest.importorskip("pandas")
    table = result.to_pandas()
    assert isinstance(table, pandas.DataFrame) and list(table.columns) == list(ts.HISTORY_COLUMNS)
    pyvista = pytest.importorskip("pyvista")
    grid = result.to_pyvista()
    assert grid.n_points == len(frame.points) and grid.n_cells == len(frame.cell_types)
    # formed: the punch (moving up, +z) carried the blank's centre through the stroke
    assert grid.points[:, 2].max() == pytest.approx(result.summary["stroke_reached"], abs=0.5)
    assert "contact_status" in grid.point_data


def test_a_folder_another_run_is_writing_raises_output_error(tmp_path):
    import subprocess

    from conftest import cli_exe

    other = subprocess.Popen(
        [str(cli_exe()), "run", str(HEMISPHERE), "--output", str(tmp_path)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        deadline = time.time() + 60
        while not (tmp_path / "forming.csv").exists():
            assert other.poll() is None and time.time() < deadline
            time.sleep(0.02)
        with pytest.raises(ts.OutputError) as caught:
            ts.run(ts.Scenario.load(HEMISPHERE, set=QUICK), output=tmp_path)
        assert "thermostamp run" in str(caught.value) and isinstance(caught.value, OSError)
    finally:
        other.kill()
        other.wait()


def test_a_non_isothermal_run_hands_over_its_temperatures():
    """tests/data/hemisphere-hot.toml: the blank out of the oven cools in the history, and the
    frames carry each layer's temperature and crystallinity."""
    scenario = ts.Scenario.load(ROOT / "tests" / "data" / "hemisphere-hot.toml", set={"process.stroke": 4.0})
    result = ts.run(scenario)
    assert result.ok, result.status
    mean = result.history["temperature_mean"]
    assert mean[0] < 320.0 and mean[-1] < mean[0]
    assert np.all(result.history["temperature_min"] <= mean)
    assert np.all(mean <= result.history["temperature_max"])
    cells = result.frame.cell_data
    for name in ["temperature", "temperature_layer_1", "temperature_layer_3", "crystallinity_layer_2", "frozen"]:
        assert name in cells, name
    assert np.all(cells["temperature_layer_1"] < 320.0)
    assert result.summary["temperature_mean"] == pytest.approx(mean[-1], rel=1e-12)
