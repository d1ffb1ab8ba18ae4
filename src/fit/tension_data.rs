//! Neat-resin uniaxial tension curves for `thermostamp fit matrix`: a TOML manifest lists one
//! CSV file per (temperature, strain rate). Every error names the file, and the line where
//! there is one.
//!
//! Manifest (paths relative to the manifest; unknown keys are errors):
//! ```toml
//! [[curve]]
//! file = "pps-280C-slow.csv"
//! temperature = 280.0        # °C
//! strain_rate = 0.01         # 1/s, engineering: crosshead speed / gauge length
//! [[curve]]
//! file = "pps-280C-fast.csv"
//! temperature = 280.0
//! crosshead_speed = 2.0      # mm/s   (instead of strain_rate,
//! gauge_length = 20.0        # mm      with the gauge length)
//! ```
//! CSV: a header naming one of `strain` (engineering, `d / L0`) or `stretch` (`1 + strain`),
//! and one of `stress` (true, Cauchy stress, MPa, the sigma11 of docs/model.md §5) or
//! `nominal_stress` (force over the initial section, MPa; converted with incompressibility,
//! `sigma = lambda * P`).

use crate::io::xy_curve::{parse_xy_curve, read_curve_text, CurveLayout};
use crate::io::{from_toml_text, InputError};
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// One tension curve at constant crosshead speed, in the form the model uses.
#[derive(Clone, Debug, PartialEq)]
pub struct TensionCurve {
    /// The CSV file, as given in messages.
    pub origin: String,
    pub temperature: f64,
    /// `lambdadot = v / L0`, constant at constant crosshead speed (1/s).
    pub strain_rate: f64,
    pub stretch: Vec<f64>,
    /// True (Cauchy) stress, MPa.
    pub stress: Vec<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Manifest {
    curve: Vec<CurveEntry>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CurveEntry {
    file: PathBuf,
    temperature: f64,
    strain_rate: Option<f64>,
    crosshead_speed: Option<f64>,
    gauge_length: Option<f64>,
}

/// Reads the manifest at `path` and every curve it lists.
pub fn read_manifest(path: &Path) -> Result<Vec<TensionCurve>, InputError> {
    let origin = path.display().to_string();
    let text = std::fs::read_to_string(path)
        .map_err(|e| InputError::in_file(&origin, format!("cannot read the manifest: {e}")))?;
    let manifest: Manifest = from_toml_text(&text).map_err(|e| InputError::in_file(&origin, e))?;
    if manifest.curve.is_empty() {
        return Err(InputError::in_file(
            &origin,
            "the manifest lists no [[curve]]",
        ));
    }
    let base = path.parent().unwrap_or_else(|| Path::new(""));
    manifest
        .curve
        .iter()
        .enumerate()
        .map(|(i, entry)| {
            let spec = CurveSpec {
                temperature: entry.temperature,
                strain_rate: entry.strain_rate,
                crosshead_speed: entry.crosshead_speed,
                gauge_length: entry.gauge_length,
            };
            let label = entry.file.display().to_string();
            manifest_curve(&origin, (i + 1, &label), &spec, |t, rate| {
                read_curve(&base.join(&entry.file), t, rate)
            })
        })
        .collect()
}

/// The conditions of one curve of a manifest: its temperature (°C) and its strain rate,
/// given (1/s) or as `crosshead_speed` (mm/s) over `gauge_length` (mm).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CurveSpec {
    pub temperature: f64,
    pub strain_rate: Option<f64>,
    pub crosshead_speed: Option<f64>,
    pub gauge_length: Option<f64>,
}

/// Checks the conditions of the `index`-th curve (from 1, `label` its file) of the manifest
/// `origin` and reads it with `read(temperature, strain_rate)`.
pub fn manifest_curve(
    origin: &str,
    (index, label): (usize, &str),
    spec: &CurveSpec,
    read: impl FnOnce(f64, f64) -> Result<TensionCurve, InputError>,
) -> Result<TensionCurve, InputError> {
    let at = |message: String| {
        InputError::in_file(origin, format!("[[curve]] #{index} ({label}): {message}"))
    };
    let rate = strain_rate(spec).map_err(at)?;
    if !spec.temperature.is_finite() {
        return Err(at("temperature must be a finite number of °C".into()));
    }
    read(spec.temperature, rate)
}

/// `strain_rate`, or `crosshead_speed / gauge_length`; exactly one of the two forms.
fn strain_rate(entry: &CurveSpec) -> Result<f64, String> {
    let rate = match (entry.strain_rate, entry.crosshead_speed, entry.gauge_length) {
        (Some(rate), None, None) => rate,
        (None, Some(speed), Some(length)) => {
            if !(length.is_finite() && length > 0.0) {
                return Err(format!(
                    "gauge_length = {length}: must be a positive length (mm)"
                ));
            }
            speed / length
        }
        (None, None, None) => {
            return Err(
                "give strain_rate (1/s) or crosshead_speed (mm/s) and gauge_length (mm)".into(),
            )
        }
        (Some(_), _, _) => {
            return Err("give strain_rate or crosshead_speed and gauge_length, not both".into())
        }
        _ => return Err("crosshead_speed and gauge_length go together".into()),
    };
    if rate.is_finite() && rate > 0.0 {
        Ok(rate)
    } else {
        Err(format!(
            "strain rate {rate} 1/s: must be positive (a tension test)"
        ))
    }
}

/// Columns of a tension curve file (see the module's documentation).
const LAYOUT: CurveLayout = CurveLayout {
    x_names: &["strain", "stretch"],
    y_names: &["stress", "nominal_stress"],
    expected: "strain or stretch, and stress (true, MPa) or nominal_stress (MPa)",
    why_increasing: "a curve at constant crosshead speed must stretch monotonically",
    why_non_negative: "tension curves have stresses >= 0",
};

/// Reads one curve file and checks it point by point.
pub fn read_curve(
    path: &Path,
    temperature: f64,
    strain_rate: f64,
) -> Result<TensionCurve, InputError> {
    let (origin, text) = read_curve_text(path)?;
    parse_curve(&text, &origin, temperature, strain_rate)
}

/// Parses and checks the CSV `text` of one curve; `origin` names it in messages.
pub fn parse_curve(
    text: &str,
    origin: &str,
    temperature: f64,
    strain_rate: f64,
) -> Result<TensionCurve, InputError> {
    let data = parse_xy_curve(text, origin, &LAYOUT)?;
    let stretch = data.stretch(origin)?;
    // Incompressible: the section shrinks as 1/lambda, so sigma = lambda P.
    let stress = if data.y_name == "nominal_stress" {
        stretch.iter().zip(&data.y).map(|(l, p)| l * p).collect()
    } else {
        data.y
    };
    Ok(TensionCurve {
        origin: origin.to_string(),
        temperature,
        strain_rate,
        stretch,
        stress,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn error(text: &str) -> String {
        parse_curve(text, "c.csv", 300.0, 0.01)
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn reads_strain_or_stretch_and_true_or_nominal_stress() {
        let a = parse_curve("strain,stress\n0,0\n0.5,1.5\n", "c.csv", 300.0, 0.01).unwrap();
        assert_eq!(a.stretch, vec![1.0, 1.5]);
        assert_eq!(a.stress, vec![0.0, 1.5]);
        let b = parse_curve("nominal_stress,stretch\n0,1\n1,1.5\n", "c.csv", 300.0, 0.01).unwrap();
        assert_eq!(b.stretch, vec![1.0, 1.5]);
        assert_eq!(b.stress, vec![0.0, 1.5]);
    }

    #[test]
    fn bad_curves_name_file_and_line() {
        assert_eq!(error(""), "c.csv: the file is empty");
        assert_eq!(error("  \n\n"), "c.csv: the file is empty");
        assert!(error("strain,stress\n").contains("no data rows"));
        assert_eq!(
            error("strain,stress\n0,0\n0.1,x\n"),
            "c.csv: line 3: column 'stress': 'x' is not a finite number"
        );
        let e = error("strain,stress\n0,0\n0.2,1\n0.1,2\n");
        assert!(
            e.starts_with("c.csv: line 4: strain = 0.1 does not increase"),
            "{e}"
        );
        let e = error("strain,stress\n0,0\n0.2,-1\n");
        assert!(
            e.starts_with("c.csv: line 3: stress = -1 is negative"),
            "{e}"
        );
        assert_eq!(
            error("strain,stress\n-1,0\n0,1\n"),
            "c.csv: line 2: strain = -1: the stretch must be positive"
        );
        let e = error("x,stress\n0,0\n");
        assert!(e.starts_with("c.csv: line 1: header 'x,stress'"), "{e}");
    }
}
