//! The implicit solver's hot loops on the hemisphere pressed 10 mm into its tools
//! (`examples/hemisphere.toml`): `cargo bench --bench implicit_assembly`.
//!
//! For 8 mm and 4 mm cells (400 and 1,600 quadrilaterals; other sizes in mm with
//! `BENCH_CELLS`, e.g. `BENCH_CELLS=4,2.26` for the 5,041-cell benchmark mesh), on the threads
//! rayon is given (`RAYON_NUM_THREADS`): one residual with the consistent tangent (laminate, hourglass,
//! bending patches and contact, their tangents differenced where docs/solver.md says), one
//! residual alone (what each line-search probe costs), and the sparse Cholesky
//! factorisation and solve of that tangent. A plain timing loop, like the other benches; the
//! figures go in docs/dev/performance-history.md.

use nalgebra::Matrix2;
use std::path::Path;
use std::time::{Duration, Instant};
use thermostamp::forming::{FormingModel, Scenario};
use thermostamp::solver::implicit::assembly::{Evaluator, IncrementStart, Tangent, Trial};
use thermostamp::solver::implicit::linear::Cholesky;
use thermostamp::solver::implicit::{self, ImplicitSettings, ImplicitStatistics};
use thermostamp::solver::{Model, Observer, State};

struct Silent;
impl Observer for Silent {
    fn record(&mut self, _: &Model, _: &State) -> anyhow::Result<()> {
        Ok(())
    }
}

/// Seconds per call of `f`, over calls lasting about `budget`.
fn per_call(budget: Duration, mut f: impl FnMut()) -> f64 {
    f();
    let start = Instant::now();
    let mut calls = 0;
    while start.elapsed() < budget {
        f();
        calls += 1;
    }
    start.elapsed().as_secs_f64() / calls as f64
}

fn main() {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/hemisphere.toml");
    println!(
        "{:>6} {:>9} {:>16} {:>16} {:>16} {:>16}",
        "cell", "elements", "tangent (ms)", "residual (ms)", "factorise (ms)", "solve (ms)"
    );
    let cells = std::env::var("BENCH_CELLS").unwrap_or_else(|_| "8,4".into());
    for cell in cells.split(',').map(str::trim) {
        let overrides = [
            format!("blank.element_size={cell}"),
            "process.stroke=10".into(),
        ];
        let scenario = Scenario::load(&file, &overrides).expect("shipped scenario");
        let forming = FormingModel::new(&scenario).expect("model");
        let model = &forming.model;
        let settings =
            ImplicitSettings::new(forming.settings.end_time, forming.settings.output_interval);
        let pressed = implicit::run(
            model,
            &settings,
            &mut Silent,
            &mut ImplicitStatistics::default(),
        )
        .expect("10 mm of stroke");
        let layout = implicit::layout(model, &settings, &[]).expect("layout");
        let evaluator = Evaluator {
            model,
            layout: &layout,
            exact: settings.exact_tangent,
            stick_slip: implicit::stick_slip(model, &settings),
            plies: None,
        };
        let strains: Vec<Matrix2<f64>> = model
            .elements
            .iter()
            .map(|e| {
                let f = e.gradient(&pressed.positions);
                f.transpose() * f
            })
            .collect();
        let friction = vec![vec![None; model.tools.len()]; model.mesh.nodes.len()];
        let start = IncrementStart {
            positions: &pressed.positions,
            strains: &strains,
            laminate_states: &pressed.laminate_states,
            friction: &friction,
            velocities: &pressed.velocities,
            masses: &pressed.masses,
            dt: settings.output_interval,
            ply_lags: &[],
            ply_lists: &[],
            ply_faces: &[],
            temperatures: &[],
            bending_rigidities: &[],
            released: &[],
        };
        // the next increment's first trial: every node a little farther along its way
        let positions: Vec<_> = pressed
            .positions
            .iter()
            .zip(&pressed.velocities)
            .map(|(x, v)| x + v * (0.25 * settings.output_interval))
            .collect();
        let trial = Trial {
            positions: &positions,
            translations: &pressed.tool_translations,
            engaged: None,
            near: None,
        };
        let budget = Duration::from_secs(3);
        let tangent = per_call(budget, || {
            evaluator
                .evaluate(&start, &trial, Tangent::Consistent)
                .expect("evaluation");
        });
        let residual = per_call(budget, || {
            evaluator
                .evaluate(&start, &trial, Tangent::None)
                .expect("evaluation");
        });
        let mut cholesky = Cholesky::analyse(&layout.pattern).expect("analysis");
        // where the consistent tangent is not positive definite the solver factorises the
        // projected one, as here
        let mut kind = "consistent";
        let mut values = evaluator
            .evaluate(&start, &trial, Tangent::Consistent)
            .expect("evaluation")
            .matrix
            .expect("tangent");
        if cholesky.factorise(&layout.pattern, &values).is_err() {
            kind = "projected";
            values = evaluator
                .evaluate(&start, &trial, Tangent::Projected)
                .expect("evaluation")
                .matrix
                .expect("tangent");
        }
        let factorise = per_call(budget, || {
            cholesky
                .factorise(&layout.pattern, &values)
                .expect("positive definite");
        });
        let solve = per_call(budget, || {
            let mut rhs = vec![1.0; layout.size];
            cholesky.solve(&mut rhs);
        });
        println!(
            "{:>6} {:>9} {:>16.2} {:>16.2} {:>16.2} {:>16.2}  ({kind} tangent factorised)",
            cell,
            model.elements.len(),
            1e3 * tangent,
            1e3 * residual,
            1e3 * factorise,
            1e3 * solve,
        );
    }
}
