//! `fit shear` on a prepreg (issue 5, docs/model.md §5): the matrix layers' share of a shear test's
//! force is subtracted before the fabric's law is fitted.
//!
//! The data are made by the FE picture-frame test (`experiment::picture_frame`), whose sheet
//! shears homogeneously, so the only difference between the data and the fit's model is the
//! subtraction under test: the fit must give back the card's fabric shear law, and fitting the
//! raw force instead must not. Two cards: the viscous test prepreg (eta1 = 5 MPa·s, its matrix
//! force largely viscous at the test's 20 mm/min), and through the command line the shipped
//! T300/PPS prepreg at 300 °C (a nearly elastic melt at that speed).

mod common;

use common::{repo_path, run_ok, scratch_dir, shear_law_error};
use thermostamp::experiment::picture_frame::PictureFrame;
use thermostamp::experiment::sheet_test::SheetTest;
use thermostamp::fit::shear::{fit_shear, polynomial_terms, ForceCurve, ShearTest};
use thermostamp::fit::shear_matrix::{matrix_layers, subtract_matrix, TestConditions};
use thermostamp::material::fabric::ShearInteraction;
use thermostamp::material::MaterialCard;

const MAX_SHEAR_DEG: f64 = 40.0;
const FRAME: ShearTest = ShearTest::PictureFrame {
    frame_side: 150.0,
    fabric_side: 150.0,
};

/// The FE picture-frame curve of `card` at 300 °C (the standard test: 150 mm frame, 20 mm/min,
/// 60 mm of pull), points from 1 mm on.
fn fe_curve(card: &MaterialCard) -> (ForceCurve, f64) {
    let test = PictureFrame::standard(300.0);
    let run = common::on_the_pool(|| test.run(&card.laminate, card.density, None, None)).unwrap();
    let rows: Vec<_> = run.rows.iter().filter(|r| r.displacement > 1.0).collect();
    let curve = ForceCurve {
        origin: "FE picture frame".into(),
        lines: (2..rows.len() + 2).collect(),
        displacement: rows.iter().map(|r| r.displacement).collect(),
        force: rows.iter().map(|r| r.force).collect(),
    };
    (curve, test.process.speed)
}

/// Largest relative difference of the normalised shear force of `fitted` from the card's law
/// between 5° and 40°.
fn law_error(fitted: &ShearInteraction, card: &MaterialCard, thickness: f64) -> f64 {
    shear_law_error(fitted, &card.fabric.shear, thickness, 5..=40)
}

fn fabric_thickness(card: &MaterialCard) -> f64 {
    card.laminate
        .layers()
        .iter()
        .find(|l| l.law.name() == "fabric")
        .unwrap()
        .thickness
}

/// Fits with and without the subtraction; returns their law errors.
fn fit_both_ways(card: &MaterialCard, curve: &ForceCurve, speed: f64) -> (f64, f64) {
    let thickness = fabric_thickness(card);
    let matrix = matrix_layers(&card.laminate).unwrap();
    let conditions = TestConditions {
        temperature: 300.0,
        speed,
    };
    let (fabric, share) = subtract_matrix(curve, &matrix, &FRAME, conditions).unwrap();
    let last = curve.force.len() - 1;
    println!(
        "matrix share at {} mm: {:.3} N of {:.3} N",
        curve.displacement[last], share[last], curve.force[last]
    );
    let max = MAX_SHEAR_DEG.to_radians();
    let subtracted = fit_shear(&fabric, &FRAME, thickness, &polynomial_terms(3), max).unwrap();
    let raw = fit_shear(curve, &FRAME, thickness, &polynomial_terms(3), max).unwrap();
    let errors = (
        law_error(&subtracted.law(), card, thickness),
        law_error(&raw.law(), card, thickness),
    );
    println!(
        "c subtracted {:?}, raw {:?}; law errors {:.4} / {:.4}",
        subtracted.result.parameters, raw.result.parameters, errors.0, errors.1
    );
    errors
}

#[test]
fn subtracting_viscous_skins_gives_back_the_fabric_law() {
    let card = MaterialCard::load(&repo_path("tests/data/viscous-prepreg.toml")).unwrap();
    let (curve, speed) = fe_curve(&card);
    let (subtracted, raw) = fit_both_ways(&card, &curve, speed);
    assert!(subtracted < 0.005, "subtracted: {subtracted}");
    assert!(raw > 0.05, "raw: {raw}");
}

/// The README's tutorial as a user types it: the virtual picture-frame test of the shipped
/// T300/PPS card at 300 °C, then `fit shear` on the history it writes, with the test's
/// temperature and crosshead speed (20 mm/min).
#[test]
fn cli_fits_the_virtual_picture_frame_of_the_t300_pps_card() {
    let card_path = repo_path("materials/t300-5hs-pps.toml");
    let card_arg = card_path.to_str().unwrap();
    let dir = scratch_dir("fit-shear", "prepreg");
    let results = dir.join("frame");
    run_ok(&[
        "test",
        "picture-frame",
        "--card",
        card_arg,
        "--temperature",
        "300",
        "--frames",
        "0",
        "--output",
        results.to_str().unwrap(),
    ]);
    let output = dir.join("fitted.toml");
    let plot = dir.join("fit.png");
    let data = results.join("picture-frame.csv");
    let stdout = run_ok(&[
        "fit",
        "shear",
        "--test",
        "picture-frame",
        "--frame-side",
        "150",
        "--data",
        data.to_str().unwrap(),
        "--card",
        card_arg,
        "--temperature",
        "300",
        "--speed",
        "0.333333",
        "--max-shear",
        "40",
        "--output",
        output.to_str().unwrap(),
        "--plot",
        plot.to_str().unwrap(),
    ]);
    assert!(stdout.contains("matrix layers at 300 °C"), "{stdout}");
    let card = MaterialCard::load(&card_path).unwrap();
    let fitted = MaterialCard::load(&output).unwrap();
    let error = law_error(&fitted.fabric.shear, &card, fabric_thickness(&card));
    assert!(error < 0.005, "{error}");
    let text = std::fs::read_to_string(&output).unwrap();
    assert!(text.contains("matrix layers' force at 300 °C"), "{text}");
    assert!(std::fs::metadata(&plot).unwrap().len() > 1000);
}
