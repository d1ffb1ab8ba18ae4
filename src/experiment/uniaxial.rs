//! Virtual uniaxial (strip) tension test (docs/model.md §5, "fabric tension coefficients A_k from
//! uniaxial tension along warp and weft"): a strip clamped at its bottom edge and pulled at its
//! top edge with the crosshead, the yarns at any angle to the pull.
//!
//! Along a yarn family (0° or 90°) the strip stretches homogeneously with no lateral strain: the
//! clamps allow exactly that and the fabric has no Poisson coupling between warp and weft. The
//! force per unit width is then the yarn tension law of docs/model.md §3 times the layer thickness,
//! `F / W = t_B dW_t/dlambda` at `lambda = 1 + d / L` (the first Piola–Kirchhoff resultant
//! `lambda N_yy` with `N_yy = t_B 2 W_4 = t_B W_t'(lambda) / lambda`). Off-axis strips shear
//! between the clamps like a bias-extension specimen and are far softer.

use super::sheet_test::{
    clamped_strip, clamped_strip_measurement, validate_strip, Measurement, Record, SheetTest,
    SheetTestRun, TestProcess,
};
use crate::material::Laminate;
use crate::mesh::DiagonalPattern;
use crate::solver::Model;
use crate::solver::SolverKind;
use nalgebra::Vector3;

/// A strip tension test: specimen, ply angle, and the shared process settings.
#[derive(Clone, Debug, PartialEq)]
pub struct UniaxialTension {
    /// Strip width W and free length L between the clamps (mm).
    pub width: f64,
    pub length: f64,
    /// Angle of the warp to the pulling direction y, towards +x (degrees): 0 pulls the warp,
    /// 90 the weft, 45 makes a bias strip.
    pub ply_angle: f64,
    pub process: TestProcess,
}

/// Cells across the width of the default mesh: a strip stretches uniformly across its width,
/// so two cells carry it (the standard's 12.5 mm on 25 mm).
pub const STRIP_CELLS_ACROSS: f64 = 2.0;

/// One row of the strip test's history.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UniaxialRow {
    pub time: f64,
    pub displacement: f64,
    /// Crosshead force (N).
    pub force: f64,
    /// Engineering strain `d / L`.
    pub strain: f64,
    /// Nominal stress resultant: force per unit reference width, `F / W` (N/mm).
    pub stress_resultant: f64,
    /// Mean shear angle of the gauge section, the middle third of the free length (degrees).
    pub shear_angle: f64,
}

/// The run and its post-processed history.
pub type UniaxialRun = SheetTestRun<UniaxialRow>;

impl UniaxialTension {
    /// The default element size, relative to the specimen: [`STRIP_CELLS_ACROSS`] cells
    /// across the width.
    pub fn default_element_size(&self) -> f64 {
        self.width / STRIP_CELLS_ACROSS
    }

    /// A typical laboratory strip **(choice)**: 25 mm wide with 150 mm between the grips (the
    /// proportions of tensile strips of woven composites), warp along the pull, pulled 3 mm
    /// (2 % strain: the crimp is out of a carbon weave and its yarns are near their failure
    /// strain) at 20 mm/min, the crosshead speed of the bias-extension benchmark. Run 300 times
    /// faster with eta1 divided by 300 (docs/model.md §6) on 12.5 mm crossed cells (two across the
    /// width) with physical mass. Along a yarn the strip stretches homogeneously, so the coarse mesh is exact there;
    /// the crosshead moves at below 2e-5 of the yarn wave speed of the shipped T300/PPS card
    /// and the run takes a few seconds. Refine the mesh for off-axis strips.
    pub fn standard(temperature: f64) -> Self {
        Self {
            width: 25.0,
            length: 150.0,
            ply_angle: 0.0,
            process: TestProcess {
                solver: SolverKind::Explicit,
                element_size: 12.5,
                pattern: DiagonalPattern::Crossed,
                temperature,
                speed: 20.0 / 60.0,
                time_scaling: 300.0,
                end_displacement: 3.0,
                target_time_step: None,
                damping: 0.0,
                yarn_damping: 0.06,
                history_points: 120,
            },
        }
    }

    /// The warp: the pull direction y turned by the ply angle towards +x.
    pub fn warp_direction(&self) -> Vector3<f64> {
        let (s, c) = self.ply_angle.to_radians().sin_cos();
        Vector3::new(s, c, 0.0)
    }

    /// Elements whose reference centroid lies in the middle third of the free length: away
    /// from the clamps, where an off-axis strip is free to shear.
    pub fn gauge_section(&self, model: &Model) -> Vec<usize> {
        let half = self.length / 6.0;
        (0..model.elements.len())
            .filter(|&k| model.mesh.centroid(k).y.abs() < half)
            .collect()
    }
}

impl SheetTest for UniaxialTension {
    type Row = UniaxialRow;

    fn process(&self) -> &TestProcess {
        &self.process
    }

    fn process_mut(&mut self) -> &mut TestProcess {
        &mut self.process
    }

    fn validate(&self) -> Result<(), String> {
        validate_strip(self.width, self.length, self.ply_angle)?;
        self.process.validate_on(("width", self.width))?;
        if self.process.end_displacement >= self.length {
            return Err(format!(
                "end displacement {} mm: a strip of free length {} mm would be stretched by 100 % \
                 or more",
                self.process.end_displacement, self.length
            ));
        }
        Ok(())
    }

    /// Meshed strip, bottom clamp fixed, top clamp moving along +y with the crosshead.
    fn model(&self, laminate: &Laminate, density: f64) -> Result<Model, String> {
        self.validate()?;
        let warp = self.warp_direction();
        clamped_strip(
            (self.width, self.length),
            warp,
            &self.process,
            laminate,
            density,
        )
    }

    /// Force: the top clamp's reaction along the pull; shear angle: the gauge section's.
    fn measurement(&self, model: &Model) -> Result<Measurement, String> {
        clamped_strip_measurement(model, &self.process, self.gauge_section(model))
    }

    fn rows(&self, records: &[Record]) -> Vec<UniaxialRow> {
        records
            .iter()
            .map(|r| UniaxialRow {
                time: r.time,
                displacement: r.reading.displacement,
                force: r.reading.force,
                strain: r.reading.displacement / self.length,
                stress_resultant: r.reading.force / self.width,
                shear_angle: r.reading.shear_angle,
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn standard_strip_is_valid_and_bad_numbers_are_named() {
        let test = UniaxialTension::standard(300.0);
        test.validate().unwrap();
        let mut bad = test.clone();
        bad.width = -25.0;
        assert!(bad.validate().unwrap_err().contains("width"));
        let mut bad = test.clone();
        bad.process.element_size = 20.0;
        assert!(bad
            .validate()
            .unwrap_err()
            .contains("two elements along the width"));
        let mut bad = test.clone();
        bad.ply_angle = f64::NAN;
        assert!(bad.validate().unwrap_err().contains("ply angle"));
        let mut bad = test;
        bad.process.time_scaling = 0.5;
        assert!(bad.validate().unwrap_err().contains("time scaling"));
    }

    #[test]
    fn warp_turns_from_the_pull_towards_x() {
        let mut test = UniaxialTension::standard(300.0);
        assert!((test.warp_direction() - Vector3::y()).norm() < 1e-15);
        test.ply_angle = 90.0;
        assert!((test.warp_direction() - Vector3::x()).norm() < 1e-15);
    }
}
