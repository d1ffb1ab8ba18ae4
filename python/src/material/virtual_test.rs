//! `thermostamp.uniaxial_test`, `bias_extension_test`, `picture_frame_test`: the virtual tests
//! of `thermostamp test ...` in this process, the interpreter free while they run, progress
//! and Ctrl-C as `thermostamp.run` has them.

use super::{columns_dict, python_names};
use crate::errors::{input_error, output_error};
use crate::run::{check_lines, outcome_kind, worker_pool};
use crate::watch::{supervise, Watch};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;
use thermostamp::experiment::virtual_test::{prepare, Specimen, TestOptions};
use thermostamp::limits::{FRAMES, HISTORY_POINTS};
use thermostamp::mesh::DiagonalPattern;
use thermostamp::solver::error::outcome_status;
use thermostamp::solver::SolverKind;

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(virtual_test, m)?)?;
    Ok(())
}

/// Runs the virtual test `kind` (`uniaxial`, `bias-extension`, `picture-frame`) on the card at
/// `card`; `options` holds every option of the test by its Python name (the Python side
/// fills in the defaults). Returns the result as a dictionary and the exception that stopped
/// the run early (`KeyboardInterrupt`, or what the progress callable raised).
#[pyfunction]
#[pyo3(signature = (kind, card, options, output=None, threads=None, progress=None, command=String::new()))]
#[allow(clippy::too_many_arguments)]
fn virtual_test(
    py: Python<'_>,
    kind: &str,
    card: PathBuf,
    options: &Bound<'_, PyDict>,
    output: Option<PathBuf>,
    threads: Option<usize>,
    progress: Option<Py<PyAny>>,
    command: String,
) -> PyResult<(Py<PyDict>, Option<PyErr>)> {
    let get = |key: &str| -> PyResult<Option<f64>> {
        match options.get_item(key)? {
            Some(v) => v.extract::<Option<f64>>(),
            None => Ok(None),
        }
    };
    let number = |key: &str| -> PyResult<f64> {
        get(key)?.ok_or_else(|| input_error(py, format!("{key}: a number is needed")))
    };
    let count = |key: &str, range: thermostamp::limits::Range| -> PyResult<usize> {
        let value: i64 = match options.get_item(key)? {
            Some(v) => v.extract()?,
            None => return Err(input_error(py, format!("{key}: a number is needed"))),
        };
        usize::try_from(value).map_err(|_| {
            input_error(
                py,
                range
                    .check(key, value as f64)
                    .err()
                    .unwrap_or_else(|| format!("{key} = {value} must be >= 0")),
            )
        })
    };
    let word = |key: &str, default: &str| -> PyResult<String> {
        match options.get_item(key)? {
            Some(v) => v.extract(),
            None => Ok(default.to_string()),
        }
    };
    let specimen = match kind {
        "uniaxial" => Specimen::Uniaxial {
            width: number("width")?,
            length: number("length")?,
            ply_angle: number("ply_angle")?,
        },
        "bias-extension" => Specimen::BiasExtension {
            width: number("width")?,
            length: number("length")?,
        },
        "picture-frame" => Specimen::PictureFrame {
            side: number("side")?,
        },
        other => return Err(input_error(py, format!("unknown test '{other}'"))),
    };
    let pattern = match word("pattern", "crossed")?.as_str() {
        "quad" => DiagonalPattern::Quad,
        "right" => DiagonalPattern::Right,
        "alternating" => DiagonalPattern::Alternating,
        "crossed" => DiagonalPattern::Crossed,
        other => {
            return Err(input_error(
                py,
                format!("pattern '{other}': quad, right, alternating or crossed"),
            ))
        }
    };
    let solver = SolverKind::parse(&word("solver", "explicit")?)
        .map_err(|e| input_error(py, format!("solver: {e}")))?;
    let test_options = TestOptions {
        temperature: get("temperature")?,
        speed: get("speed")?,
        time_scaling: get("time_scaling")?,
        target_step: get("target_step")?,
        damping: get("damping")?.unwrap_or(0.0),
        element_size: get("element_size")?,
        pattern,
        end_displacement: get("end_displacement")?,
        frames: count("frames", FRAMES)?,
        history_points: count("history_points", HISTORY_POINTS)?,
        solver,
    };
    let pool = worker_pool(py, threads)?;
    let job = |beacon: &_| -> Result<Done, Failure> {
        let mut notes = Vec::new();
        let test = prepare(&card, specimen, &test_options, python_names, &mut |line| {
            notes.push(line)
        })
        .map_err(Failure::Input)?;
        let start = |end_time| Watch::new(beacon, end_time, test.time_scaling);
        let folder = output.as_deref().map(|dir| (dir, command.as_str()));
        let (outcome, _watch) = test.run(folder, start).map_err(Failure::Output)?;
        Ok(Done {
            outcome,
            notes,
            chosen: test.chosen.clone(),
            time_scaling: test.time_scaling,
            estimated_steps: test.estimate.steps,
        })
    };
    let (done, raised) = supervise(py, pool.as_ref(), progress.as_ref(), job);
    let done = match done {
        Ok(done) => done,
        Err(Failure::Input(e)) => return Err(input_error(py, e)),
        Err(Failure::Output(e)) => return Err(output_error(py, e)),
    };
    let dict = result_dict(py, &done)?;
    Ok((dict.unbind(), raised))
}

enum Failure {
    Input(anyhow::Error),
    Output(anyhow::Error),
}

struct Done {
    outcome: thermostamp::experiment::virtual_test::TestOutcome,
    notes: Vec<String>,
    chosen: Vec<String>,
    time_scaling: f64,
    estimated_steps: f64,
}

/// The summary, the history columns, the checks, the files and the notes of a test run.
fn result_dict<'py>(py: Python<'py>, done: &Done) -> PyResult<Bound<'py, PyDict>> {
    let run = &done.outcome.run;
    let dict = PyDict::new(py);
    dict.set_item("status", outcome_status(&run.outcome))?;
    dict.set_item("outcome", outcome_kind(&run.outcome))?;
    dict.set_item(
        "error",
        run.outcome.as_ref().err().map(|e| format!("{e:#}")),
    )?;
    let s = &run.summary;
    let summary = PyDict::new(py);
    summary.set_item("steps", s.steps)?;
    summary.set_item("elements", s.elements)?;
    summary.set_item("time_step", s.time_step)?;
    summary.set_item("added_mass", s.added_mass)?;
    summary.set_item("physical_mass", s.physical_mass)?;
    summary.set_item("time_scaling", done.time_scaling)?;
    summary.set_item("worst_balance_error", s.worst_balance_error)?;
    summary.set_item("worst_kinetic_ratio", s.worst_kinetic_ratio)?;
    summary.set_item("wall_seconds", s.wall_seconds)?;
    summary.set_item("threads", s.threads)?;
    summary.set_item("element_steps_per_second", s.element_steps_per_second())?;
    summary.set_item("estimated_steps", done.estimated_steps)?;
    summary.set_item(
        "solver",
        if s.implicit.is_some() {
            "implicit"
        } else {
            "explicit"
        },
    )?;
    summary.set_item("defaults_chosen", done.chosen.clone())?;
    dict.set_item("summary", summary)?;
    dict.set_item(
        "history",
        columns_dict(py, &done.outcome.header, &done.outcome.history)?,
    )?;
    dict.set_item("checks", check_lines(&run.checks))?;
    dict.set_item("files", done.outcome.files.clone())?;
    dict.set_item("notes", done.notes.clone())?;
    Ok(dict)
}
