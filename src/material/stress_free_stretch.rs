//! Safeguarded Newton iteration for a stretch that makes one stress component vanish: the
//! plane-stress thickness stretch of a layer (docs/model.md §2, (choice)) or the lateral stretch of
//! a uniaxial-stress test.

use super::MaterialError;

/// Iterations before giving up; Newton from the previous step's stretch needs 2–4.
pub const MAX_ITERATIONS: usize = 60;

/// Relative step of the finite-difference slope at the first iterate, and its floor later on.
const SLOPE_STEP: f64 = 1e-7;
const SLOPE_STEP_FLOOR: f64 = 1e-11;

/// Newton steps smaller than this fraction of the stretch end the iteration.
const STEP_RESOLUTION: f64 = 1e-14;

/// The last iterate when no root was found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NotConverged {
    pub iterations: usize,
    pub stretch: f64,
    pub residual: f64,
}

/// One evaluation of the stress component that must vanish.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StressSample {
    /// The component driven to zero (MPa).
    pub value: f64,
    /// Magnitude of the other stress components, the scale the tolerance is relative to.
    pub scale: f64,
}

/// What an evaluation of the stress is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Evaluation {
    /// The residual at an iterate: its value and scale decide convergence, and the iterate may
    /// be the root.
    Residual,
    /// The second point of the finite-difference slope: only its value is read, and it is never
    /// the root, so a caller may compute the stress component alone.
    SlopeProbe,
}

/// Finds `lambda > 0` with `stress(lambda).value = 0`, starting from `guess`.
///
/// `stress` must increase with the stretch near the root, as any stable material's
/// through-thickness stress does. It is converged when `|value| <= tolerance * scale` or when
/// the Newton step falls below 1e-14 of the stretch. Newton steps with a finite-difference slope
/// are kept inside a bracket of the root once one is known, and replaced by bisection when they
/// leave it. The difference step follows the last Newton step down (to 1e-11 of the stretch):
/// a fixed step biases the slope by `h S''/2`, which for a strongly curved stress (a viscous
/// melt whose thickness rate is `(lambda - lambda_prev) / dt` on a short step) stalls Newton
/// into slow linear convergence.
pub fn find_stress_free_stretch(
    mut stress: impl FnMut(f64) -> Result<StressSample, MaterialError>,
    guess: f64,
    tolerance: f64,
) -> Result<Result<f64, NotConverged>, MaterialError> {
    find_stress_free_stretch_probed(|lambda, _| Ok((stress(lambda)?, None)), guess, tolerance)
}

/// [`find_stress_free_stretch`] telling `stress` what each evaluation is for, for a caller
/// that knows more than the stress: a residual evaluation may return the exact slope
/// `dstress/dlambda` with its sample, which replaces the finite-difference probe (one stress
/// evaluation less per iteration); a probe is asked for only when it returns `None`, and the
/// `scale` of a probe's sample is not read.
pub fn find_stress_free_stretch_probed(
    mut stress: impl FnMut(f64, Evaluation) -> Result<(StressSample, Option<f64>), MaterialError>,
    guess: f64,
    tolerance: f64,
) -> Result<Result<f64, NotConverged>, MaterialError> {
    let mut lambda = if guess.is_finite() && guess > 0.0 {
        guess
    } else {
        1.0
    };
    let mut below = 0.0_f64; // largest stretch known to give stress < 0
    let mut above = f64::INFINITY; // smallest stretch known to give stress > 0
    let mut residual = f64::NAN;
    let mut h = SLOPE_STEP * lambda;
    for iteration in 0..MAX_ITERATIONS {
        let (sample, exact_slope) = stress(lambda, Evaluation::Residual)?;
        residual = sample.value;
        if !residual.is_finite() {
            return Ok(Err(NotConverged {
                iterations: iteration,
                stretch: lambda,
                residual,
            }));
        }
        if residual.abs() <= tolerance * sample.scale {
            return Ok(Ok(lambda));
        }
        if residual < 0.0 {
            below = below.max(lambda);
        } else {
            above = above.min(lambda);
        }
        if above - below <= STEP_RESOLUTION * lambda {
            // the root is bracketed to the resolution of lambda
            return Ok(Ok(lambda));
        }
        let slope = match exact_slope {
            Some(slope) => slope,
            None => (stress(lambda + h, Evaluation::SlopeProbe)?.0.value - residual) / h,
        };
        let newton = lambda - residual / slope;
        // A Newton step below the resolution of lambda: the residual is rounding noise.
        if slope > 0.0 && (newton - lambda).abs() <= STEP_RESOLUTION * lambda {
            return Ok(Ok(lambda));
        }
        h = (newton - lambda)
            .abs()
            .clamp(SLOPE_STEP_FLOOR * lambda, SLOPE_STEP * lambda);
        let inside = |x: f64| x.is_finite() && x > below && x < above;
        lambda = if slope > 0.0 && inside(newton) {
            newton
        } else if above.is_finite() {
            0.5 * (below + above)
        } else {
            2.0 * lambda.max(below)
        };
    }
    Ok(Err(NotConverged {
        iterations: MAX_ITERATIONS,
        stretch: lambda,
        residual,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(value: f64) -> Result<StressSample, MaterialError> {
        Ok(StressSample { value, scale: 1.0 })
    }

    #[test]
    fn finds_the_root_of_a_stiffening_law() {
        // S(l) = l^3 - 0.5: root at 0.5^(1/3)
        let root = find_stress_free_stretch(|l| sample(l.powi(3) - 0.5), 1.0, 1e-14)
            .unwrap()
            .unwrap();
        assert!((root - 0.5f64.cbrt()).abs() < 1e-12);
    }

    #[test]
    fn survives_a_bad_guess_and_a_flat_start() {
        // flat for small stretch, steep beyond: Newton alone would overshoot
        let law = |l: f64| sample((l - 2.0).atan() * 1e3 + 1e-3 * (l - 2.0).powi(3));
        let root = find_stress_free_stretch(law, 0.01, 1e-10).unwrap().unwrap();
        assert!((root - 2.0).abs() < 1e-10, "{root}");
    }

    #[test]
    fn converges_on_a_stress_curved_below_the_difference_step() {
        // S = x (1 + |x| / delta), x = l - r, delta = 1e-10: near the root the slope is 1, but
        // over a difference step of 1e-7 it looks 1000 times steeper, and Newton with that
        // slope creeps by 0.1 % a step (the plane-stress S33 of a very viscous melt on a short
        // step is curved like this: its rate is (lambda - lambda_prev) / dt)
        let (r, delta) = (0.999_997_8, 1e-10);
        let law = |l: f64| {
            let x = l - r;
            sample(x * (1.0 + x.abs() / delta))
        };
        let root = find_stress_free_stretch(law, 1.0, 1e-12).unwrap().unwrap();
        assert!((root - r).abs() < 1e-12, "{root}");
    }

    #[test]
    fn reports_failure_when_there_is_no_root() {
        let failure = find_stress_free_stretch(|l| sample(1.0 + l), 1.0, 1e-12)
            .unwrap()
            .unwrap_err();
        assert!(failure.residual > 0.0);
    }
}
