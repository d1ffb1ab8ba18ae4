//! `fit shear` round trips (docs/model.md §5): bias-extension curves made from known laws by the
//! forward form of Cao's normalisation (`fit::synthetic::bias_extension_curve`) give the
//! coefficients back — within 1 % without noise, within two reported standard errors with 2 %
//! multiplicative noise on the force — for every kind of term of `W_s` (docs/model.md §3): the
//! polynomial, the friction-like term and the locking term.

use thermostamp::fit::shear::{fit_shear, parse_force_curve, ShearFit, ShearTest};
use thermostamp::fit::synthetic::{bias_extension_curve, Lcg};
use thermostamp::material::fabric::{ShearInteraction, ShearTerm};

const THICKNESS: f64 = 1.2;
const SPECIMEN: ShearTest = ShearTest::BiasExtension {
    width: 150.0,
    length: 450.0,
};

/// The laws of the round trips (MPa, on a 1.2 mm layer, the 150 x 450 mm benchmark specimen):
/// a Twintex-like polynomial; a friction-like plateau that stiffens (`c_3`); the same with
/// locking from 40°.
fn laws() -> Vec<(&'static str, ShearInteraction)> {
    let locking = ShearTerm::Locking {
        angle: 40f64.to_radians(),
    };
    vec![
        (
            "polynomial",
            ShearInteraction::new(vec![0.004, 0.002, 0.03]),
        ),
        (
            "friction",
            ShearInteraction::from_terms(vec![
                (ShearTerm::friction(), 0.004),
                (ShearTerm::Power(1), 0.002),
                (ShearTerm::Power(3), 0.03),
            ]),
        ),
        (
            "friction and locking",
            ShearInteraction::from_terms(vec![
                (ShearTerm::friction(), 0.004),
                (ShearTerm::Power(1), 0.004),
                (locking, 0.3),
            ]),
        ),
    ]
}

/// The curve of `law` up to 52° (60 points, noise `noise`), fitted with the law's own terms up
/// to 50°.
fn fitted(law: &ShearInteraction, noise: f64, seed: u64) -> ShearFit {
    let text = bias_extension_curve(
        law,
        THICKNESS,
        (150.0, 450.0),
        (52f64.to_radians(), 60),
        noise,
        &mut Lcg::new(seed),
    );
    let curve = parse_force_curve(&text, "synthetic.csv").unwrap();
    fit_shear(
        &curve,
        &SPECIMEN,
        THICKNESS,
        &law.shapes(),
        50f64.to_radians(),
    )
    .unwrap()
}

#[test]
fn noiseless_curve_gives_the_coefficients_within_one_percent() {
    for (name, law) in laws() {
        let fit = fitted(&law, 0.0, 1);
        for ((term, c), truth) in fit
            .terms
            .iter()
            .zip(&fit.result.parameters)
            .zip(law.values())
        {
            let error = (c - truth).abs() / truth;
            println!(
                "{name}, {}: {c:.6e}, truth {truth:.6e}, error {:.3} %",
                term.name(),
                100.0 * error
            );
            assert!(error < 0.01, "{name}: {:?}", fit.result);
        }
    }
}

#[test]
fn noisy_curve_gives_the_coefficients_within_two_standard_errors() {
    for (name, law) in laws() {
        let fit = fitted(&law, 0.02, 2018);
        for (((term, c), se), truth) in fit
            .terms
            .iter()
            .zip(&fit.result.parameters)
            .zip(&fit.result.standard_errors)
            .zip(law.values())
        {
            println!(
                "{name}, {}: {c:.4e} ± {se:.2e}, truth {truth:.4e}: {:.2} se",
                term.name(),
                (c - truth) / se
            );
            assert!((c - truth).abs() < 2.0 * se, "{name}: {:?}", fit.result);
        }
    }
}

/// Over many seeds, how often the truth lies within two standard errors (every coefficient
/// counted). Cao's recursion couples each point to the one at half its angle, so the residuals
/// are not quite independent; the count shows how far the linearised standard errors still
/// hold.
#[test]
fn standard_errors_cover_the_truth_over_many_seeds() {
    for (name, law) in laws() {
        let (mut inside, mut total) = (0, 0);
        for seed in 0..40 {
            let fit = fitted(&law, 0.02, seed);
            for ((c, se), truth) in fit
                .result
                .parameters
                .iter()
                .zip(&fit.result.standard_errors)
                .zip(law.values())
            {
                total += 1;
                inside += usize::from((c - truth).abs() < 2.0 * se);
            }
        }
        let share = inside as f64 / total as f64;
        println!(
            "{name}: coverage at 2 se: {inside}/{total} = {:.1} %",
            100.0 * share
        );
        assert!(share > 0.8, "{name}: {inside} of {total}");
    }
}

/// Picture frame (docs/model.md §5): a curve made from the law by the frame's kinematics,
/// `theta = arccos((sqrt 2 L + d) / (2 L))`, `gamma = 90° - 2 theta`, and its force,
/// `F = 2 cos(theta) F_sh(gamma) L_fabric^2 / L_frame`, gives the coefficients back within 1 %.
#[test]
fn picture_frame_curve_gives_the_coefficients_within_one_percent() {
    let (frame_side, fabric_side) = (145.0, 120.0);
    let test = ShearTest::PictureFrame {
        frame_side,
        fabric_side,
    };
    for (name, law) in laws() {
        let mut text = String::from("displacement_mm,force_N\n0,0\n");
        for i in 1..=60 {
            let d = 60.0 * i as f64 / 60.0;
            let theta = ((2f64.sqrt() * frame_side + d) / (2.0 * frame_side)).acos();
            let gamma = std::f64::consts::FRAC_PI_2 - 2.0 * theta;
            let force = 2.0
                * theta.cos()
                * law.normalised_shear_force(THICKNESS, gamma)
                * fabric_side
                * fabric_side
                / frame_side;
            text.push_str(&format!("{d},{force}\n"));
        }
        let curve = parse_force_curve(&text, "frame.csv").unwrap();
        let fit = fit_shear(&curve, &test, THICKNESS, &law.shapes(), 50f64.to_radians()).unwrap();
        for (c, truth) in fit.result.parameters.iter().zip(law.values()) {
            assert!((c - truth).abs() < 0.01 * truth, "{name}: {:?}", fit.result);
        }
    }
}
