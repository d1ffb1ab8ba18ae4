//! Layer A: molten thermoplastic matrix, temperature-dependent visco-hyperelastic law
//! (docs/model.md §2; Eqs. (5)–(9) of Gong et al. 2018).
//!
//! Parameters (each a [`TemperatureTable`]):
//! - `C10(T)`, MPa — neo-Hookean shear parameter (initial shear modulus `2 C10`);
//! - `D1(T)`, 1/MPa — compressibility (bulk modulus `K = 2 / D1`);
//! - `eta1(T)`, MPa·s — viscous parameter of the potential `psi_v = eta1 J2 (I1 - 3)`.
//!
//! State variables: none; the law depends on `C`, `Cdot` and `T` only.

use super::{
    ensure_finite, MaterialError, MaterialLaw, PointKinematics, StepModuli, TemperatureTable,
    ThicknessRule, ThroughThicknessTangent,
};
use nalgebra::Matrix3;
use std::sync::Arc;

/// The matrix parameters at one temperature.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MatrixParameters {
    pub c10: f64,
    pub d1: f64,
    pub eta1: f64,
}

#[derive(Clone, Debug)]
pub struct ViscoHyperelasticMatrix {
    c10: TemperatureTable,
    d1: TemperatureTable,
    eta1: TemperatureTable,
    /// The parameters interpolated once at the temperature of an isothermal run
    /// ([`MaterialLaw::at_temperature`]): the tables are otherwise interpolated at every stress
    /// evaluation, several per element and step in the plane-stress solve. Any other
    /// temperature is still interpolated, so a varying temperature stays correct.
    pinned: Option<PinnedParameters>,
}

/// [`MatrixParameters`] at one temperature, from the same interpolation as any other lookup, so
/// that using them changes no result.
#[derive(Clone, Copy, Debug)]
struct PinnedParameters {
    temperature: f64,
    parameters: MatrixParameters,
}

/// Two matrices are equal when their tables are: the pinned parameters only cache them.
impl PartialEq for ViscoHyperelasticMatrix {
    fn eq(&self, other: &Self) -> bool {
        self.c10 == other.c10 && self.d1 == other.d1 && self.eta1 == other.eta1
    }
}

/// Invariants of `C` used by Eqs. (5)–(9).
struct Invariants {
    i1: f64,
    i3: f64,
    /// `I3^(-1/3)`, the factor of the deviatoric stress and of its tangent: one `cbrt` per
    /// evaluation, the costliest operation of the law.
    i3_pow_minus_third: f64,
}

impl Invariants {
    // Eq. (3) of Gong et al. 2018
    fn of(c: &Matrix3<f64>) -> Result<Self, MaterialError> {
        let i3 = c.determinant();
        if i3.is_nan() || i3 <= 0.0 {
            return Err(MaterialError::NonPositiveVolume { det_c: i3 });
        }
        Ok(Self {
            i1: c.trace(),
            i3,
            i3_pow_minus_third: i3.cbrt().recip(),
        })
    }
}

impl ViscoHyperelasticMatrix {
    pub fn new(c10: TemperatureTable, d1: TemperatureTable, eta1: TemperatureTable) -> Self {
        Self {
            c10,
            d1,
            eta1,
            pinned: None,
        }
    }

    /// The same law with its parameters interpolated once at `temperature`; unchanged where the
    /// tables do not cover it (every evaluation there reports the error, as before).
    fn pinned_at(mut self, temperature: f64) -> Self {
        self.pinned = self
            .interpolate(temperature)
            .ok()
            .map(|parameters| PinnedParameters {
                temperature,
                parameters,
            });
        self
    }

    /// The pinned parameters when `temperature` is the pinned one.
    fn pinned(&self, temperature: f64) -> Option<&MatrixParameters> {
        self.pinned
            .as_ref()
            .filter(|p| p.temperature == temperature)
            .map(|p| &p.parameters)
    }

    fn interpolate(&self, temperature: f64) -> Result<MatrixParameters, MaterialError> {
        Ok(MatrixParameters {
            c10: self.c10.at(temperature)?,
            d1: self.d1.at(temperature)?,
            eta1: self.eta1.at(temperature)?,
        })
    }

    /// `C10` alone: a temperature inside its table but outside another's is no error here.
    fn c10_at(&self, temperature: f64) -> Result<f64, MaterialError> {
        match self.pinned(temperature) {
            Some(p) => Ok(p.c10),
            None => self.c10.at(temperature),
        }
    }

    /// `eta1` alone, like [`Self::c10_at`].
    fn eta1_at(&self, temperature: f64) -> Result<f64, MaterialError> {
        match self.pinned(temperature) {
            Some(p) => Ok(p.eta1),
            None => self.eta1.at(temperature),
        }
    }

    /// The `D1` table, as read from the card.
    pub fn d1_table(&self) -> &TemperatureTable {
        &self.d1
    }

    /// The `eta1` table, as read from the card.
    pub fn eta1_table(&self) -> &TemperatureTable {
        &self.eta1
    }

    /// The temperatures over which all three tables are defined.
    pub fn parameters_range(&self) -> (f64, f64) {
        let ranges = [self.c10.range(), self.d1.range(), self.eta1.range()];
        (
            ranges.iter().map(|r| r.0).fold(f64::NEG_INFINITY, f64::max),
            ranges.iter().map(|r| r.1).fold(f64::INFINITY, f64::min),
        )
    }

    /// `C10`, `D1` and `eta1` interpolated at `temperature`.
    pub fn parameters_at(&self, temperature: f64) -> Result<MatrixParameters, MaterialError> {
        match self.pinned(temperature) {
            Some(p) => Ok(*p),
            None => self.interpolate(temperature),
        }
    }
}

/// Elastic stress, Eq. (8) of Gong et al. 2018:
/// `S_e = 2 C10 I3^(-1/3) (I - I1/3 C^-1) + (2/D1) (I3 - I3^(1/2)) C^-1`.
fn elastic_stress(p: &MatrixParameters, c: &Matrix3<f64>, inv: &Invariants) -> Matrix3<f64> {
    let c_inv = c.try_inverse().unwrap_or_else(Matrix3::zeros);
    let deviatoric =
        (Matrix3::identity() - c_inv * (inv.i1 / 3.0)) * (2.0 * p.c10 * inv.i3_pow_minus_third);
    let volumetric = c_inv * (2.0 / p.d1 * (inv.i3 - inv.i3.sqrt()));
    deviatoric + volumetric
}

/// `S33` of [`elastic_stress`] without the rest of the tensor: `(C^-1)33` is the cofactor of
/// `C33` over `I3`, and every operation is the one the full tensor does (nalgebra's 3x3 inverse
/// divides the same cofactor by the same determinant), so the two agree to the last bit.
fn elastic_stress_33(p: &MatrixParameters, c: &Matrix3<f64>, inv: &Invariants) -> f64 {
    let c_inv_33 = (c[(0, 0)] * c[(1, 1)] - c[(1, 0)] * c[(0, 1)]) / inv.i3;
    let deviatoric = (1.0 - c_inv_33 * (inv.i1 / 3.0)) * (2.0 * p.c10 * inv.i3_pow_minus_third);
    let volumetric = c_inv_33 * (2.0 / p.d1 * (inv.i3 - inv.i3.sqrt()));
    deviatoric + volumetric
}

/// `dS33/dC33` of Eq. (8) of Gong et al. 2018, the other components of `C` held. With the cofactor
/// `k = C11 C22 - C12 C21` of `C33`, `c = (C^-1)33 = k / I3` and `J3 = I3^(-1/3)`:
/// `dI3 = k`, `dI1 = 1`, `dc = -c^2`, `dJ3 = -J3 c / 3`, so
/// `d(deviatoric) = -(2/3) C10 J3 c (2 - (4/3) c I1)` and
/// `d(volumetric) = (2/D1) (c k (1 - 1 / (2 sqrt(I3))) - c^2 (I3 - sqrt(I3)))`.
fn elastic_tangent_33(p: &MatrixParameters, c: &Matrix3<f64>, inv: &Invariants) -> f64 {
    let k = c[(0, 0)] * c[(1, 1)] - c[(1, 0)] * c[(0, 1)];
    let c_inv_33 = k / inv.i3;
    let j = inv.i3.sqrt();
    let deviatoric = -2.0 / 3.0
        * p.c10
        * inv.i3_pow_minus_third
        * c_inv_33
        * (2.0 - 4.0 / 3.0 * c_inv_33 * inv.i1);
    let volumetric =
        2.0 / p.d1 * (c_inv_33 * k * (1.0 - 0.5 / j) - c_inv_33 * c_inv_33 * (inv.i3 - j));
    deviatoric + volumetric
}

/// Viscous stress, Eq. (9) of Gong et al. 2018: `S_v = 2 eta1 (I1 - 3) Cdot`.
fn viscous_stress(p: &MatrixParameters, c_dot: &Matrix3<f64>, inv: &Invariants) -> Matrix3<f64> {
    c_dot * (2.0 * p.eta1 * (inv.i1 - 3.0))
}

impl MaterialLaw for ViscoHyperelasticMatrix {
    fn name(&self) -> &'static str {
        "matrix"
    }

    fn thickness_rule(&self) -> ThicknessRule {
        ThicknessRule::PlaneStress
    }

    fn second_piola_kirchhoff(
        &self,
        point: &PointKinematics,
    ) -> Result<Matrix3<f64>, MaterialError> {
        ensure_finite(self.name(), point)?;
        let p = self.parameters_at(point.temperature)?;
        let inv = Invariants::of(&point.c)?;
        Ok(elastic_stress(&p, &point.c, &inv) + viscous_stress(&p, &point.c_dot, &inv))
    }

    /// Eqs. (8)–(9) of Gong et al. 2018, the `33` component only.
    fn through_thickness_stress(&self, point: &PointKinematics) -> Result<f64, MaterialError> {
        ensure_finite(self.name(), point)?;
        let p = self.parameters_at(point.temperature)?;
        let inv = Invariants::of(&point.c)?;
        let viscous = point.c_dot[(2, 2)] * (2.0 * p.eta1 * (inv.i1 - 3.0));
        Ok(elastic_stress_33(&p, &point.c, &inv) + viscous)
    }

    /// The stress of Eqs. (8)–(9) of Gong et al. 2018 with `elastic_tangent_33` plus the viscous
    /// part of the tangent, Eq. (9) of Gong et al. 2018: `dS33/dC33 = 2 eta1 Cdot33` (through `I1`)
    /// and `dS33/dCdot33 = 2 eta1 (I1 - 3)`; the invariants and parameters are shared.
    fn stress_with_through_thickness_tangent(
        &self,
        point: &PointKinematics,
    ) -> Result<(Matrix3<f64>, Option<ThroughThicknessTangent>), MaterialError> {
        ensure_finite(self.name(), point)?;
        let p = self.parameters_at(point.temperature)?;
        let inv = Invariants::of(&point.c)?;
        let s = elastic_stress(&p, &point.c, &inv) + viscous_stress(&p, &point.c_dot, &inv);
        let tangent = ThroughThicknessTangent {
            wrt_c33: elastic_tangent_33(&p, &point.c, &inv) + 2.0 * p.eta1 * point.c_dot[(2, 2)],
            wrt_c_dot33: 2.0 * p.eta1 * (inv.i1 - 3.0),
        };
        Ok((s, Some(tangent)))
    }

    /// The directional derivatives of Eqs. (8)–(9) of Gong et al. 2018 (docs/model.md §2,
    /// "Tangent"). With `c = C^-1`, `a = 2 C10 I3^(-1/3)` and `b = (2/D1)(I3 - sqrt(I3))`, so
    /// that `S_e = a (I - I1/3 c) + b c`, and `dI1 = tr dC`, `dI3 = I3 tr(c dC)`,
    /// `dc = -c dC c`:
    /// `dS_e = -(a/3) tr(c dC) (I - I1/3 c) - (a/3) tr(dC) c + (a I1/3 - b) c dC c
    /// + (2/D1)(I3 - sqrt(I3)/2) tr(c dC) c`, and
    /// `dS_v = 2 eta1 (tr(dC) Cdot + (I1 - 3) dCdot)`.
    fn stress_derivatives(
        &self,
        point: &PointKinematics,
        directions: &[(Matrix3<f64>, Matrix3<f64>)],
        derivatives: &mut [Matrix3<f64>],
    ) -> Result<bool, MaterialError> {
        ensure_finite(self.name(), point)?;
        let p = self.parameters_at(point.temperature)?;
        let inv = Invariants::of(&point.c)?;
        let c_inv = point.c.try_inverse().unwrap_or_else(Matrix3::zeros);
        let a = 2.0 * p.c10 * inv.i3_pow_minus_third;
        let b = 2.0 / p.d1 * (inv.i3 - inv.i3.sqrt());
        let db = 2.0 / p.d1 * (inv.i3 - 0.5 * inv.i3.sqrt());
        let deviatoric = Matrix3::identity() - c_inv * (inv.i1 / 3.0);
        for ((dc, dc_dot), ds) in directions.iter().zip(derivatives.iter_mut()) {
            let c_dc = (c_inv * dc).trace();
            let tr_dc = dc.trace();
            let elastic = deviatoric * (-a / 3.0 * c_dc) - c_inv * (a / 3.0 * tr_dc)
                + c_inv * dc * c_inv * (a * inv.i1 / 3.0 - b)
                + c_inv * (db * c_dc);
            let viscous = (point.c_dot * tr_dc + dc_dot * (inv.i1 - 3.0)) * (2.0 * p.eta1);
            *ds = elastic + viscous;
        }
        Ok(true)
    }

    /// Eq. (5) of Gong et al. 2018: `W_e = C10 (I1bar - 3) + (J - 1)^2 / D1`, `I1bar = J^(-2/3)
    /// I1`.
    fn strain_energy(&self, point: &PointKinematics) -> Result<f64, MaterialError> {
        ensure_finite(self.name(), point)?;
        let p = self.parameters_at(point.temperature)?;
        let inv = Invariants::of(&point.c)?;
        let j = inv.i3.sqrt();
        let i1_bar = inv.i1 / inv.i3.cbrt();
        Ok(p.c10 * (i1_bar - 3.0) + (j - 1.0).powi(2) / p.d1)
    }

    /// Plane-stress incompressible neo-Hookean: biaxial modulus `4 mu = 8 C10` at small strain,
    /// growing roughly with `I1/3`; doubled for safety. The viscous term has its own bound,
    /// [`MaterialLaw::viscous_modulus`].
    fn wave_modulus(&self, point: &PointKinematics) -> Result<f64, MaterialError> {
        let c10 = self.c10_at(point.temperature)?;
        Ok(16.0 * c10 * (point.c.trace() / 3.0).max(1.0))
    }

    /// Eq. (9) of Gong et al. 2018 with `Cdot = 2 Edot`: `S_v = 4 eta1 (I1 - 3) Edot`, a 3D
    /// viscosity of `eta' = 4 eta1 |I1 - 3|` (its sign, negative for `I1 < 3`, does not matter for
    /// the step). In plane stress the nearly incompressible melt thins as it stretches,
    /// `Edot33 = -(Edot11 + Edot22)`, and the in-plane viscosity is
    /// `eta' [[2, 1], [1, 2]]`: three times `eta'` for equibiaxial stretching.
    fn viscous_modulus(&self, point: &PointKinematics) -> Result<f64, MaterialError> {
        let eta1 = self.eta1_at(point.temperature)?;
        Ok(3.0 * 4.0 * eta1 * (point.c.trace() - 3.0).abs())
    }

    /// Both bounds above from one trace of `C`.
    fn step_moduli(&self, point: &PointKinematics) -> Result<StepModuli, MaterialError> {
        let c10 = self.c10_at(point.temperature)?;
        let eta1 = self.eta1_at(point.temperature)?;
        let i1 = point.c.trace();
        Ok(StepModuli {
            wave: 16.0 * c10 * (i1 / 3.0).max(1.0),
            viscous: 3.0 * 4.0 * eta1 * (i1 - 3.0).abs(),
        })
    }

    /// docs/model.md §6: `eta1 / s`, so the viscous stress at `s` times the rate is unchanged.
    /// The pinned parameters are interpolated again from the scaled table, as any lookup is.
    fn time_scaled(&self, speed_up: f64) -> Arc<dyn MaterialLaw> {
        let scaled = Self {
            eta1: self.eta1.scaled(1.0 / speed_up),
            ..self.clone()
        };
        Arc::new(match self.pinned {
            Some(p) => scaled.pinned_at(p.temperature),
            None => scaled,
        })
    }

    fn at_temperature(&self, temperature: f64) -> Option<Arc<dyn MaterialLaw>> {
        Some(Arc::new(self.clone().pinned_at(temperature)))
    }

    /// Eq. (6) of Gong et al. 2018: `psi_v = eta1 J2 (I1 - 3)`, `J2 = tr(Cdot^2) / 2` (Eq. (4)).
    fn viscous_potential(&self, point: &PointKinematics) -> Result<f64, MaterialError> {
        ensure_finite(self.name(), point)?;
        let p = self.parameters_at(point.temperature)?;
        let j2 = 0.5 * (point.c_dot * point.c_dot).trace();
        Ok(p.eta1 * j2 * (point.c.trace() - 3.0))
    }
}
