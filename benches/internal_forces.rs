//! The explicit solver's hot loop on the bias-extension benchmark specimen (150 x 450 mm,
//! ±45°, T300/PPS laminate at 300 °C): `cargo bench --bench internal_forces`.
//!
//! For 2 mm and 1 mm cells, crossed triangles (four per cell), single-diagonal triangles (two)
//! and quadrilaterals (one), on 1 and 2 threads: the internal-force pass alone (element loop
//! plus nodal gather, as in every step) and whole explicit steps (force pass, stable step,
//! nodal update, energy sums), as element-steps per second. A plain timing loop, like the
//! material-point bench. Record the figures in docs/dev/performance-history.md.

use nalgebra::Matrix3;
use std::path::Path;
use std::time::{Duration, Instant};
use thermostamp::experiment::bias_extension::BiasExtension;
use thermostamp::experiment::sheet_test::SheetTest;
use thermostamp::material::MaterialCard;
use thermostamp::mesh::DiagonalPattern;
use thermostamp::solver::{self, InternalForces, Model, Observer, SolverSettings, State};

const TEMPERATURE: f64 = 300.0;

/// Deforms the sheet by a uniform in-plane stretch and shear with a small rate, so that every
/// layer law does the work of a sheared, moving state rather than of the rest state.
fn deformed(model: &Model, state: &mut State) {
    let f = Matrix3::new(1.01, 0.12, 0.0, 0.03, 0.995, 0.0, 0.0, 0.0, 1.0);
    let rate = Matrix3::new(0.5, 2.0, 0.0, 1.0, -0.2, 0.0, 0.0, 0.0, 0.0);
    for (a, x0) in model.mesh.nodes.iter().enumerate() {
        state.positions[a] = f * x0;
        state.velocities[a] = rate * x0;
    }
}

struct Silent;
impl Observer for Silent {
    fn record(&mut self, _: &Model, _: &State) -> anyhow::Result<()> {
        Ok(())
    }
}

/// Seconds per internal-force pass, over passes lasting about `budget`.
fn force_pass(model: &Model, settings: &SolverSettings, budget: Duration) -> f64 {
    let mut state = thermostamp::solver::explicit::initial_state(model, settings).unwrap();
    deformed(model, &mut state);
    let mut forces = InternalForces::new(model);
    let dt = 1e-6;
    forces
        .evaluate(model, &mut state, dt, settings.yarn_damping)
        .unwrap();
    let start = Instant::now();
    let mut passes = 0;
    while start.elapsed() < budget {
        forces
            .evaluate(model, &mut state, dt, settings.yarn_damping)
            .unwrap();
        passes += 1;
    }
    start.elapsed().as_secs_f64() / passes as f64
}

/// Seconds per whole explicit step over the first `steps` steps of the test.
fn whole_steps(model: &Model, settings: &SolverSettings, steps: usize) -> f64 {
    let mut state = thermostamp::solver::explicit::initial_state(model, settings).unwrap();
    let (dt, _) = InternalForces::new(model)
        .evaluate(model, &mut state, 0.0, 0.0)
        .unwrap();
    let mut short = settings.clone();
    short.end_time = steps as f64 * dt * settings.time_step_safety;
    short.output_interval = short.end_time;
    let start = Instant::now();
    let end = solver::run(model, &short, &mut Silent).unwrap();
    start.elapsed().as_secs_f64() / end.step.max(1) as f64
}

fn main() {
    let card = MaterialCard::load(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("materials/t300-5hs-pps.toml"),
    )
    .expect("shipped card");
    println!(
        "{:>6} {:>11} {:>9} {:>7} {:>14} {:>16} {:>16} {:>8}",
        "cell",
        "pattern",
        "elements",
        "threads",
        "pass (ms)",
        "el/s (forces)",
        "el-steps/s",
        "speedup"
    );
    let patterns = [
        DiagonalPattern::Crossed,
        DiagonalPattern::Right,
        DiagonalPattern::Quad,
    ];
    for (size, pattern) in [2.0, 1.0]
        .into_iter()
        .flat_map(|s| patterns.map(|p| (s, p)))
    {
        let mut test = BiasExtension::benchmark(TEMPERATURE);
        test.process.element_size = size;
        test.process.pattern = pattern;
        let model = test.model(&card.laminate, card.density).expect("model");
        let settings = test.settings();
        let elements = model.elements.len() as f64;
        let mut serial = None;
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let (pass, step) = pool.install(|| {
                (
                    force_pass(&model, &settings, Duration::from_secs(3)),
                    whole_steps(&model, &settings, if size < 1.5 { 20 } else { 60 }),
                )
            });
            let speedup = serial.map_or(1.0, |s: f64| s / step);
            serial.get_or_insert(step);
            let name = format!("{pattern:?}").to_lowercase();
            println!(
                "{size:>4}mm {name:>11} {elements:>9} {threads:>7} {:>14.2} {:>16.3e} {:>16.3e} {speedup:>8.2}",
                pass * 1e3,
                elements / pass,
                elements / step
            );
        }
    }
}
