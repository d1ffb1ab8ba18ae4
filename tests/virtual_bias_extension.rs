//! The virtual bias-extension test against physics (docs/model.md §5): the central-zone shear angle
//! and the clamp force of the equilibrium of an inextensible net (`experiment::ideal_net`),
//! three kinematic zones, energy balance, quasi-static kinetic energy, the normalised shear
//! force recovered from the simulated force curve equal to the fabric's own shear law, and
//! convergence of the force under mesh refinement.

mod common;

use common::repo_path;
use thermostamp::experiment::bias_extension::{BiasExtension, BiasExtensionRun};
use thermostamp::experiment::ideal_net::{fabric_trellis_energy, IdealNetBias};
use thermostamp::experiment::kinematics::bias_extension_displacement;
use thermostamp::experiment::sheet_test::{mean_shear_angle, SheetTest};
use thermostamp::material::MaterialCard;
use thermostamp::mesh::DiagonalPattern;
use thermostamp::solver::Model;

fn stiff_yarn_fabric() -> MaterialCard {
    MaterialCard::load(&repo_path("tests/data/stiff-yarn-fabric.toml")).unwrap()
}

/// A coarse, fast specimen: 25 mm crossed cells, crosshead at 100 mm/s, physical mass, pulled
/// until the pin-jointed central zone passes 40°.
fn coarse_test() -> BiasExtension {
    let mut test = BiasExtension::benchmark(20.0);
    test.process.element_size = 25.0;
    test.process.speed = 100.0;
    test.process.time_scaling = 1.0;
    test.process.target_time_step = None;
    test.process.end_displacement = bias_extension_displacement(150.0, 450.0, 40.5f64.to_radians());
    test.process.history_points = 60;
    test
}

/// Mean of the ideal net's shear angle (degrees) over `elements`, area-weighted, sampled at
/// three interior points of each of its triangles (the net's field is not constant in an
/// element).
fn net_mean_over(model: &Model, elements: &[usize], angle: impl Fn(f64, f64) -> f64) -> f64 {
    let (mut sum, mut area) = (0.0, 0.0);
    for &k in elements {
        for t in model.mesh.cells[k].triangles() {
            let p = t.map(|n| model.mesh.nodes[n]);
            let a = 0.5 * (p[1] - p[0]).cross(&(p[2] - p[0])).norm();
            for w in [[4.0, 1.0, 1.0], [1.0, 4.0, 1.0], [1.0, 1.0, 4.0]] {
                let q = (p[0] * w[0] + p[1] * w[1] + p[2] * w[2]) / 6.0;
                sum += a * angle(q.x, q.y) / 3.0;
            }
            area += a;
        }
    }
    (sum / area).to_degrees()
}

fn run(test: &BiasExtension, card: &MaterialCard) -> (Model, BiasExtensionRun) {
    let model = test.model(&card.laminate, card.density).unwrap();
    let result = test.run(&card.laminate, card.density, None, None).unwrap();
    (model, result)
}

/// Pin-jointed zone of a reference point of a W x H specimen centred on the origin: trace
/// the two yarns through it (slopes +1 and -1) to the clamp lines y = +-H/2. 'A' when both
/// reach the same clamp (undeformed), 'B' when one reaches a clamp (half-sheared), 'C' when
/// neither does (fully sheared); '-' within `margin` of a clamp corner's yarn (a zone border).
fn zone(x: f64, y: f64, (w, h): (f64, f64), margin: f64) -> char {
    // where each yarn meets the bottom and the top clamp line
    let hits = [
        [x - (y + h / 2.0), x + (h / 2.0 - y)], // slope +1: down-left, up-right
        [x + (y + h / 2.0), x - (h / 2.0 - y)], // slope -1: down-right, up-left
    ];
    let mut reached = Vec::new();
    for yarn in hits {
        for (clamp, hit) in yarn.iter().enumerate() {
            let off_corner = (hit.abs() - w / 2.0).abs();
            if off_corner < margin {
                return '-';
            }
            if hit.abs() < w / 2.0 {
                reached.push(clamp);
            }
        }
    }
    match reached.as_slice() {
        [a, b] if a == b => 'A',
        [_] => 'B',
        [] => 'C',
        _ => '-',
    }
}

#[test]
fn zones_of_the_pin_jointed_net() {
    let size = (150.0, 450.0);
    assert_eq!(zone(0.0, 0.0, size, 5.0), 'C');
    assert_eq!(zone(0.0, 200.0, size, 5.0), 'A');
    assert_eq!(zone(0.0, -200.0, size, 5.0), 'A');
    assert_eq!(zone(50.0, 150.0, size, 5.0), 'B');
    assert_eq!(zone(-50.0, -150.0, size, 5.0), 'B');
    assert_eq!(zone(60.0, 0.0, size, 5.0), 'C');
}

/// On crossed triangles (edges along the yarns) and on as many quadrilaterals (yarns across
/// the elements at ±45°: an element that locked would hold the central zone back; these lag
/// the net by up to 2.18° and 16 % of its force (0.8375) at the end, softer, not locked).
#[test]
fn central_zone_and_force_follow_the_equilibrium_of_the_inextensible_net() {
    for pattern in [DiagonalPattern::Crossed, DiagonalPattern::Quad] {
        central_zone_follows_the_net(pattern);
    }
}

fn central_zone_follows_the_net(pattern: DiagonalPattern) {
    let card = stiff_yarn_fabric();
    let mut test = coarse_test();
    test.process.pattern = pattern;
    if pattern == DiagonalPattern::Quad {
        // as many elements as the crossed cells (432): one quadrilateral per 12.5 mm cell
        test.process.element_size = 12.5;
    }
    let (model, result) = run(&test, &card);
    let t_b = card.laminate.layers()[0].thickness;
    let law = fabric_trellis_energy(&card.fabric.shear, t_b);
    let net = IdealNetBias {
        width: test.width,
        length: test.length,
        cells: 60,
    };
    let zone = test.central_zone(&model);
    let rows: Vec<_> = result
        .rows
        .iter()
        .filter(|r| r.displacement > 5.0)
        .collect();
    let d: Vec<f64> = rows.iter().map(|r| r.displacement).collect();
    let equilibria = net.solve(&law, &d).unwrap();
    assert!(rows.last().unwrap().shear_angle_pin_jointed > 40.0);
    let (mut lowest, mut lag) = (f64::INFINITY, f64::NEG_INFINITY);
    for (row, eq) in rows.iter().zip(&equilibria) {
        let expected = net_mean_over(&model, &zone, |x, y| eq.shear_angle(x, y));
        // quadrilaterals lag the net, by about 2° at the end (docs/model.md §4)
        let within = if pattern == DiagonalPattern::Quad {
            3.0
        } else {
            1.0
        };
        lag = lag.max(expected - row.shear_angle);
        assert!(
            (row.shear_angle - expected).abs() < within,
            "{pattern:?}, d = {:.1} mm: central zone {:.2}° vs net equilibrium {expected:.2}° (pin-jointed {:.2}°)",
            row.displacement,
            row.shear_angle,
            row.shear_angle_pin_jointed
        );
        // the net is inextensible, the test fabric nearly so: its force is an upper bound.
        // The quadrilaterals, whose hourglass mode only shear holds when the yarns cross them,
        // come lower as the shear grows (down to about 0.84 on 12.5 mm cells at the end;
        // docs/model.md §4): this checks they stay below the bound, and how far
        // below is the figure printed
        let ratio = row.force / eq.force;
        lowest = lowest.min(ratio);
        let floor = if pattern == DiagonalPattern::Quad {
            0.75
        } else {
            0.95
        };
        assert!(
            (floor..1.01).contains(&ratio),
            "{pattern:?}, d = {:.1} mm: force {:.4} N vs net equilibrium {:.4} N",
            row.displacement,
            row.force,
            eq.force
        );
    }
    eprintln!(
        "{pattern:?}: force at least {lowest:.4} of the net equilibrium's, central zone \
         {lag:.2}° behind it at most"
    );
    // the rising shear force of the fabric makes the centre lag the pin-jointed formula
    let last = rows.last().unwrap();
    assert!(last.shear_angle < last.shear_angle_pin_jointed - 2.0);
}

#[test]
fn three_zones_energy_balance_and_normalised_shear_force() {
    let card = stiff_yarn_fabric();
    let mut test = coarse_test();
    test.process.end_displacement = 75.0;
    let (model, result) = run(&test, &card);
    let state = result.run.outcome.as_ref().expect("the run finishes");
    let s = &result.run.summary;
    assert!(
        s.worst_balance_error < 0.01,
        "energy balance error {}",
        s.worst_balance_error
    );
    assert!(
        s.worst_kinetic_ratio < 0.05,
        "kinetic / internal {}",
        s.worst_kinetic_ratio
    );

    // three zones: undeformed at the clamps, half-sheared beside them, fully sheared centre
    let mean_in = |label: char| {
        let elements: Vec<usize> = (0..model.elements.len())
            .filter(|&k| {
                let c = model.mesh.centroid(k);
                zone(c.x, c.y, (150.0, 450.0), 10.0) == label
            })
            .collect();
        assert!(!elements.is_empty(), "no element in zone {label}");
        mean_shear_angle(&model, state, &elements)
    };
    let (a, b, c) = (mean_in('A'), mean_in('B'), mean_in('C'));
    assert!(a.abs() < 1.5, "zone A sheared {a}°");
    assert!(c > 25.0, "zone C only {c}°");
    assert!(
        (b - 0.5 * c).abs() < 0.15 * c,
        "zone B {b}° is not half of zone C {c}°"
    );

    // Cao's normalisation of the simulated force gives back the fabric's shear law
    let t_b = card.laminate.layers()[0].thickness;
    for row in result
        .rows
        .iter()
        .filter(|r| (15.0..=35.0).contains(&r.shear_angle_pin_jointed))
    {
        let expected = card
            .fabric
            .shear
            .normalised_shear_force(t_b, row.shear_angle_pin_jointed.to_radians());
        let got = row.normalised_shear_force;
        assert!(
            (got - expected).abs() < 0.05 * expected,
            "{:.1}°: F_sh {got} vs {expected}",
            row.shear_angle_pin_jointed
        );
    }
}

/// Clamp force at d = 30 mm on 4, 8 and 16 crossed cells across the width.
#[test]
fn force_converges_under_mesh_refinement() {
    let card = stiff_yarn_fabric();
    let forces: Vec<f64> = [37.5, 18.75, 9.375]
        .iter()
        .map(|&size| {
            let mut test = coarse_test();
            test.process.element_size = size;
            test.process.end_displacement = 30.0;
            test.process.history_points = 6;
            let result = test.run(&card.laminate, card.density, None, None).unwrap();
            assert!(
                result.run.outcome.is_ok(),
                "{size} mm: {:?}",
                result.run.outcome.err()
            );
            let last = result.rows.last().unwrap();
            assert!((last.displacement - 30.0).abs() < 1e-9);
            last.force
        })
        .collect();
    let change = |a: f64, b: f64| (a - b).abs() / b;
    let (coarse, finest) = (change(forces[0], forces[1]), change(forces[1], forces[2]));
    assert!(finest < 0.05, "forces {forces:?}");
    assert!(finest < coarse, "not converging: {forces:?}");
    let t_b = card.laminate.layers()[0].thickness;
    let net = IdealNetBias {
        width: 150.0,
        length: 450.0,
        cells: 60,
    };
    let eq = &net
        .solve(&fabric_trellis_energy(&card.fabric.shear, t_b), &[30.0])
        .unwrap()[0];
    assert!(
        change(forces[2], eq.force) < 0.02,
        "finest {} N vs net equilibrium {} N",
        forces[2],
        eq.force
    );
}

/// The default mesh (ten cells across the width, `BiasExtension::default_element_size`) is
/// converged for the shipped cards' shear laws: halving its cells changes the clamp force at 30°
/// of pin-jointed shear by under 2 %, on a 100 x 200 and a 150 x 450 mm specimen, for the
/// Twintex card (friction-like shear term) and the T300/PPS prepreg at 300 °C. Implicit solver at
/// the physical 20 mm/min. Measured (Twintex): 0.05 % (100 x 200) and 0.14 % (150 x 450); the
/// explicit solver with the test's defaults agrees within 0.35 % on 100 x 200.
#[test]
fn the_default_mesh_is_converged_for_the_shipped_cards() {
    let cards = [
        ("materials/twintex-plain-weave.toml", 20.0),
        ("materials/t300-5hs-pps.toml", 300.0),
    ];
    for (path, temperature) in cards {
        let card = MaterialCard::load(&repo_path(path)).unwrap();
        for (width, length) in [(100.0, 200.0), (150.0, 450.0)] {
            let d30 = bias_extension_displacement(width, length, 30f64.to_radians());
            let force_at_30 = |refinement: f64| {
                let test =
                    common::implicit_bias_test((width, length), temperature, refinement, 30.0, 40);
                let result = test.run(&card.laminate, card.density, None, None).unwrap();
                assert!(
                    result.run.outcome.is_ok(),
                    "{path}, {width} x {length}: {:?}",
                    result.run.outcome.err()
                );
                let last = result.rows.last().unwrap();
                assert!((last.displacement - d30).abs() < 1e-9);
                last.force
            };
            let (default, halved) = (force_at_30(1.0), force_at_30(2.0));
            let change = (default - halved).abs() / halved;
            println!(
                "{path}, {width} x {length} mm: {default:.4} N on the default mesh, {halved:.4} N \
                 on cells half as large: {:.2} %",
                100.0 * change
            );
            assert!(
                change < 0.02,
                "{path}, {width} x {length}: {:.2} %",
                100.0 * change
            );
        }
    }
}
