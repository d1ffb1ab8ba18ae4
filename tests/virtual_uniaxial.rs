//! The virtual strip tension test against physics: along a yarn family the force per unit width
//! is the card's yarn tension law times the fabric thickness (docs/model.md §3, §5), for a linear
//! and a nonlinear law; the energy balances; the weft strip of a balanced fabric gives the warp
//! strip's curve; a bias strip is shear-dominated, far softer, and carries the force of Cao's
//! bias-extension energy balance.

mod common;

use common::{repo_path, t300_card};
use thermostamp::experiment::kinematics::{bias_extension_force, bias_extension_shear_angle};
use thermostamp::experiment::sheet_test::SheetTest;
use thermostamp::experiment::uniaxial::{UniaxialRun, UniaxialTension};
use thermostamp::material::MaterialCard;

fn stiff_yarn_fabric() -> MaterialCard {
    MaterialCard::load(&repo_path("tests/data/stiff-yarn-fabric.toml")).unwrap()
}

/// Thickness of the card's fabric layer (mm).
fn fabric_thickness(card: &MaterialCard) -> f64 {
    let layers = card.laminate.layers();
    let fabric = layers.iter().find(|l| l.law.name() == "fabric").unwrap();
    fabric.thickness
}

/// The standard 25 x 150 mm strip on coarse cells (two across the width: a yarn strip stretches
/// homogeneously), pulled 6 mm (4 %) at 200 mm/s with physical mass: 1e-4 of the yarn wave
/// speed of the test fabric, so the smooth start leaves no ringing worth the name.
fn coarse_strip(ply_angle: f64) -> UniaxialTension {
    let mut test = UniaxialTension::standard(20.0);
    test.ply_angle = ply_angle;
    test.process.element_size = 12.5;
    test.process.speed = 200.0;
    test.process.time_scaling = 1.0;
    test.process.end_displacement = 6.0;
    test.process.history_points = 24;
    test
}

fn run(test: &UniaxialTension, card: &MaterialCard) -> UniaxialRun {
    let result = test.run(&card.laminate, card.density, None, None).unwrap();
    assert!(
        result.run.outcome.is_ok(),
        "{:?}",
        result.run.outcome.as_ref().err()
    );
    assert_eq!(result.rows.len(), test.process.history_points + 1);
    result
}

/// Largest `|F/W / (t_B T(1 + d/L)) - 1|` over the rows past 0.5 % strain, with `T` the warp
/// tension law of the card; and how many rows that was.
fn worst_error_against_the_yarn_law(result: &UniaxialRun, card: &MaterialCard) -> (f64, usize) {
    let t_b = fabric_thickness(card);
    let checked: Vec<f64> = result
        .rows
        .iter()
        .filter(|r| r.strain > 0.005)
        .map(|r| {
            let expected = t_b * card.fabric.warp.tension(1.0 + r.strain);
            (r.stress_resultant / expected - 1.0).abs()
        })
        .collect();
    (checked.iter().copied().fold(0.0, f64::max), checked.len())
}

#[test]
fn warp_strip_follows_the_yarn_tension_law_and_balances_its_energy() {
    let card = stiff_yarn_fabric();
    let result = run(&coarse_strip(0.0), &card);
    let (worst, rows) = worst_error_against_the_yarn_law(&result, &card);
    assert!(rows >= 20, "only {rows} rows past 0.5 % strain");
    assert!(worst < 0.02, "F/W off the yarn law by {worst}");
    let last = result.rows.last().unwrap();
    assert!((last.strain - 0.04).abs() < 1e-12);
    assert!(last.shear_angle.abs() < 0.01, "{}°", last.shear_angle);
    let s = &result.run.summary;
    assert!(s.worst_balance_error < 0.01, "{}", s.worst_balance_error);
    assert!(s.worst_kinetic_ratio < 0.05, "{}", s.worst_kinetic_ratio);
}

/// The shipped T300/PPS card at 300 °C: a nonlinear yarn law (`A2 (l-1) + A3 (l-1)^2`, the
/// tangent doubles by 1 % strain), with molten matrix skins whose share of the force is below
/// 1e-5 of the yarns'. Pulled 3 mm (2 %) at 200 mm/s, 3e-5 of its yarn wave speed.
#[test]
fn warp_strip_follows_a_nonlinear_yarn_law() {
    let card = t300_card();
    let mut test = coarse_strip(0.0);
    test.process.temperature = 300.0;
    test.process.end_displacement = 3.0;
    test.process.history_points = 12;
    let result = run(&test, &card);
    let (worst, rows) = worst_error_against_the_yarn_law(&result, &card);
    assert!(rows >= 8, "only {rows} rows past 0.5 % strain");
    assert!(worst < 0.02, "F/W off the yarn law by {worst}");
    assert!(result.run.summary.worst_balance_error < 0.01);
}

#[test]
fn weft_strip_of_a_balanced_fabric_gives_the_warp_curve() {
    let card = stiff_yarn_fabric();
    let warp = run(&coarse_strip(0.0), &card);
    let weft = run(&coarse_strip(90.0), &card);
    for (a, b) in warp.rows.iter().zip(&weft.rows).skip(1) {
        assert!((a.displacement - b.displacement).abs() < 1e-9);
        assert!(
            (a.force - b.force).abs() < 0.005 * a.force,
            "d = {:.2} mm: warp {} N, weft {} N",
            a.displacement,
            a.force,
            b.force
        );
    }
}

/// A ±45° strip (L/W = 6) shears between the clamps like a bias-extension specimen. Its force is
/// set by the shear law, not the yarns: below 1 % of the warp strip's (the yarn law, which the
/// warp strip follows), and within 10 % of the force of Cao's energy balance
/// (`bias_extension_force`) with the card's `F_sh` at the pin-jointed angle. Pulled at 50 mm/s,
/// 0.35 % of the test fabric's shear wave speed, so that the strip is quasi-static in shear too.
#[test]
fn bias_strip_is_shear_dominated_and_far_softer() {
    let card = stiff_yarn_fabric();
    let t_b = fabric_thickness(&card);
    let mut test = coarse_strip(45.0);
    test.process.speed = 50.0;
    let bias = run(&test, &card);
    let (w, l) = (test.width, test.length);
    for row in bias.rows.iter().filter(|r| r.displacement > 3.0) {
        let warp = w * t_b * card.fabric.warp.tension(1.0 + row.strain);
        assert!(
            row.force > 0.0 && row.force < 0.01 * warp,
            "d = {:.2} mm: bias {} N, warp {warp} N",
            row.displacement,
            row.force,
        );
        let gamma = bias_extension_shear_angle(w, l, row.displacement);
        let cao = bias_extension_force(w, l, gamma, |g| {
            card.fabric.shear.normalised_shear_force(t_b, g)
        });
        assert!(
            (row.force / cao - 1.0).abs() < 0.10,
            "d = {:.2} mm: bias strip {} N, Cao's energy balance {cao} N",
            row.displacement,
            row.force
        );
    }
    let last = bias.rows.last().unwrap();
    assert!(
        last.shear_angle > 4.0,
        "gauge section {}°",
        last.shear_angle
    );
    assert!(bias.run.summary.worst_balance_error < 0.01);
}
