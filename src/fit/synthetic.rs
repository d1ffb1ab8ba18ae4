//! Synthetic tension and bias-extension curves for round-trip checks and examples of the fits: the closed form of
//! docs/model.md §5 with optional multiplicative Gaussian noise from a seeded generator, so that
//! the same seed gives the same data on every machine (no RNG dependency).

use super::fabric_tension::strip_force_per_width;
use super::matrix::uniaxial_stress;
use super::strip_data::StripCurve;
use super::tension_data::TensionCurve;
use crate::experiment::kinematics::{
    bias_extension_displacement, bias_extension_force, bias_extension_shear_angle,
};
use crate::material::fabric::ShearInteraction;

/// Knuth's MMIX linear congruential generator: tiny, deterministic, good enough for test noise.
#[derive(Clone, Debug)]
pub struct Lcg {
    state: u64,
}

impl Lcg {
    pub fn new(seed: u64) -> Self {
        Self { state: seed }
    }

    /// Uniform in the open interval (0, 1), from the top 53 bits.
    pub fn uniform(&mut self) -> f64 {
        self.state = self
            .state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((self.state >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }

    /// Standard normal by the Box–Muller transform.
    pub fn normal(&mut self) -> f64 {
        let (u1, u2) = (self.uniform(), self.uniform());
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }
}

/// `points` stretches evenly from 1 to `1 + max_strain`, and `model` at each multiplied by
/// `1 + noise * N(0, 1)` (clamped at zero, as a load cell in tension reads).
fn noisy_curve(
    (max_strain, points): (f64, usize),
    noise: f64,
    rng: &mut Lcg,
    model: impl Fn(f64) -> f64,
) -> (Vec<f64>, Vec<f64>) {
    let stretch: Vec<f64> = (0..points)
        .map(|i| 1.0 + max_strain * i as f64 / (points - 1) as f64)
        .collect();
    let values = stretch
        .iter()
        .map(|&l| (model(l) * (1.0 + noise * rng.normal())).max(0.0))
        .collect();
    (stretch, values)
}

/// A curve at `temperature` and `strain_rate` from `(C10, eta1)`: `points` stretches evenly
/// from 1 to `1 + max_strain` (given as `(max_strain, points)`), each true stress multiplied by
/// `1 + noise * N(0, 1)` (clamped at zero, as a load cell in tension reads).
pub fn tension_curve(
    origin: &str,
    temperature: f64,
    strain_rate: f64,
    (c10, eta1): (f64, f64),
    (max_strain, points): (f64, usize),
    noise: f64,
    rng: &mut Lcg,
) -> TensionCurve {
    let (stretch, stress) = noisy_curve((max_strain, points), noise, rng, |l| {
        uniaxial_stress(c10, eta1, l, strain_rate)
    });
    TensionCurve {
        origin: origin.to_string(),
        temperature,
        strain_rate,
        stretch,
        stress,
    }
}

/// A strip tension curve along one yarn family from the law `A_2, A_3, ...` of a fabric layer
/// of thickness `thickness` (docs/model.md §5, `N = t_B sum_k A_k (lambda - 1)^(k-1)`): `points`
/// stretches evenly from 1 to `1 + max_strain`, each force per width multiplied by
/// `1 + noise * N(0, 1)` (clamped at zero).
pub fn strip_curve(
    origin: &str,
    thickness: f64,
    coefficients: &[f64],
    (max_strain, points): (f64, usize),
    noise: f64,
    rng: &mut Lcg,
) -> StripCurve {
    let (stretch, force_per_width) = noisy_curve((max_strain, points), noise, rng, |l| {
        strip_force_per_width(thickness, coefficients, l)
    });
    StripCurve {
        origin: origin.to_string(),
        stretch,
        force_per_width,
    }
}

/// A bias-extension curve (CSV text, `displacement_mm,force_N`) of a `width` x `length`
/// specimen of a fabric layer `thickness` thick with shear law `law`: `points` displacements
/// evenly up to the pin-jointed angle `max_gamma` (radians), forces from the forward form of
/// Cao's normalisation (docs/model.md §5, `bias_extension_force`), each multiplied by
/// `1 + noise * N(0, 1)` and clamped at zero. The first row is `0,0`.
pub fn bias_extension_curve(
    law: &ShearInteraction,
    thickness: f64,
    (width, length): (f64, f64),
    (max_gamma, points): (f64, usize),
    noise: f64,
    rng: &mut Lcg,
) -> String {
    let d_max = bias_extension_displacement(width, length, max_gamma);
    let mut text = String::from("displacement_mm,force_N\n0,0\n");
    for i in 1..=points {
        let d = d_max * i as f64 / points as f64;
        let gamma = bias_extension_shear_angle(width, length, d);
        let exact = bias_extension_force(width, length, gamma, |g| {
            law.normalised_shear_force(thickness, g)
        });
        let f = (exact * (1.0 + noise * rng.normal())).max(0.0);
        text.push_str(&format!("{d},{f}\n"));
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_deviates_have_unit_variance() {
        let mut rng = Lcg::new(42);
        let n = 20_000;
        let samples: Vec<f64> = (0..n).map(|_| rng.normal()).collect();
        let mean = samples.iter().sum::<f64>() / n as f64;
        let variance = samples.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
        assert!(mean.abs() < 0.03, "{mean}");
        assert!((variance - 1.0).abs() < 0.05, "{variance}");
    }
}
