//! The lamination model A:B:A (MODEL.md §4): perfectly bonded layers sharing the in-plane
//! deformation, each in plane stress, summed into the membrane resultant `N = sum_k t_k S2_k`.
//!
//! State variables, per layer `k`: the thickness stretch `lambda3_k` and its rate at the end of
//! the last converged step ([`LaminateState`]); the viscous matrix needs the rate because its
//! through-thickness stress depends on `Cdot33 = 2 lambda3 lambda3dot`.

use super::stress_free_stretch::find_stress_free_stretch;
use super::{FibreDirections, MaterialError, MaterialLaw, PointKinematics, ThicknessRule};
use nalgebra::{Matrix2, Matrix3, Matrix3x2};
use std::sync::Arc;

/// Plane-stress iterations stop when `|S33|` is below this fraction of the in-plane stress.
const PLANE_STRESS_TOLERANCE: f64 = 1e-12;

/// One layer of the stack: its law and reference thickness (mm).
#[derive(Clone, Debug)]
pub struct Layer {
    pub law: Arc<dyn MaterialLaw>,
    pub thickness: f64,
}

/// A stack of perfectly bonded layers, by default matrix : fabric : matrix.
#[derive(Clone, Debug)]
pub struct Laminate {
    layers: Vec<Layer>,
}

/// In-plane kinematics of the sheet in an orthonormal local basis `(e1, e2)` of the reference
/// tangent plane (MODEL.md §1).
#[derive(Clone, Copy, Debug)]
pub struct MembraneKinematics {
    /// `C2 = F^T F` (2x2).
    pub c: Matrix2<f64>,
    /// `C2dot = Fdot^T F + F^T Fdot` (2x2).
    pub c_dot: Matrix2<f64>,
    /// Temperature, °C.
    pub temperature: f64,
    /// Warp and weft in the local basis (third components zero).
    pub fibres: FibreDirections,
}

impl MembraneKinematics {
    /// From the in-plane deformation gradient `F` (3x2: local reference coordinates to current
    /// 3D positions) and its rate.
    pub fn from_deformation(
        f: &Matrix3x2<f64>,
        f_dot: &Matrix3x2<f64>,
        temperature: f64,
        fibres: FibreDirections,
    ) -> Self {
        Self {
            c: f.transpose() * f,
            c_dot: f_dot.transpose() * f + f.transpose() * f_dot,
            temperature,
            fibres,
        }
    }

    /// A layer's 3D kinematics, `C = diag-block(C2, lambda3^2)` (MODEL.md §1).
    pub fn layer_point(&self, lambda3: f64, lambda3_rate: f64) -> PointKinematics {
        let mut c = Matrix3::zeros();
        let mut c_dot = Matrix3::zeros();
        c.fixed_view_mut::<2, 2>(0, 0).copy_from(&self.c);
        c_dot.fixed_view_mut::<2, 2>(0, 0).copy_from(&self.c_dot);
        c[(2, 2)] = lambda3 * lambda3;
        c_dot[(2, 2)] = 2.0 * lambda3 * lambda3_rate;
        PointKinematics {
            c,
            c_dot,
            temperature: self.temperature,
            fibres: self.fibres,
        }
    }
}

/// The laminate's state variables at one point: per layer, `lambda3` and `dlambda3/dt`.
#[derive(Clone, Debug, PartialEq)]
pub struct LaminateState {
    pub thickness_stretch: Vec<f64>,
    pub thickness_stretch_rate: Vec<f64>,
}

/// Membrane response of the laminate at one point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MembraneResponse {
    /// 2nd Piola–Kirchhoff membrane resultant per unit reference width (N/mm), MODEL.md §4.
    pub n: Matrix2<f64>,
    /// Current thickness `t = sum_k t_k lambda3_k` (mm).
    pub thickness: f64,
}

impl Laminate {
    /// A stack of `layers`, each with a positive finite thickness.
    pub fn new(layers: Vec<Layer>) -> Result<Self, String> {
        if layers.is_empty() {
            return Err("a laminate needs at least one layer".into());
        }
        if let Some((k, layer)) = layers
            .iter()
            .enumerate()
            .find(|(_, l)| !(l.thickness.is_finite() && l.thickness > 0.0))
        {
            return Err(format!(
                "layer {k} ({}) has thickness {} mm; it must be > 0",
                layer.law.name(),
                layer.thickness
            ));
        }
        Ok(Self { layers })
    }

    /// The A:B:A stack of the lamination model: `matrix (t_A) : fabric (t_B) : matrix (t_A)`.
    pub fn matrix_fabric_matrix(
        matrix: Arc<dyn MaterialLaw>,
        matrix_thickness: f64,
        fabric: Arc<dyn MaterialLaw>,
        fabric_thickness: f64,
    ) -> Result<Self, String> {
        Self::new(vec![
            Layer {
                law: matrix.clone(),
                thickness: matrix_thickness,
            },
            Layer {
                law: fabric,
                thickness: fabric_thickness,
            },
            Layer {
                law: matrix,
                thickness: matrix_thickness,
            },
        ])
    }

    pub fn layers(&self) -> &[Layer] {
        &self.layers
    }

    /// Sum of the layers' reference thicknesses (mm).
    pub fn reference_thickness(&self) -> f64 {
        self.layers.iter().map(|l| l.thickness).sum()
    }

    /// The undeformed state: every `lambda3 = 1`, at rest.
    pub fn initial_state(&self) -> LaminateState {
        LaminateState {
            thickness_stretch: vec![1.0; self.layers.len()],
            thickness_stretch_rate: vec![0.0; self.layers.len()],
        }
    }

    /// Advances `state` to the kinematics `kin`, reached `dt` seconds after the state's, and
    /// returns the membrane resultant and thickness (MODEL.md §4).
    ///
    /// Each layer's thickness stretch follows its [`ThicknessRule`]; with `dt = 0` the
    /// thickness rate is taken as zero.
    pub fn membrane_response(
        &self,
        kin: &MembraneKinematics,
        dt: f64,
        state: &mut LaminateState,
    ) -> Result<MembraneResponse, MaterialError> {
        let mut n = Matrix2::zeros();
        let mut thickness = 0.0;
        for (k, layer) in self.layers.iter().enumerate() {
            let previous = state.thickness_stretch[k];
            let lambda3 = self.thickness_stretch(k, kin, previous, dt)?;
            let rate = thickness_rate(lambda3, previous, dt);
            state.thickness_stretch[k] = lambda3;
            state.thickness_stretch_rate[k] = rate;
            let s = layer
                .law
                .second_piola_kirchhoff(&kin.layer_point(lambda3, rate))?;
            n += s.fixed_view::<2, 2>(0, 0) * layer.thickness;
            thickness += layer.thickness * lambda3;
        }
        Ok(MembraneResponse { n, thickness })
    }

    /// 3D stress `S` of layer `k` for the kinematics and a state already advanced to them.
    pub fn layer_stress(
        &self,
        k: usize,
        kin: &MembraneKinematics,
        state: &LaminateState,
    ) -> Result<Matrix3<f64>, MaterialError> {
        let point = kin.layer_point(state.thickness_stretch[k], state.thickness_stretch_rate[k]);
        self.layers[k].law.second_piola_kirchhoff(&point)
    }

    /// Stored energy per unit reference area, `sum_k t_k W_k` (N/mm), in an advanced state.
    pub fn stored_energy(
        &self,
        kin: &MembraneKinematics,
        state: &LaminateState,
    ) -> Result<f64, MaterialError> {
        self.layers
            .iter()
            .enumerate()
            .try_fold(0.0, |sum, (k, layer)| {
                let point =
                    kin.layer_point(state.thickness_stretch[k], state.thickness_stretch_rate[k]);
                Ok(sum + layer.thickness * layer.law.strain_energy(&point)?)
            })
    }

    fn thickness_stretch(
        &self,
        k: usize,
        kin: &MembraneKinematics,
        previous: f64,
        dt: f64,
    ) -> Result<f64, MaterialError> {
        let det_c2 = kin.c.determinant();
        if det_c2.is_nan() || det_c2 <= 0.0 {
            return Err(MaterialError::NonPositiveVolume { det_c: det_c2 });
        }
        let law = &self.layers[k].law;
        match law.thickness_rule() {
            ThicknessRule::VolumeConserving => Ok(det_c2.sqrt().recip()),
            ThicknessRule::PlaneStress => {
                let s33 = |lambda3: f64| {
                    let rate = thickness_rate(lambda3, previous, dt);
                    Ok(law.second_piola_kirchhoff(&kin.layer_point(lambda3, rate))?[(2, 2)])
                };
                let guess = previous;
                let start = law.second_piola_kirchhoff(
                    &kin.layer_point(guess, thickness_rate(guess, previous, dt)),
                )?;
                let in_plane_scale = start.fixed_view::<2, 2>(0, 0).amax();
                find_stress_free_stretch(s33, guess, PLANE_STRESS_TOLERANCE * in_plane_scale)?
                    .map_err(|failure| MaterialError::PlaneStressNotConverged {
                        layer: k,
                        law: law.name(),
                        iterations: failure.iterations,
                        lambda3: failure.stretch,
                        s33: failure.residual,
                    })
            }
        }
    }
}

/// Backward-difference thickness rate; zero for a step of no duration.
fn thickness_rate(lambda3: f64, previous: f64, dt: f64) -> f64 {
    if dt > 0.0 {
        (lambda3 - previous) / dt
    } else {
        0.0
    }
}
