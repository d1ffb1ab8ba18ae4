//! A forming run: the explicit solver on the blank between the tools, with the histories an
//! engineer reads (punch force against stroke, blank-holder force and travel, draw-in, largest
//! shear angle, energies) and ParaView frames.

use super::setup::FormingModel;
use crate::contact::ply_contact::InterplyNode;
use crate::experiment::sheet_test::{LiveOutput, Progress};
use crate::solver::checks::{self, CheckReport, CheckSettings};
use crate::solver::implicit::{self, ImplicitSettings, ImplicitStatistics};
use crate::solver::{estimate, explicit};
use crate::solver::{Energies, Model, Observer, SolverError, SolverKind, State};
use crate::thermal::blank::FieldExtremes;
use nalgebra::Vector3;
use std::time::Instant;

/// One row of the forming history.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FormingRecord {
    /// Simulated time (s).
    pub time: f64,
    /// Punch travel (mm).
    pub stroke: f64,
    /// Force the press puts on the punch along the stroke (N): with the explicit solver
    /// averaged since the last record (the load cell's reading: the contact springs ring from
    /// step to step), with the implicit solver the force at the record.
    pub punch_force: f64,
    /// Normal force between the blank and the holder (N), and the holder's travel (mm).
    pub holder_force: f64,
    pub holder_travel: f64,
    /// Largest inward displacement of a node of the blank's edge, in the blank's plane (mm).
    pub draw_in: f64,
    /// Largest shear angle of an element (degrees).
    pub max_shear: f64,
    /// Wrinkling of the flange ([`Wrinkles`]).
    pub wrinkles: Wrinkles,
    pub energies: Energies,
    /// The blank's coldest, mean and hottest temperature (°C; the run's own in an isothermal
    /// run) and the area where a layer has frozen (mm²).
    pub temperature: FieldExtremes,
    pub frozen_area: f64,
    /// Force of the blank on the die along `+z`, against its closing (N): what holds a pair of
    /// matched dies closed.
    pub die_force: f64,
    /// The springs', grippers' and gravity's share ([`SupportRecord`]).
    pub supports: SupportRecord,
}

/// What the springs and grippers hold and how far the blank sags.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SupportRecord {
    /// Sum of the magnitudes of the springs' and of the grippers' resultants on the blank (N).
    pub springs: f64,
    pub grippers: f64,
    /// Largest displacement of a node along gravity from where it started (mm); 0 without
    /// gravity.
    pub sag: f64,
}

/// The supports' record of `state`.
pub fn support_record(model: &Model, state: &State) -> SupportRecord {
    let loads = &state.supports.loads;
    let total = |forces: &[Vector3<f64>]| forces.iter().map(|f| f.norm()).sum();
    let sag = model.supports.gravity.map_or(0.0, |g| {
        let down = g.acceleration.normalize();
        state
            .positions
            .iter()
            .zip(&model.mesh.nodes)
            .map(|(x, x0)| (x - x0).dot(&down))
            .fold(0.0, f64::max)
    });
    SupportRecord {
        springs: total(&loads.springs),
        grippers: total(&loads.grippers),
        sag,
    }
}

/// A finished (or stopped) forming run.
pub struct FormingRun {
    pub records: Vec<FormingRecord>,
    /// The final state, or why the run stopped (records and frames so far kept).
    pub outcome: Result<State, SolverError>,
    pub steps: usize,
    pub wall_seconds: f64,
    /// The run-time checks (`solver::checks`).
    pub checks: CheckReport,
    /// Increments, iterations and time split of an implicit run.
    pub implicit: Option<ImplicitStatistics>,
    /// The state of the last record: where an implicit increment did not converge, the last
    /// converged state, which the run recorded before it stopped.
    pub last_recorded: Option<State>,
}

impl FormingRun {
    /// The state the part's pictures and files are made of: the final one, or for a run that
    /// stopped because an increment did not converge or the user asked, the last one recorded
    /// (its frames and history end there too). `None` for a run stopped as meaningless.
    pub fn formed_state(&self) -> Option<&State> {
        match &self.outcome {
            Ok(state) => Some(state),
            Err(
                SolverError::NotConverged { .. }
                | SolverError::Interrupted { .. }
                | SolverError::Temperature { .. },
            ) => self
                .last_recorded
                .as_ref()
                .filter(|s| s.positions.iter().all(|x| x.iter().all(|c| c.is_finite()))),
            Err(_) => None,
        }
    }
}

struct Recorder<'a, 'p, 'o> {
    forming: &'a FormingModel,
    edge: Vec<usize>,
    nodal_area: Vec<f64>,
    records: Vec<FormingRecord>,
    output: Option<LiveOutput<'o, FormingRecord>>,
    progress: Option<&'p mut dyn Progress>,
    steps: usize,
    /// Time and punch impulse at the last record.
    last_impulse: Option<(f64, Vector3<f64>)>,
    /// Set once the user asked to stop: the next record is the last.
    stopping: bool,
    last_recorded: Option<State>,
}

impl Recorder<'_, '_, '_> {
    /// The punch force of the record: for the explicit solver averaged since the last record,
    /// from the punch's impulse (the contact springs ring from step to step), the instantaneous
    /// force at the first record; for the implicit solver, whose increments end in equilibrium,
    /// the force at the record, so that it does not depend on how often records are made.
    fn punch_force(&mut self, state: &State) -> f64 {
        let punch = self.forming.punch_tool;
        let impulse = state.tool_impulses[punch];
        let mean = match self.last_impulse {
            Some((time, last))
                if state.time > time && self.forming.solver == SolverKind::Explicit =>
            {
                (impulse - last) / (state.time - time)
            }
            _ => state.tool_loads[punch].force,
        };
        self.last_impulse = Some((state.time, impulse));
        -mean.z
    }
}

impl Observer for Recorder<'_, '_, '_> {
    fn record(&mut self, model: &Model, state: &State) -> anyhow::Result<()> {
        let f = self.forming;
        let holder = f.holder_tool;
        let punch_force = self.punch_force(state);
        self.records.push(FormingRecord {
            time: state.time,
            stroke: f.punch_travel(state.time),
            punch_force,
            holder_force: holder.map_or(0.0, |h| state.tool_loads[h].normal_force),
            holder_travel: holder.map_or(0.0, |h| state.tool_translations[h].z),
            draw_in: draw_in(model, state, &self.edge),
            max_shear: max_shear_angle(model, state),
            wrinkles: flange_wrinkles(f, state, &self.nodal_area),
            energies: state.energies,
            temperature: temperature_extremes(model, state),
            frozen_area: frozen_area(model, state),
            die_force: state.tool_loads[f.die_tool].force.z,
            supports: support_record(model, state),
        });
        self.steps = state.step;
        self.last_recorded = Some(state.clone());
        if let Some(output) = &mut self.output {
            output.at_record(&self.records, self.stopping, model, state)?;
        }
        Ok(())
    }

    fn progress(&mut self, state: &State) {
        self.steps = state.step;
        if let Some(p) = self.progress.as_deref_mut() {
            p.update(state.time, state.step);
        }
    }

    fn interrupted(&mut self) -> bool {
        self.stopping = self.progress.as_deref().is_some_and(|p| p.interrupted());
        self.stopping
    }
}

/// The blank's coldest, mean and hottest temperature: the run's own where it is isothermal.
pub fn temperature_extremes(model: &Model, state: &State) -> FieldExtremes {
    match (&model.heat, &state.thermal) {
        (Some(heat), Some(thermal)) => heat.blank.extremes(thermal),
        _ => FieldExtremes {
            min: model.temperature,
            mean: model.temperature,
            max: model.temperature,
        },
    }
}

/// The reference area of the elements where a layer has frozen (mm²); 0 in an isothermal run.
pub fn frozen_area(model: &Model, state: &State) -> f64 {
    frozen_areas(model, state).map_or(0.0, |(_, any)| any)
}

/// `BlankHeat::frozen_areas` of a non-isothermal run's state: per layer, and any layer.
pub fn frozen_areas(model: &Model, state: &State) -> Option<(Vec<f64>, f64)> {
    let (heat, thermal) = (model.heat.as_ref()?, state.thermal.as_ref()?);
    let areas: Vec<f64> = model.elements.iter().map(|e| e.area).collect();
    Some(heat.blank.frozen_areas(thermal, &areas))
}

/// Runs the forming model, recording at every output interval; `output` is written as the
/// run goes.
/// The run's outcome and final measures in one row, written by `thermostamp run` (what a
/// study collects).
pub const RESULT_CSV: &str = "forming-result.csv";

/// Columns of [`RESULT_CSV`]: the status (text), then numbers; a measure the run could not
/// take (no final state, no locking angle, no flange) is left empty.
pub const RESULT_COLUMNS: [&str; 12] = [
    "status",
    "stroke_reached",
    "peak_punch_force",
    "max_shear_deg",
    "area_above_locking",
    "max_thinning",
    "lift_off",
    "lifted_area",
    "waviness",
    "wavy_area",
    "draw_in",
    "energy_balance_error",
];

pub fn run(
    forming: &FormingModel,
    output: Option<LiveOutput<'_, FormingRecord>>,
    progress: Option<&mut dyn Progress>,
) -> FormingRun {
    let start = Instant::now();
    let edge = boundary_nodes(&forming.model);
    let mut recorder = Recorder {
        forming,
        edge,
        nodal_area: forming.model.nodal_areas(),
        records: Vec::new(),
        output,
        progress,
        steps: 0,
        last_impulse: None,
        stopping: false,
        last_recorded: None,
    };
    let mut statistics = ImplicitStatistics::default();
    let (outcome, checks) = match check_settings(forming) {
        Ok(check) => match forming.solver {
            SolverKind::Explicit => {
                explicit::run_checked(&forming.model, &forming.settings, check, &mut recorder)
            }
            SolverKind::Implicit => {
                let settings = ImplicitSettings {
                    max_increment: Some(forming.max_increment),
                    ..ImplicitSettings::new(
                        forming.settings.end_time,
                        forming.settings.output_interval,
                    )
                };
                checks::watched(&forming.model, check, &mut recorder, |observer| {
                    implicit::run(&forming.model, &settings, observer, &mut statistics)
                })
            }
        },
        Err(e) => (Err(SolverError::Settings(e)), CheckReport::default()),
    };
    let steps = match &outcome {
        Ok(state) => state.step,
        Err(_) => recorder.steps,
    };
    FormingRun {
        records: recorder.records,
        outcome,
        steps,
        wall_seconds: start.elapsed().as_secs_f64(),
        checks,
        implicit: (forming.solver == SolverKind::Implicit).then_some(statistics),
        last_recorded: recorder.last_recorded,
    }
}

/// What the run-time checks of a forming run need: the punch's smooth start (two ramp times,
/// as for the virtual tests) does not count, and the force bound of the blank and tools.
fn check_settings(forming: &FormingModel) -> Result<CheckSettings, String> {
    Ok(CheckSettings {
        settle_time: 2.0 * forming.punch.ramp_time,
        end_time: forming.settings.end_time,
        force_bound: checks::force_bound(&forming.model)?,
        loaded_work: estimate::carried_kinetic_energy(
            &forming.model,
            &forming.settings,
            forming.punch.speed,
        )?,
        dynamic_advice: match forming.solver {
            SolverKind::Explicit => {
                "lower process.punch_speed, process.time_scaling or process.target_time_step"
            }
            SolverKind::Implicit => {
                "lower process.max_increment, or refine the blank (blank.element_size)"
            }
        },
    })
}

/// Wrinkling of the flange, the part of the blank that the die's flat face and the blank
/// holder should keep flat (docs/model.md §6, "wrinkling: out-of-plane waviness where the sheet
/// does not follow the tool"), from each flange node's gap to the die:
///
/// - **lift-off**: the largest gap, and the area lifted by more than half the ply. A flange
///   that leaves the die as a smooth cone counts here as much as a wavy one.
/// - **waviness**: the gap's variation *around* the part. Flange nodes are grouped in bands of
///   one element size by their distance from the punch's ridge (axis); in each band the gap's
///   trend with that distance (a least-squares line) is taken out, and the waviness is half
///   the spread of what remains. It is zero for any flange that is the same all around (flat
///   or coned) and the wave amplitude for a wrinkled one. The wavy area is where a node stands
///   more than half the ply above the lowest of its band, trend taken out.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Wrinkles {
    /// Largest gap of a flange node to the die (mm).
    pub height: f64,
    /// Area of the flange whose gap exceeds half the ply thickness (mm^2, reference area).
    pub area: f64,
    /// Largest half spread of the gap around the part within a band (mm).
    pub waviness: f64,
    /// Area of the flange more than half the ply above the lowest node of its band (mm^2).
    pub wavy_area: f64,
}

/// One flange node: its distance from the ridge, its band, its gap to the die and its area.
struct FlangeNode {
    distance: f64,
    band: usize,
    gap: f64,
    area: f64,
}

/// The gap's least-squares line against the distance from the ridge, in one band.
#[derive(Clone, Copy, Default)]
struct BandTrend {
    n: f64,
    sum_d: f64,
    sum_g: f64,
    sum_dd: f64,
    sum_dg: f64,
}

impl BandTrend {
    fn add(&mut self, d: f64, g: f64) {
        self.n += 1.0;
        self.sum_d += d;
        self.sum_g += g;
        self.sum_dd += d * d;
        self.sum_dg += d * g;
    }

    /// The gap less its trend at distance `d`.
    fn residual(&self, d: f64, g: f64) -> f64 {
        let (mean_d, mean_g) = (self.sum_d / self.n, self.sum_g / self.n);
        let variance = self.sum_dd / self.n - mean_d * mean_d;
        let covariance = self.sum_dg / self.n - mean_d * mean_g;
        // nodes all at one distance: no trend to take out
        let slope = if variance > 1e-12 * (1.0 + mean_d * mean_d) {
            covariance / variance
        } else {
            0.0
        };
        g - mean_g - slope * (d - mean_d)
    }
}

/// The [`Wrinkles`] of the flange in `state` (of a layup, of the ply against the die);
/// `nodal_area` from [`Model::nodal_areas`].
pub fn flange_wrinkles(f: &FormingModel, state: &State, nodal_area: &[f64]) -> Wrinkles {
    ply_wrinkles(f, state, nodal_area, f.model.plies.len() - 1)
}

/// The [`Wrinkles`] of ply `ply`'s flange in `state` (index into [`Model::plies`], from the
/// punch's side): its gaps measured from where it lies flat on the die under the plies above
/// it, and lifted where that gap exceeds half its own thickness.
pub fn ply_wrinkles(f: &FormingModel, state: &State, nodal_area: &[f64], ply: usize) -> Wrinkles {
    let half = 0.5 * f.model.plies[ply].laminate.reference_thickness();
    let own = f.model.plies[ply].nodes.clone();
    let nodes: Vec<FlangeNode> = own
        .map(|n| (state.positions[n], nodal_area[n]))
        .filter(|(x, _)| f.in_flange(x))
        .map(|(x, area)| FlangeNode {
            distance: f.distance_from_ridge(&x),
            band: f.flange_band(&x),
            gap: die_gap(f, state, ply, &x),
            area,
        })
        .collect();
    let bands = nodes.iter().map(|n| n.band + 1).max().unwrap_or(0);
    let mut trends = vec![BandTrend::default(); bands];
    for n in &nodes {
        trends[n.band].add(n.distance, n.gap);
    }
    let residuals: Vec<f64> = nodes
        .iter()
        .map(|n| trends[n.band].residual(n.distance, n.gap))
        .collect();
    let mut lowest = vec![f64::INFINITY; bands];
    let mut highest = vec![f64::NEG_INFINITY; bands];
    for (n, &r) in nodes.iter().zip(&residuals) {
        lowest[n.band] = lowest[n.band].min(r);
        highest[n.band] = highest[n.band].max(r);
    }
    let above_threshold = |gap: f64, area: f64| if gap > half { area } else { 0.0 };
    nodes
        .iter()
        .zip(&residuals)
        .fold(Wrinkles::default(), |w, (n, &r)| Wrinkles {
            height: w.height.max(n.gap),
            area: w.area + above_threshold(n.gap, n.area),
            waviness: w.waviness.max(0.5 * (highest[n.band] - lowest[n.band])),
            wavy_area: w.wavy_area + above_threshold(r - lowest[n.band], n.area),
        })
}

/// The gap of a point `x` of ply `ply` (index into [`Model::plies`]) to the die in `state`
/// (mm, 0 in contact): measured from where the ply lies flat on the die under the plies above
/// it, as [`ply_wrinkles`] measures the flange.
pub fn die_gap(f: &FormingModel, state: &State, ply: usize, x: &Vector3<f64>) -> f64 {
    let plies = &f.model.plies;
    let half = 0.5 * plies[ply].laminate.reference_thickness();
    let above: f64 = plies[ply + 1..]
        .iter()
        .map(|p| p.laminate.reference_thickness())
        .sum();
    let die = &f.model.tools[f.die_tool];
    die.gap(&(x - state.tool_translations[f.die_tool]), half + above)
        .max(0.0)
}

/// Nodes on the edge of the blank: those of the edges that belong to one element only.
fn boundary_nodes(model: &Model) -> Vec<usize> {
    let mut count = std::collections::HashMap::new();
    for t in &model.mesh.cells {
        for (a, b) in t.edges() {
            *count.entry((a.min(b), a.max(b))).or_insert(0usize) += 1;
        }
    }
    let mut nodes: Vec<usize> = count
        .into_iter()
        .filter(|&(_, c)| c == 1)
        .flat_map(|((a, b), _)| [a, b])
        .collect();
    nodes.sort_unstable();
    nodes.dedup();
    nodes
}

/// Largest inward displacement of an edge node in the x-y plane, towards the punch axis.
fn draw_in(model: &Model, state: &State, edge: &[usize]) -> f64 {
    edge.iter()
        .map(|&n| {
            let x0 = model.mesh.nodes[n];
            let radial = Vector3::new(x0.x, x0.y, 0.0);
            let d = state.positions[n] - x0;
            -Vector3::new(d.x, d.y, 0.0).dot(&radial) / radial.norm().max(1e-12)
        })
        .fold(0.0, f64::max)
}

/// What a layup's ply did: its largest shear angle (degrees), how far its nodes slid over its
/// neighbours at most (mm, `interply_slip`), its edge's draw-in (mm) and its flange's
/// [`Wrinkles`] ([`ply_wrinkles`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlyMeasures {
    pub max_shear: f64,
    pub max_slip: f64,
    pub draw_in: f64,
    pub wrinkles: Wrinkles,
}

/// Each ply's [`PlyMeasures`] (one for a single ply: the blank's).
pub fn ply_measures(f: &FormingModel, state: &State) -> Vec<PlyMeasures> {
    let model = &f.model;
    let shear = shear_angles(model, state);
    let edge = boundary_nodes(model);
    let areas = model.nodal_areas();
    model
        .plies
        .iter()
        .enumerate()
        .map(|(k, ply)| {
            let own: Vec<usize> = edge
                .iter()
                .copied()
                .filter(|n| ply.nodes.contains(n))
                .collect();
            let max_slip = state
                .interply
                .get(ply.nodes.clone())
                .into_iter()
                .flatten()
                .map(InterplyNode::slip)
                .fold(0.0_f64, f64::max);
            PlyMeasures {
                max_shear: shear[ply.elements.clone()]
                    .iter()
                    .fold(0.0_f64, |m, g| m.max(g.abs())),
                max_slip,
                draw_in: draw_in(model, state, &own),
                wrinkles: ply_wrinkles(f, state, &areas, k),
            }
        })
        .collect()
}

/// The columns a layup's `forming-result.csv` adds per ply `k` (from 1), in
/// [`PlyMeasures`]'s order, its flange's lift-off and waviness last.
pub fn ply_columns(k: usize) -> [String; 5] {
    [
        format!("ply{k}_max_shear_deg"),
        format!("ply{k}_max_slip"),
        format!("ply{k}_draw_in"),
        format!("ply{k}_lift_off"),
        format!("ply{k}_waviness"),
    ]
}

/// Shear angle of every element (degrees, signed).
pub fn shear_angles(model: &Model, state: &State) -> Vec<f64> {
    model
        .elements
        .iter()
        .map(|e| e.shear_angle(&state.positions).to_degrees())
        .collect()
}

/// Largest shear angle over the elements (degrees).
pub fn max_shear_angle(model: &Model, state: &State) -> f64 {
    shear_angles(model, state)
        .into_iter()
        .map(f64::abs)
        .fold(0.0, f64::max)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::forming::Scenario;

    fn example(overrides: &[&str]) -> FormingModel {
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/hemisphere.toml");
        let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
        FormingModel::new(&Scenario::load(&path, &overrides).unwrap()).unwrap()
    }

    /// A stopped run's advice names only keys its solver takes: the implicit solver refuses
    /// `process.time_scaling` and `process.target_time_step`, so its advice cannot name them.
    #[test]
    fn the_advice_of_a_stopped_run_names_keys_its_solver_takes() {
        let implicit = check_settings(&example(&["process.stroke=5"])).unwrap();
        let advice = implicit.dynamic_advice;
        assert!(advice.contains("process.max_increment"), "{advice}");
        assert!(
            !advice.contains("time_scaling") && !advice.contains("target_time_step"),
            "{advice}"
        );
        let explicit = check_settings(&example(&[
            "process.stroke=5",
            "process.solver=explicit",
            "process.time_scaling=10",
        ]))
        .unwrap();
        assert!(
            explicit.dynamic_advice.contains("process.time_scaling"),
            "{}",
            explicit.dynamic_advice
        );
        assert!(!explicit.dynamic_advice.contains("max_increment"));
    }
}
