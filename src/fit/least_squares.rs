//! Nonlinear least squares: a small wrapper over the `levenberg-marquardt` crate (a port of
//! MINPACK's `lmder`) that adds what a parameter fit has to report — standard errors of the
//! parameters and the RMS residual — and refuses problems whose parameters the data cannot
//! determine.

use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt};
use nalgebra::storage::Owned;
use nalgebra::{DMatrix, DVector, Dyn};

/// Residuals `r(p)` (model minus data, one per observation) and their Jacobian `dr/dp`.
pub trait Residuals {
    /// Number of observations, the length of the residual vector.
    fn observations(&self) -> usize;
    fn residuals(&self, parameters: &DVector<f64>) -> DVector<f64>;
    /// `observations x parameters`.
    fn jacobian(&self, parameters: &DVector<f64>) -> DMatrix<f64>;
}

/// A converged fit.
#[derive(Clone, Debug, PartialEq)]
pub struct FitResult {
    pub parameters: Vec<f64>,
    /// `sqrt(diag(s^2 (J^T J)^-1))` with `s^2 = SSR / (n - p)`: the usual linearised standard
    /// errors for independent residuals of equal variance.
    pub standard_errors: Vec<f64>,
    /// Per parameter, the most that one standard error of it moves a residual: how much its
    /// uncertainty matters to the fit (for the relative residuals of this crate's fits, a share
    /// of the observation).
    pub uncertain_shares: Vec<f64>,
    /// `sqrt(SSR / n)`, in the units of the residuals.
    pub rms_residual: f64,
    /// Sum of squared residuals.
    pub ssr: f64,
    pub observations: usize,
}

#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum FitError {
    #[error(
        "{observations} data points for {parameters} parameters: a fit needs more points \
         than parameters"
    )]
    TooFewPoints {
        observations: usize,
        parameters: usize,
    },
    #[error(
        "the parameters cannot be told apart from these data (the Jacobian is singular, \
         condition number {condition:.1e})"
    )]
    Singular { condition: f64 },
    #[error("the fit did not converge: {reason}")]
    NotConverged { reason: String },
}

/// Highest power of its variable a polynomial fit may have **(choice)**: `fit shear`'s
/// `c_k I10^k` (k <= 10) and `fit fabric-tension`'s `A_k (lambda - 1)^(k-1)` (10
/// coefficients). A higher power is flat over most of the data and fits only its last few
/// points (`c_10 I10^10` at half the largest `I10` is 1/1000 of its value there; `c_100` fitted
/// to a bias-extension curve came out as 2.5e19 MPa), and the full polynomials of that degree
/// are past [`MAX_CONDITION`] anyway.
pub const MAX_POWER: u32 = 10;

/// A parameter whose standard error exceeds its value and moves a residual by more than this
/// (5 % of an observation, for relative residuals) is not determined by the data: the fit is
/// refused ([`FitResult::determination`]). One whose uncertainty moves the fit less is merely
/// not needed, its term harmless.
pub const UNDETERMINED_SHARE: f64 = 0.05;

/// Columns of a Jacobian whose scaled condition number exceeds this are taken as dependent:
/// well past what double precision can resolve in `(J^T J)^-1`. The FE refinement's surrogate
/// Jacobian (`shear_fe`) is held to the same bound.
pub(crate) const MAX_CONDITION: f64 = 1e10;

/// How well the data fix the parameters of a fit: those whose standard error is larger than
/// their value (each could as well be zero, or twice as large), split by whether that matters.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Determination {
    /// The first whose uncertainty moves the fit by more than [`UNDETERMINED_SHARE`]
    /// somewhere: the data do not determine it, and a fit with it is refused.
    pub undetermined: Option<usize>,
    /// Those whose uncertainty moves the fit less: terms the fit does not need, harmless.
    pub not_needed: Vec<usize>,
}

impl FitResult {
    pub fn determination(&self) -> Determination {
        let loose = |i: &usize| self.standard_errors[*i] > self.parameters[*i].abs();
        let (undetermined, not_needed): (Vec<usize>, Vec<usize>) = (0..self.parameters.len())
            .filter(loose)
            .partition(|&i| self.uncertain_shares[i] > UNDETERMINED_SHARE);
        Determination {
            undetermined: undetermined.first().copied(),
            not_needed,
        }
    }
}

/// Whether `data` vary at all (by more than a rounding error of their size): a curve of one
/// value has no shape to fit, and its misfit over its range would be infinite.
pub fn varies(data: &[f64]) -> bool {
    let (lo, hi) = data
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        });
    hi - lo > crate::limits::ROUNDING * lo.abs().max(hi.abs())
}

/// Fits `problem` starting from `initial` with Levenberg–Marquardt.
pub fn fit<R: Residuals>(problem: &R, initial: &[f64]) -> Result<FitResult, FitError> {
    let n = problem.observations();
    let p = initial.len();
    if n <= p {
        return Err(FitError::TooFewPoints {
            observations: n,
            parameters: p,
        });
    }
    let start = DVector::from_column_slice(initial);
    // A singular start would let LM wander along the null space; report it instead.
    covariance_factor(&problem.jacobian(&start))?;
    let adapter = Adapter {
        problem,
        parameters: start,
    };
    let (solved, report) = LevenbergMarquardt::new().minimize(adapter);
    if !report.termination.was_successful() {
        return Err(FitError::NotConverged {
            reason: format!("{:?}", report.termination),
        });
    }
    let x = solved.parameters;
    let r = problem.residuals(&x);
    let ssr = r.norm_squared();
    if !ssr.is_finite() || x.iter().any(|v| !v.is_finite()) {
        return Err(FitError::NotConverged {
            reason: "the parameters or residuals are not finite".into(),
        });
    }
    let jacobian = problem.jacobian(&x);
    let inverse = covariance_factor(&jacobian)?;
    let s2 = ssr / (n - p) as f64;
    let standard_errors: Vec<f64> = (0..p).map(|i| (s2 * inverse[(i, i)]).sqrt()).collect();
    let uncertain_shares = jacobian
        .column_iter()
        .zip(&standard_errors)
        .map(|(column, se)| se * column.amax())
        .collect();
    Ok(FitResult {
        parameters: x.iter().copied().collect(),
        standard_errors,
        uncertain_shares,
        rms_residual: (ssr / n as f64).sqrt(),
        ssr,
        observations: n,
    })
}

/// `(J^T J)^-1`, or [`FitError::Singular`]. The columns are scaled to unit length first so that
/// parameters of very different sizes (a modulus of 0.1 MPa, a viscosity of 1e-4 MPa·s) do not
/// read as ill-conditioned.
fn covariance_factor(jacobian: &DMatrix<f64>) -> Result<DMatrix<f64>, FitError> {
    let scales: Vec<f64> = jacobian.column_iter().map(|c| c.norm()).collect();
    if scales.iter().any(|&s| !(s.is_finite() && s > 0.0)) {
        return Err(FitError::Singular {
            condition: f64::INFINITY,
        });
    }
    let mut scaled = jacobian.clone();
    for (mut column, &s) in scaled.column_iter_mut().zip(&scales) {
        column /= s;
    }
    let singular = scaled.clone().svd(false, false).singular_values;
    let condition = singular.max() / singular.min();
    if !(condition.is_finite() && condition < MAX_CONDITION) {
        return Err(FitError::Singular { condition });
    }
    let inverse = (scaled.transpose() * scaled)
        .try_inverse()
        .ok_or(FitError::Singular { condition })?;
    Ok(DMatrix::from_fn(
        inverse.nrows(),
        inverse.ncols(),
        |i, j| inverse[(i, j)] / (scales[i] * scales[j]),
    ))
}

/// The crate's problem trait over a [`Residuals`].
struct Adapter<'a, R> {
    problem: &'a R,
    parameters: DVector<f64>,
}

impl<R: Residuals> LeastSquaresProblem<f64, Dyn, Dyn> for Adapter<'_, R> {
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, Dyn>;
    type ParameterStorage = Owned<f64, Dyn>;

    fn set_params(&mut self, x: &DVector<f64>) {
        self.parameters.copy_from(x);
    }

    fn params(&self) -> DVector<f64> {
        self.parameters.clone()
    }

    fn residuals(&self) -> Option<DVector<f64>> {
        Some(self.problem.residuals(&self.parameters))
    }

    fn jacobian(&self) -> Option<DMatrix<f64>> {
        Some(self.problem.jacobian(&self.parameters))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `y = a x + b` at the given points.
    struct Line {
        x: Vec<f64>,
        y: Vec<f64>,
    }

    impl Residuals for Line {
        fn observations(&self) -> usize {
            self.x.len()
        }
        fn residuals(&self, p: &DVector<f64>) -> DVector<f64> {
            DVector::from_iterator(
                self.x.len(),
                self.x.iter().zip(&self.y).map(|(x, y)| p[0] * x + p[1] - y),
            )
        }
        fn jacobian(&self, _: &DVector<f64>) -> DMatrix<f64> {
            DMatrix::from_fn(self.x.len(), 2, |i, j| if j == 0 { self.x[i] } else { 1.0 })
        }
    }

    /// `y = a exp(k x)`.
    struct Exponential {
        x: Vec<f64>,
        y: Vec<f64>,
    }

    impl Residuals for Exponential {
        fn observations(&self) -> usize {
            self.x.len()
        }
        fn residuals(&self, p: &DVector<f64>) -> DVector<f64> {
            DVector::from_iterator(
                self.x.len(),
                self.x
                    .iter()
                    .zip(&self.y)
                    .map(|(x, y)| p[0] * (p[1] * x).exp() - y),
            )
        }
        fn jacobian(&self, p: &DVector<f64>) -> DMatrix<f64> {
            DMatrix::from_fn(self.x.len(), 2, |i, j| {
                let e = (p[1] * self.x[i]).exp();
                if j == 0 {
                    e
                } else {
                    p[0] * self.x[i] * e
                }
            })
        }
    }

    #[test]
    fn exact_line_is_recovered_with_zero_residual() {
        let x: Vec<f64> = (0..10).map(f64::from).collect();
        let y = x.iter().map(|x| 2.5 * x - 1.0).collect();
        let fit = fit(&Line { x, y }, &[0.0, 0.0]).unwrap();
        assert!((fit.parameters[0] - 2.5).abs() < 1e-10, "{fit:?}");
        assert!((fit.parameters[1] + 1.0).abs() < 1e-9, "{fit:?}");
        assert!(fit.rms_residual < 1e-9);
    }

    #[test]
    fn line_standard_errors_match_the_textbook_formula() {
        // Alternating residuals of ±0.1 about y = x: se(slope) = s / sqrt(Sxx).
        let x: Vec<f64> = (0..8).map(f64::from).collect();
        let y: Vec<f64> = x
            .iter()
            .enumerate()
            .map(|(i, x)| x + if i % 2 == 0 { 0.1 } else { -0.1 })
            .collect();
        let fit = fit(&Line { x: x.clone(), y }, &[1.0, 0.0]).unwrap();
        let mean = x.iter().sum::<f64>() / 8.0;
        let sxx: f64 = x.iter().map(|x| (x - mean).powi(2)).sum();
        let s = (fit.ssr / 6.0).sqrt();
        assert!(
            (fit.standard_errors[0] - s / sxx.sqrt()).abs() < 1e-12,
            "{fit:?}"
        );
        let se_b = s * (1.0 / 8.0 + mean * mean / sxx).sqrt();
        assert!((fit.standard_errors[1] - se_b).abs() < 1e-12, "{fit:?}");
    }

    #[test]
    fn exponential_is_recovered_from_a_distant_start() {
        let x: Vec<f64> = (0..20).map(|i| 0.1 * f64::from(i)).collect();
        let y = x.iter().map(|x| 3.0 * (-1.7 * x).exp()).collect();
        let fit = fit(&Exponential { x, y }, &[1.0, 0.0]).unwrap();
        assert!((fit.parameters[0] - 3.0).abs() < 1e-8, "{fit:?}");
        assert!((fit.parameters[1] + 1.7).abs() < 1e-8, "{fit:?}");
    }

    /// A line fitted to points scattered about a flat level: the slope's standard error exceeds
    /// it and, over a wide span of x, moves the fit by far more than 5 %: undetermined. The
    /// level is determined.
    #[test]
    fn a_parameter_the_data_do_not_fix_is_undetermined() {
        let x: Vec<f64> = (0..6).map(f64::from).collect();
        let y: Vec<f64> = [1.0, 0.6, 1.4, 0.6, 1.4, 1.0].to_vec();
        let fit = fit(&Line { x, y }, &[0.0, 0.0]).unwrap();
        assert!(fit.standard_errors[0] > fit.parameters[0].abs(), "{fit:?}");
        assert_eq!(fit.determination().undetermined, Some(0), "{fit:?}");
        let exact = Line {
            x: (0..6).map(f64::from).collect(),
            y: (0..6)
                .map(|i| 2.0 * f64::from(i) + 1.0 + 1e-3 * f64::from(i % 2))
                .collect(),
        };
        let fit = super::fit(&exact, &[0.0, 0.0]).unwrap();
        assert_eq!(fit.determination(), Determination::default(), "{fit:?}");
    }

    #[test]
    fn constant_data_do_not_vary() {
        assert!(!varies(&[5.0; 4]));
        assert!(!varies(&[0.0; 3]));
        assert!(!varies(&[1.0, 1.0 + 1e-12]));
        assert!(varies(&[0.0, 1e-300]));
        assert!(varies(&[1.0, 2.0]));
    }

    #[test]
    fn too_few_points_and_singular_problems_are_errors() {
        let two = Line {
            x: vec![0.0, 1.0],
            y: vec![0.0, 1.0],
        };
        assert_eq!(
            fit(&two, &[0.0, 0.0]),
            Err(FitError::TooFewPoints {
                observations: 2,
                parameters: 2
            })
        );
        // Every x the same: slope and intercept cannot be told apart.
        let flat = Line {
            x: vec![2.0; 5],
            y: vec![1.0; 5],
        };
        assert!(matches!(
            fit(&flat, &[0.0, 0.0]),
            Err(FitError::Singular { .. })
        ));
    }
}
