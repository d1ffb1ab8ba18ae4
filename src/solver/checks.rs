//! Run-time checks that wrap every run of either solver (forming runs and the virtual
//! tests): what explicit codes watch so that a run whose result means nothing does not end
//! quietly. At every checkpoint (the explicit solver's records, the implicit solver's
//! increments, [`Observer::checkpoint`]): the kinetic energy against the internal work, the energy balance,
//! the sign of the internal work, the size of the forces and the nodes lost behind a tool. A
//! check past its hard limit stops the run with [`SolverError::Check`] (the records so far are
//! kept by the observer); one past its warning level is reported in the [`CheckReport`].

use super::energy::Energies;
use super::error::{CheckStop, SolverError};
use super::model::{Model, Ply};
use super::observer::Observer;
use super::state::State;
use crate::contact::penalty::nodes_through_tools;
use crate::contact::ToolMotion;
use nalgebra::Vector3;

/// Kinetic energy over internal work, once the sheet is loaded, above which the result carries
/// the sheet's inertia: a quasi-static run stays well under it (a few per cent is the usual
/// rule of explicit forming codes).
pub const KINETIC_WARNING: f64 = 0.05;

/// Kinetic energy over internal work above which the run is dynamic, not a forming or a test:
/// half the work put in still moving. Stopped when it lasts [`KINETIC_STOP_SPAN`] of the run,
/// so that a contact impact does not stop a sound run, however often the checks look.
pub const KINETIC_STOP: f64 = 0.5;

/// Fraction of the run's duration over which the kinetic energy must stay past
/// [`KINETIC_STOP`] to stop the run (it was 5 records in a row, which made the stop depend on
/// how often a run records: 5 % of the run at the default 100 records).
pub const KINETIC_STOP_SPAN: f64 = 0.05;

/// Energy balance error `|W_ext - W_int - E_kin - W_damp| / W_ext` reported as a warning. The
/// solver stops a run at 50 % (a blow-up); a sound run stays within a few per cent.
pub const BALANCE_WARNING: f64 = 0.05;

/// The records whose internal work is at least this fraction of its final value count as
/// loaded for the kinetic-energy figure of the report: before that the ratio of two tiny
/// numbers means nothing.
pub const LOADED_FRACTION: f64 = 0.05;

/// Internal work below `-NEGATIVE_WORK_TOLERANCE x max(|W_ext|, E_kin)` stops the run: the
/// laminate stores or dissipates energy, it never gives back more than it took, so negative
/// internal work beyond round-off means the material law is outside its range.
pub const NEGATIVE_WORK_TOLERANCE: f64 = 1e-3;

/// Strain of every yarn across the blank that the physical force bound stands for: no woven
/// ply carries 100 % strain, so a force beyond `E t L` (plus the tools' applied forces) is a
/// numerical artefact, not a load.
pub const FORCE_BOUND_STRAIN: f64 = 1.0;

/// Fraction of the blank's nodes behind a tool beyond the contact's reach that stops the run:
/// a tool that passed through the blank.
pub const TUNNELLED_STOP_FRACTION: f64 = 0.01;

/// How a check came out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CheckStatus {
    Ok,
    Warning,
    Stopped,
}

impl std::fmt::Display for CheckStatus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            CheckStatus::Ok => "OK",
            CheckStatus::Warning => "WARNING",
            CheckStatus::Stopped => "STOPPED",
        })
    }
}

/// One line of the report: the check, its figure, how it came out.
#[derive(Clone, Debug, PartialEq)]
pub struct CheckLine {
    pub name: &'static str,
    pub figure: String,
    pub status: CheckStatus,
}

/// The checks of a finished (or stopped) run.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CheckReport {
    pub lines: Vec<CheckLine>,
}

impl CheckReport {
    /// The lines that are not OK.
    pub fn warnings(&self) -> impl Iterator<Item = &CheckLine> {
        self.lines.iter().filter(|l| l.status != CheckStatus::Ok)
    }

    /// `(name, "STATUS: figure")` rows for a summary table.
    pub fn rows(&self) -> Vec<(&'static str, String)> {
        self.lines
            .iter()
            .map(|l| (l.name, format!("{}: {}", l.status, l.figure)))
            .collect()
    }
}

/// What the checks know of a run beyond its model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CheckSettings {
    /// Records before this time (s) do not count: the smooth start of the crosshead or punch.
    pub settle_time: f64,
    /// Largest physical force of the run (N), [`force_bound`].
    pub force_bound: f64,
    /// Internal work from which the kinetic energy may stop the run (N·mm),
    /// [`carried_kinetic_energy`].
    pub loaded_work: f64,
    /// The run's duration (s): [`KINETIC_STOP_SPAN`] of it stops a dynamic run.
    pub end_time: f64,
    /// What to change when the run is too dynamic, for the messages ("lower --speed ...").
    pub dynamic_advice: &'static str,
}

/// The physical bound of the forces of a run (N): every yarn across the blank stretched by
/// [`FORCE_BOUND_STRAIN`] at its laminate's stiffest wave modulus at rest, `sum_plies E t L`
/// with `L` the perimeter of the blank's bounding box, plus the forces applied to force-driven
/// tools.
pub fn force_bound(model: &Model) -> Result<f64, String> {
    let (mut lo, mut hi) = (
        Vector3::repeat(f64::INFINITY),
        Vector3::repeat(f64::NEG_INFINITY),
    );
    for x in &model.mesh.nodes {
        lo = lo.inf(x);
        hi = hi.sup(x);
    }
    let extent = hi - lo;
    let perimeter = 2.0 * (extent.x + extent.y + extent.z);
    let applied: f64 = model
        .tools
        .iter()
        .map(|t| match &t.motion {
            ToolMotion::Force { force, .. } => force.norm(),
            _ => 0.0,
        })
        .sum();
    let mut stiffness = 0.0;
    for ply in &model.plies {
        stiffness += rest_wave_modulus(model, ply)? * ply.laminate.reference_thickness();
    }
    Ok(FORCE_BOUND_STRAIN * stiffness * perimeter + applied)
}

/// The largest wave modulus of the ply's elements at rest (MPa).
fn rest_wave_modulus(model: &Model, ply: &Ply) -> Result<f64, String> {
    let rest = ply.laminate.initial_state();
    ply.elements.clone().try_fold(0.0, |most: f64, k| {
        let kin = model.rest_kinematics(k);
        let modulus = ply
            .laminate
            .wave_modulus(&kin, &rest)
            .map_err(|err| err.to_string())?;
        Ok(most.max(modulus))
    })
}

/// Runs `solve` (either solver) with the checks watching every checkpoint it makes
/// ([`Observer::checkpoint`]).
pub fn watched(
    model: &Model,
    check: CheckSettings,
    observer: &mut dyn Observer,
    solve: impl FnOnce(&mut dyn Observer) -> Result<State, SolverError>,
) -> (Result<State, SolverError>, CheckReport) {
    let mut checked = Checked {
        inner: observer,
        watch: Watch::new(check, model.mesh.nodes.len()),
    };
    let outcome = solve(&mut checked).map_err(|e| match e {
        SolverError::Output { time, source } => match source.downcast::<CheckStop>() {
            Ok(stop) => SolverError::Check(stop),
            Err(source) => SolverError::Output { time, source },
        },
        other => other,
    });
    let report = checked.watch.report(!model.tools.is_empty());
    (outcome, report)
}

/// The observer of the run, with the checks at each of its checkpoints.
struct Checked<'a> {
    inner: &'a mut dyn Observer,
    watch: Watch,
}

impl Observer for Checked<'_> {
    fn record(&mut self, model: &Model, state: &State) -> anyhow::Result<()> {
        self.inner.record(model, state)
    }

    fn checkpoint(&mut self, model: &Model, state: &State) -> anyhow::Result<()> {
        self.inner.checkpoint(model, state)?;
        self.watch.at_checkpoint(model, state)?;
        Ok(())
    }

    fn progress(&mut self, state: &State) {
        self.inner.progress(state);
    }

    fn interrupted(&mut self) -> bool {
        self.inner.interrupted()
    }
}

/// What the checks keep between checkpoints.
struct Watch {
    settings: CheckSettings,
    nodes: usize,
    /// Time and energies of every checkpoint.
    records: Vec<(f64, Energies)>,
    /// Since when (s) the kinetic energy has been past [`KINETIC_STOP`] at every checkpoint.
    kinetic_since: Option<f64>,
    largest_force: f64,
    most_tunnelled: usize,
    stop: Option<&'static str>,
}

impl Watch {
    fn new(settings: CheckSettings, nodes: usize) -> Self {
        Self {
            settings,
            nodes,
            records: Vec::new(),
            kinetic_since: None,
            largest_force: 0.0,
            most_tunnelled: 0,
            stop: None,
        }
    }

    fn at_checkpoint(&mut self, model: &Model, state: &State) -> Result<(), CheckStop> {
        self.records.push((state.time, state.energies));
        let result = self.check_record(model, state);
        if let Err(stop) = &result {
            self.stop = Some(stop.check);
        }
        result
    }

    fn check_record(&mut self, model: &Model, state: &State) -> Result<(), CheckStop> {
        let stop = |check: &'static str, figure: String, advice: &str| CheckStop {
            check,
            step: state.step,
            time: state.time,
            figure,
            advice: advice.into(),
        };
        let force = largest_force(state);
        self.largest_force = self.largest_force.max(force);
        if !force.is_finite() || force > self.settings.force_bound {
            return Err(stop(
                FORCES,
                format!(
                    "a force of {force:.3e} N, beyond the physical bound {:.3e} N of this blank \
                     and card",
                    self.settings.force_bound
                ),
                "check the card's stiffness and density and the mass scaling \
                 (target time step)",
            ));
        }
        let e = &state.energies;
        let settled = state.time > self.settings.settle_time;
        let scale = e.external_work.abs().max(e.kinetic);
        if settled && e.internal_work < -NEGATIVE_WORK_TOLERANCE * scale {
            return Err(stop(
                INTERNAL_WORK,
                format!(
                    "the internal work is negative, {:.4e} N·mm against {:.4e} N·mm put in",
                    e.internal_work, e.external_work
                ),
                "the laminate gives back more than it took: its card is outside its range \
                 (check the stiffness and shear parameters)",
            ));
        }
        let ratio = kinetic_ratio(e);
        let loaded = settled && e.internal_work >= self.settings.loaded_work;
        self.kinetic_since = if loaded && ratio > KINETIC_STOP {
            self.kinetic_since.or(Some(state.time))
        } else {
            None
        };
        let span = KINETIC_STOP_SPAN * self.settings.end_time;
        if let Some(since) = self.kinetic_since.filter(|&t| state.time - t >= span) {
            return Err(stop(
                KINETIC,
                format!(
                    "the kinetic energy is {:.0} % of the internal work, above {:.0} % since \
                     t = {since:.4e} s ({:.0} % of the run): the run is dynamic, not quasi-static",
                    100.0 * ratio,
                    100.0 * KINETIC_STOP,
                    100.0 * KINETIC_STOP_SPAN
                ),
                self.settings.dynamic_advice,
            ));
        }
        let tunnelled = nodes_through_tools(
            &model.tools,
            &state.tool_translations,
            &state.positions,
            &model.tool_contacts(),
        );
        self.most_tunnelled = self.most_tunnelled.max(tunnelled);
        if tunnelled as f64 > TUNNELLED_STOP_FRACTION * self.nodes as f64 {
            return Err(stop(
                PENETRATION,
                format!(
                    "{tunnelled} of {} nodes are behind a tool beyond the contact's reach: a \
                     tool passed through the blank",
                    self.nodes
                ),
                self.settings.dynamic_advice,
            ));
        }
        Ok(())
    }

    fn report(&self, tools: bool) -> CheckReport {
        let status = |name: &str, warn: bool| {
            if self.stop == Some(name) {
                CheckStatus::Stopped
            } else if warn {
                CheckStatus::Warning
            } else {
                CheckStatus::Ok
            }
        };
        let final_work = self.records.last().map_or(0.0, |r| r.1.internal_work);
        let loaded_records = self.records.iter().filter(|(t, e)| {
            *t > self.settings.settle_time
                && e.internal_work > 0.0
                && e.internal_work >= LOADED_FRACTION * final_work
        });
        let loaded = loaded_records.clone();
        let kinetic = loaded
            .clone()
            .map(|(_, e)| kinetic_ratio(e))
            .fold(0.0, f64::max);
        let balance = loaded.map(|(_, e)| e.balance_error()).fold(0.0, f64::max);
        let least_work = self
            .records
            .iter()
            .map(|r| r.1.internal_work)
            .fold(f64::INFINITY, f64::min);
        let mut lines = vec![
            CheckLine {
                name: KINETIC,
                figure: format!(
                    "{:.2} % at most once loaded (warning above {} %, stop above {} %)",
                    100.0 * kinetic,
                    100.0 * KINETIC_WARNING,
                    100.0 * KINETIC_STOP
                ),
                status: status(KINETIC, kinetic > KINETIC_WARNING),
            },
            CheckLine {
                name: BALANCE,
                figure: format!(
                    "{:.3} % of the external work at most once loaded (warning above {} %)",
                    100.0 * balance,
                    100.0 * BALANCE_WARNING
                ),
                status: status(BALANCE, balance > BALANCE_WARNING),
            },
            CheckLine {
                name: INTERNAL_WORK,
                figure: format!("{:.4e} N·mm at least", least_work.min(0.0)),
                status: status(INTERNAL_WORK, false),
            },
            CheckLine {
                name: FORCES,
                figure: format!(
                    "{:.3e} N at most (physical bound {:.3e} N)",
                    self.largest_force, self.settings.force_bound
                ),
                status: status(FORCES, false),
            },
        ];
        let damping = loaded_records
            .clone()
            .map(|(_, e)| e.damping / e.internal_work)
            .fold(0.0, f64::max);
        if damping > 0.0 {
            lines.push(CheckLine {
                name: DAMPING,
                figure: format!(
                    "{:.3} % of the internal work at most (warning above {} %)",
                    100.0 * damping,
                    100.0 * DAMPING_WARNING
                ),
                status: status(DAMPING, damping > DAMPING_WARNING),
            });
        }
        if tools {
            lines.push(CheckLine {
                name: PENETRATION,
                figure: format!(
                    "{} nodes at most behind a tool beyond the contact's reach",
                    self.most_tunnelled
                ),
                status: status(PENETRATION, self.most_tunnelled > 0),
            });
        }
        CheckReport { lines }
    }
}

const KINETIC: &str = "kinetic / internal energy";
const BALANCE: &str = "energy balance";
const INTERNAL_WORK: &str = "internal work";
const FORCES: &str = "forces";
const PENETRATION: &str = "tool penetration";
const DAMPING: &str = "damping / internal work";

/// Work of the damping (the explicit solver's global damping, the implicit solver's drag) over
/// the internal work above which the result is reported as biased by it.
pub const DAMPING_WARNING: f64 = 0.05;

/// `E_kin / W_int`, 0 before any internal work.
fn kinetic_ratio(e: &Energies) -> f64 {
    if e.internal_work > 0.0 {
        e.kinetic / e.internal_work
    } else {
        0.0
    }
}

/// The largest force of the run at this state (N): a tool's load or the sum of the reactions
/// at the constrained nodes; infinite when one is not a number.
fn largest_force(state: &State) -> f64 {
    let finite = |v: &Vector3<f64>| {
        if v.iter().all(|c| c.is_finite()) {
            v.norm()
        } else {
            f64::INFINITY
        }
    };
    let tools = state
        .tool_loads
        .iter()
        .map(|l| finite(&l.force))
        .fold(0.0, f64::max);
    let reactions: f64 = state.reactions.iter().map(finite).sum();
    tools.max(reactions)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn watch(records: &[(f64, f64, f64)]) -> Watch {
        let settings = CheckSettings {
            settle_time: 0.1,
            force_bound: 1e6,
            loaded_work: 0.0,
            end_time: 1.0,
            dynamic_advice: "",
        };
        let mut w = Watch::new(settings, 10);
        w.records = records
            .iter()
            .map(|&(time, kinetic, internal_work)| {
                let energies = Energies {
                    kinetic,
                    internal_work,
                    external_work: kinetic + internal_work,
                    ..Energies::default()
                };
                (time, energies)
            })
            .collect();
        w
    }

    fn status(report: &CheckReport, name: &str) -> CheckStatus {
        report.lines.iter().find(|l| l.name == name).unwrap().status
    }

    #[test]
    fn kinetic_energy_counts_only_once_loaded() {
        // the start (before the settle time) and the records under 5 % of the final work are
        // left out: their ratios are those of a blank carried along
        let quiet = watch(&[
            (0.05, 5.0, 1.0),
            (0.2, 0.4, 2.0),
            (0.5, 0.3, 10.0),
            (1.0, 1.0, 100.0),
        ]);
        let report = quiet.report(false);
        assert_eq!(status(&report, KINETIC), CheckStatus::Ok);
        assert!(
            report.lines[0].figure.starts_with("3.00 %"),
            "{:?}",
            report.lines[0]
        );
        assert_eq!(report.lines.len(), 4, "no tool line without tools");
        let dynamic = watch(&[(0.5, 8.0, 10.0), (1.0, 1.0, 100.0)]);
        let report = dynamic.report(true);
        assert_eq!(status(&report, KINETIC), CheckStatus::Warning);
        assert_eq!(report.warnings().count(), 1);
        assert_eq!(report.rows().len(), 5);
    }

    #[test]
    fn a_stop_is_reported_as_stopped() {
        let mut w = watch(&[(0.5, 8.0, 10.0)]);
        w.stop = Some(FORCES);
        let report = w.report(false);
        assert_eq!(status(&report, FORCES), CheckStatus::Stopped);
        assert!(report
            .rows()
            .iter()
            .any(|(n, v)| *n == FORCES && v.starts_with("STOPPED")));
    }

    #[test]
    fn the_kinetic_ratio_is_zero_before_any_internal_work() {
        let e = Energies {
            kinetic: 1.0,
            ..Energies::default()
        };
        assert_eq!(kinetic_ratio(&e), 0.0);
    }
}
