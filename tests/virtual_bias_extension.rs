//! The virtual bias-extension test against physics (MODEL.md §5): three kinematic zones,
//! energy balance, quasi-static kinetic energy, and the normalised shear force recovered from
//! the simulated force curve equal to the fabric's own shear law.

mod common;

use common::repo_path;
use thermostamp::experiment::bias_extension::{BiasExtension, BiasExtensionRun};
use thermostamp::experiment::sheet_test::mean_shear_angle;
use thermostamp::material::MaterialCard;
use thermostamp::solver::Model;

fn stiff_yarn_fabric() -> MaterialCard {
    MaterialCard::load(&repo_path("tests/data/stiff-yarn-fabric.toml")).unwrap()
}

/// A coarse, fast specimen: 25 mm crossed cells, crosshead at 100 mm/s, physical mass.
fn coarse_test() -> BiasExtension {
    let mut test = BiasExtension::benchmark(20.0);
    test.element_size = 25.0;
    test.speed = 100.0;
    test.time_scaling = 1.0;
    test.target_time_step = None;
    test.end_displacement = 75.0;
    test.history_points = 60;
    test
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

#[test]
fn three_zones_energy_balance_and_normalised_shear_force() {
    let card = stiff_yarn_fabric();
    let test = coarse_test();
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
