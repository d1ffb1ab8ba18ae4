//! Constitutive laws of the prepreg (docs/model.md §2–§4).
//!
//! Every layer law implements [`MaterialLaw`]: given the right Cauchy–Green tensor `C`, its
//! rate `Cdot`, the temperature and the fibre directions of one material point, it returns the
//! second Piola–Kirchhoff stress and the potentials it derives from. The [`laminate`] module
//! stacks such layers into the A:B:A membrane section of the lamination model.

pub mod card;
pub mod fabric;
pub mod fabric_shear;
pub mod laminate;
pub mod matrix;
pub mod stress_free_stretch;
pub mod temperature_table;

pub use card::MaterialCard;
pub use fabric::WovenFabric;
pub use laminate::{
    Laminate, LaminateState, Layer, LayerTemperatures, MembraneKinematics, MembraneResponse,
};
pub use matrix::ViscoHyperelasticMatrix;
pub use stress_free_stretch::Evaluation;
pub use temperature_table::TemperatureTable;

use nalgebra::{Matrix3, Vector3};
use std::fmt::Debug;
use std::sync::Arc;

/// Warp and weft directions `a0`, `b0` in the reference configuration (docs/model.md §1).
///
/// Unit vectors in the reference tangent plane; they are material directions, so the current
/// yarns are `a = F a0` and `b = F b0` (non-orthogonal fibre tracking).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FibreDirections {
    pub warp: Vector3<f64>,
    pub weft: Vector3<f64>,
}

impl FibreDirections {
    /// Warp at `angle` (radians) from the x axis in the x–y plane, weft 90° further on.
    pub fn in_plane(angle: f64) -> Self {
        let (s, c) = angle.sin_cos();
        Self {
            warp: Vector3::new(c, s, 0.0),
            weft: Vector3::new(-s, c, 0.0),
        }
    }
}

impl Default for FibreDirections {
    fn default() -> Self {
        Self::in_plane(0.0)
    }
}

/// Everything a layer law needs at one material point.
#[derive(Clone, Copy, Debug)]
pub struct PointKinematics {
    /// Right Cauchy–Green tensor `C = F^T F`, Eq. (1) of Gong et al. 2018.
    pub c: Matrix3<f64>,
    /// Its material rate `Cdot = Fdot^T F + F^T Fdot`, Eq. (2) of Gong et al. 2018.
    pub c_dot: Matrix3<f64>,
    /// Temperature, °C.
    pub temperature: f64,
    pub fibres: FibreDirections,
}

impl PointKinematics {
    /// The undeformed point at rest.
    pub fn at_rest(temperature: f64, fibres: FibreDirections) -> Self {
        Self {
            c: Matrix3::identity(),
            c_dot: Matrix3::zeros(),
            temperature,
            fibres,
        }
    }

    /// Kinematics from the deformation gradient and its rate, Eqs. (1)–(2) of Gong et al. 2018.
    pub fn from_deformation(
        f: &Matrix3<f64>,
        f_dot: &Matrix3<f64>,
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
}

/// How a layer's thickness stretch `lambda3` follows from the in-plane deformation when the
/// layer is part of a thin sheet (docs/model.md §2 and §3).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ThicknessRule {
    /// `lambda3` is solved so that the through-thickness stress `S33` vanishes.
    PlaneStress,
    /// The layer carries no through-thickness stress and keeps its volume:
    /// `lambda3 = 1 / sqrt(det C2)`.
    VolumeConserving,
}

/// A constitutive law of one layer of the prepreg.
pub trait MaterialLaw: Debug + Send + Sync {
    /// Short name used in messages and output ("matrix", "fabric").
    fn name(&self) -> &'static str;

    /// How the layer's thickness follows the in-plane deformation in a sheet.
    fn thickness_rule(&self) -> ThicknessRule;

    /// Second Piola–Kirchhoff stress `S` (MPa), elastic and viscous parts together.
    fn second_piola_kirchhoff(
        &self,
        point: &PointKinematics,
    ) -> Result<Matrix3<f64>, MaterialError>;

    /// The through-thickness component `S33` of [`MaterialLaw::second_piola_kirchhoff`], the
    /// same number: the plane-stress solve needs only it to probe the slope of `S33`, and a
    /// law may compute it without the rest of the tensor.
    fn through_thickness_stress(&self, point: &PointKinematics) -> Result<f64, MaterialError> {
        Ok(self.second_piola_kirchhoff(point)?[(2, 2)])
    }

    /// [`MaterialLaw::second_piola_kirchhoff`] with the partial derivatives of `S33` with
    /// respect to `C33` and to `Cdot33` (the other components held), for the Newton iteration
    /// of plane stress; `None` when the law does not provide them, and the iteration then
    /// differences `S33`.
    fn stress_with_through_thickness_tangent(
        &self,
        point: &PointKinematics,
    ) -> Result<(Matrix3<f64>, Option<ThroughThicknessTangent>), MaterialError> {
        Ok((self.second_piola_kirchhoff(point)?, None))
    }

    /// The derivatives of [`MaterialLaw::second_piola_kirchhoff`] along changes of the
    /// kinematics: for each `(dC, dCdot)` of `directions` (symmetric), `dS = dS/dC : dC +
    /// dS/dCdot : dCdot` (MPa) into `derivatives`, for the consistent tangent of the implicit
    /// solver (docs/solver.md, "Implicit"). Returns `false`, with `derivatives` untouched,
    /// when the law does not provide them: the laminate then differences its response.
    fn stress_derivatives(
        &self,
        _point: &PointKinematics,
        _directions: &[(Matrix3<f64>, Matrix3<f64>)],
        _derivatives: &mut [Matrix3<f64>],
    ) -> Result<bool, MaterialError> {
        Ok(false)
    }

    /// The tensions of the two yarn families, warp and weft (MPa, force per unit reference
    /// cross-section of the layer: `dW_t/dlambda` of each, docs/model.md §3); `None` for a law
    /// without yarns.
    fn yarn_tensions(&self, _point: &PointKinematics) -> Result<Option<[f64; 2]>, MaterialError> {
        Ok(None)
    }

    /// Stored (hyperelastic) energy per unit reference volume (MPa); `S_e = 2 dW/dC`.
    fn strain_energy(&self, point: &PointKinematics) -> Result<f64, MaterialError>;

    /// Viscous potential per unit reference volume (MPa); `S_v = 2 dpsi/dCdot`.
    /// Zero for purely elastic laws.
    fn viscous_potential(&self, _point: &PointKinematics) -> Result<f64, MaterialError> {
        Ok(0.0)
    }

    /// An upper bound of the in-plane tangent modulus at this point (MPa, per unit reference
    /// area), for the stable time step of explicit dynamics: wave speed `sqrt(modulus / rho)`.
    fn wave_modulus(&self, point: &PointKinematics) -> Result<f64, MaterialError>;

    /// An upper bound of the tangent viscosity `|dS/dEdot|` at this point (MPa·s), for the
    /// stable time step: a viscous stress damps the highest mode of an element and shortens
    /// the step of central differences. Zero for purely elastic laws.
    fn viscous_modulus(&self, _point: &PointKinematics) -> Result<f64, MaterialError> {
        Ok(0.0)
    }

    /// [`MaterialLaw::wave_modulus`] and [`MaterialLaw::viscous_modulus`] together, as the
    /// stable step needs both at every step; a law may share the work between them.
    fn step_moduli(&self, point: &PointKinematics) -> Result<StepModuli, MaterialError> {
        Ok(StepModuli {
            wave: self.wave_modulus(point)?,
            viscous: self.viscous_modulus(point)?,
        })
    }

    /// This law for an isothermal run at `temperature`, with what depends on the temperature
    /// evaluated once instead of at every point; the same numbers at that temperature, and any
    /// other temperature still evaluated as before. `None` when nothing is gained.
    fn at_temperature(&self, _temperature: f64) -> Option<Arc<dyn MaterialLaw>> {
        None
    }

    /// This law for a process run `speed_up` times faster than the real one (docs/model.md §6,
    /// time scaling): rate-dependent parameters change so that the response at the scaled
    /// rate equals the real response at the real rate.
    fn time_scaled(&self, speed_up: f64) -> Arc<dyn MaterialLaw>;
}

/// `dS33/dC33` (MPa) and `dS33/dCdot33` (MPa·s) at a point, see
/// [`MaterialLaw::stress_with_through_thickness_tangent`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThroughThicknessTangent {
    pub wrt_c33: f64,
    pub wrt_c_dot33: f64,
}

/// The two moduli that set the stable step of an element (see [`MaterialLaw::wave_modulus`]
/// and [`MaterialLaw::viscous_modulus`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepModuli {
    /// Upper bound of the in-plane tangent modulus (MPa).
    pub wave: f64,
    /// Upper bound of the tangent viscosity (MPa·s).
    pub viscous: f64,
}

/// Cauchy stress `sigma = F S F^T / det F`.
pub fn cauchy_stress(f: &Matrix3<f64>, s: &Matrix3<f64>) -> Matrix3<f64> {
    f * s * f.transpose() / f.determinant()
}

/// `temperature`, outside the table from `min` to `max`, with the digits that tell it from the
/// end it passed.
fn beyond(temperature: &f64, min: &f64, max: &f64) -> String {
    let nearest = if temperature < min { *min } else { *max };
    crate::limits::shown_apart(*temperature, nearest)
}

/// Why a material law could not produce a stress.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MaterialError {
    #[error(
        "temperature {} °C is outside the table of {quantity} ({} to {} °C); extend the table \
         in the material card",
        beyond(.temperature, .min, .max),
        crate::limits::shown(*.min),
        crate::limits::shown(*.max)
    )]
    TemperatureOutOfRange {
        quantity: String,
        temperature: f64,
        min: f64,
        max: f64,
    },
    #[error("the material is inverted or crushed: det C = {det_c:e} must be > 0")]
    NonPositiveVolume { det_c: f64 },
    #[error("fibre stretch squared {invariant} = {value:e} must be > 0")]
    DegenerateFibre { invariant: &'static str, value: f64 },
    #[error("non-finite input to the {law} law: {what}")]
    NonFinite {
        law: &'static str,
        what: &'static str,
    },
    #[error(
        "no stress-free thickness stretch found for layer {layer} ({law}) after {iterations} \
         iterations (last lambda3 = {lambda3:e}, S33 = {s33:e} MPa)"
    )]
    PlaneStressNotConverged {
        layer: usize,
        law: &'static str,
        iterations: usize,
        lambda3: f64,
        s33: f64,
    },
}

pub(crate) fn ensure_finite(
    law: &'static str,
    point: &PointKinematics,
) -> Result<(), MaterialError> {
    let finite = |m: &Matrix3<f64>| m.iter().all(|v| v.is_finite());
    if !finite(&point.c) {
        return Err(MaterialError::NonFinite { law, what: "C" });
    }
    if !finite(&point.c_dot) {
        return Err(MaterialError::NonFinite { law, what: "Cdot" });
    }
    if !point.temperature.is_finite() {
        return Err(MaterialError::NonFinite {
            law,
            what: "temperature",
        });
    }
    Ok(())
}
