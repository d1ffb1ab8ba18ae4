//! `thermostamp.run`: a forming run in this process, the interpreter free meanwhile (a Python
//! thread goes on running), progress reported to a callable, Ctrl-C honoured as the command
//! line honours it (the run stops after its step and keeps its results so far). Files are
//! written, the same as `thermostamp run` writes, only into a given output folder.

use crate::errors::{input_error, output_error, scenario_error};
use crate::frame::frame_dict;
use crate::watch::{supervise, Beacon, Watch};
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::{Path, PathBuf};
use thermostamp::experiment::sheet_test::Progress;
use thermostamp::forming::advice::stop_advice;
use thermostamp::forming::output::{
    history_row, live_output, products, result_row, write_final_results, HISTORY_COLUMNS,
};
use thermostamp::forming::{FormingModel, FormingRun, Scenario};
use thermostamp::io::output_folder::take_folder;
use thermostamp::solver::checks::CheckReport;
use thermostamp::solver::SolverError;

/// Runs the scenario of standalone `text`; returns the result as a dictionary and the
/// exception that stopped it early (`KeyboardInterrupt`, or what the progress callable
/// raised), which the Python side raises with the result attached.
#[pyfunction]
#[pyo3(signature = (text, origin, output=None, threads=None, progress=None, command=String::new()))]
pub fn run_scenario(
    py: Python<'_>,
    text: &str,
    origin: &str,
    output: Option<PathBuf>,
    threads: Option<usize>,
    progress: Option<Py<PyAny>>,
    command: String,
) -> PyResult<(Py<PyDict>, Option<PyErr>)> {
    let scenario = crate::scenario::checked(py, text, origin)?;
    let pool = worker_pool(py, threads)?;
    let (done, raised) = supervise(py, pool.as_ref(), progress.as_ref(), |beacon| {
        form(&scenario, output.as_deref(), Some(beacon), &command)
    });
    let done = match done {
        Ok(done) => done,
        Err(Failure::Setup(message)) => return Err(scenario_error(py, origin, &message)),
        Err(Failure::Output(e)) => return Err(output_error(py, e)),
    };
    let dict = result_dict(py, &scenario, &done)?;
    Ok((dict.unbind(), raised))
}

/// A rayon pool of `threads` workers (cut to the cores), `None` for the global pool of all
/// cores.
pub fn worker_pool(py: Python<'_>, threads: Option<usize>) -> PyResult<Option<rayon::ThreadPool>> {
    let Some(requested) = threads else {
        return Ok(None);
    };
    let cores = std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get);
    let (n, _note) = thermostamp::solver::threads::thread_count(requested, cores)
        .map_err(|e| input_error(py, format!("threads = {requested}: {e}")))?;
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .map(Some)
        .map_err(|e| input_error(py, format!("cannot start the worker threads: {e}")))
}

/// Why a run did not even start: a scenario the model cannot be built from, or an output
/// folder that cannot be taken.
pub enum Failure {
    Setup(String),
    Output(anyhow::Error),
}

/// A run that started, and what it wrote.
pub struct Done {
    pub forming: FormingModel,
    pub run: FormingRun,
    pub files: Vec<PathBuf>,
}

/// Builds the model of `scenario` and runs it, writing into `output` (taken with `command`
/// for its lock) when given, its progress left in `beacon` (whose stop flag stops it).
pub fn form(
    scenario: &Scenario,
    output: Option<&Path>,
    beacon: Option<&Beacon>,
    command: &str,
) -> Result<Done, Failure> {
    let forming = FormingModel::reporting(scenario, &mut |_| {}).map_err(Failure::Setup)?;
    let _lock = match output {
        Some(dir) => {
            Some(take_folder(dir, command, &products()).map_err(|e| Failure::Output(e.into()))?)
        }
        None => None,
    };
    let live = match output {
        Some(dir) => Some(live_output(dir, scenario, &forming).map_err(Failure::Output)?),
        None => None,
    };
    let mut watch = beacon.map(|beacon| {
        Watch::new(
            beacon,
            forming.settings.end_time,
            scenario.process.time_scaling,
        )
    });
    let run = thermostamp::forming::run::run(
        &forming,
        live,
        watch.as_mut().map(|w| w as &mut dyn Progress),
    );
    let files = match output {
        Some(dir) if !run.records.is_empty() => {
            write_final_results(dir, scenario, &forming, &run).map_err(Failure::Output)?
        }
        _ => Vec::new(),
    };
    Ok(Done {
        forming,
        run,
        files,
    })
}

/// The result as the Python `Result` is made from: status, summary, history columns (NumPy
/// arrays handed over without a copy), the last frame, checks, files and notes.
fn result_dict<'py>(
    py: Python<'py>,
    scenario: &Scenario,
    done: &Done,
) -> PyResult<Bound<'py, PyDict>> {
    let Done {
        forming,
        run,
        files,
        ..
    } = done;
    let dict = PyDict::new(py);
    let row = result_row(scenario, forming, run);
    dict.set_item("status", &row.status)?;
    dict.set_item("outcome", outcome_kind(&run.outcome))?;
    dict.set_item(
        "error",
        run.outcome.as_ref().err().map(|e| format!("{e:#}")),
    )?;
    let summary = PyDict::new(py);
    for (name, value) in row.names.iter().zip(&row.values) {
        summary.set_item(name, *value)?;
    }
    summary.set_item("steps", run.steps)?;
    summary.set_item("wall_seconds", run.wall_seconds)?;
    summary.set_item("elements", forming.model.elements.len())?;
    summary.set_item("nodes", forming.model.mesh.nodes.len())?;
    summary.set_item("solver", forming.solver.name())?;
    summary.set_item("threads", rayon::current_num_threads())?;
    dict.set_item("summary", summary)?;
    dict.set_item("history", history_dict(py, scenario, run)?)?;
    let frame = match run.formed_state() {
        Some(state) => Some(frame_dict(py, &forming.model, state)?),
        None => None,
    };
    dict.set_item("frame", frame)?;
    dict.set_item("checks", check_lines(&run.checks))?;
    dict.set_item("files", files.clone())?;
    let mut notes = forming.notes.clone();
    notes.extend(stop_advice(scenario, forming, run));
    dict.set_item("notes", notes)?;
    Ok(dict)
}

/// The run-time checks as `(name, status, figure)`, as `thermostamp.Check` takes them.
pub(crate) fn check_lines(checks: &CheckReport) -> Vec<(String, String, String)> {
    checks
        .lines
        .iter()
        .map(|l| (l.name.to_string(), l.status.to_string(), l.figure.clone()))
        .collect()
}

/// `finished`, `interrupted`, `output` (a result could not be written) or `failed` (the solver
/// or a check stopped the run, results so far kept).
pub(crate) fn outcome_kind<T>(outcome: &Result<T, SolverError>) -> &'static str {
    match outcome {
        Ok(_) => "finished",
        Err(SolverError::Interrupted { .. }) => "interrupted",
        Err(SolverError::Output { .. }) => "output",
        Err(_) => "failed",
    }
}

/// The history by column, the values of `forming.csv` ([`HISTORY_COLUMNS`]).
fn history_dict<'py>(
    py: Python<'py>,
    scenario: &Scenario,
    run: &FormingRun,
) -> PyResult<Bound<'py, PyDict>> {
    let mut columns: Vec<Vec<f64>> = (0..HISTORY_COLUMNS.len())
        .map(|_| Vec::with_capacity(run.records.len()))
        .collect();
    for record in &run.records {
        let row = history_row(record, scenario.process.time_scaling);
        for (column, value) in columns.iter_mut().zip(row) {
            column.push(value);
        }
    }
    let dict = PyDict::new(py);
    for (name, column) in HISTORY_COLUMNS.iter().zip(columns) {
        // the vector's buffer becomes the array's: no copy
        dict.set_item(name, PyArray1::from_vec(py, column))?;
    }
    Ok(dict)
}
