//! Virtual bias-extension test (MODEL.md §5): a rectangular specimen with the yarns at ±45° to
//! its length, clamped at both ends, pulled at constant crosshead speed. The central zone
//! shears like a pin-jointed net, `gamma = 90° - 2 arccos((D + d)/(sqrt(2) D))`.

use super::kinematics::{bias_extension_normalised_shear_force, bias_extension_shear_angle};
use super::sheet_test::{
    mean_shear_angle, reaction_along, run_sheet_test, Crosshead, FrameOutput, Progress, Reading,
    TestRun,
};
use crate::material::Laminate;
use crate::mesh::{rectangle, DiagonalPattern};
use crate::solver::{Constraint, Model, Motion, SolverSettings};
use nalgebra::Vector3;
use std::sync::Arc;

/// A bias-extension test: specimen, mesh, process and output density.
#[derive(Clone, Debug, PartialEq)]
pub struct BiasExtension {
    /// Specimen width W and free length H between the clamps (mm), H/W >= 2.
    pub width: f64,
    pub length: f64,
    /// Warp angle to the specimen's width direction x (degrees), 45 for the standard test.
    pub ply_angle: f64,
    /// Target element size (mm) and cell pattern.
    pub element_size: f64,
    pub pattern: DiagonalPattern,
    /// Test temperature (°C).
    pub temperature: f64,
    /// Physical crosshead speed (mm/s).
    pub speed: f64,
    /// Time scaling: the simulation runs this many times faster, with eta1 divided by it.
    pub time_scaling: f64,
    /// Crosshead travel at the end of the test (mm).
    pub end_displacement: f64,
    /// Mass scaling to this time step (s), if any.
    pub target_time_step: Option<f64>,
    /// Global mass-proportional damping (1/s), see [`SolverSettings::damping`].
    pub damping: f64,
    /// Yarn-rate damping, fraction of critical, see [`SolverSettings::yarn_damping`].
    pub yarn_damping: f64,
    /// Number of history records.
    pub history_points: usize,
}

/// One row of the bias-extension history.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BiasRow {
    pub time: f64,
    pub displacement: f64,
    pub force: f64,
    /// Mean shear angle of the central zone in the simulation (degrees).
    pub shear_angle: f64,
    /// Pin-jointed prediction (degrees).
    pub shear_angle_pin_jointed: f64,
    /// Normalised shear force from the force curve (N/mm), Cao et al. 2008; NaN at d = 0.
    pub normalised_shear_force: f64,
}

/// The run and its post-processed history.
pub struct BiasExtensionRun {
    pub run: TestRun,
    pub rows: Vec<BiasRow>,
}

impl BiasExtension {
    /// The benchmark specimen of Cao et al. 2008: 150 x 450 mm, ±45°, pulled 60 mm at
    /// 20 mm/min. Run 300 times faster (eta1 divided by 300, MODEL.md §6) on 15 mm cells with
    /// physical mass: for the shipped T300/PPS card the crosshead then moves at under 1 % of
    /// the laminate's shear wave speed, the run is quasi-static (kinetic energy below 3 % of
    /// internal energy) and takes a few minutes on 2 cores. Mass scaling would not make it
    /// cheaper at the same inertia (the step and the shear wave speed both go with
    /// `sqrt(rho)`), so it is off.
    pub fn benchmark(temperature: f64) -> Self {
        Self {
            width: 150.0,
            length: 450.0,
            ply_angle: 45.0,
            element_size: 15.0,
            pattern: DiagonalPattern::Crossed,
            temperature,
            speed: 20.0 / 60.0,
            time_scaling: 300.0,
            end_displacement: 60.0,
            target_time_step: None,
            damping: 0.0,
            yarn_damping: 0.06,
            history_points: 120,
        }
    }

    /// Checks the numbers a user gave.
    pub fn validate(&self) -> Result<(), String> {
        let positive = [
            ("width", self.width),
            ("length", self.length),
            ("element size", self.element_size),
            ("speed", self.speed),
            ("end displacement", self.end_displacement),
        ];
        for (name, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("{name} = {v} must be a positive number"));
            }
        }
        if !(self.time_scaling.is_finite() && self.time_scaling >= 1.0) {
            return Err(format!("time scaling = {} must be >= 1", self.time_scaling));
        }
        if self.length < 2.0 * self.width {
            return Err(format!(
                "length/width = {:.3}: the bias-extension kinematics needs a free length of at least twice the width",
                self.length / self.width
            ));
        }
        let limit = (std::f64::consts::SQRT_2 - 1.0) * (self.length - self.width);
        if self.end_displacement >= limit {
            return Err(format!(
                "end displacement {} mm reaches the pin-jointed limit of {limit:.1} mm (90° of shear)",
                self.end_displacement
            ));
        }
        if self.element_size > 0.25 * self.width {
            return Err(format!(
                "element size {} mm: at least four elements across the width are needed",
                self.element_size
            ));
        }
        Ok(())
    }

    /// The crosshead in simulated time.
    pub fn crosshead(&self) -> Crosshead {
        let speed = self.speed * self.time_scaling;
        Crosshead {
            speed,
            ramp_time: 0.05 * self.end_displacement / speed,
        }
    }

    /// Meshed specimen, bottom clamp fixed, top clamp moving along +y; the laminate is
    /// time-scaled.
    pub fn model(&self, laminate: &Laminate, density: f64) -> Result<Model, String> {
        self.validate()?;
        let nx = (self.width / self.element_size).round().max(1.0) as usize;
        let ny = (self.length / self.element_size).round().max(1.0) as usize;
        let mesh = rectangle(self.width, self.length, nx, ny, self.pattern);
        let crosshead = self.crosshead();
        let constraints = vec![
            Constraint {
                name: "bottom clamp".into(),
                nodes: mesh.node_set("bottom").map_err(|e| e.to_string())?.to_vec(),
                motion: Motion::Fixed,
            },
            Constraint {
                name: "top clamp".into(),
                nodes: mesh.node_set("top").map_err(|e| e.to_string())?.to_vec(),
                motion: Motion::Velocity(Arc::new(move |t, _| {
                    Vector3::new(0.0, crosshead.velocity(t), 0.0)
                })),
            },
        ];
        let angle = self.ply_angle.to_radians();
        Model::new(
            mesh,
            laminate.time_scaled(self.time_scaling),
            density,
            self.temperature,
            Vector3::new(angle.cos(), angle.sin(), 0.0),
            constraints,
        )
        .map_err(|e| e.to_string())
    }

    /// Elements whose reference centroid lies in the central square of side W/3: deep inside
    /// the fully sheared zone C.
    pub fn central_zone(&self, model: &Model) -> Vec<usize> {
        let half = self.width / 6.0;
        (0..model.elements.len())
            .filter(|&k| {
                let c = model.mesh.centroid(k);
                c.x.abs() < half && c.y.abs() < half
            })
            .collect()
    }

    pub fn settings(&self) -> SolverSettings {
        let end_time = self.crosshead().time_to(self.end_displacement);
        SolverSettings {
            end_time,
            time_step_safety: 0.9,
            target_time_step: self.target_time_step,
            output_interval: end_time / self.history_points.max(1) as f64,
            damping: self.damping,
            yarn_damping: self.yarn_damping,
        }
    }

    /// Runs the test on `laminate` (of `density`).
    pub fn run(
        &self,
        laminate: &Laminate,
        density: f64,
        frames: Option<FrameOutput>,
        progress: Option<&mut dyn Progress>,
    ) -> Result<BiasExtensionRun, String> {
        let model = self.model(laminate, density)?;
        let zone = self.central_zone(&model);
        let crosshead = self.crosshead();
        let top = model
            .mesh
            .node_set("top")
            .map_err(|e| e.to_string())?
            .to_vec();
        let measure = move |model: &Model, state: &crate::solver::State| Reading {
            displacement: crosshead.displacement(state.time),
            force: reaction_along(state, &top, &Vector3::y()),
            shear_angle: mean_shear_angle(model, state, &zone),
        };
        let run = run_sheet_test(
            &model,
            &self.settings(),
            &measure,
            frames,
            progress,
            crosshead.ramp_time * 2.0,
        );
        let rows = self.rows(&run);
        Ok(BiasExtensionRun { run, rows })
    }

    fn rows(&self, run: &TestRun) -> Vec<BiasRow> {
        let d: Vec<f64> = run.records.iter().map(|r| r.reading.displacement).collect();
        let f: Vec<f64> = run.records.iter().map(|r| r.reading.force).collect();
        let mut f_sh =
            bias_extension_normalised_shear_force(self.width, self.length, &d, &f).into_iter();
        run.records
            .iter()
            .map(|r| {
                let d = r.reading.displacement;
                BiasRow {
                    time: r.time,
                    displacement: d,
                    force: r.reading.force,
                    shear_angle: r.reading.shear_angle,
                    shear_angle_pin_jointed: bias_extension_shear_angle(self.width, self.length, d)
                        .to_degrees(),
                    normalised_shear_force: if d > 0.0 {
                        f_sh.next().map_or(f64::NAN, |p| p.1)
                    } else {
                        f64::NAN
                    },
                }
            })
            .collect()
    }
}
