//! Forming over the hemisphere against kinematics (MODEL.md §6): a fabric of stiff yarns and
//! soft shear, 0/90, drapes with the four-fold symmetry of its net, its largest shear angle is
//! that of the pin-jointed net on the same cap, it stays out of the tools, and the run is
//! quasi-static.

mod common;

use nalgebra::Vector3;
use thermostamp::forming::drape_preview::drape_preview;
use thermostamp::forming::{run, FormingModel, Scenario};

/// The example with the test fabric, 10 mm cells, 15 mm of stroke at 25 mm/s, no time scaling
/// (at 50 mm/s the kinetic energy reaches 6 % of the internal energy early in the stroke).
fn scenario() -> Scenario {
    let overrides = [
        "blank.card=../tests/data/forming-fabric.toml",
        "blank.element_size=10",
        "process.stroke=15",
        "process.punch_speed=25",
        "process.time_scaling=1",
        "output.history_points=20",
    ];
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    Scenario::load(&common::repo_path("examples/hemisphere.toml"), &overrides).unwrap()
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
/// draped on the same cap (`thermostamp drape`, 8.04°); no node deeper in a tool than 10 % of the
/// ply; kinetic energy below 5 % of the internal energy once the blank carries load.
#[test]
fn hemisphere_shear_is_symmetric_and_follows_the_pin_jointed_net() {
    let scenario = scenario();
    let forming = FormingModel::new(&scenario).unwrap();
    let result = run::run(&forming, None, None);
    let state = result.outcome.as_ref().unwrap();
    let maxima = quadrant_maxima(&forming, &state.positions);
    let (lo, hi) = (
        maxima.iter().copied().fold(f64::INFINITY, f64::min),
        maxima.iter().copied().fold(0.0, f64::max),
    );
    assert!(hi - lo < 2.0, "quadrant maxima {maxima:?}");
    let net = drape_preview(&scenario).unwrap();
    let pin_jointed = net.max_shear().unwrap().shear_deg.abs();
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
    for r in &result.records {
        let e = &r.energies;
        if e.internal_work > 0.05 * final_work {
            assert!(
                e.kinetic < 0.05 * e.internal_work,
                "stroke {} mm: kinetic {} of internal {}",
                r.stroke,
                e.kinetic,
                e.internal_work
            );
        }
    }
}
