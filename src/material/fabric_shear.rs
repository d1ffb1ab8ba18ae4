//! The woven fabric's in-plane shear energy, fibre–fibre–matrix interaction `W_s(I10)`
//! (docs/model.md §3), `I10 = sin^2(gamma)`, as a sum of terms, each a coefficient times a
//! shape of `I10`:
//! - polynomial `c_k I10^k`, `k >= 1`: a shear force `F_sh = 2 t_B sin(gamma) W_s'` that starts
//!   from zero with a linear slope (the paper's form);
//! - friction-like `k_0 (sqrt(I10 + eps^2) - eps)`, `eps = sin(onset)`: a nearly constant shear
//!   force `t_B k_0` from the first degrees, the resistance of yarns rubbing at their
//!   crossovers that woven fabrics show at once; `eps` keeps the energy smooth at `gamma = 0`
//!   (at `gamma = onset` the force is `t_B k_0 / sqrt 2`);
//! - locking `(k_l / 3) <I10 - sin^2(gamma_l)>^3`: no force below the locking angle `gamma_l`,
//!   a force growing as `(sin^2 gamma - sin^2 gamma_l)^2` beyond it, where the yarns jam.
//!
//! Every term is even in `gamma` (positive and negative shear alike) and linear in its
//! coefficient, so a fit of the coefficients to a shear curve is linear least squares
//! (`fit::shear`). State variables: none (hyperelastic).

/// Regularisation of the friction-like term by default **(choice)**: `eps = sin(1°)`; the
/// force reaches 71 % of its plateau at 1° of shear and 98 % at 5°.
pub const DEFAULT_FRICTION_ONSET_DEG: f64 = 1.0;

/// The shape of one term of `W_s`, its coefficient left out.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ShearTerm {
    /// `I10^k`, `k >= 1`; coefficient `c_k` (MPa).
    Power(u32),
    /// `sqrt(I10 + eps^2) - eps`, `eps = sin(onset)`, `onset` in radians; coefficient `k_0`
    /// (MPa).
    Friction { onset: f64 },
    /// `<I10 - sin^2(angle)>^3 / 3`, `angle` the locking angle in radians; coefficient `k_l`
    /// (MPa).
    Locking { angle: f64 },
}

impl ShearTerm {
    /// The friction-like term with the default onset.
    pub fn friction() -> Self {
        Self::Friction {
            onset: DEFAULT_FRICTION_ONSET_DEG.to_radians(),
        }
    }

    /// The name of its coefficient: `c1`, `c2`, ..., `friction`, `locking`.
    pub fn name(&self) -> String {
        match self {
            Self::Power(k) => format!("c{k}"),
            Self::Friction { .. } => "friction".into(),
            Self::Locking { .. } => "locking".into(),
        }
    }

    /// The shape at `i10`.
    pub fn shape(&self, i10: f64) -> f64 {
        match *self {
            Self::Power(k) => i10.powi(k as i32),
            Self::Friction { onset } => {
                let eps = onset.sin();
                (i10 + eps * eps).sqrt() - eps
            }
            Self::Locking { angle } => beyond_locking(i10, angle).powi(3) / 3.0,
        }
    }

    /// Its derivative in `I10`: what the coefficient multiplies in `W_s'`.
    pub fn slope(&self, i10: f64) -> f64 {
        match *self {
            Self::Power(k) => f64::from(k) * i10.powi(k as i32 - 1),
            Self::Friction { onset } => {
                let eps = onset.sin();
                0.5 / (i10 + eps * eps).sqrt()
            }
            Self::Locking { angle } => beyond_locking(i10, angle).powi(2),
        }
    }

    /// Its second derivative in `I10`.
    pub fn curvature(&self, i10: f64) -> f64 {
        match *self {
            Self::Power(1) => 0.0,
            Self::Power(k) => f64::from(k * (k - 1)) * i10.powi(k as i32 - 2),
            Self::Friction { onset } => {
                let eps = onset.sin();
                -0.25 / (i10 + eps * eps).powf(1.5)
            }
            Self::Locking { angle } => 2.0 * beyond_locking(i10, angle),
        }
    }

    /// What the coefficient multiplies in the normalised shear force of pure shear,
    /// `F_sh = 2 t sin(gamma) W_s'(sin^2 gamma)` (docs/model.md §5): `dF_sh / d coefficient`.
    pub fn force_basis(&self, thickness: f64, gamma: f64) -> f64 {
        let s = gamma.sin();
        2.0 * thickness * s * self.slope(s * s)
    }
}

/// `<I10 - sin^2(angle)>`, zero below the locking angle.
fn beyond_locking(i10: f64, angle: f64) -> f64 {
    (i10 - angle.sin().powi(2)).max(0.0)
}

/// Fibre–fibre–matrix interaction energy `W_s(I10) = sum coefficient * shape(I10)`.
#[derive(Clone, Debug, PartialEq)]
pub struct ShearInteraction {
    /// Each term with its coefficient (MPa).
    terms: Vec<(ShearTerm, f64)>,
}

impl ShearInteraction {
    /// The polynomial `sum_k c_k I10^k` of `c_1, c_2, ...` (MPa).
    pub fn new(coefficients: Vec<f64>) -> Self {
        Self::from_terms(
            coefficients
                .into_iter()
                .enumerate()
                .map(|(i, c)| (ShearTerm::Power(i as u32 + 1), c))
                .collect(),
        )
    }

    /// The sum of `terms`, each with its coefficient (MPa).
    pub fn from_terms(terms: Vec<(ShearTerm, f64)>) -> Self {
        Self { terms }
    }

    /// `terms[i]` with the coefficient `values[i]` (MPa).
    pub fn of(terms: &[ShearTerm], values: &[f64]) -> Self {
        Self::from_terms(terms.iter().copied().zip(values.iter().copied()).collect())
    }

    /// The terms, without their coefficients.
    pub fn shapes(&self) -> Vec<ShearTerm> {
        self.terms.iter().map(|(term, _)| *term).collect()
    }

    /// The coefficients, in the order of the terms (MPa).
    pub fn values(&self) -> Vec<f64> {
        self.terms.iter().map(|(_, value)| *value).collect()
    }

    /// Each term with its coefficient.
    pub fn terms(&self) -> &[(ShearTerm, f64)] {
        &self.terms
    }

    /// `c_1, c_2, ..., c_m` of the polynomial part, up to its highest power (zero for a power
    /// left out; empty without one).
    pub fn coefficients(&self) -> Vec<f64> {
        let mut c = Vec::new();
        for &(term, value) in &self.terms {
            if let ShearTerm::Power(k) = term {
                let k = k as usize;
                if c.len() < k {
                    c.resize(k, 0.0);
                }
                c[k - 1] += value;
            }
        }
        c
    }

    /// The friction-like term's coefficient `k_0` (MPa) and onset (radians), if any.
    pub fn friction(&self) -> Option<(f64, f64)> {
        self.terms.iter().find_map(|&(term, value)| match term {
            ShearTerm::Friction { onset } => Some((value, onset)),
            _ => None,
        })
    }

    /// The locking term's coefficient `k_l` (MPa) and angle (radians), if any.
    pub fn locking(&self) -> Option<(f64, f64)> {
        self.terms.iter().find_map(|&(term, value)| match term {
            ShearTerm::Locking { angle } => Some((value, angle)),
            _ => None,
        })
    }

    fn sum(&self, part: impl Fn(&ShearTerm) -> f64) -> f64 {
        self.terms.iter().map(|(term, c)| c * part(term)).sum()
    }

    pub fn energy(&self, i10: f64) -> f64 {
        self.sum(|t| t.shape(i10))
    }

    /// `W_s'(I10)`.
    pub fn derivative(&self, i10: f64) -> f64 {
        self.sum(|t| t.slope(i10))
    }

    /// `W_s''(I10)`.
    pub fn second_derivative(&self, i10: f64) -> f64 {
        self.sum(|t| t.curvature(i10))
    }

    /// A bound on the shear stiffness for the explicit solver's stable step (MPa): for the
    /// polynomial and locking terms `4 (|W'| + |W''|)` of their sum, as the law always had; for
    /// the friction-like term `4 |W'| + 64 I10 |W''|`, since its `W''` (of order `k_0 / eps^3`
    /// at `I10 = 0`) enters the stiffness only through `(dI10/dE)^2 <= 16 I10` for small
    /// stretches, `E` the strain: about `3 k_0 / eps` at most.
    pub fn wave_stiffness(&self, i10: f64) -> f64 {
        let (mut smooth_slope, mut smooth_curvature, mut friction) = (0.0, 0.0, 0.0);
        for (term, c) in &self.terms {
            match term {
                ShearTerm::Friction { .. } => {
                    friction += 4.0 * (c * term.slope(i10)).abs()
                        + 64.0 * i10 * (c * term.curvature(i10)).abs()
                }
                _ => {
                    smooth_slope += c * term.slope(i10);
                    smooth_curvature += c * term.curvature(i10);
                }
            }
        }
        4.0 * (smooth_slope.abs() + smooth_curvature.abs()) + friction
    }

    /// Normalised shear force of a pure-shear (trellis) deformation of a layer of thickness
    /// `thickness`, docs/model.md §5: `F_sh = 2 t sin(gamma) W_s'(sin^2 gamma)` (N/mm).
    pub fn normalised_shear_force(&self, thickness: f64, gamma: f64) -> f64 {
        self.sum(|t| t.force_basis(thickness, gamma))
    }

    /// `dF_sh / dgamma` of [`Self::normalised_shear_force`] (N/mm per radian):
    /// `2 t (cos(gamma) W_s' + 2 sin^2(gamma) cos(gamma) W_s'')`.
    pub fn normalised_shear_stiffness(&self, thickness: f64, gamma: f64) -> f64 {
        let (s, c) = gamma.sin_cos();
        let i10 = s * s;
        2.0 * thickness * c * (self.derivative(i10) + 2.0 * i10 * self.second_derivative(i10))
    }

    /// The first whole degree from 0 to `limit_deg` at which the shear force falls as the
    /// shear grows (`dF_sh/dgamma < 0`), if any: a law that softens in shear has a negative
    /// shear stiffness there.
    pub fn first_softening_degree(&self, limit_deg: u32) -> Option<u32> {
        (0..=limit_deg).find(|&deg| {
            self.normalised_shear_stiffness(1.0, f64::from(deg).to_radians())
                < -1e-12 * self.scale()
        })
    }

    /// Whether the friction-like and locking coefficients are `>= 0`: a negative one would be
    /// a resistance that pushes the shear on, which a card refuses.
    pub fn sign_constraints_hold(&self) -> bool {
        self.first_negative_constrained().is_none()
    }

    /// The first friction-like or locking term with a negative coefficient, if any.
    pub fn first_negative_constrained(&self) -> Option<(ShearTerm, f64)> {
        self.terms
            .iter()
            .copied()
            .find(|(term, value)| !matches!(term, ShearTerm::Power(_)) && *value < 0.0)
    }

    /// Sum of the coefficients' magnitudes (MPa): a scale for round-off.
    fn scale(&self) -> f64 {
        self.terms
            .iter()
            .map(|(_, c)| c.abs())
            .sum::<f64>()
            .max(f64::MIN_POSITIVE)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn every_term() -> Vec<ShearTerm> {
        vec![
            ShearTerm::Power(1),
            ShearTerm::Power(2),
            ShearTerm::Power(3),
            ShearTerm::friction(),
            ShearTerm::Friction {
                onset: 3f64.to_radians(),
            },
            ShearTerm::Locking {
                angle: 40f64.to_radians(),
            },
        ]
    }

    /// Each term's slope and curvature are the central differences of its shape and slope,
    /// across the friction term's onset and the locking angle.
    #[test]
    fn slopes_and_curvatures_are_the_derivatives_of_the_shapes() {
        for term in every_term() {
            for deg in [0.5, 1.0, 2.0, 5.0, 20.0, 39.0, 41.0, 50.0, 60.0] {
                let i10 = f64::to_radians(deg).sin().powi(2);
                let h = 1e-6 * i10;
                let slope = (term.shape(i10 + h) - term.shape(i10 - h)) / (2.0 * h);
                let curvature = (term.slope(i10 + h) - term.slope(i10 - h)) / (2.0 * h);
                let scale = |x: f64| 1e-6 * (1.0 + x.abs());
                assert!(
                    (slope - term.slope(i10)).abs() < scale(slope),
                    "{term:?} at {deg}°: {slope} vs {}",
                    term.slope(i10)
                );
                assert!(
                    (curvature - term.curvature(i10)).abs() < 1e-4 * (1.0 + curvature.abs()),
                    "{term:?} at {deg}°: {curvature} vs {}",
                    term.curvature(i10)
                );
            }
            assert_eq!(term.shape(0.0), 0.0, "{term:?}");
        }
    }

    /// The friction-like term's force: `t k_0 sin(g) / sqrt(sin^2 g + eps^2)`, at the onset
    /// `t k_0 / sqrt 2`, within 2 % of the plateau `t k_0` from 5° on, and zero at rest.
    #[test]
    fn the_friction_term_gives_a_plateau_from_the_first_degrees() {
        let (t, k0) = (0.23, 0.05);
        let law = ShearInteraction::from_terms(vec![(ShearTerm::friction(), k0)]);
        assert_eq!(law.normalised_shear_force(t, 0.0), 0.0);
        let onset = law.normalised_shear_force(t, 1f64.to_radians());
        assert!((onset - t * k0 / 2f64.sqrt()).abs() < 1e-12, "{onset}");
        for deg in [5.0, 10.0, 30.0, 60.0] {
            let f = law.normalised_shear_force(t, f64::to_radians(deg));
            assert!(f < t * k0 && f > 0.98 * t * k0, "{deg}°: {f}");
        }
        assert_eq!(law.first_softening_degree(89), None);
    }

    /// The locking term: no force below the locking angle, `2 t sin(g) k_l (sin^2 g -
    /// sin^2 g_l)^2` beyond it.
    #[test]
    fn the_locking_term_acts_beyond_its_angle_only() {
        let (t, kl, angle) = (0.5, 3.0, 45f64.to_radians());
        let law = ShearInteraction::from_terms(vec![(ShearTerm::Locking { angle }, kl)]);
        assert_eq!(law.normalised_shear_force(t, 44f64.to_radians()), 0.0);
        let g = 55f64.to_radians();
        let expected = 2.0 * t * g.sin() * kl * (g.sin().powi(2) - 0.5).powi(2);
        assert!((law.normalised_shear_force(t, g) - expected).abs() < 1e-12);
    }

    /// The shear stiffness is the derivative of the force in the angle; a polynomial with a
    /// negative `c_2` large enough softens where its force turns down (`0.1 - 0.5 I10`: where
    /// `0.1 - 3 I10 < 0`, past 10.5°).
    #[test]
    fn shear_stiffness_is_the_derivative_of_the_force() {
        let law = ShearInteraction::from_terms(vec![
            (ShearTerm::friction(), 0.02),
            (ShearTerm::Power(1), 0.01),
            (ShearTerm::Power(2), -0.03),
            (ShearTerm::Power(3), 0.05),
            (
                ShearTerm::Locking {
                    angle: 45f64.to_radians(),
                },
                1.0,
            ),
        ]);
        for deg in [0.3, 2.0, 10.0, 30.0, 50.0, 70.0] {
            let g = f64::to_radians(deg);
            let h = 1e-6;
            let fd = (law.normalised_shear_force(1.2, g + h)
                - law.normalised_shear_force(1.2, g - h))
                / (2.0 * h);
            let exact = law.normalised_shear_stiffness(1.2, g);
            assert!(
                (fd - exact).abs() < 1e-6 * (1.0 + exact.abs()),
                "{deg}°: {fd} vs {exact}"
            );
        }
        let softening = ShearInteraction::new(vec![0.1, -0.5]);
        assert_eq!(softening.first_softening_degree(75), Some(11));
        assert_eq!(
            ShearInteraction::new(vec![0.1, 0.5]).first_softening_degree(75),
            None
        );
    }

    /// The polynomial's coefficients come back as they were given, and powers left out as
    /// zeros.
    #[test]
    fn polynomial_coefficients_come_back() {
        assert_eq!(
            ShearInteraction::new(vec![0.1, 0.2, 0.3]).coefficients(),
            vec![0.1, 0.2, 0.3]
        );
        let law = ShearInteraction::from_terms(vec![
            (ShearTerm::friction(), 0.02),
            (ShearTerm::Power(3), 0.5),
        ]);
        assert_eq!(law.coefficients(), vec![0.0, 0.0, 0.5]);
        assert_eq!(law.friction(), Some((0.02, 1f64.to_radians())));
        assert_eq!(law.locking(), None);
    }
}
