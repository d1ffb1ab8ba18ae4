//! Studies from Python: the study's cases, one case run in this process with the same folder,
//! lock, scenario, log and result as `thermostamp sweep --case N`, and the summary. The
//! executor that spreads the cases over processes is Python's (`thermostamp/study.py`).

use crate::errors::raise;
use crate::run::{form, Failure};
use crate::watch::{supervise, Beacon};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::{Path, PathBuf};
use thermostamp::forming::advice::stop_advice;
use thermostamp::forming::output::result_row;
use thermostamp::forming::Scenario;
use thermostamp::io::message::tidy_message;
use thermostamp::solver::SolverError;
use thermostamp::study::run::{case_status, run_case_with, unfinished, CaseRun, RunEnd};
use thermostamp::study::summary::{rows, write_summary, SUMMARY_CSV};
use thermostamp::study::{folder, identity, Study};

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(study_open, m)?)?;
    m.add_function(wrap_pyfunction!(study_cases, m)?)?;
    m.add_function(wrap_pyfunction!(study_prepare, m)?)?;
    m.add_function(wrap_pyfunction!(study_run_case, m)?)?;
    m.add_function(wrap_pyfunction!(study_summarise, m)?)?;
    Ok(())
}

fn study_error(py: Python<'_>, message: impl std::fmt::Display) -> PyErr {
    raise(py, "StudyError", (format!("{message:#}"),))
}

/// The checked study of a study file's `text` (`base` relative to `base_dir`, `output.folder`
/// to `run_dir`).
fn open(
    py: Python<'_>,
    text: &str,
    origin: &str,
    base_dir: &Path,
    run_dir: &Path,
) -> PyResult<Study> {
    py.detach(|| Study::from_text(text, origin, base_dir, run_dir))
        .map_err(|e| study_error(py, e))
}

/// The study's folder, parameter keys, number of cases and threads per case.
#[pyfunction]
fn study_open<'py>(
    py: Python<'py>,
    text: &str,
    origin: &str,
    base_dir: PathBuf,
    run_dir: PathBuf,
) -> PyResult<Bound<'py, PyDict>> {
    let study = open(py, text, origin, &base_dir, &run_dir)?;
    let dict = PyDict::new(py);
    dict.set_item("folder", &study.folder)?;
    let keys: Vec<&str> = study.parameters.iter().map(|p| p.key.as_str()).collect();
    dict.set_item("parameters", keys)?;
    dict.set_item("cases", study.cases_count())?;
    dict.set_item("threads_per_case", study.threads_per_case)?;
    Ok(dict)
}

/// A case as `sweep --list` shows it: its number, its parameters' values and its status.
type CaseLine<'py> = (usize, Vec<Bound<'py, PyAny>>, String);

/// Every case, as `sweep --list`.
#[pyfunction]
fn study_cases<'py>(
    py: Python<'py>,
    text: &str,
    origin: &str,
    base_dir: PathBuf,
    run_dir: PathBuf,
) -> PyResult<Vec<CaseLine<'py>>> {
    let study = open(py, text, origin, &base_dir, &run_dir)?;
    let folder_exists = study.folder.exists();
    study
        .cases()
        .map(|case| {
            let values = case
                .values
                .iter()
                .map(|v| crate::scenario::to_python(py, v))
                .collect::<PyResult<Vec<_>>>()?;
            let status = case_status(&study, case.number, folder_exists);
            Ok((case.number, values, status))
        })
        .collect()
}

/// Claims the study's folder for this study (a folder holding another is refused), checks the
/// scenario of every case not finished, and returns their numbers.
#[pyfunction]
fn study_prepare(
    py: Python<'_>,
    text: &str,
    origin: &str,
    base_dir: PathBuf,
    run_dir: PathBuf,
    command: &str,
) -> PyResult<Vec<usize>> {
    let study = open(py, text, origin, &base_dir, &run_dir)?;
    py.detach(|| -> anyhow::Result<Vec<usize>> {
        identity::verify(&study)?;
        let pending = unfinished(&study);
        for case in pending.iter().filter_map(|&n| study.case(n)) {
            study.check_case(&case)?;
        }
        drop(folder::take_shared(&study, command)?);
        Ok(pending)
    })
    .map_err(|e| study_error(py, e))
}

/// Runs case `number` in this process, as `thermostamp sweep --case N` runs it in a child:
/// its status (`done` or `failed`), the failure's reason and its wall time.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
fn study_run_case(
    py: Python<'_>,
    text: &str,
    origin: &str,
    base_dir: PathBuf,
    run_dir: PathBuf,
    number: usize,
    command: &str,
) -> PyResult<(String, String, f64)> {
    let study = open(py, text, origin, &base_dir, &run_dir)?;
    let case = study.case(number).ok_or_else(|| {
        study_error(
            py,
            format!(
                "case {number}: the study has cases 1 to {}",
                study.cases_count()
            ),
        )
    })?;
    let (result, interrupt) = supervise(py, None, None, |beacon| -> anyhow::Result<_> {
        identity::verify(&study)?;
        study.check_case(&case)?;
        let _folder = folder::take_shared(&study, command)?;
        run_case_with(&study, &case, command, &|run: &CaseRun| {
            run_here(run, command, beacon)
        })
    });
    // Ctrl-C left the case unfinished: it is raised as such, not as the case's error
    if let Some(interrupt) = interrupt {
        return Err(interrupt);
    }
    let result = result.map_err(|e| study_error(py, e))?;
    Ok((result.status, result.reason, result.wall_seconds))
}

/// Writes the summary and charts from the case folders (the study's folder taken whole); the
/// path of `summary.csv`.
#[pyfunction]
fn study_summarise(
    py: Python<'_>,
    text: &str,
    origin: &str,
    base_dir: PathBuf,
    run_dir: PathBuf,
    command: &str,
) -> PyResult<PathBuf> {
    let study = open(py, text, origin, &base_dir, &run_dir)?;
    py.detach(|| -> anyhow::Result<PathBuf> {
        let _folder = folder::take_whole(&study, command)?;
        write_summary(&study, &rows(&study))?;
        Ok(study.folder.join(SUMMARY_CSV))
    })
    .map_err(|e| study_error(py, e))
}

/// A case's forming run in this process, into its folder: what `thermostamp run` would print on
/// standard error (the checks' warnings, advice, the error that stopped it) is the run's
/// `stderr`, from which the study takes a failure's reason; the log gets the summary too. A
/// run interrupted (Ctrl-C in the worker) is an error, not a failed case: the case is left
/// unfinished, so that the study runs it again when resumed.
fn run_here(run: &CaseRun, command: &str, beacon: &Beacon) -> anyhow::Result<RunEnd> {
    let failed = |message: String| RunEnd {
        success: false,
        stderr: format!("error: {}", tidy_message(&message)),
        exit_code: Some(2),
    };
    let scenario = match Scenario::load(&run.scenario, &[]) {
        Ok(s) => s,
        Err(e) => return Ok(logged(run, failed(e.to_string()), "")),
    };
    let pool = match rayon::ThreadPoolBuilder::new()
        .num_threads(run.threads)
        .build()
    {
        Ok(pool) => pool,
        Err(e) => {
            let message = format!("cannot start the worker threads: {e}");
            return Ok(logged(run, failed(message), ""));
        }
    };
    let done = match pool.install(|| form(&scenario, Some(&run.folder), Some(beacon), command)) {
        Ok(done) => done,
        Err(Failure::Setup(message)) => return Ok(logged(run, failed(message), "")),
        Err(Failure::Output(e)) => return Ok(logged(run, failed(format!("{e:#}")), "")),
    };
    if let Err(e @ SolverError::Interrupted { .. }) = &done.run.outcome {
        anyhow::bail!("{}: {e}", run.folder.display());
    }
    let mut stderr: Vec<String> = done
        .run
        .checks
        .warnings()
        .map(|l| format!("warning: {}: {}: {}", l.name, l.status, l.figure))
        .collect();
    stderr.extend(stop_advice(&scenario, &done.forming, &done.run));
    if let Err(e) = &done.run.outcome {
        stderr.push(format!("error: {}", tidy_message(&error_chain(e))));
    }
    let row = result_row(&scenario, &done.forming, &done.run);
    let mut summary = vec![format!("status: {}", row.status)];
    summary.extend(
        row.names
            .iter()
            .zip(&row.values)
            .map(|(n, v)| format!("{n}: {}", v.map_or("-".into(), |v| format!("{v:e}")))),
    );
    summary.extend(done.files.iter().map(|f| format!("wrote {}", f.display())));
    let end = RunEnd {
        success: done.run.outcome.is_ok(),
        stderr: stderr.join("\n"),
        exit_code: Some(if done.run.outcome.is_ok() { 0 } else { 1 }),
    };
    Ok(logged(run, end, &summary.join("\n")))
}

/// An error and its causes, `: ` between them, as the command line prints an error.
fn error_chain(e: &dyn std::error::Error) -> String {
    let mut text = e.to_string();
    let mut cause = e.source();
    while let Some(c) = cause {
        text += &format!(": {c}");
        cause = c.source();
    }
    text
}

/// Writes the run's summary and `end`'s standard error to the case's log, as the command
/// line's run would have; a log that cannot be written is said on standard error.
fn logged(run: &CaseRun, end: RunEnd, summary: &str) -> RunEnd {
    let text = format!(
        "run in-process by thermostamp's Python package\n{summary}\n{}\n",
        end.stderr
    );
    if let Err(e) = thermostamp::io::product_file::write(&run.log, text.as_bytes()) {
        eprintln!("cannot write {}: {e}", run.log.display());
    }
    end
}
