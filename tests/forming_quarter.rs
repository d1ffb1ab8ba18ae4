//! Symmetry planes from a mesh file's node sets (issue 6): `examples/hemisphere-quarter.toml`,
//! the quarter x, y >= 0 of the hemisphere example's blank read from Gmsh and held across
//! x = 0 and y = 0, forms as that quarter of the full built-in blank does: every element's
//! shear angle within 0.5° of its twin, and a quarter of the punch force within 3 %. The file's
//! quadrilaterals are elements as they are, so the full blank is the built-in one in
//! quadrilaterals (pattern `quad`). Both examples run the implicit solver; measured after 15 mm:
//! 0.094° largest difference on 8.4° of shear, punch force 0.17 % apart.

mod common;

use common::{element_shear, largest_twin_difference, repo_path};
use nalgebra::Vector3;
use thermostamp::forming::{run, FormingModel, Scenario};

const STROKE: &str = "process.stroke=15";

/// Runs `example`; the peak punch force and, per element, its final centroid and shear angle.
fn formed(example: &str, overrides: &[&str]) -> (f64, Vec<(Vector3<f64>, f64)>) {
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    let scenario = Scenario::load(&repo_path(example), &overrides).unwrap();
    let forming = FormingModel::new(&scenario).unwrap();
    let result = run::run(&forming, None, None);
    let state = result.outcome.unwrap();
    let x = &state.positions;
    let peak = result
        .records
        .iter()
        .map(|r| r.punch_force)
        .fold(0.0, f64::max);
    (peak, element_shear(&forming.model, x))
}

#[test]
fn the_quarter_model_forms_as_a_quarter_of_the_whole() {
    // the two runs side by side
    let ((full_force, full), (quarter_force, quarter)) = common::both(
        || {
            formed(
                "examples/hemisphere.toml",
                &[STROKE, "blank.pattern=quad", "blank.element_size=8"],
            )
        },
        || formed("examples/hemisphere-quarter.toml", &[STROKE]),
    );
    assert_eq!(4 * quarter.len(), full.len());
    let worst = largest_twin_difference(&full, &quarter, 0.5);
    let largest = quarter.iter().map(|q| q.1.abs()).fold(0.0, f64::max);
    let force_error = (4.0 * quarter_force - full_force).abs() / full_force;
    println!(
        "largest shear {largest:.2}°, largest difference {worst:.3}°; punch force {full_force:.2} \
         N (full) vs 4 x {quarter_force:.2} N (quarter): {:.2} %",
        100.0 * force_error
    );
    assert!(largest > 5.0, "too little shear to compare: {largest}°");
    assert!(worst < 0.5, "{worst}°");
    assert!(force_error < 0.03, "{force_error}");
}
