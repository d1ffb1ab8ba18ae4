//! Identification of the yarn tension law (docs/model.md §3, §5): `A_2..A_n` of
//! `W_t(I) = sum_{k=2..n} (A_k / k) (sqrt(I) - 1)^k` from a strip tension test along the warp
//! or the weft.
//!
//! Model: along a yarn family the strip stretches homogeneously and its force per unit
//! reference width is the fabric layer's yarn tension times its thickness (docs/model.md §5; the
//! virtual test `experiment::uniaxial` checks this against the finite elements),
//! `N(lambda) = t_B dW_t/dlambda = t_B sum_{k=2..n} A_k (lambda - 1)^(k-1)`.
//!
//! Choices:
//! - The matrix layers' share of the strip force is neglected **(choice)**. Their in-plane
//!   stress in a strip with no lateral strain is `2 C10 (lambda^2 - lambda^-2)`, about
//!   `8 C10 eps`: with the shipped T300/PPS card's largest `C10 = 0.2 MPa` and its two 0.04 mm
//!   skins, 0.0026 N/mm at 2 % strain against 368 N/mm from the yarns (7e-6 of the force; the
//!   viscous part at a test's crosshead speed is smaller still).
//! - Only the points in tension (`lambda > 1`) are fitted: in compression the yarns buckle and
//!   the law's small compression stiffness is a fixed fraction of `A_2`, not a measurement.
//! - Residuals are relative, `(model - data) / max(data, floor)` as in [`super::matrix`]: the
//!   noise of a load cell grows with its reading. The floor is 1 % of the largest force.
//! - The model is linear in the `A_k`; the Levenberg–Marquardt wrapper of
//!   [`super::least_squares`] is used all the same for its standard errors and its checks.

use super::least_squares::{fit, varies, Determination, FitError, Residuals, MAX_POWER};
use super::strip_data::StripCurve;
use crate::io::InputError;
use nalgebra::{DMatrix, DVector};

/// `N(lambda) = t_B sum_k A_k (lambda - 1)^(k-1)` (N/mm) for `lambda > 1`, docs/model.md §3/§5
/// (the law's slack band, a shift of `A_2 1e-4 / 2`, left out);
/// `coefficients` are `A_2, A_3, ...` (MPa), `thickness` is `t_B` (mm).
pub fn strip_force_per_width(thickness: f64, coefficients: &[f64], stretch: f64) -> f64 {
    let e = stretch - 1.0;
    thickness
        * coefficients
            .iter()
            .enumerate()
            .map(|(i, a)| a * e.powi(i as i32 + 1))
            .sum::<f64>()
}

/// `dN / dA_k = t_B (lambda - 1)^(k-1)`, `k = index + 2`.
fn coefficient_shape(thickness: f64, index: usize, stretch: f64) -> f64 {
    thickness * (stretch - 1.0).powi(index as i32 + 1)
}

/// The fit of one direction.
#[derive(Clone, Debug, PartialEq)]
pub struct TensionFit {
    /// `A_2, A_3, ...` (MPa).
    pub coefficients: Vec<f64>,
    pub standard_errors: Vec<f64>,
    /// RMS of model minus data over the fitted points, N/mm (unweighted).
    pub rms_residual: f64,
    /// Points fitted (those with `lambda > 1`).
    pub points: usize,
    /// How well the points fix each `A_k`.
    pub determination: Determination,
}

/// Share of the largest force under which a point's residual is no longer relative.
const RELATIVE_FLOOR: f64 = 0.01;

/// Fits `terms` coefficients `A_2..A_{terms+1}` to `curve` for a fabric layer of thickness
/// `thickness` (mm). Errors name the curve's file.
pub fn fit_yarn_tension(
    curve: &StripCurve,
    thickness: f64,
    terms: usize,
) -> Result<TensionFit, InputError> {
    let error = |message: String| InputError::in_file(&curve.origin, message);
    check_terms(terms).map_err(|why| error(format!("--terms {terms}: {why}")))?;
    let points = StripPoints::of(curve, thickness);
    // more points than coefficients, all of one force: nothing to follow; fewer are the fit's
    // own refusal
    if points.force.len() > terms && !varies(&points.force) {
        return Err(error(format!(
            "the force does not vary: force_per_width is {} N/mm at all {} points in tension; \
             there is nothing to fit",
            crate::limits::shown(points.force[0]),
            points.force.len()
        )));
    }
    let result = fit(&points, &points.initial(terms)).map_err(|e| error(describe(e, terms)))?;
    let a2 = result.parameters[0];
    if a2 <= 0.0 {
        return Err(error(format!(
            "fitted A2 = {a2:.4e} ± {:.1e} MPa is not positive: the curve does not start \
             stiffening from zero strain as docs/model.md §3 assumes (fewer --terms?)",
            result.standard_errors[0]
        )));
    }
    Ok(TensionFit {
        rms_residual: points.rms_misfit(&result.parameters),
        determination: result.determination(),
        coefficients: result.parameters,
        standard_errors: result.standard_errors,
        points: result.observations,
    })
}

/// `terms` coefficients `A_2..` can be fitted: at least one, at most [`MAX_POWER`] (checked
/// before anything is made for them).
pub fn check_terms(terms: usize) -> Result<(), String> {
    match terms {
        0 => Err("the law needs at least A2".into()),
        n if n > MAX_POWER as usize => Err(format!(
            "more than the {MAX_POWER} coefficients A_2..A_{} a fit determines (a higher power \
             of the strain is flat over all but the last points of a curve)",
            MAX_POWER + 1
        )),
        _ => Ok(()),
    }
}

fn describe(e: FitError, terms: usize) -> String {
    match e {
        FitError::TooFewPoints { observations, .. } => format!(
            "{observations} points with strain > 0 for {terms} coefficients A_k: a fit needs \
             more points in tension than coefficients"
        ),
        other => other.to_string(),
    }
}

/// The points in tension of one curve and the weight of each residual.
struct StripPoints {
    thickness: f64,
    stretch: Vec<f64>,
    force: Vec<f64>,
    scale: Vec<f64>,
}

impl StripPoints {
    fn of(curve: &StripCurve, thickness: f64) -> Self {
        let tensile = curve.tensile_points();
        let stretch: Vec<f64> = tensile.iter().map(|&i| curve.stretch[i]).collect();
        let force: Vec<f64> = tensile.iter().map(|&i| curve.force_per_width[i]).collect();
        let largest = force.iter().copied().fold(0.0, f64::max);
        let floor = (RELATIVE_FLOOR * largest).max(f64::MIN_POSITIVE);
        let scale = force.iter().map(|f| f.abs().max(floor)).collect();
        Self {
            thickness,
            stretch,
            force,
            scale,
        }
    }

    /// All the force at the largest strain read as linear (`A_2`), the rest zero.
    fn initial(&self, terms: usize) -> Vec<f64> {
        let mut start = vec![0.0; terms];
        let last = self.stretch.len().saturating_sub(1);
        start[0] = match (self.stretch.get(last), self.force.get(last)) {
            (Some(&l), Some(&f)) if f > 0.0 => f / coefficient_shape(self.thickness, 0, l),
            _ => 1.0,
        };
        start
    }

    fn rms_misfit(&self, coefficients: &[f64]) -> f64 {
        let ssr: f64 = (0..self.stretch.len())
            .map(|i| {
                (strip_force_per_width(self.thickness, coefficients, self.stretch[i])
                    - self.force[i])
                    .powi(2)
            })
            .sum();
        (ssr / self.stretch.len() as f64).sqrt()
    }
}

impl Residuals for StripPoints {
    fn observations(&self) -> usize {
        self.stretch.len()
    }

    fn residuals(&self, p: &DVector<f64>) -> DVector<f64> {
        DVector::from_fn(self.stretch.len(), |i, _| {
            (strip_force_per_width(self.thickness, p.as_slice(), self.stretch[i]) - self.force[i])
                / self.scale[i]
        })
    }

    fn jacobian(&self, p: &DVector<f64>) -> DMatrix<f64> {
        DMatrix::from_fn(self.stretch.len(), p.len(), |i, k| {
            coefficient_shape(self.thickness, k, self.stretch[i]) / self.scale[i]
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::synthetic::{strip_curve, Lcg};
    use crate::material::fabric::YarnTension;

    /// The shipped T300/PPS card: `t_B` and the warp `A_k`.
    const THICKNESS: f64 = 0.23;
    const CARD: [f64; 2] = [4.0e4, 2.0e6];

    #[test]
    fn model_is_the_thickness_times_the_yarn_tension_law() {
        let law = YarnTension::new(vec![4.0e4, 2.0e6, 3.0e7], 1e-3);
        for l in [1.001, 1.01, 1.03] {
            let n = strip_force_per_width(THICKNESS, &[4.0e4, 2.0e6, 3.0e7], l);
            // the law's slack band shifts the taut branch by A_2 SLACK_BAND / 2
            let band = THICKNESS * 4.0e4 * crate::material::fabric::SLACK_BAND / 2.0;
            assert!((n - THICKNESS * law.tension(l)).abs() < band + 1e-14 * n);
        }
    }

    #[test]
    fn noiseless_curve_gives_the_coefficients_back() {
        let curve = strip_curve("w.csv", THICKNESS, &CARD, (0.02, 21), 0.0, &mut Lcg::new(1));
        let fit = fit_yarn_tension(&curve, THICKNESS, 2).unwrap();
        for (a, b) in fit.coefficients.iter().zip(CARD) {
            assert!((a / b - 1.0).abs() < 1e-8, "{fit:?}");
        }
        assert_eq!(fit.points, 20);
        assert!(fit.rms_residual < 1e-8, "{fit:?}");
    }

    #[test]
    fn noisy_curves_stay_within_two_standard_errors() {
        // 2 % noise, 41 points to 2 % strain; at least 90 % of 40 seeds inside 2 se for each A_k.
        let mut inside = [0; 2];
        let seeds = 40;
        for seed in 0..seeds {
            let mut rng = Lcg::new(seed);
            let curve = strip_curve("w.csv", THICKNESS, &CARD, (0.02, 41), 0.02, &mut rng);
            let fit = fit_yarn_tension(&curve, THICKNESS, 2).unwrap();
            for k in 0..2 {
                if (fit.coefficients[k] - CARD[k]).abs() < 2.0 * fit.standard_errors[k] {
                    inside[k] += 1;
                }
            }
        }
        for count in inside {
            assert!(count >= 36, "{inside:?} of {seeds}");
        }
    }

    #[test]
    fn too_few_points_and_a_falling_curve_are_errors_naming_the_file() {
        let curve = strip_curve("w.csv", THICKNESS, &CARD, (0.02, 3), 0.0, &mut Lcg::new(1));
        let e = fit_yarn_tension(&curve, THICKNESS, 2)
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("w.csv: 2 points with strain > 0 for 2 coefficients"),
            "{e}"
        );
        let falling = StripCurve {
            origin: "f.csv".into(),
            stretch: vec![1.0, 1.01, 1.02, 1.03],
            force_per_width: vec![0.0, 0.0, 0.0, 1.0],
        };
        let e = fit_yarn_tension(&falling, THICKNESS, 2)
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("f.csv: fitted A2 = "), "{e}");
        assert!(fit_yarn_tension(&falling, THICKNESS, 0).is_err());
    }

    /// A flat curve has nothing to fit; more coefficients than [`MAX_POWER`] are refused
    /// before anything is allocated for them.
    #[test]
    fn flat_curves_and_too_many_terms_are_refused() {
        let flat = StripCurve {
            origin: "flat.csv".into(),
            stretch: vec![1.0, 1.01, 1.02, 1.03, 1.04],
            force_per_width: vec![5.0; 5],
        };
        let e = fit_yarn_tension(&flat, THICKNESS, 2)
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("flat.csv: the force does not vary"), "{e}");
        let curve = strip_curve("w.csv", THICKNESS, &CARD, (0.02, 21), 0.0, &mut Lcg::new(1));
        for terms in [11, usize::MAX] {
            let e = fit_yarn_tension(&curve, THICKNESS, terms)
                .unwrap_err()
                .to_string();
            assert!(
                e.contains(&format!("--terms {terms}: more than the 10")),
                "{e}"
            );
        }
    }
}
