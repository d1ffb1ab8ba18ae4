//! Forming over the hemisphere and the double dome against kinematics (docs/model.md §6): a fabric
//! of stiff yarns and soft shear, 0/90, drapes with the symmetry of its net (four-fold on the
//! hemisphere, the two mirror planes on the double dome), its largest shear angle is that of
//! the pin-jointed net on the same punch, it stays out of the tools, and the run is
//! quasi-static.

mod common;

use nalgebra::Vector3;
use thermostamp::forming::drape_preview::{drape_preview, Generators};
use thermostamp::forming::{run, FormingModel, Scenario};

/// An example with the test fabric, 10 mm cells, 15 mm of stroke at 50 mm/s, no time scaling,
/// and the `more` overrides. Kinetic energy at most 1.1 % of the internal energy (before the
/// force-driven holder was damped it rang on the flange and pushed this to 5-10 %).
fn scenario(example: &str, more: &[&str]) -> Scenario {
    let overrides = [
        "blank.card=forming-fabric.toml",
        "blank.element_size=10",
        "process.stroke=15",
        "process.punch_speed=50",
        "process.time_scaling=1",
        "output.history_points=20",
    ];
    let overrides: Vec<String> = overrides
        .iter()
        .chain(more)
        .map(|s| s.to_string())
        .collect();
    Scenario::load(&common::repo_path(example), &overrides).unwrap()
}

/// Largest |shear| of the elements whose current centroid lies in each quadrant (degrees).
fn quadrant_maxima(forming: &FormingModel, x: &[Vector3<f64>]) -> [f64; 4] {
    let mut maxima = [0.0f64; 4];
    for e in &forming.model.elements {
        let centroid = e.centroid(x);
        let gamma = e.shear_angle(x).abs().to_degrees();
        let q = usize::from(centroid.x > 0.0) + 2 * usize::from(centroid.y > 0.0);
        maxima[q] = maxima[q].max(gamma);
    }
    maxima
}

/// Quadrant maxima of the shear angle within 2° of each other (measured 7.40 to 7.85°: the
/// single diagonals of the mesh are the asymmetry); the largest within 5° of the pin-jointed net
/// draped on the same cap (`thermostamp drape`, 8.04°); see [`check_against_the_net`].
#[test]
fn hemisphere_shear_is_symmetric_and_follows_the_pin_jointed_net() {
    check_against_the_net(&scenario("tests/data/hemisphere-explicit.toml", &[]));
}

/// The double dome, shortened to a 200 x 140 mm blank: the ends shear as the hemisphere does
/// and the cylindrical middle hardly at all; the four quadrants are mirror images.
#[test]
fn double_dome_shear_is_symmetric_and_follows_the_pin_jointed_net() {
    let scenario = scenario(
        "tests/data/double-dome-explicit.toml",
        &["blank.width=200", "blank.length=140"],
    );
    check_against_the_net(&scenario);
}

/// Quadrant maxima of the shear angle within 2° of each other; the largest within 5° of the
/// pin-jointed net draped on the same punch; no node deeper in a tool than 10 % of the ply;
/// kinetic energy below 5 % of the internal energy once the blank carries load.
fn check_against_the_net(scenario: &Scenario) {
    let forming = FormingModel::new(scenario).unwrap();
    let result = common::on_the_pool(|| run::run(&forming, None, None));
    let state = result.outcome.as_ref().unwrap();
    let maxima = quadrant_maxima(&forming, &state.positions);
    let (lo, hi) = (
        maxima.iter().copied().fold(f64::INFINITY, f64::min),
        maxima.iter().copied().fold(0.0, f64::max),
    );
    assert!(hi - lo < 2.0, "quadrant maxima {maxima:?}");
    eprintln!("{}: quadrant maxima {maxima:?}", scenario.origin);
    let net = drape_preview(scenario, &Generators::of(scenario)).unwrap();
    let pin_jointed = net.max_shear().unwrap().shear_deg.abs();
    eprintln!("FE {hi:.2}°, pin-jointed net {pin_jointed:.2}°");
    assert!(
        (hi - pin_jointed).abs() < 5.0,
        "FE {hi}°, pin-jointed net {pin_jointed}°"
    );
    let thickness = forming.card.laminate.reference_thickness();
    let offset = forming.model.contact.offset;
    for (k, tool) in forming.model.tools.iter().enumerate() {
        let deepest = state
            .positions
            .iter()
            .map(|x| -tool.gap(&(x - state.tool_translations[k]), offset))
            .fold(f64::NEG_INFINITY, f64::max);
        assert!(
            deepest < 0.1 * thickness,
            "{}: a node {deepest} mm inside",
            tool.name
        );
    }
    let final_work = result.records.last().unwrap().energies.internal_work;
    let loaded = result
        .records
        .iter()
        .filter(|r| r.energies.internal_work > 0.05 * final_work);
    let (stroke, ratio) = loaded
        .map(|r| (r.stroke, r.energies.kinetic / r.energies.internal_work))
        .fold((0.0, 0.0), |a, b| if b.1 > a.1 { b } else { a });
    eprintln!("kinetic / internal energy at most {ratio:.4} (stroke {stroke:.1} mm)");
    assert!(
        ratio < 0.05,
        "stroke {stroke} mm: kinetic {ratio} of internal energy"
    );
}
