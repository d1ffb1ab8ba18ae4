//! The blank holder against the flange's lift-off (MODEL.md §6): without a blank-holder force
//! the flange leaves the die as the punch draws the blank in; with one it stays flat.

mod common;

use thermostamp::forming::{run, FormingModel, Scenario};

fn flange_lift(holder_force: &str) -> (f64, f64) {
    let scenario = Scenario::load(
        &common::repo_path("examples/hemisphere.toml"),
        &[
            "blank.element_size=10".into(),
            "process.stroke=10".into(),
            format!("process.blank_holder_force={holder_force}"),
            "output.history_points=10".into(),
        ],
    )
    .unwrap();
    let forming = FormingModel::new(&scenario).unwrap();
    let result = run::run(&forming, None, None);
    assert!(result.outcome.is_ok(), "{:?}", result.outcome.err());
    let last = result.records.last().unwrap();
    (last.wrinkles.height, last.wrinkles.area)
}

/// 10 mm of stroke on 10 mm cells: with no holder the flange is more than a ply thickness off
/// the die over a large area; with 200 N it stays within half a ply.
#[test]
fn holder_force_keeps_the_flange_on_the_die() {
    let thickness = 0.31;
    let (free_height, free_area) = flange_lift("0");
    let (held_height, held_area) = flange_lift("200");
    assert!(
        free_height > thickness && free_area > 1000.0,
        "no holder: {free_height} mm, {free_area} mm^2"
    );
    assert!(
        held_height < 0.5 * thickness && held_area == 0.0,
        "200 N: {held_height} mm, {held_area} mm^2"
    );
}
