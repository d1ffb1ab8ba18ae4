//! Layer B: impregnated woven fabric, anisotropic hyperelastic with fibre–fibre–matrix
//! interaction (docs/model.md §3; Eqs. (10)–(11) of Gong et al. 2018).
//!
//! `W = W_t,warp(I4) + W_t,weft(I6) + W_s(I10)`, energy per unit reference volume of layer B:
//! - yarn tension `W_t(I) = sum_k (A_k / k) (sqrt(I) - 1)^k`, `k = 2..n`, for `sqrt(I) > 1`;
//!   in compression `W_t = (f A_2 / 2) (sqrt(I) - 1)^2`, a fraction `f` of the initial tensile
//!   stiffness `A_2`, so that yarns buckle instead of carrying compression; the change of slope
//!   spread over `0 < sqrt(I) - 1 < SLACK_BAND`;
//! - in-plane shear `W_s(I10)`, `I10 = I8^2 / (I4 I6) = sin^2(gamma)`: polynomial, friction-like
//!   and locking terms (`fabric_shear`).
//!
//! State variables: none (hyperelastic). The fibre directions come with each point.

pub use super::fabric_shear::{ShearInteraction, ShearTerm};
use super::{
    ensure_finite, FibreDirections, MaterialError, MaterialLaw, PointKinematics, ThicknessRule,
};
use nalgebra::{Matrix3, Vector3};
use std::sync::Arc;

/// Width of the strain band `0 < lambda - 1 < SLACK_BAND` over which a yarn's stiffness goes
/// from slack (`f A_2`) to taut (`A_2`) **(choice)**: a kink at `lambda = 1` would leave the
/// tangent of Newton's method undefined where the yarns of a shearing fabric sit, at their
/// rest length (docs/model.md §3). Slack yarns and a yarn at rest are as before (no stress);
/// past the band the taut tension is the law's less `A_2 SLACK_BAND / 2`, as if the yarn were
/// longer by half the band (5e-5: 2.5 % of the tension at 0.2 % strain, 0.5 % at 1 %).
pub const SLACK_BAND: f64 = 1e-4;

/// Tension energy of one yarn family as a function of its stretch.
#[derive(Clone, Debug, PartialEq)]
pub struct YarnTension {
    /// `A_2, A_3, ...` in MPa.
    coefficients: Vec<f64>,
    /// Stiffness in compression, `f A_2` (MPa).
    compression_stiffness: f64,
}

impl YarnTension {
    /// `coefficients` are `A_2, A_3, ...` (MPa); `compression_fraction` is `f`.
    pub fn new(coefficients: Vec<f64>, compression_fraction: f64) -> Self {
        let a2 = coefficients.first().copied().unwrap_or(0.0);
        Self {
            coefficients,
            compression_stiffness: compression_fraction * a2,
        }
    }

    /// `A_2, A_3, ...` (MPa).
    pub fn coefficients(&self) -> &[f64] {
        &self.coefficients
    }

    /// `W_t` as a function of the yarn stretch `lambda = sqrt(I)`.
    pub fn energy(&self, stretch: f64) -> f64 {
        let e = stretch - 1.0;
        let higher: f64 = self
            .coefficients
            .iter()
            .enumerate()
            .skip(1)
            .map(|(i, a)| {
                let k = (i + 2) as i32;
                a / k as f64 * e.max(0.0).powi(k)
            })
            .sum();
        self.linear_part_energy(e) + higher
    }

    /// The energy of the linear part of the tension (`A_2 e` taut, `f A_2 e` slack), its slope
    /// rising linearly from `f A_2` at `e = 0` to `A_2` at `e = SLACK_BAND`, and the taut
    /// branch beyond shifted by what that takes off it.
    fn linear_part_energy(&self, e: f64) -> f64 {
        let (a2, f_a2) = (self.initial_stiffness(), self.compression_stiffness);
        let b = SLACK_BAND;
        if e <= 0.0 {
            return 0.5 * f_a2 * e * e;
        }
        let s = e.min(b);
        let band = 0.5 * f_a2 * s * s + (a2 - f_a2) * s * s * s / (6.0 * b);
        if e <= b {
            band
        } else {
            band + 0.5 * a2 * (e * e - b * b) - self.taut_shift() * (e - b)
        }
    }

    /// The linear part of the tension, see [`Self::linear_part_energy`].
    fn linear_part_tension(&self, e: f64) -> f64 {
        let (a2, f_a2) = (self.initial_stiffness(), self.compression_stiffness);
        let b = SLACK_BAND;
        if e <= 0.0 {
            f_a2 * e
        } else if e >= b {
            a2 * e - self.taut_shift()
        } else {
            f_a2 * e + (a2 - f_a2) * e * e / (2.0 * b)
        }
    }

    /// What the band takes off the taut tension, `(A_2 - f A_2) SLACK_BAND / 2` (MPa): the
    /// yarn's rest length as if longer by half the band.
    fn taut_shift(&self) -> f64 {
        0.5 * (self.initial_stiffness() - self.compression_stiffness) * SLACK_BAND
    }

    fn initial_stiffness(&self) -> f64 {
        self.coefficients.first().copied().unwrap_or(0.0)
    }

    /// `dW_t/dlambda`: the yarn tension per unit reference area of the layer (MPa).
    pub fn tension(&self, stretch: f64) -> f64 {
        let e = stretch - 1.0;
        let higher: f64 = self
            .coefficients
            .iter()
            .enumerate()
            .skip(1)
            .map(|(i, a)| a * e.max(0.0).powi(i as i32 + 1))
            .sum();
        self.linear_part_tension(e) + higher
    }

    /// Tangent `d tension / d lambda` (MPa), never below the initial tensile modulus `A_2`: a
    /// slack yarn may be pulled taut within one step, and the stable step must allow for it.
    pub fn wave_modulus(&self, stretch: f64) -> f64 {
        let e = (stretch - 1.0).max(0.0);
        let tangent: f64 = self
            .coefficients
            .iter()
            .enumerate()
            .map(|(i, a)| a * (i + 1) as f64 * e.powi(i as i32))
            .sum();
        tangent.max(self.coefficients.first().copied().unwrap_or(0.0))
    }

    /// `d tension / d lambda` (MPa): `f A_2` slack, rising across the slack band to `A_2`, plus
    /// the slope of the higher terms when taut.
    pub fn stiffness(&self, stretch: f64) -> f64 {
        let e = stretch - 1.0;
        let (a2, f_a2) = (self.initial_stiffness(), self.compression_stiffness);
        let linear = if e <= 0.0 {
            f_a2
        } else if e >= SLACK_BAND {
            a2
        } else {
            f_a2 + (a2 - f_a2) * e / SLACK_BAND
        };
        let higher: f64 = self
            .coefficients
            .iter()
            .enumerate()
            .skip(1)
            .map(|(i, a)| a * (i + 1) as f64 * e.max(0.0).powi(i as i32))
            .sum();
        linear + higher
    }

    /// `dW_t/dI = (dW_t/dlambda) / (2 lambda)` with `lambda = sqrt(I)`.
    fn derivative_wrt_invariant(&self, invariant: f64) -> f64 {
        let stretch = invariant.sqrt();
        self.tension(stretch) / (2.0 * stretch)
    }

    /// `d^2 W_t / dI^2 = (lambda t'(lambda) - t(lambda)) / (4 lambda^3)`, `t` the tension.
    fn second_derivative_wrt_invariant(&self, invariant: f64) -> f64 {
        let stretch = invariant.sqrt();
        (stretch * self.stiffness(stretch) - self.tension(stretch)) / (4.0 * stretch.powi(3))
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct WovenFabric {
    pub warp: YarnTension,
    pub weft: YarnTension,
    pub shear: ShearInteraction,
}

/// Fibre invariants of Eq. (11) of Gong et al. 2018 used by the energy.
#[derive(Clone, Copy, Debug)]
struct FibreInvariants {
    i4: f64,
    i6: f64,
    i8: f64,
}

impl FibreInvariants {
    fn of(c: &Matrix3<f64>, fibres: &FibreDirections) -> Result<Self, MaterialError> {
        let (a0, b0) = (&fibres.warp, &fibres.weft);
        let i4 = a0.dot(&(c * a0));
        let i6 = b0.dot(&(c * b0));
        if i4.is_nan() || i4 <= 0.0 {
            return Err(MaterialError::DegenerateFibre {
                invariant: "I4",
                value: i4,
            });
        }
        if i6.is_nan() || i6 <= 0.0 {
            return Err(MaterialError::DegenerateFibre {
                invariant: "I6",
                value: i6,
            });
        }
        Ok(Self {
            i4,
            i6,
            i8: a0.dot(&(c * b0)),
        })
    }

    /// `I10 = I8^2 / (I4 I6) = cos^2(theta) = sin^2(gamma)` (docs/model.md §3).
    fn i10(&self) -> f64 {
        self.i8 * self.i8 / (self.i4 * self.i6)
    }
}

/// Shear angle `gamma = pi/2 - theta`, `cos(theta) = I8 / sqrt(I4 I6)` (docs/model.md §1), radians.
///
/// Positive when the yarns close up from 90°.
pub fn shear_angle(c: &Matrix3<f64>, fibres: &FibreDirections) -> f64 {
    let a0 = &fibres.warp;
    let b0 = &fibres.weft;
    let cos_theta = a0.dot(&(c * b0)) / (a0.dot(&(c * a0)) * b0.dot(&(c * b0))).sqrt();
    std::f64::consts::FRAC_PI_2 - cos_theta.clamp(-1.0, 1.0).acos()
}

fn dyad(u: &Vector3<f64>, v: &Vector3<f64>) -> Matrix3<f64> {
    u * v.transpose()
}

impl WovenFabric {
    pub fn new(warp: YarnTension, weft: YarnTension, shear: ShearInteraction) -> Self {
        Self { warp, weft, shear }
    }

    /// `W_ij = d^2 W / dI_i dI_j` over `(I4, I6, I8)` (docs/model.md §3, "Tangent"): the
    /// yarns' `d^2 W_t / dI^2` on the diagonal, and the shear's `W_s' d^2 I10 + W_s'' dI10 (x)
    /// dI10` with `I10 = I8^2 / (I4 I6)`.
    fn invariant_hessian(&self, inv: &FibreInvariants) -> Matrix3<f64> {
        let (i4, i6, i8) = (inv.i4, inv.i6, inv.i8);
        let i10 = inv.i10();
        let grad = Vector3::new(-i10 / i4, -i10 / i6, 2.0 * i8 / (i4 * i6));
        let d46 = i10 / (i4 * i6);
        let d48 = -2.0 * i8 / (i4 * i4 * i6);
        let d68 = -2.0 * i8 / (i4 * i6 * i6);
        let hessian = Matrix3::new(
            2.0 * i10 / (i4 * i4),
            d46,
            d48,
            d46,
            2.0 * i10 / (i6 * i6),
            d68,
            d48,
            d68,
            2.0 / (i4 * i6),
        );
        let mut w = hessian * self.shear.derivative(i10)
            + grad * grad.transpose() * self.shear.second_derivative(i10);
        w[(0, 0)] += self.warp.second_derivative_wrt_invariant(i4);
        w[(1, 1)] += self.weft.second_derivative_wrt_invariant(i6);
        w
    }
}

impl MaterialLaw for WovenFabric {
    fn name(&self) -> &'static str {
        "fabric"
    }

    fn thickness_rule(&self) -> ThicknessRule {
        ThicknessRule::VolumeConserving
    }

    /// docs/model.md §3: each family's `dW_t/dlambda` at its stretch `lambda = sqrt(I4)`,
    /// `sqrt(I6)`; the shear term is not a yarn tension and is left out.
    fn yarn_tensions(&self, point: &PointKinematics) -> Result<Option<[f64; 2]>, MaterialError> {
        ensure_finite(self.name(), point)?;
        let inv = FibreInvariants::of(&point.c, &point.fibres)?;
        Ok(Some([
            self.warp.tension(inv.i4.sqrt()),
            self.weft.tension(inv.i6.sqrt()),
        ]))
    }

    /// docs/model.md §3: `S = 2 W4 a0(x)a0 + 2 W6 b0(x)b0 + W8 (a0(x)b0 + b0(x)a0)`.
    fn second_piola_kirchhoff(
        &self,
        point: &PointKinematics,
    ) -> Result<Matrix3<f64>, MaterialError> {
        ensure_finite(self.name(), point)?;
        let inv = FibreInvariants::of(&point.c, &point.fibres)?;
        let ws = self.shear.derivative(inv.i10());
        let i8_sq = inv.i8 * inv.i8;
        // dI10/dI4, dI10/dI6, dI10/dI8 (docs/model.md §3)
        let w4 =
            self.warp.derivative_wrt_invariant(inv.i4) - ws * i8_sq / (inv.i4 * inv.i4 * inv.i6);
        let w6 =
            self.weft.derivative_wrt_invariant(inv.i6) - ws * i8_sq / (inv.i4 * inv.i6 * inv.i6);
        let w8 = ws * 2.0 * inv.i8 / (inv.i4 * inv.i6);
        let (a0, b0) = (&point.fibres.warp, &point.fibres.weft);
        Ok(dyad(a0, a0) * (2.0 * w4)
            + dyad(b0, b0) * (2.0 * w6)
            + (dyad(a0, b0) + dyad(b0, a0)) * w8)
    }

    /// docs/model.md §3, "Tangent": with `W_ij` the second partial derivatives of `W` in the
    /// invariants `(I4, I6, I8)` ([`WovenFabric::invariant_hessian`]), `dW_i = sum_j W_ij dI_j`
    /// with `dI4 = a0.dC.a0`, `dI6 = b0.dC.b0`, `dI8 = a0.dC.b0`, and
    /// `dS = 2 dW4 a0(x)a0 + 2 dW6 b0(x)b0 + dW8 (a0(x)b0 + b0(x)a0)`. Exact across the yarns'
    /// slack band, where central differences of the stress straddle the jump of the tension's
    /// curvature at the rest length; rate-independent.
    fn stress_derivatives(
        &self,
        point: &PointKinematics,
        directions: &[(Matrix3<f64>, Matrix3<f64>)],
        derivatives: &mut [Matrix3<f64>],
    ) -> Result<bool, MaterialError> {
        ensure_finite(self.name(), point)?;
        let inv = FibreInvariants::of(&point.c, &point.fibres)?;
        let w = self.invariant_hessian(&inv);
        let (a0, b0) = (&point.fibres.warp, &point.fibres.weft);
        let (aa, bb, ab) = (dyad(a0, a0), dyad(b0, b0), dyad(a0, b0) + dyad(b0, a0));
        for ((dc, _), ds) in directions.iter().zip(derivatives.iter_mut()) {
            let di = Vector3::new(a0.dot(&(dc * a0)), b0.dot(&(dc * b0)), a0.dot(&(dc * b0)));
            let dw = w * di;
            *ds = aa * (2.0 * dw.x) + bb * (2.0 * dw.y) + ab * dw.z;
        }
        Ok(true)
    }

    /// Both yarn families plus a bound on the shear stiffness
    /// ([`ShearInteraction::wave_stiffness`]). The yarn moduli add rather than take the
    /// larger: both families load the same nodes of a triangle, and with the larger alone the
    /// step exceeds the critical step of skewed triangles (checked against element eigenvalues
    /// in `tests/solver_patch.rs`) and a bias-extension run of stiff yarns blows up.
    fn wave_modulus(&self, point: &PointKinematics) -> Result<f64, MaterialError> {
        let inv = FibreInvariants::of(&point.c, &point.fibres)?;
        let yarns = self.warp.wave_modulus(inv.i4.sqrt()) + self.weft.wave_modulus(inv.i6.sqrt());
        let i10 = inv.i10();
        Ok(yarns + self.shear.wave_stiffness(i10))
    }

    /// Rate-independent: the same law.
    fn time_scaled(&self, _speed_up: f64) -> Arc<dyn MaterialLaw> {
        Arc::new(self.clone())
    }

    fn strain_energy(&self, point: &PointKinematics) -> Result<f64, MaterialError> {
        ensure_finite(self.name(), point)?;
        let inv = FibreInvariants::of(&point.c, &point.fibres)?;
        Ok(self.warp.energy(inv.i4.sqrt())
            + self.weft.energy(inv.i6.sqrt())
            + self.shear.energy(inv.i10()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The blended slack-to-taut band: tension is the energy's derivative, zero at rest, the
    /// slack law below it, the taut law shifted by `(A_2 - f A_2) b / 2` past it, and its
    /// slope goes from `f A_2` to `A_2` across it.
    #[test]
    fn the_slack_band_is_smooth_and_leaves_rest_and_slack_alone() {
        let yarn = YarnTension::new(vec![4.0e4, 2.0e6], 1e-3);
        let b = SLACK_BAND;
        for e in [-3.0 * b, -0.5 * b, 0.0, 0.3 * b, b, 2.0 * b, 0.01] {
            let l = 1.0 + e;
            let h = 1e-3 * b;
            let slope = (yarn.energy(l + h) - yarn.energy(l - h)) / (2.0 * h);
            let scale = 1.0 + yarn.tension(l).abs();
            assert!((slope - yarn.tension(l)).abs() < 1e-6 * scale, "{e}");
        }
        assert_eq!(yarn.tension(1.0), 0.0);
        assert_eq!(yarn.energy(1.0), 0.0);
        assert!((yarn.tension(1.0 - 2.0 * b) + 40.0 * 2.0 * b).abs() < 1e-12);
        let shift = 0.5 * (4.0e4 - 40.0) * b;
        let taut = 4.0e4 * 2.0 * b + 2.0e6 * 4.0 * b * b - shift;
        assert!((yarn.tension(1.0 + 2.0 * b) - taut).abs() < 1e-9);
        let stiffness =
            |e: f64| (yarn.tension(1.0 + e + 1e-9) - yarn.tension(1.0 + e - 1e-9)) / 2e-9;
        assert!((stiffness(0.001 * b) - 40.0).abs() < 0.01 * 4.0e4);
        assert!((stiffness(0.5 * b) - (0.5 * (4.0e4 + 40.0) + 2.0e6 * b)).abs() < 1e-3 * 4.0e4);
        assert!((stiffness(0.999 * b) - 4.0e4).abs() < 0.01 * 4.0e4);
    }
}
