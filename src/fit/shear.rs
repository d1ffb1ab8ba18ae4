//! Shear coefficients `c_k` of the fabric's interaction energy `W_s(I10) = sum c_k I10^k`
//! (docs/model.md §3) from a bias-extension or picture-frame force–displacement curve
//! (docs/model.md §5).
//!
//! 1. The curve is read and checked point by point (every error names the file and line).
//! 2. Each point becomes `(gamma, F_sh)`: for a bias-extension test the pin-jointed angle of
//!    the central zone and the normalised shear force of Cao et al. 2008, solved recursively
//!    from small angles (docs/model.md §5, `experiment::kinematics`); for a picture frame the
//!    frame's angle and `F_norm = F L_frame / (2 cos(theta) L_fabric^2)` (docs/model.md §5).
//! 3. `c_1..c_m` are fitted to `F_sh(gamma) = 2 t_B sin(gamma) W_s'(sin^2 gamma)` (docs/model.md
//!    §5, last bullet) up to a largest angle, by Levenberg–Marquardt (`least_squares`).
//!
//! The model is linear in `c_k`; LM is used anyway for its standard errors and checks, started
//! from zero.

use super::least_squares::{fit, FitError, FitResult, Residuals};
use crate::experiment::kinematics::{
    bias_extension_normalised_shear_force, bias_extension_shear_angle, picture_frame_angles,
    picture_frame_normalised_force,
};
use crate::io::xy_curve::{parse_xy_curve, read_curve_text, CurveLayout};
use crate::io::InputError;
use crate::material::fabric::ShearInteraction;
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
    /// Line of the curve point it comes from.
    pub line: usize,
}

/// The fitted shear law.
#[derive(Clone, Debug, PartialEq)]
pub struct ShearFit {
    /// `c_1..c_m` (MPa) with their standard errors and the RMS relative residual.
    pub result: FitResult,
    /// The points the fit used (`gamma <= max_shear`).
    pub points: Vec<ShearPoint>,
    /// RMS of `F_model - F_data` over the fitted points (N/mm).
    pub rms_force: f64,
}

impl ShearFit {
    pub fn law(&self) -> ShearInteraction {
        ShearInteraction::new(self.result.parameters.clone())
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
                if length < 2.0 * width {
                    return Err(format!(
                        "length/width = {:.3}: the bias-extension kinematics (docs/model.md §5) \
                         needs a free length of at least twice the width",
                        length / width
                    ));
                }
                Ok(())
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

/// `d F_sh / d c_k = 2 t sin(g) k sin^(2(k-1))(g)` at shear angle `g` (radians) for fabric
/// layers of total thickness `t` (mm), `k` from 1: the model `F_sh = 2 t sin(g) W_s'(sin^2 g)`
/// of docs/model.md §5 is linear in the coefficients, so `F_sh = sum_k c_k basis(t, g, k)`. The
/// analytic fit's Jacobian here, and through Cao's forward model the surrogate Jacobian of the
/// FE refinement (`shear_fe`).
pub(crate) fn basis(thickness: f64, gamma: f64, k: usize) -> f64 {
    let s = gamma.sin();
    2.0 * thickness * s * k as f64 * (s * s).powi(k as i32 - 1)
}

/// Share of the largest normalised shear force under which a point's residual is no longer
/// relative.
pub const RELATIVE_FLOOR: f64 = 0.05;

/// Residuals `(F_model - F_data) / max(|F_data|, floor)` **(choice)**, as in `fit matrix`:
/// load-cell noise is a share of the reading, and equal weights would let the few points near
/// locking decide the whole curve. The floor, 5 % of the largest fitted `F_sh`, is wider than
/// the matrix fit's 1 %: bias-extension forces at a few degrees are a few per cent of the
/// final force, where a digitised curve's absolute error (a fraction of the plot's full scale)
/// and the recursion's start (`F_sh` taken proportional to `gamma` below the first point)
/// make relative errors meaningless.
struct ShearResiduals {
    thickness: f64,
    terms: usize,
    gamma: Vec<f64>,
    force: Vec<f64>,
    scale: Vec<f64>,
}

impl ShearResiduals {
    fn new(thickness: f64, terms: usize, points: &[ShearPoint]) -> Self {
        let largest = points.iter().map(|p| p.force.abs()).fold(0.0, f64::max);
        let floor = (RELATIVE_FLOOR * largest).max(f64::MIN_POSITIVE);
        Self {
            thickness,
            terms,
            gamma: points.iter().map(|p| p.gamma).collect(),
            force: points.iter().map(|p| p.force).collect(),
            scale: points.iter().map(|p| p.force.abs().max(floor)).collect(),
        }
    }

    fn model(&self, c: &[f64], gamma: f64) -> f64 {
        (1..=self.terms)
            .map(|k| c[k - 1] * basis(self.thickness, gamma, k))
            .sum()
    }
}

impl Residuals for ShearResiduals {
    fn observations(&self) -> usize {
        self.gamma.len()
    }

    fn residuals(&self, c: &DVector<f64>) -> DVector<f64> {
        DVector::from_fn(self.gamma.len(), |i, _| {
            (self.model(c.as_slice(), self.gamma[i]) - self.force[i]) / self.scale[i]
        })
    }

    fn jacobian(&self, _: &DVector<f64>) -> DMatrix<f64> {
        DMatrix::from_fn(self.gamma.len(), self.terms, |i, j| {
            basis(self.thickness, self.gamma[i], j + 1) / self.scale[i]
        })
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
}

/// Fits `terms` coefficients `c_1..c_m` to the points of `curve` up to `max_shear` (radians),
/// for a fabric layer of thickness `thickness` (mm).
pub fn fit_shear(
    curve: &ForceCurve,
    test: &ShearTest,
    thickness: f64,
    terms: usize,
    max_shear: f64,
) -> Result<ShearFit, ShearFitError> {
    let points: Vec<ShearPoint> = shear_points(curve, test)?
        .into_iter()
        .filter(|p| p.gamma <= max_shear)
        .collect();
    let fail = |source: FitError, n: usize| ShearFitError::Fit {
        origin: curve.origin.clone(),
        points: n,
        terms,
        max_shear_deg: max_shear.to_degrees(),
        source,
    };
    if terms == 0 {
        return Err(fail(
            FitError::NotConverged {
                reason: "--terms must be at least 1".into(),
            },
            points.len(),
        ));
    }
    let problem = ShearResiduals::new(thickness, terms, &points);
    let result = fit(&problem, &vec![0.0; terms]).map_err(|e| fail(e, points.len()))?;
    let ssr: f64 = points
        .iter()
        .map(|p| (problem.model(&result.parameters, p.gamma) - p.force).powi(2))
        .sum();
    Ok(ShearFit {
        rms_force: (ssr / points.len() as f64).sqrt(),
        result,
        points,
    })
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
        let e = fit_shear(&curve, &short, 1.0, 3, 1.0)
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("b.csv: length/width = 1.667"), "{e}");
        let test = ShearTest::BiasExtension {
            width: 150.0,
            length: 450.0,
        };
        let e = fit_shear(&curve, &test, 1.0, 3, 1.0)
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("b.csv: 3 data points for 3 parameters"),
            "{e}"
        );
        let far = parse_force_curve("displacement_mm,force_N\n1,1\n200,2\n", "b.csv").unwrap();
        let e = fit_shear(&far, &test, 1.0, 1, 1.0).unwrap_err().to_string();
        assert!(
            e.starts_with("b.csv: line 3: displacement_mm = 200 is past"),
            "{e}"
        );
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
        let fitted = fit_shear(&curve, &test, t, 3, 50f64.to_radians()).unwrap();
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
