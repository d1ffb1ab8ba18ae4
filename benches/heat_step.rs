//! What the heat equation costs a non-isothermal run (docs/model.md §9), on the four-ply
//! double dome of `examples/double-dome-nonisothermal.toml` over the first millimetres of its
//! stroke: `cargo bench --bench heat_step`.
//!
//! Each solver runs the stroke (the transfer in air before it included): the wall time of the
//! run, the heat equation's own time (`ThermalState::wall_seconds`), its time per step
//! (explicit) or increment (implicit) and its share of the run.
//! Stroke and cell size in mm with `BENCH_STROKE` and `BENCH_CELL` (default 3 and 8). A plain
//! timing run, like the other benches; the figures go in docs/performance.md.

use std::path::Path;
use std::time::Instant;
use thermostamp::forming::{FormingModel, Scenario};

fn main() {
    let file =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/double-dome-nonisothermal.toml");
    let stroke = std::env::var("BENCH_STROKE").unwrap_or_else(|_| "3".into());
    let cell = std::env::var("BENCH_CELL").unwrap_or_else(|_| "8".into());
    println!(
        "{:>9} {:>9} {:>11} {:>12} {:>14} {:>10}",
        "solver", "steps", "run (s)", "heat (s)", "heat/step (ms)", "heat share"
    );
    for solver in ["explicit", "implicit"] {
        let overrides = vec![
            format!("process.solver={solver}"),
            format!("process.stroke={stroke}"),
            format!("blank.element_size={cell}"),
            "output.frames=0".to_string(),
        ];
        let scenario = match solver {
            "implicit" => implicit_scenario(&file, &overrides),
            _ => Scenario::load(&file, &overrides).expect("the example loads"),
        };
        let forming = FormingModel::new(&scenario).expect("the example's model");
        let started = Instant::now();
        let run = thermostamp::forming::run::run(&forming, None, None);
        let wall = started.elapsed().as_secs_f64();
        let state = run.outcome.expect("the example runs");
        let heat = state
            .thermal
            .as_ref()
            .expect("a temperature field")
            .wall_seconds;
        let steps = run.steps.max(1);
        println!(
            "{:>9} {:>9} {:>11.2} {:>12.3} {:>14.4} {:>9.1} %",
            solver,
            steps,
            wall,
            heat,
            1e3 * heat / steps as f64,
            100.0 * heat / wall
        );
    }
}

/// The example on the implicit solver: without the explicit solver's time and mass scaling,
/// which the implicit solver refuses.
fn implicit_scenario(file: &Path, overrides: &[String]) -> Scenario {
    let text = std::fs::read_to_string(file).expect("the example");
    let text: String = text
        .lines()
        .filter(|l| !l.starts_with("time_scaling") && !l.starts_with("target_time_step"))
        .map(|l| format!("{l}\n"))
        .collect();
    let folder = file.parent().expect("the example's folder");
    Scenario::from_text(&text, &file.display().to_string(), folder, overrides)
        .expect("the example on the implicit solver")
}
