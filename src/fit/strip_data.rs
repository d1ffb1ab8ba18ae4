//! Strip (uniaxial) tension curves of the prepreg along warp or weft for
//! `thermostamp fit fabric-tension` (docs/model.md §5). Every error names the file, and the line
//! where there is one.
//!
//! CSV: a header naming one of `strain` (engineering, `d / L0`) or `stretch` (`1 + strain`),
//! and one of `force_per_width` (N/mm, the force over the reference width) or `force` (N, then
//! the specimen width is given separately and the force divided by it).

use crate::io::xy_curve::{parse_xy_curve, read_curve_text, CurveLayout};
use crate::io::InputError;
use std::path::Path;

/// One strip curve: stretch along the pull and force per unit reference width.
#[derive(Clone, Debug, PartialEq)]
pub struct StripCurve {
    /// The CSV file, as given in messages.
    pub origin: String,
    pub stretch: Vec<f64>,
    /// `F / W`, N/mm.
    pub force_per_width: Vec<f64>,
}

impl StripCurve {
    /// Indices of the points in tension (`lambda > 1`), the only ones that carry the `A_k`.
    pub fn tensile_points(&self) -> Vec<usize> {
        (0..self.stretch.len())
            .filter(|&i| self.stretch[i] > 1.0)
            .collect()
    }
}

/// Columns of a strip curve file (see the module's documentation).
const LAYOUT: CurveLayout = CurveLayout {
    x_names: &["strain", "stretch"],
    y_names: &["force_per_width", "force"],
    expected: "strain or stretch, and force_per_width (N/mm) or force (N, with --width)",
    why_increasing: "a strip test must stretch monotonically",
    why_non_negative: "tension curves have forces >= 0",
};

/// Reads the strip curve at `path`; `width` (mm) converts a `force` column.
pub fn read_strip_curve(path: &Path, width: Option<f64>) -> Result<StripCurve, InputError> {
    let (origin, text) = read_curve_text(path)?;
    parse_strip_curve(&text, &origin, width)
}

/// Parses and checks the CSV `text` of one strip curve; `origin` names it in messages.
pub fn parse_strip_curve(
    text: &str,
    origin: &str,
    width: Option<f64>,
) -> Result<StripCurve, InputError> {
    let data = parse_xy_curve(text, origin, &LAYOUT)?;
    let x_name = data.x_name;
    let divisor = force_divisor(data.y_name, width, origin)?;
    let curve = StripCurve {
        origin: origin.to_string(),
        stretch: data.stretch(origin)?,
        force_per_width: data.y.iter().map(|y| y / divisor).collect(),
    };
    if curve.tensile_points().is_empty() {
        return Err(InputError::in_file(
            origin,
            format!(
                "no point with {x_name} > {}: compression-only data say nothing of the yarn \
                 tension coefficients",
                if x_name == "strain" { 0 } else { 1 }
            ),
        ));
    }
    Ok(curve)
}

/// 1 for `force_per_width`; the width for `force`, which then must be given.
fn force_divisor(y_name: &str, width: Option<f64>, origin: &str) -> Result<f64, InputError> {
    match (y_name, width) {
        ("force_per_width", _) => Ok(1.0),
        (_, Some(w)) if w.is_finite() && w > 0.0 => Ok(w),
        (_, Some(w)) => Err(InputError::in_file(
            origin,
            format!("--width {w}: must be a positive width (mm)"),
        )),
        (_, None) => Err(InputError::in_file(
            origin,
            "the force column is in N: give the specimen width with --width (mm), or a \
             force_per_width column (N/mm)",
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn error(text: &str) -> String {
        parse_strip_curve(text, "w.csv", None)
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn reads_strain_or_stretch_and_force_per_width_or_force() {
        let a = parse_strip_curve("strain,force_per_width\n0,0\n0.01,2\n", "w.csv", None).unwrap();
        assert_eq!(a.stretch, vec![1.0, 1.01]);
        assert_eq!(a.force_per_width, vec![0.0, 2.0]);
        assert_eq!(a.tensile_points(), vec![1]);
        let b = parse_strip_curve("force,stretch\n0,1\n50,1.01\n", "w.csv", Some(25.0)).unwrap();
        assert_eq!(b.stretch, vec![1.0, 1.01]);
        assert_eq!(b.force_per_width, vec![0.0, 2.0]);
    }

    #[test]
    fn bad_curves_name_file_and_line() {
        assert_eq!(error(""), "w.csv: the file is empty");
        assert!(error("strain,force_per_width\n").contains("no data rows"));
        let e = error("strain,force_per_width\n0,0\n0.02,1\n0.01,2\n");
        assert!(
            e.starts_with("w.csv: line 4: strain = 0.01 does not increase"),
            "{e}"
        );
        let e = error("strain,force_per_width\n0,0\n0.02,-1\n");
        assert!(
            e.starts_with("w.csv: line 3: force_per_width = -1 is negative"),
            "{e}"
        );
        let e = error("strain,force_per_width\n-0.02,0\n-0.01,0\n0,0\n");
        assert!(
            e.starts_with("w.csv: no point with strain > 0: compression-only"),
            "{e}"
        );
        let e = error("stretch,force\n1,0\n1.01,5\n");
        assert!(e.contains("give the specimen width with --width"), "{e}");
        let e = error("x,force\n0,0\n");
        assert!(e.starts_with("w.csv: line 1: header 'x,force'"), "{e}");
    }
}
