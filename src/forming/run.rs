//! A forming run: the explicit solver on the blank between the tools, with the histories an
//! engineer reads (punch force against stroke, blank-holder force and travel, draw-in, largest
//! shear angle, energies) and ParaView frames.

use super::setup::FormingModel;
use crate::experiment::sheet_test::{write_frame, FrameOutput, Progress};
use crate::solver::{self, Energies, Model, Observer, SolverError, State};
use nalgebra::Vector3;
use std::time::Instant;

/// One row of the forming history.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FormingRecord {
    /// Simulated time (s).
    pub time: f64,
    /// Punch travel (mm).
    pub stroke: f64,
    /// Force the press puts on the punch along the stroke (N).
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
}

/// A finished (or stopped) forming run.
pub struct FormingRun {
    pub records: Vec<FormingRecord>,
    /// The final state, or why the run stopped (records and frames so far kept).
    pub outcome: Result<State, SolverError>,
    pub steps: usize,
    pub wall_seconds: f64,
}

struct Recorder<'a, 'p> {
    forming: &'a FormingModel,
    edge: Vec<usize>,
    nodal_area: Vec<f64>,
    records: Vec<FormingRecord>,
    frames: Option<FrameOutput>,
    progress: Option<&'p mut dyn Progress>,
    steps: usize,
}

impl Observer for Recorder<'_, '_> {
    fn record(&mut self, model: &Model, state: &State) -> anyhow::Result<()> {
        let f = self.forming;
        let holder = f.holder_tool;
        self.records.push(FormingRecord {
            time: state.time,
            stroke: f.punch.displacement(state.time),
            punch_force: -state.tool_loads[f.punch_tool].force.z,
            holder_force: holder.map_or(0.0, |h| state.tool_loads[h].normal_force),
            holder_travel: holder.map_or(0.0, |h| state.tool_translations[h].z),
            draw_in: draw_in(model, state, &self.edge),
            max_shear: max_shear_angle(model, state),
            wrinkles: flange_wrinkles(f, state, &self.nodal_area),
            energies: state.energies,
        });
        self.steps = state.step;
        if let Some(frames) = &mut self.frames {
            if (self.records.len() - 1).is_multiple_of(frames.every.max(1)) {
                write_frame(&mut frames.series, model, state)?;
            }
        }
        Ok(())
    }

    fn progress(&mut self, state: &State) {
        self.steps = state.step;
        if let Some(p) = self.progress.as_deref_mut() {
            p.update(state.time, state.step);
        }
    }
}

/// Runs the forming model, recording at every output interval.
pub fn run(
    forming: &FormingModel,
    frames: Option<FrameOutput>,
    progress: Option<&mut dyn Progress>,
) -> FormingRun {
    let start = Instant::now();
    let edge = boundary_nodes(&forming.model);
    let mut recorder = Recorder {
        forming,
        edge,
        nodal_area: forming.model.nodal_areas(),
        records: Vec::new(),
        frames,
        progress,
        steps: 0,
    };
    let outcome = solver::run(&forming.model, &forming.settings, &mut recorder);
    let steps = match &outcome {
        Ok(state) => state.step,
        Err(_) => recorder.steps,
    };
    FormingRun {
        records: recorder.records,
        outcome,
        steps,
        wall_seconds: start.elapsed().as_secs_f64(),
    }
}

/// Out-of-tool waviness of the flange, the part of the blank that the die's flat face and the
/// blank holder should keep flat: for each node beyond the flange radius, its face's gap to the
/// die (MODEL.md §6, "wrinkling: out-of-plane waviness where the sheet does not follow the
/// tool"). It counts wrinkles and a flange that lifts off the die as a whole alike; telling
/// them apart (the waviness around the part) is still to come.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Wrinkles {
    /// Largest gap of a flange node to the die (mm).
    pub height: f64,
    /// Area of the flange whose gap exceeds half the ply thickness (mm^2, reference area).
    pub area: f64,
}

fn flange_wrinkles(f: &FormingModel, state: &State, nodal_area: &[f64]) -> Wrinkles {
    let die = &f.model.tools[f.die_tool];
    let offset = f.model.contact.offset;
    let translation = state.tool_translations[f.die_tool];
    state
        .positions
        .iter()
        .zip(nodal_area)
        .filter(|(x, _)| f.in_flange(x))
        .map(|(x, &a)| (die.gap(&(x - translation), offset).max(0.0), a))
        .fold(Wrinkles::default(), |w, (gap, a)| Wrinkles {
            height: w.height.max(gap),
            area: w.area + if gap > offset { a } else { 0.0 },
        })
}

/// Nodes on the edge of the blank: those of the edges that belong to one triangle only.
fn boundary_nodes(model: &Model) -> Vec<usize> {
    let mut count = std::collections::HashMap::new();
    for t in &model.mesh.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
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
