//! Non-isothermal forming (docs/model.md §9) as a user runs it: a hot blank on colder tools.
//! The isothermal limit must give the isothermal run to round-off; a blank out of the oven
//! must cool first where the punch touches it first, its punch-side skin before its core; the
//! punch must push harder on a colder blank; and the heat must balance.

mod common;

use thermostamp::forming::run::FormingRun;
use thermostamp::forming::{FormingModel, Scenario};

const HOT: &str = "tests/data/hemisphere-hot.toml";

fn hot(overrides: &[&str]) -> (FormingModel, FormingRun) {
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    common::form(HOT, &overrides)
}

fn peak_force(run: &FormingRun) -> f64 {
    run.records
        .iter()
        .map(|r| r.punch_force)
        .fold(0.0, f64::max)
}

/// Tools, room and blank all at 300 °C, no transfer, no friction heating: the temperature field
/// never moves, and the run is the isothermal run at 300 °C to 1e-12.
#[test]
fn isothermal_limit_is_the_isothermal_run() {
    let ((_, iso), (_, limit)) = common::both(
        || {
            common::form(
                "examples/hemisphere.toml",
                &[
                    "blank.element_size=10".into(),
                    "process.stroke=10".into(),
                    "output.history_points=20".into(),
                ],
            )
        },
        || {
            hot(&[
                "process.blank_temperature=300",
                "process.transfer_time=0",
                "tools.temperature=300",
                "thermal.room_temperature=300",
                "thermal.friction_heat_fraction=0",
            ])
        },
    );
    assert_eq!(iso.records.len(), limit.records.len());
    let scale = peak_force(&iso);
    assert!(scale > 1.0, "the punch pushes: {scale} N");
    for (a, b) in iso.records.iter().zip(&limit.records) {
        assert!(
            (a.punch_force - b.punch_force).abs() <= 1e-12 * scale,
            "punch force {} against {} at t = {}",
            b.punch_force,
            a.punch_force,
            a.time
        );
        assert!((a.draw_in - b.draw_in).abs() <= 1e-12 * 10.0);
    }
    let (x, y) = (
        iso.outcome.expect("isothermal run").positions,
        limit.outcome.expect("isothermal limit").positions,
    );
    let largest = x
        .iter()
        .zip(&y)
        .map(|(a, b)| (a - b).norm())
        .fold(0.0, f64::max);
    assert!(largest <= 1e-12 * 100.0, "positions {largest} mm apart");
    let t = limit.records.last().unwrap().temperature;
    assert_eq!((t.min, t.max), (300.0, 300.0));
}

/// A blank out of the oven at 320 °C on tools at 200 °C: at the end of 10 mm of stroke the
/// cells at the apex, which the punch touched first, are colder than the wall's, which it
/// touched last or not at all; at the apex the skin on the punch's side is colder than the
/// fabric in the middle, and that colder than the skin in the air; the heat balances.
#[test]
fn a_hot_blank_cools_where_the_punch_touches_it_first() {
    let (forming, run) = hot(&[]);
    let state = run.outcome.expect("hot run reaches the end of the stroke");
    let model = &forming.model;
    let heat = model.heat.as_ref().expect("a non-isothermal model");
    let thermal = state.thermal.as_ref().expect("a temperature field");
    let layers = heat.blank.layers();
    assert_eq!(layers, 3);
    let t = heat.blank.element_layer_temperatures(thermal);
    let radius = |k: usize| {
        let c = model.elements[k]
            .nodes()
            .iter()
            .map(|&n| model.mesh.nodes[n])
            .sum::<nalgebra::Vector3<f64>>()
            / model.elements[k].nodes().len() as f64;
        c.xy().norm()
    };
    let mean = |k: usize| t[k * layers..(k + 1) * layers].iter().sum::<f64>() / layers as f64;
    let apex: Vec<usize> = (0..model.elements.len())
        .filter(|&k| radius(k) < 10.0)
        .collect();
    let wall: Vec<usize> = (0..model.elements.len())
        .filter(|&k| (20.0..35.0).contains(&radius(k)))
        .collect();
    assert!(!apex.is_empty() && !wall.is_empty());
    let apex_warmest = apex.iter().map(|&k| mean(k)).fold(f64::MIN, f64::max);
    let wall_mean = wall.iter().map(|&k| mean(k)).sum::<f64>() / wall.len() as f64;
    assert!(
        apex_warmest < wall_mean - 5.0,
        "apex up to {apex_warmest:.1} °C, wall {wall_mean:.1} °C on average"
    );
    for &k in &apex {
        let (punch_side, core, air_side) = (t[k * 3], t[k * 3 + 1], t[k * 3 + 2]);
        assert!(
            punch_side < core && core < air_side,
            "element {k}: skins {punch_side:.1} / {air_side:.1} °C, core {core:.1} °C"
        );
    }
    let q = &thermal.heat;
    assert!(q.to_tools.iter().sum::<f64>() > 0.0 && q.to_air > 0.0);
    assert!(
        q.imbalance().abs() <= 1e-6 * q.scale(),
        "heat balance {:e} of {:e} N·mm",
        q.imbalance(),
        q.scale()
    );
    eprintln!(
        "apex up to {apex_warmest:.1} °C, wall {wall_mean:.1} °C; heat balance {:.1e}",
        q.imbalance() / q.scale()
    );
}

/// The longer the blank waits in air and the colder the tools, the harder the punch pushes.
#[test]
fn the_punch_pushes_harder_on_a_colder_blank() {
    let ((_, quick), (_, slow)) = common::both(
        || hot(&["process.transfer_time=0.5"]),
        || hot(&["process.transfer_time=3"]),
    );
    let ((_, warm), (_, cold)) = common::both(
        || hot(&["tools.temperature=250"]),
        || hot(&["tools.temperature=170"]),
    );
    let [quick, slow, warm, cold] = [&quick, &slow, &warm, &cold].map(peak_force);
    eprintln!(
        "peak punch force: transfer 0.5 s {quick:.1} N, 3 s {slow:.1} N; tools 250 °C \
         {warm:.1} N, 170 °C {cold:.1} N"
    );
    assert!(slow > quick, "transfer 3 s {slow} N, 0.5 s {quick} N");
    assert!(cold > warm, "tools 170 °C {cold} N, 250 °C {warm} N");
}

/// The two solvers advance the same heat equation: the explicit run (time scaling 10, the heat
/// in process time) ends with the blank's temperatures within 2 K of the implicit run's.
#[test]
fn both_solvers_cool_the_blank_alike() {
    let ((_, implicit), (_, explicit)) = common::both(
        || hot(&[]),
        || {
            hot(&[
                "process.solver=explicit",
                "process.time_scaling=10",
                "process.target_time_step=3e-6",
            ])
        },
    );
    let (a, b) = (
        implicit.records.last().unwrap().temperature,
        explicit.records.last().unwrap().temperature,
    );
    eprintln!(
        "end of stroke: implicit {:.2} / {:.2} / {:.2} °C, explicit {:.2} / {:.2} / {:.2} °C",
        a.min, a.mean, a.max, b.min, b.mean, b.max
    );
    assert!(a.mean < 300.0, "the blank cooled: {} °C", a.mean);
    assert!((a.mean - b.mean).abs() < 2.0 && (a.min - b.min).abs() < 5.0);
}

fn refusal(overrides: &[&str]) -> String {
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    match Scenario::load(&common::repo_path(HOT), &overrides) {
        Err(e) => e.to_string(),
        Ok(s) => match FormingModel::new(&s) {
            Err(e) => e,
            Ok(_) => panic!("{overrides:?} was accepted"),
        },
    }
}

/// Bad thermal input is refused before the first step, naming the key.
#[test]
fn bad_thermal_input_is_refused_by_key() {
    let e = refusal(&["tools.punch.temperature=100"]);
    assert!(
        e.contains("tools.punch.temperature") && e.contains("outside"),
        "{e}"
    );
    let e = refusal(&["blank.card=../../materials/twintex-plain-weave.toml"]);
    assert!(e.contains("[thermal]"), "{e}");
    let e = refusal(&["thermal.air_convection=-5"]);
    assert!(e.contains("thermal.air_convection"), "{e}");
    let e = refusal(&["process.temperature=300"]);
    assert!(e.contains("process.blank_temperature"), "{e}");
}

/// examples/double-dome-nonisothermal.toml on 10 mm cells over 3 mm of stroke: it runs; the
/// four-ply stack left the oven at 320 °C and cooled from its two outer faces during the
/// transfer, so at the start of the stroke the skin on the punch's side of the outer ply is
/// colder than the fabric of the ply inside it; the plies exchange heat without creating any
/// (the heat balances with the ply-to-ply flows in).
#[test]
fn the_nonisothermal_example_runs_in_reduced_form() {
    let (forming, run) = common::form(
        "examples/double-dome-nonisothermal.toml",
        &[
            "blank.element_size=10".into(),
            "process.stroke=3".into(),
            "output.history_points=5".into(),
        ],
    );
    let state = run.outcome.expect("the example runs");
    let model = &forming.model;
    assert_eq!(model.plies.len(), 4);
    let heat = model.heat.as_ref().expect("a non-isothermal model");
    let thermal = state.thermal.as_ref().expect("a temperature field");
    let first = run.records.first().unwrap().temperature;
    assert!(
        first.max < 320.0 && first.min > 250.0,
        "after 4 s in air: {first:?}"
    );
    let t = heat.blank.element_layer_temperatures(thermal);
    let layer_mean = |ply: usize, layer: usize| {
        let elements = model.plies[ply].elements.clone();
        let n = elements.len() as f64;
        elements.map(|k| t[k * 3 + layer]).sum::<f64>() / n
    };
    let (outer_skin, inner_fabric) = (layer_mean(0, 0), layer_mean(1, 1));
    assert!(
        outer_skin < inner_fabric - 1.0,
        "outer skin {outer_skin:.1} °C, second ply's fabric {inner_fabric:.1} °C"
    );
    let q = &thermal.heat;
    assert!(
        q.imbalance().abs() <= 1e-6 * q.scale(),
        "heat balance {:e} of {:e}",
        q.imbalance(),
        q.scale()
    );
}

/// A blank left in air until it cools below the card's tables stops the run with the element,
/// the time and the table named, and the run is not taken for finished.
#[test]
fn a_blank_cooled_below_the_tables_stops_naming_the_table() {
    let (_, run) = hot(&["tools.temperature=150", "process.transfer_time=30"]);
    let e = run
        .outcome
        .expect_err("a blank at 150 °C and below cannot be formed");
    assert!(
        matches!(e, thermostamp::solver::SolverError::Temperature { .. }),
        "{e}"
    );
    let text = e.to_string();
    assert!(
        text.contains("element") && text.contains("below the crystallisation table"),
        "{text}"
    );
}

/// The friction between plies follows their temperature: with `blank.interply.friction` a table
/// from 0.5 at 150 °C to 0.1 at 320 °C, each interface ends the stroke with the table's value at
/// the mean temperature of its two facing skins, above the 0.1 of the blank out of the oven.
#[test]
fn interply_friction_follows_the_interfaces_temperature() {
    let (forming, run) = common::form(
        "examples/double-dome-nonisothermal.toml",
        &[
            "blank.element_size=10".into(),
            "process.stroke=3".into(),
            "output.history_points=3".into(),
            "blank.interply.friction=[[150.0, 0.5], [320.0, 0.1]]".into(),
        ],
    );
    let state = run.outcome.expect("the example runs");
    let model = &forming.model;
    assert_eq!(state.interface_frictions.len(), 3);
    for (face, friction) in model.interfaces.iter().zip(&state.interface_frictions) {
        let facing = [(face.lower, 2), (face.upper, 0)];
        let (mut sum, mut area) = (0.0, 0.0);
        for (ply, layer) in facing {
            for k in model.plies[ply].elements.clone() {
                sum += model.elements[k].area * state.temperatures[k].layer(layer);
                area += model.elements[k].area;
            }
        }
        let t = sum / area;
        let expected = 0.5 + (0.1 - 0.5) * (t - 150.0) / 170.0;
        assert!(t < 318.0, "interface {}: {t} °C", face.lower + 1);
        assert!(
            (friction.coulomb - expected).abs() < 1e-12 && friction.coulomb > 0.1,
            "interface {}: mu {} at {t:.2} °C, the table gives {expected}",
            face.lower + 1,
            friction.coulomb
        );
    }
}

/// A layup whose interply friction table does not reach down to the tools' temperature is
/// refused before the first step, naming the tool's key and the table's.
#[test]
fn an_interply_table_short_of_the_tools_is_refused() {
    let overrides: Vec<String> = ["blank.interply.friction=[[280.0, 0.3], [320.0, 0.2]]"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    let scenario = Scenario::load(
        &common::repo_path("examples/double-dome-nonisothermal.toml"),
        &overrides,
    )
    .expect("the scenario itself is sound at the blank's temperature");
    let e = FormingModel::new(&scenario).err().expect("refused");
    assert!(
        e.contains("tools.punch.temperature") && e.contains("blank.interply.friction"),
        "{e}"
    );
}
