//! Coefficients of the fabric's interaction energy `W_s(I10)` (docs/model.md §3: polynomial
//! `c_k I10^k`, friction-like and locking terms, `material::fabric_shear`) from a
//! bias-extension or picture-frame force–displacement curve (docs/model.md §5).
//!
//! 1. The curve is read and checked point by point (every error names the file and line).
//! 2. Each point becomes `(gamma, F_sh)`: for a bias-extension test the pin-jointed angle of
//!    the central zone and the normalised shear force of Cao et al. 2008, solved recursively
//!    from small angles (docs/model.md §5, `experiment::kinematics`); for a picture frame the
//!    frame's angle and `F_norm = F L_frame / (2 cos(theta) L_fabric^2)` (docs/model.md §5).
//! 3. The chosen terms' coefficients are fitted, up to a largest angle, by Levenberg–Marquardt
//!    (`least_squares`): for a picture frame to `F_sh(gamma) = 2 t_B sin(gamma) W_s'(sin^2
//!    gamma)` (docs/model.md §5, last bullet); for a bias extension to the crosshead force of
//!    a pin-jointed specimen of that `F_sh` (the forward form of Cao's normalisation,
//!    [`observations`]).
//! 4. A fitted law whose shear force falls as the shear grows somewhere over the fitted angles
//!    (a negative shear stiffness) is refused: fewer or other terms are needed.
//!
//! The model is linear in the coefficients; LM is used anyway for its standard errors and
//! checks, started from zero.

use super::least_squares::{fit, varies, FitError, FitResult, Residuals};
use crate::experiment::kinematics::{
    bias_extension_force, bias_extension_normalised_shear_force, bias_extension_shear_angle,
    check_bias_aspect, picture_frame_angles, picture_frame_normalised_force,
};
use crate::io::xy_curve::{parse_xy_curve, read_curve_text, CurveLayout};
use crate::io::InputError;
use crate::material::fabric::{ShearInteraction, ShearTerm};
use nalgebra::{DMatrix, DVector};
use std::path::Path;

/// CSV columns of a force–displacement curve (header names).
pub const DISPLACEMENT_COLUMN: &str = "displacement_mm";
pub const FORCE_COLUMN: &str = "force_N";

/// A crosshead force–displacement curve, checked: displacement increasing, force >= 0.
#[derive(Clone, Debug, PartialEq)]
pub struct ForceCurve {
    pub origin: String,
    /// Line of each point in the file.
    pub lines: Vec<usize>,
    /// Crosshead displacement (mm).
    pub displacement: Vec<f64>,
    /// Force (N).
    pub force: Vec<f64>,
}

/// Which test the curve comes from, with the geometry its normalisation needs (mm).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ShearTest {
    /// Specimen width W and free length H between the clamps, H/W >= 2.
    BiasExtension { width: f64, length: f64 },
    /// Frame side L_frame (pin to pin) and side of the sheared fabric square L_fabric.
    PictureFrame { frame_side: f64, fabric_side: f64 },
}

/// One point of the normalised shear curve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShearPoint {
    /// Shear angle (radians).
    pub gamma: f64,
    /// Normalised shear force (N/mm).
    pub force: f64,
    /// The measured crosshead force it was normalised from (N).
    pub crosshead_force: f64,
    /// Line of the curve point it comes from.
    pub line: usize,
}

/// The fitted shear law.
#[derive(Clone, Debug, PartialEq)]
pub struct ShearFit {
    /// The terms fitted, in the order of the parameters.
    pub terms: Vec<ShearTerm>,
    /// Their coefficients (MPa) with their standard errors and the RMS relative residual.
    pub result: FitResult,
    /// The data's points normalised (`gamma`, `F_sh`), those the fit used (`gamma <=
    /// max_shear`): for plots, and the fitted quantity of a picture frame.
    pub points: Vec<ShearPoint>,
    /// What the fit matched at each of them ([`FittedPoint`]): the crosshead force (N) of a
    /// bias extension, `F_sh` (N/mm) of a picture frame.
    pub fitted: Vec<FittedPoint>,
    /// The fitted quantity and its unit, for tables.
    pub quantity: &'static str,
    /// RMS of `model - data` over the fitted points, in the fitted quantity's unit.
    pub rms: f64,
    /// That RMS over the mean of the data over the fitted points.
    pub rms_of_mean: f64,
    /// That RMS over the range (largest minus smallest) of the data.
    pub rms_of_range: f64,
}

impl ShearFit {
    pub fn law(&self) -> ShearInteraction {
        ShearInteraction::of(&self.terms, &self.result.parameters)
    }
}

/// Columns of a force–displacement curve file.
/// `displacement` and `force` are the columns of `thermostamp test bias-extension` and
/// `picture-frame` histories (mm, N), so a virtual test's curve is fitted as it is written.
const LAYOUT: CurveLayout = CurveLayout {
    x_names: &[DISPLACEMENT_COLUMN, "displacement"],
    y_names: &[FORCE_COLUMN, "force"],
    expected: "displacement_mm (crosshead, mm) and force_N (N), or displacement and force",
    why_increasing: "the normalisation needs a monotonic loading curve",
    why_non_negative: "a shear test pulls, forces are >= 0",
};

/// Reads and checks the force–displacement curve at `path`.
pub fn read_force_curve(path: &Path) -> Result<ForceCurve, InputError> {
    let (origin, text) = read_curve_text(path)?;
    parse_force_curve(&text, &origin)
}

/// Parses and checks the CSV `text` of a force–displacement curve; `origin` names it.
pub fn parse_force_curve(text: &str, origin: &str) -> Result<ForceCurve, InputError> {
    let data = parse_xy_curve(text, origin, &LAYOUT)?;
    if let Some((&d, &line)) = data.x.iter().zip(&data.lines).find(|(&d, _)| d < 0.0) {
        return Err(InputError::at_line(
            origin,
            line,
            format!("{DISPLACEMENT_COLUMN} = {d} is negative: the crosshead pulls from 0"),
        ));
    }
    Ok(ForceCurve {
        origin: origin.to_string(),
        lines: data.lines,
        displacement: data.x,
        force: data.y,
    })
}

impl ShearTest {
    /// Checks the geometry: positive lengths; bias extension with H/W >= 2 (docs/model.md §5).
    pub fn validate(&self) -> Result<(), String> {
        let positive = |name: &str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(format!("{name} = {v} mm: must be a positive length"))
            }
        };
        match *self {
            ShearTest::BiasExtension { width, length } => {
                positive("width", width)?;
                positive("length", length)?;
                check_bias_aspect(width, length)
            }
            ShearTest::PictureFrame {
                frame_side,
                fabric_side,
            } => {
                positive("frame side", frame_side)?;
                positive("fabric side", fabric_side)
            }
        }
    }
}

/// The normalised shear curve of `curve` (points with positive displacement), docs/model.md §5.
/// Errors name the first point past the test's kinematic limit (90° of shear).
pub fn shear_points(curve: &ForceCurve, test: &ShearTest) -> Result<Vec<ShearPoint>, InputError> {
    test.validate()
        .map_err(|m| InputError::in_file(&curve.origin, m))?;
    let loaded: Vec<usize> = (0..curve.displacement.len())
        .filter(|&i| curve.displacement[i] > 0.0)
        .collect();
    for &i in &loaded {
        let gamma = shear_angle(test, curve.displacement[i]);
        if gamma.is_nan() || gamma >= std::f64::consts::FRAC_PI_2 {
            return Err(InputError::at_line(
                &curve.origin,
                curve.lines[i],
                format!(
                    "{DISPLACEMENT_COLUMN} = {} is past the kinematic limit of the test (90° of \
                     shear)",
                    curve.displacement[i]
                ),
            ));
        }
    }
    let values: Vec<(f64, f64)> = match *test {
        ShearTest::BiasExtension { width, length } => {
            let d: Vec<f64> = loaded.iter().map(|&i| curve.displacement[i]).collect();
            let f: Vec<f64> = loaded.iter().map(|&i| curve.force[i]).collect();
            bias_extension_normalised_shear_force(width, length, &d, &f)
        }
        ShearTest::PictureFrame {
            frame_side,
            fabric_side,
        } => loaded
            .iter()
            .map(|&i| {
                let (d, f) = (curve.displacement[i], curve.force[i]);
                let gamma = picture_frame_angles(frame_side, d).1;
                (
                    gamma,
                    picture_frame_normalised_force(frame_side, fabric_side, d, f),
                )
            })
            .collect(),
    };
    Ok(values
        .into_iter()
        .zip(&loaded)
        .map(|((gamma, force), &i)| ShearPoint {
            gamma,
            force,
            crosshead_force: curve.force[i],
            line: curve.lines[i],
        })
        .collect())
}

/// Shear angle of the test at crosshead displacement `d` (radians), docs/model.md §5.
pub fn shear_angle(test: &ShearTest, d: f64) -> f64 {
    match *test {
        ShearTest::BiasExtension { width, length } => bias_extension_shear_angle(width, length, d),
        ShearTest::PictureFrame { frame_side, .. } => picture_frame_angles(frame_side, d).1,
    }
}

/// Share of the largest observed force under which a point's residual is no longer relative.
pub const RELATIVE_FLOOR: f64 = 0.05;

/// One observation the fit matches: the crosshead force (N) of a bias-extension point, or the
/// normalised shear force `F_sh` (N/mm) of a picture-frame point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FittedPoint {
    /// Line of the curve point in the file.
    pub line: usize,
    /// Shear angle of the point (radians).
    pub gamma: f64,
    pub data: f64,
    /// The fitted law's value.
    pub model: f64,
}

/// What the fit matches, per test **(choice)**:
/// - bias extension: the crosshead force itself, through the analytic forward model of a
///   pin-jointed specimen, `F(d) = bias_extension_force(W, H, gamma(d), F_sh)` (Cao et al.
///   2008, docs/model.md §5), linear in the coefficients. Normalising the data instead (the
///   recursion of `shear_points`) needs `F_sh` below the first point, taken proportional to
///   `gamma`; a law with a friction-like term is not, and the fit was off by 3 % on exact data;
/// - picture frame: `F_sh` of each point, which the frame's kinematics give exactly.
///
/// Each row of the returned matrix is `d observation / d coefficient` of one point.
fn observations(
    test: &ShearTest,
    thickness: f64,
    terms: &[ShearTerm],
    points: &[ShearPoint],
) -> (DMatrix<f64>, DVector<f64>) {
    match *test {
        ShearTest::BiasExtension { width, length } => (
            DMatrix::from_fn(points.len(), terms.len(), |i, j| {
                bias_extension_force(width, length, points[i].gamma, |g| {
                    terms[j].force_basis(thickness, g)
                })
            }),
            DVector::from_iterator(points.len(), points.iter().map(|p| p.crosshead_force)),
        ),
        ShearTest::PictureFrame { .. } => (
            DMatrix::from_fn(points.len(), terms.len(), |i, j| {
                terms[j].force_basis(thickness, points[i].gamma)
            }),
            DVector::from_iterator(points.len(), points.iter().map(|p| p.force)),
        ),
    }
}

/// Residuals `(model - data) / max(|data|, floor)` **(choice)**, as in `fit matrix`: load-cell
/// noise is a share of the reading, and equal weights would let the few points near locking
/// decide the whole curve. The floor, 5 % of the largest observation, is wider than the matrix
/// fit's 1 %: bias-extension forces at a few degrees are a few per cent of the final force,
/// where a digitised curve's absolute error (a fraction of the plot's full scale) makes relative
/// errors meaningless. The model is linear, `basis * coefficients`.
struct ShearResiduals {
    basis: DMatrix<f64>,
    data: DVector<f64>,
    scale: DVector<f64>,
}

impl ShearResiduals {
    fn new(basis: DMatrix<f64>, data: DVector<f64>) -> Self {
        let largest = data.iter().map(|d| d.abs()).fold(0.0, f64::max);
        let floor = (RELATIVE_FLOOR * largest).max(f64::MIN_POSITIVE);
        let scale = data.map(|d| d.abs().max(floor));
        Self { basis, data, scale }
    }

    fn model(&self, c: &[f64]) -> DVector<f64> {
        &self.basis * DVector::from_column_slice(c)
    }
}

impl Residuals for ShearResiduals {
    fn observations(&self) -> usize {
        self.data.len()
    }

    fn residuals(&self, c: &DVector<f64>) -> DVector<f64> {
        (self.model(c.as_slice()) - &self.data).component_div(&self.scale)
    }

    fn jacobian(&self, _: &DVector<f64>) -> DMatrix<f64> {
        let mut j = self.basis.clone();
        for (mut row, s) in j.row_iter_mut().zip(self.scale.iter()) {
            row /= *s;
        }
        j
    }
}

/// Why a shear fit failed, naming the data file.
#[derive(Debug, thiserror::Error)]
pub enum ShearFitError {
    #[error(transparent)]
    Input(#[from] InputError),
    #[error("{origin}: {source} ({points} points up to {max_shear_deg}° of shear, {terms} coefficients)")]
    Fit {
        origin: String,
        points: usize,
        terms: usize,
        max_shear_deg: f64,
        source: FitError,
    },
    #[error(
        "{origin}: the force does not vary: {} is {} N at all {points} points up to {}° of \
         shear; there is nothing to fit",
        FORCE_COLUMN,
        crate::limits::shown(*.force),
        crate::limits::shown(*.max_shear_deg)
    )]
    Flat {
        origin: String,
        force: f64,
        points: usize,
        max_shear_deg: f64,
    },
    #[error(
        "{origin}: the fitted law ({law}) gives a shear force that falls as the shear grows at \
         {angle_deg}°, inside the fitted range (up to {max_shear_deg}°): a negative shear \
         stiffness; fit fewer or other terms (--terms), e.g. friction,1,3"
    )]
    Softening {
        origin: String,
        law: String,
        angle_deg: u32,
        max_shear_deg: f64,
    },
    #[error(
        "{origin}: the fitted {term} coefficient is {value:.4e} MPa, negative: the data do not \
         show that term (a {term} term resists shear, it cannot push it on); leave it out of \
         --terms"
    )]
    NegativeTerm {
        origin: String,
        term: String,
        value: f64,
    },
}

/// `name = value` of each term, for messages.
pub fn describe_law(law: &ShearInteraction) -> String {
    law.terms()
        .iter()
        .map(|(term, value)| format!("{} = {value:.4e}", term.name()))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Fits the coefficients of `terms` to the points of `curve` up to `max_shear` (radians), for a
/// fabric layer of thickness `thickness` (mm).
pub fn fit_shear(
    curve: &ForceCurve,
    test: &ShearTest,
    thickness: f64,
    terms: &[ShearTerm],
    max_shear: f64,
) -> Result<ShearFit, ShearFitError> {
    let points: Vec<ShearPoint> = shear_points(curve, test)?
        .into_iter()
        .filter(|p| p.gamma <= max_shear)
        .collect();
    let fail = |source: FitError, n: usize| ShearFitError::Fit {
        origin: curve.origin.clone(),
        points: n,
        terms: terms.len(),
        max_shear_deg: max_shear.to_degrees(),
        source,
    };
    if terms.is_empty() {
        return Err(fail(
            FitError::NotConverged {
                reason: "--terms must name at least one term".into(),
            },
            points.len(),
        ));
    }
    // more points than terms, all of one force: the fit would follow nothing (and its misfit
    // over the data's range would be infinite); fewer points are the fit's own refusal
    let forces: Vec<f64> = points.iter().map(|p| p.crosshead_force).collect();
    if points.len() > terms.len() && !varies(&forces) {
        return Err(ShearFitError::Flat {
            origin: curve.origin.clone(),
            force: forces[0],
            points: points.len(),
            max_shear_deg: max_shear.to_degrees(),
        });
    }
    let (basis, data) = observations(test, thickness, terms, &points);
    let problem = ShearResiduals::new(basis, data);
    let result = fit(&problem, &vec![0.0; terms.len()]).map_err(|e| fail(e, points.len()))?;
    let law = ShearInteraction::of(terms, &result.parameters);
    let max_shear_deg = max_shear.to_degrees();
    if let Some((term, value)) = law.first_negative_constrained() {
        return Err(ShearFitError::NegativeTerm {
            origin: curve.origin.clone(),
            term: term.name(),
            value,
        });
    }
    if let Some(angle_deg) = law.first_softening_degree(max_shear_deg.floor() as u32) {
        return Err(ShearFitError::Softening {
            origin: curve.origin.clone(),
            law: describe_law(&law),
            angle_deg,
            max_shear_deg,
        });
    }
    let model = problem.model(&result.parameters);
    let fitted: Vec<FittedPoint> = points
        .iter()
        .zip(model.iter().zip(problem.data.iter()))
        .map(|(p, (&model, &data))| FittedPoint {
            line: p.line,
            gamma: p.gamma,
            data,
            model,
        })
        .collect();
    let n = fitted.len() as f64;
    let rms = (fitted
        .iter()
        .map(|p| (p.model - p.data).powi(2))
        .sum::<f64>()
        / n)
        .sqrt();
    let mean = fitted.iter().map(|p| p.data).sum::<f64>() / n;
    let (lo, hi) = fitted
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p.data), hi.max(p.data))
        });
    let quantity = match test {
        ShearTest::BiasExtension { .. } => "crosshead force (N)",
        ShearTest::PictureFrame { .. } => "normalised shear force F_sh (N/mm)",
    };
    Ok(ShearFit {
        terms: terms.to_vec(),
        quantity,
        rms,
        rms_of_mean: rms / mean.abs().max(f64::MIN_POSITIVE),
        rms_of_range: rms / (hi - lo).max(f64::MIN_POSITIVE),
        fitted,
        result,
        points,
    })
}

/// The polynomial terms `c_1..c_m`.
pub fn polynomial_terms(m: u32) -> Vec<ShearTerm> {
    (1..=m).map(ShearTerm::Power).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiment::kinematics::{bias_extension_displacement, bias_extension_force};

    fn error(text: &str) -> String {
        parse_force_curve(text, "b.csv").unwrap_err().to_string()
    }

    #[test]
    fn bad_curves_name_file_and_line() {
        assert_eq!(error(""), "b.csv: the file is empty");
        assert!(error("displacement_mm,force_N\n").contains("no data rows"));
        let e = error("displacement_mm,force_N\n0,0\n2,1\n1,2\n");
        assert!(
            e.starts_with("b.csv: line 4: displacement_mm = 1 does not increase"),
            "{e}"
        );
        let e = error("displacement_mm,force_N\n0,0\n1,-0.5\n");
        assert!(
            e.starts_with("b.csv: line 3: force_N = -0.5 is negative"),
            "{e}"
        );
        assert_eq!(
            error("displacement_mm,force_N\n-1,0\n0,1\n"),
            "b.csv: line 2: displacement_mm = -1 is negative: the crosshead pulls from 0"
        );
        let e = error("d,force_N\n0,0\n");
        assert!(e.starts_with("b.csv: line 1: header 'd,force_N'"), "{e}");
    }

    #[test]
    fn short_specimens_and_too_few_points_are_errors() {
        let curve = parse_force_curve("displacement_mm,force_N\n1,1\n2,2\n3,3\n", "b.csv").unwrap();
        let short = ShearTest::BiasExtension {
            width: 150.0,
            length: 250.0,
        };
        let e = fit_shear(&curve, &short, 1.0, &polynomial_terms(3), 1.0)
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("b.csv: length/width = 1.66667"), "{e}");
        let e = ShearTest::BiasExtension {
            width: 150.0,
            length: 299.9999,
        }
        .validate()
        .unwrap_err();
        assert!(e.starts_with("length/width = 1.999999:"), "{e}");
        let test = ShearTest::BiasExtension {
            width: 150.0,
            length: 450.0,
        };
        let e = fit_shear(&curve, &test, 1.0, &polynomial_terms(3), 1.0)
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("b.csv: 3 data points for 3 parameters"),
            "{e}"
        );
        let far = parse_force_curve("displacement_mm,force_N\n1,1\n200,2\n", "b.csv").unwrap();
        let e = fit_shear(&far, &test, 1.0, &polynomial_terms(1), 1.0)
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("b.csv: line 3: displacement_mm = 200 is past"),
            "{e}"
        );
    }

    /// A curve of one force, zero or not, is refused as flat, not fitted to an infinite misfit
    /// over its range.
    #[test]
    fn constant_force_is_refused_as_flat() {
        let test = ShearTest::BiasExtension {
            width: 150.0,
            length: 450.0,
        };
        for force in [5.0, 0.0] {
            let mut text = String::from("displacement_mm,force_N\n");
            for d in 0..40 {
                text.push_str(&format!("{d},{force}\n"));
            }
            let curve = parse_force_curve(&text, "flat.csv").unwrap();
            let e = fit_shear(&curve, &test, 1.0, &polynomial_terms(1), 50f64.to_radians())
                .unwrap_err()
                .to_string();
            assert!(e.starts_with("flat.csv: the force does not vary"), "{e}");
            assert!(e.contains(&format!("is {force} N at all")), "{e}");
        }
    }

    /// A bias curve made from known `c_k` by the forward Cao formula gives them back.
    #[test]
    fn noiseless_bias_curve_round_trip() {
        let truth = ShearInteraction::new(vec![0.004, 0.002, 0.03]);
        let t = 1.2;
        let (w, h) = (150.0, 450.0);
        let d_max = bias_extension_displacement(w, h, 55f64.to_radians());
        let n = 120;
        let mut text = String::from("displacement_mm,force_N\n0,0\n");
        for i in 1..=n {
            let d = d_max * f64::from(i) / f64::from(n);
            let g = bias_extension_shear_angle(w, h, d);
            let f = bias_extension_force(w, h, g, |g| truth.normalised_shear_force(t, g));
            text.push_str(&format!("{d},{f}\n"));
        }
        let curve = parse_force_curve(&text, "synthetic.csv").unwrap();
        let test = ShearTest::BiasExtension {
            width: w,
            length: h,
        };
        let fitted = fit_shear(&curve, &test, t, &polynomial_terms(3), 50f64.to_radians()).unwrap();
        let law = fitted.law();
        for g in [10.0, 20.0, 30.0, 40.0, 50.0] {
            let g = f64::to_radians(g);
            let (a, b) = (
                law.normalised_shear_force(t, g),
                truth.normalised_shear_force(t, g),
            );
            assert!((a - b).abs() < 0.01 * b, "{}°: {a} vs {b}", g.to_degrees());
        }
    }
}
