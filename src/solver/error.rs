//! Why a run of either solver stopped early, and the settings checks they share.

use super::State;

/// Why a run stopped early.
#[derive(Debug, thiserror::Error)]
pub enum SolverError {
    #[error(
        "the run went unstable at step {step}, t = {time:.6e} s, in element {element}: {reason} \
         (energies: kinetic {kinetic:.4e}, internal {internal:.4e}, external {external:.4e} N·mm)"
    )]
    Unstable {
        step: usize,
        time: f64,
        element: usize,
        reason: String,
        kinetic: f64,
        internal: f64,
        external: f64,
    },
    /// In a non-isothermal run, the blank's temperature left one of the card's tables
    /// (docs/model.md §9): the run stops, its records kept.
    #[error(
        "the blank's temperature left the card's tables at step {step}, t = {time:.6e} s, in \
         element {element}: {reason} (the records so far are kept)"
    )]
    Temperature {
        step: usize,
        time: f64,
        element: usize,
        reason: String,
    },
    #[error("bad solver settings: {0}")]
    Settings(String),
    #[error("writing results at t = {time:.6e} s: {source:#}")]
    Output { time: f64, source: anyhow::Error },
    #[error("interrupted at step {step}, t = {time:.6e} s")]
    Interrupted { step: usize, time: f64 },
    /// The implicit solver could not converge an increment however small (the results up to
    /// the last converged one are kept).
    #[error(
        "increment {increment} from t = {time:.6e} s (last tried {increment_time:.3e} s) did not \
         converge: {reason}; residual norms (N) {residuals:?}; largest residuals at nodes \
         {worst_nodes:?}"
    )]
    NotConverged {
        increment: usize,
        time: f64,
        increment_time: f64,
        reason: String,
        residuals: Vec<f64>,
        worst_nodes: Vec<usize>,
    },
    /// A run-time check ([`super::checks`]) found the result meaningless.
    #[error(transparent)]
    Check(CheckStop),
}

/// `Ok` for a finite positive setting `v`, else a settings error naming it: either solver's
/// checks.
pub(crate) fn positive_setting(name: &str, v: f64) -> Result<(), SolverError> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(SolverError::Settings(format!("{name} = {v} must be > 0")))
    }
}

/// Why a check stopped a run.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error(
    "check '{check}' stopped the run at step {step}, t = {time:.6e} s: {figure}; {advice} \
     (the records so far are kept)"
)]
pub struct CheckStop {
    pub check: &'static str,
    pub step: usize,
    pub time: f64,
    pub figure: String,
    pub advice: String,
}

/// How a run ended, in the words of its summary and its result row.
pub fn outcome_status(outcome: &Result<State, SolverError>) -> String {
    match outcome {
        Ok(_) => "finished".to_string(),
        Err(SolverError::Interrupted { step, time }) => {
            format!("interrupted at step {step}, t = {time:.4e} s, results so far kept")
        }
        Err(SolverError::Unstable { step, time, .. }) => {
            format!("unstable at step {step}, t = {time:.4e} s, results so far kept")
        }
        Err(SolverError::Temperature { step, time, .. }) => format!(
            "stopped at step {step}, t = {time:.4e} s: a temperature outside the card's tables, \
             results so far kept"
        ),
        Err(SolverError::Output { time, .. }) => {
            format!("stopped at t = {time:.4e} s: a result could not be written")
        }
        Err(SolverError::Check(stop)) => format!(
            "stopped by the {} check at step {}, t = {:.4e} s, results so far kept",
            stop.check, stop.step, stop.time
        ),
        Err(SolverError::NotConverged {
            increment, time, ..
        }) => format!(
            "stopped: increment {increment} from t = {time:.4e} s did not converge; results up \
             to the last converged increment kept"
        ),
        Err(SolverError::Settings(_)) => "not started: bad solver settings".to_string(),
    }
}
