//! What a run reports to while it runs: records, checkpoints, progress and the user's stop.

use super::model::Model;
use super::state::State;

/// Receives the state while the solver runs.
pub trait Observer {
    /// At t = 0, every output interval and at the end; an error stops the run.
    fn record(&mut self, model: &Model, state: &State) -> anyhow::Result<()>;
    /// Where the run-time checks look ([`super::checks::watched`]), at a pace of the solver's own: the
    /// explicit solver's every record, the implicit solver's every increment, so that what
    /// they find does not depend on how often the implicit solver records. An error stops the
    /// run, the state recorded first.
    fn checkpoint(&mut self, _model: &Model, _state: &State) -> anyhow::Result<()> {
        Ok(())
    }
    /// Every few hundred steps, for progress reports.
    fn progress(&mut self, _state: &State) {}
    /// Asked once per step: whether the user asked the run to stop (Ctrl-C). When it says yes
    /// the run records the current state once more and stops with
    /// [`SolverError::Interrupted`].
    fn interrupted(&mut self) -> bool {
        false
    }
}
