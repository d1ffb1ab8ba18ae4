//! What the virtual sheet tests share: the crosshead motion, recording of force, displacement
//! and shear angle while the solver runs, ParaView frames, and the run summary.

use crate::io::sheet_frame::sheet_frame;
use crate::io::vtk::{PvdSeries, VtuFrame};
use crate::solver::{self, Energies, Model, Observer, SolverError, SolverSettings, State};
use std::time::Instant;

/// Crosshead displacement history: a smooth start over `ramp_time`, then constant `speed`
/// (simulated mm/s). The smooth start keeps the first stress wave from ringing through the
/// specimen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Crosshead {
    pub speed: f64,
    pub ramp_time: f64,
}

impl Crosshead {
    /// Velocity at `t`: `speed (3 s^2 - 2 s^3)` with `s = t / ramp_time` during the start.
    pub fn velocity(&self, t: f64) -> f64 {
        let s = (t / self.ramp_time).clamp(0.0, 1.0);
        self.speed * s * s * (3.0 - 2.0 * s)
    }

    /// Displacement at `t`, the integral of [`Crosshead::velocity`].
    pub fn displacement(&self, t: f64) -> f64 {
        if t >= self.ramp_time {
            return self.speed * (0.5 * self.ramp_time + (t - self.ramp_time));
        }
        let s = (t / self.ramp_time).max(0.0);
        self.speed * self.ramp_time * (s.powi(3) - 0.5 * s.powi(4))
    }

    /// Time at which the displacement reaches `d` (at least the ramp time).
    pub fn time_to(&self, d: f64) -> f64 {
        self.ramp_time + (d / self.speed - 0.5 * self.ramp_time).max(0.0)
    }
}

/// What a test reads off the specimen at one instant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reading {
    /// Crosshead displacement (mm).
    pub displacement: f64,
    /// Crosshead force (N).
    pub force: f64,
    /// Mean shear angle of the zone the test watches (degrees).
    pub shear_angle: f64,
}

/// One row of a test's history.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Record {
    /// Simulated time (s).
    pub time: f64,
    pub reading: Reading,
    pub energies: Energies,
}

/// Figures of a finished (or stopped) run, for the summary table.
#[derive(Clone, Debug, PartialEq)]
pub struct RunSummary {
    pub steps: usize,
    pub elements: usize,
    /// Last time step (s).
    pub time_step: f64,
    /// Mass added by mass scaling, and the physical mass (tonne).
    pub added_mass: f64,
    pub physical_mass: f64,
    /// Largest |W_ext - W_int - E_kin| / W_ext over the records after the start.
    pub worst_balance_error: f64,
    /// Largest E_kin / W_int over the records after the start.
    pub worst_kinetic_ratio: f64,
    pub wall_seconds: f64,
    pub threads: usize,
}

impl RunSummary {
    pub fn element_steps_per_second(&self) -> f64 {
        (self.steps * self.elements) as f64 / self.wall_seconds.max(1e-9)
    }
}

/// A test run: what was recorded, and how it ended.
pub struct TestRun {
    pub records: Vec<Record>,
    pub summary: RunSummary,
    /// The final state, or why the run stopped (the records and frames so far are kept).
    pub outcome: Result<State, SolverError>,
}

/// Where frames go and how often.
pub struct FrameOutput {
    pub series: PvdSeries,
    /// A frame every this many records.
    pub every: usize,
}

/// Progress reports while the solver runs (a progress bar in the command line).
pub trait Progress {
    fn update(&mut self, time: f64, step: usize);
}

struct Recorder<'m, 'p> {
    measure: &'m dyn Fn(&Model, &State) -> Reading,
    records: Vec<Record>,
    frames: Option<FrameOutput>,
    progress: Option<&'p mut dyn Progress>,
    steps: usize,
}

impl Observer for Recorder<'_, '_> {
    fn record(&mut self, model: &Model, state: &State) -> anyhow::Result<()> {
        let index = self.records.len();
        self.records.push(Record {
            time: state.time,
            reading: (self.measure)(model, state),
            energies: state.energies,
        });
        self.steps = state.step;
        if let Some(frames) = &mut self.frames {
            if index.is_multiple_of(frames.every.max(1)) {
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

fn write_frame(series: &mut PvdSeries, model: &Model, state: &State) -> anyhow::Result<()> {
    let frame = sheet_frame(model, state)?;
    series.add_frame(
        state.time,
        &VtuFrame {
            points: &frame.points,
            triangles: &model.mesh.triangles,
            point_data: &frame.point_data,
            cell_data: &frame.cell_data,
        },
    )?;
    Ok(())
}

/// Runs `model` and records `measure` at every output interval; records after `settle_time`
/// count for the energy figures of the summary.
pub fn run_sheet_test(
    model: &Model,
    settings: &SolverSettings,
    measure: &dyn Fn(&Model, &State) -> Reading,
    frames: Option<FrameOutput>,
    progress: Option<&mut dyn Progress>,
    settle_time: f64,
) -> TestRun {
    let start = Instant::now();
    let mut recorder = Recorder {
        measure,
        records: Vec::new(),
        frames,
        progress,
        steps: 0,
    };
    let outcome = solver::run(model, settings, &mut recorder);
    let wall_seconds = start.elapsed().as_secs_f64();
    let settled = recorder
        .records
        .iter()
        .filter(|r| r.time > settle_time && r.energies.internal_work > 0.0);
    let worst_balance_error = settled
        .clone()
        .map(|r| r.energies.balance_error())
        .fold(0.0, f64::max);
    let worst_kinetic_ratio = settled
        .map(|r| r.energies.kinetic / r.energies.internal_work)
        .fold(0.0, f64::max);
    let (time_step, added_mass, steps) = match &outcome {
        Ok(state) => (state.time_step, state.added_mass, state.step),
        Err(_) => (f64::NAN, f64::NAN, recorder.steps),
    };
    let physical_mass = model.density
        * model.laminate.reference_thickness()
        * model.elements.iter().map(|e| e.area).sum::<f64>();
    TestRun {
        summary: RunSummary {
            steps,
            elements: model.elements.len(),
            time_step,
            added_mass,
            physical_mass,
            worst_balance_error,
            worst_kinetic_ratio,
            wall_seconds,
            threads: rayon::current_num_threads(),
        },
        records: recorder.records,
        outcome,
    }
}

/// Mean shear angle (degrees) of the elements listed in `zone`.
pub fn mean_shear_angle(model: &Model, state: &State, zone: &[usize]) -> f64 {
    use crate::material::fabric::shear_angle;
    let sum: f64 = zone
        .iter()
        .map(|&k| {
            let e = &model.elements[k];
            let f = e.gradient(&state.positions);
            let mut c = nalgebra::Matrix3::identity();
            c.fixed_view_mut::<2, 2>(0, 0)
                .copy_from(&(f.transpose() * f));
            shear_angle(&c, &e.fibres)
        })
        .sum();
    (sum / zone.len().max(1) as f64).to_degrees()
}

/// Sum of the reactions on `nodes` along `direction` (N).
pub fn reaction_along(state: &State, nodes: &[usize], direction: &nalgebra::Vector3<f64>) -> f64 {
    nodes
        .iter()
        .map(|&n| state.reactions[n].dot(direction))
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crosshead_displacement_integrates_its_velocity() {
        let c = Crosshead {
            speed: 10.0,
            ramp_time: 0.2,
        };
        let n = 10_000;
        let t_end = 0.5;
        let dt = t_end / n as f64;
        let integral: f64 = (0..n).map(|i| c.velocity((i as f64 + 0.5) * dt) * dt).sum();
        assert!((integral - c.displacement(t_end)).abs() < 1e-6);
        assert!((c.displacement(c.time_to(3.0)) - 3.0).abs() < 1e-12);
        assert_eq!(c.velocity(0.0), 0.0);
        assert_eq!(c.velocity(0.3), 10.0);
    }
}
