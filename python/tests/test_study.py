"""ts.Study against `thermostamp sweep`: the same cases and the same summary.csv, on a Dask
cluster, killed and resumed; sampled designs reproducible from their seed."""

import csv
import os
import signal
import subprocess
import sys
import time

import pytest

import thermostamp as ts
from conftest import HEMISPHERE, ROOT, run_cli

PARAMETERS = """
[parameters]
"process.temperature" = [280.0, 320.0]
"process.blank_holder_force" = [50.0, 200.0]
"blank.element_size" = [10.0]
"process.stroke" = [10.0]
"output.frames" = [0]
"""


def study_file(folder, name, extra=""):
    """A study file of four quick hemisphere cases writing into ``folder/name-results``."""
    path = folder / f"{name}.toml"
    path.write_text(
        f'base = "{HEMISPHERE}"\n{PARAMETERS}{extra}\n[output]\nfolder = "{folder / (name + "-results")}"\n'
    )
    return path


def summary_rows(folder):
    """summary.csv's rows without the wall time, which differs from run to run."""
    with open(folder / "summary.csv", newline="") as f:
        rows = list(csv.reader(f))
    drop = rows[0].index("wall_seconds")
    return [[cell for k, cell in enumerate(row) if k != drop] for row in rows]


@pytest.fixture(scope="module")
def cli_summary(tmp_path_factory):
    folder = tmp_path_factory.mktemp("cli")
    run_cli("sweep", study_file(folder, "study"), "--jobs", "2")
    return summary_rows(folder / "study-results")


@pytest.fixture(scope="module")
def dask_executor():
    distributed = pytest.importorskip("dask.distributed")
    cluster = distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    )
    client = distributed.Client(cluster)
    yield client.get_executor()
    client.close()
    cluster.close()


def test_a_study_on_dask_gives_the_command_lines_summary(tmp_path, cli_summary, dask_executor):
    study = ts.Study.load(study_file(tmp_path, "study"))
    assert study.cases_count == 4
    seen = []
    summary = study.map(dask_executor, progress=lambda *a: seen.append(a))
    assert len(seen) == 4 and summary.failed == []
    assert summary_rows(tmp_path / "study-results") == cli_summary
    assert summary.columns["status"] == ["done"] * 4
    # each case ran in its own folder, written as `thermostamp run` writes it
    for case in study.cases():
        assert case["status"] == "done"


def test_a_killed_study_resumes_to_the_same_summary(tmp_path, cli_summary, dask_executor):
    path = study_file(tmp_path, "study")
    folder = tmp_path / "study-results"
    script = f"import thermostamp as ts; ts.Study.load({str(path)!r}).map(jobs=1)"
    child = subprocess.Popen([sys.executable, "-c", script], start_new_session=True)
    deadline = time.time() + 120
    while not list(folder.glob("*/case-result.toml")):
        assert child.poll() is None, "the study ended before it could be killed"
        assert time.time() < deadline, "no case finished within 120 s"
        time.sleep(0.05)
    os.killpg(child.pid, signal.SIGKILL)
    child.wait()
    finished = len(list(folder.glob("*/case-result.toml")))
    assert 1 <= finished < 4
    ran = []
    ts.Study.load(path).map(dask_executor, progress=lambda done, total, n, s: ran.append(n))
    assert len(ran) == 4 - finished
    assert summary_rows(folder) == cli_summary


def test_python_parameters_make_the_same_study_as_the_file(tmp_path):
    study = ts.Study(
        HEMISPHERE,
        parameters={
            "process.temperature": [280.0, 320.0],
            "process.blank_holder_force": ts.Range(50.0, 200.0, count=2),
        },
        folder=tmp_path / "out",
    )
    cases = study.cases()
    assert [(c["process.temperature"], c["process.blank_holder_force"]) for c in cases] == [
        (280.0, 50.0),
        (280.0, 200.0),
        (320.0, 50.0),
        (320.0, 200.0),
    ]
    assert all(c["status"] == "not run" for c in cases)
    (tmp_path / "same.toml").write_text(study.to_toml())
    listed = run_cli("sweep", tmp_path / "same.toml", "--list").stdout.splitlines()
    assert len(listed) == 4


@pytest.mark.parametrize("design", [ts.LatinHypercube, ts.Sobol])
def test_a_sampled_design_is_reproducible_from_its_seed(tmp_path, design):
    def cases(seed):
        study = ts.Study(
            HEMISPHERE,
            parameters={
                "process.temperature": ts.Range(280.0, 320.0),
                "process.blank_holder_force": ts.Range(20.0, 300.0),
            },
            folder=tmp_path / f"out-{seed}",
            design=design(8, seed=seed),
        )
        return [(c["process.temperature"], c["process.blank_holder_force"]) for c in study.cases()]

    first, again, other = cases(3), cases(3), cases(4)
    assert first == again and first != other
    assert len(first) == 8
    assert all(280.0 <= t <= 320.0 and 20.0 <= f <= 300.0 for t, f in first)
    # eight samples: one in each eighth of each range
    for k, (lo, hi) in enumerate([(280.0, 320.0), (20.0, 300.0)]):
        strata = sorted(int((case[k] - lo) / (hi - lo) * 8) for case in first)
        assert strata == list(range(8))


def test_a_bad_parameter_raises_a_study_error_naming_it(tmp_path):
    with pytest.raises(ts.StudyError) as caught:
        ts.Study(HEMISPHERE, parameters={"process.temperatur": [300.0]}, folder=tmp_path)
    assert "process.temperatur" in str(caught.value)


def test_the_latin_hypercube_example_runs_in_reduced_form(tmp_path):
    """examples/study-hemisphere-lhs.toml with 3 samples, 10 mm cells and 5 mm of stroke, in a
    local process pool: every case done, each temperature in its own third of the range."""
    text = (ROOT / "examples" / "study-hemisphere-lhs.toml").read_text()
    reduced = (
        text.replace('base = "hemisphere.toml"', f'base = "{HEMISPHERE}"')
        .replace("samples = 16 ", "samples = 3 ")
        .replace(
            '"process.punch_speed" = [5.0, 10.0, 20.0]',
            '"process.punch_speed" = [5.0, 10.0, 20.0]\n"blank.element_size" = [10.0]\n'
            '"process.stroke" = [5.0]\n"output.frames" = [0]',
        )
        .replace('folder = "study-hemisphere-lhs-results"', f'folder = "{tmp_path / "out"}"')
    )
    assert reduced.count("[10.0]") == 1 and "samples = 3 " in reduced
    path = tmp_path / "lhs.toml"
    path.write_text(reduced)
    summary = ts.Study.load(path).map(jobs=2)
    assert summary.columns["status"] == ["done"] * 3
    thirds = sorted(int((t - 280.0) / 40.0 * 3) for t in summary.columns["process.temperature"])
    assert thirds == [0, 1, 2]
    assert all(speed in (5.0, 10.0, 20.0) for speed in summary.columns["process.punch_speed"])


def test_a_case_interrupted_is_left_to_run_again(tmp_path):
    """Ctrl-C in the process running a case stops it without a result: the case is not
    finished, not failed, and the study runs it again. The case runs several seconds on 6 mm
    cells, so that the interrupt after one second falls inside it (on 10 mm cells it could
    finish first on an idle machine)."""
    import _thread
    import threading

    study = ts.Study(
        HEMISPHERE,
        parameters={"blank.element_size": [6.0], "output.frames": [0]},
        folder=tmp_path / "out",
    )
    timer = threading.Timer(1.0, _thread.interrupt_main)
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            study.run_case(1)
    finally:
        timer.cancel()
    assert study.cases()[0]["status"] == "not finished"
    summary = study.map(jobs=1)
    assert summary.columns["status"] == ["done"]
