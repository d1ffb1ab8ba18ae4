//! The shipped Twintex card against the curve it was fitted to (issue 16): the FE bias-extension
//! test of `materials/twintex-plain-weave.toml` (its friction-like shear term and `c_1`, `c_3`)
//! reproduces the Cao et al. 2008 benchmark curve (150 x 450 mm) within 5 % RMS of the mean
//! measured force over 2–35° of pin-jointed shear, and within 10 % at every point above 5°.
//!
//! The test runs as a user runs `thermostamp test bias-extension` on the card with its default
//! mesh (15 mm crossed cells, ten across the width; converged, `tests/virtual_bias_extension.rs`)
//! and the implicit solver at the benchmark's 20 mm/min (a dry fabric has no rate dependence).
//! Measured: 4.45 % RMS, the worst point above 5° 8.3 % off (7.8°, where the data rise
//! quickly to a short plateau); on 7.5 mm cells 4.41 % and 7.6 %; the explicit solver with the
//! test's defaults within 0.35 % of the implicit force (100 x 200 mm, 10 mm cells).

mod common;

use common::repo_path;
use thermostamp::experiment::kinematics::bias_extension_shear_angle;
use thermostamp::experiment::sheet_test::SheetTest;
use thermostamp::fit::shear::read_force_curve;
use thermostamp::material::MaterialCard;

const DATA: &str = "examples/fit-shear/bias_extension_glass_pp_plain_150x450.csv";
const CARD: &str = "materials/twintex-plain-weave.toml";
const RANGE_DEG: (f64, f64) = (2.0, 35.0);

/// Linear interpolation of `(x, y)` rows increasing in `x`.
fn interpolate(rows: &[(f64, f64)], x: f64) -> f64 {
    let i = rows.partition_point(|r| r.0 < x).clamp(1, rows.len() - 1);
    let ((x0, y0), (x1, y1)) = (rows[i - 1], rows[i]);
    y0 + (y1 - y0) * (x - x0) / (x1 - x0)
}

#[test]
fn fe_bias_extension_with_the_shipped_card_reproduces_the_benchmark_curve() {
    let card = MaterialCard::load(&repo_path(CARD)).unwrap();
    assert!(
        card.fabric.shear.friction().is_some(),
        "the card lost its friction-like term"
    );
    let data = read_force_curve(&repo_path(DATA)).unwrap();
    // the benchmark specimen, pulled just past 35° of pin-jointed shear
    let test = common::implicit_bias_test((150.0, 450.0), 20.0, 1.0, RANGE_DEG.1 + 1.0, 80);
    let run = test.run(&card.laminate, card.density, None, None).unwrap();
    assert!(run.run.outcome.is_ok(), "{:?}", run.run.outcome.err());
    let fe: Vec<(f64, f64)> = run.rows.iter().map(|r| (r.displacement, r.force)).collect();
    // (shear angle in degrees, data, FE) over the range
    let points: Vec<(f64, f64, f64)> = data
        .displacement
        .iter()
        .zip(&data.force)
        .map(|(&d, &f)| {
            let gamma = bias_extension_shear_angle(150.0, 450.0, d).to_degrees();
            (gamma, f, interpolate(&fe, d))
        })
        .filter(|p| (RANGE_DEG.0..=RANGE_DEG.1).contains(&p.0))
        .collect();
    let n = points.len() as f64;
    let mean = points.iter().map(|p| p.1).sum::<f64>() / n;
    let rms = (points.iter().map(|p| (p.2 - p.1).powi(2)).sum::<f64>() / n).sqrt();
    for (gamma, f, model) in &points {
        println!(
            "{gamma:5.1}°: data {f:7.3} N, FE {model:7.3} N, {:+5.1} %",
            100.0 * (model - f) / f
        );
    }
    println!(
        "{} points over {:?}°: RMS {rms:.3} N = {:.2} % of the mean {mean:.2} N",
        points.len(),
        RANGE_DEG,
        100.0 * rms / mean
    );
    assert!(points.len() > 30, "{} points", points.len());
    assert!(
        rms < 0.05 * mean,
        "RMS {:.2} % of the mean",
        100.0 * rms / mean
    );
    for (gamma, f, model) in points.iter().filter(|p| p.0 > 5.0) {
        assert!(
            (model - f).abs() < 0.10 * f,
            "{gamma:.1}°: FE {model:.3} N against {f:.3} N"
        );
    }
}
