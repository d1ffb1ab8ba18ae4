//! Penalty contact with Coulomb friction (docs/model.md §6) against its definition: a blank
//! squeezed between two flat plates and pulled across them needs a force equal to the friction
//! coefficient times the normal force, and no node sinks into a plate deeper than 10 % of the
//! ply thickness.

mod common;

use nalgebra::Vector3;
use std::sync::Arc;
use thermostamp::contact::{RigidTool, ToolMotion};
use thermostamp::material::MaterialCard;
use thermostamp::mesh::{rectangle, DiagonalPattern};
use thermostamp::solver::{self, Constraint, Model, Motion, Observer, SolverSettings, State};

/// Per record: time, pull force (reaction of the pulled edge along -x), normal force on the
/// upper plate, deepest penetration into either plate.
#[derive(Default)]
struct History(Vec<[f64; 4]>);

impl Observer for History {
    fn record(&mut self, model: &Model, state: &State) -> anyhow::Result<()> {
        let pulled = model.mesh.node_set("left")?;
        let pull: f64 = -pulled.iter().map(|&n| state.reactions[n].x).sum::<f64>();
        let offset = model.contact.offset;
        let upper = 0.5 * 0.3 + state.tool_translations[1].z;
        let penetration = state
            .positions
            .iter()
            .map(|p| (p.z + offset - upper).max(-0.5 * 0.3 - (p.z - offset)))
            .fold(0.0, f64::max);
        self.0.push([
            state.time,
            pull,
            state.tool_loads[1].normal_force,
            penetration,
        ]);
        Ok(())
    }
}

/// The stiff-yarn fabric (0.3 mm), 20 x 20 mm, between a frictionless lower plate at its lower
/// face and an upper plate with `mu = 0.3` at its upper face. The upper plate comes down 0.02 mm
/// in 5 ms and stays; then the left edge is pulled along -x (the yarns in tension) at 100 mm/s (smooth start over 2 ms)
/// for 2 mm. `solve` runs the model to the end time it is given, recording into the history.
/// Over the second half of the slide the pull force must be `mu N` within 2 %, `N` the normal
/// force on the upper plate; the deepest penetration below 10 % of the thickness; the energy
/// balanced within 1 % (the tools' work included).
fn slide_against_coulomb(solve: impl Fn(&Model, f64, &mut History) -> State) {
    let card = MaterialCard::load(&common::repo_path("tests/data/stiff-yarn-fabric.toml")).unwrap();
    let t = card.laminate.reference_thickness();
    let (squeeze, t_squeeze, speed, ramp, slide) = (0.02, 5e-3, 100.0, 2e-3, 2.0);
    let end = t_squeeze + ramp + slide / speed;
    let mu = 0.3;
    let mesh = rectangle(20.0, 20.0, 4, 4, DiagonalPattern::Right);
    let pulled = mesh.node_set("left").unwrap().to_vec();
    let pull = move |time: f64| {
        let s = ((time - t_squeeze) / ramp).clamp(0.0, 1.0);
        Vector3::new(-speed * s * s * (3.0 - 2.0 * s), 0.0, 0.0)
    };
    let constraints = vec![Constraint {
        name: "pulled edge".into(),
        nodes: pulled,
        motion: Motion::Velocity(Arc::new(move |time, _| pull(time))),
    }];
    let press = ToolMotion::Velocity(Arc::new(move |time| {
        let v = if time < t_squeeze {
            squeeze / t_squeeze
        } else {
            0.0
        };
        Vector3::new(0.0, 0.0, -v)
    }));
    let tools = vec![
        RigidTool::new(
            "lower plate",
            common::square_plate(-t / 2.0, 1.0),
            ToolMotion::Fixed,
            0.0,
            t,
        )
        .unwrap(),
        RigidTool::new(
            "upper plate",
            common::square_plate(t / 2.0, -1.0),
            press,
            mu,
            t,
        )
        .unwrap(),
    ];
    let model = common::sheet_among_tools(&card, mesh, constraints, tools);
    let mut history = History::default();
    let state = solve(&model, end, &mut history);
    let sliding: Vec<_> = history
        .0
        .iter()
        .filter(|r| r[0] > t_squeeze + ramp + 0.5 * slide / speed)
        .collect();
    let (pull_force, normal): (f64, f64) = sliding
        .iter()
        .fold((0.0, 0.0), |(f, n), r| (f + r[1], n + r[2]));
    let (pull_force, normal) = (
        pull_force / sliding.len() as f64,
        normal / sliding.len() as f64,
    );
    assert!(normal > 0.0, "the upper plate carries no load");
    assert!(
        (pull_force / (mu * normal) - 1.0).abs() < 0.02,
        "pull {pull_force} N, mu N = {} N",
        mu * normal
    );
    let deepest = history.0.iter().map(|r| r[3]).fold(0.0, f64::max);
    assert!(deepest < 0.1 * t, "penetration {deepest} mm");
    assert!(
        state.energies.balance_error() < 0.01,
        "{:?}",
        state.energies
    );
}

/// The explicit solver (measured: pull within 0.007 % of `mu N`; deepest penetration 0.02 mm,
/// at the pulled edge held at mid-height).
#[test]
fn sliding_needs_mu_times_the_normal_force() {
    slide_against_coulomb(|model, end, history| {
        let settings = SolverSettings {
            end_time: end,
            time_step_safety: 0.9,
            target_time_step: None,
            output_interval: end / 100.0,
            damping: 0.0,
            yarn_damping: 0.06,
        };
        solver::run(model, &settings, history).unwrap()
    });
}

/// The implicit solver, quasi-static: friction regularised by a sliding speed far below the
/// pull's 100 mm/s, so Coulomb's force (docs/solver.md, "Implicit"; measured: pull within
/// 0.001 % of `mu N`, deepest penetration 0.021 mm).
#[test]
fn implicit_sliding_needs_mu_times_the_normal_force() {
    slide_against_coulomb(|model, end, history| {
        let settings = solver::implicit::ImplicitSettings::new(end, end / 100.0);
        let mut statistics = Default::default();
        solver::implicit::run(model, &settings, history, &mut statistics).unwrap()
    });
}

/// Die load at every output.
#[derive(Default)]
struct DieLoad(Vec<(f64, f64)>);

impl Observer for DieLoad {
    fn record(&mut self, _: &Model, state: &State) -> anyhow::Result<()> {
        self.0.push((state.time, state.tool_loads[0].normal_force));
        Ok(())
    }
}

/// A blank holder driven by a force: a 20 x 20 mm blank between a fixed plate above (the die)
/// and a plate below pushed up with 50 N (the holder, free along z, ten times the blank's
/// mass). The holder closes the 0.05 mm gap, squeezes the blank, and the die carries the holder's
/// force: its mean load over the last half of 20 ms is 50 N within 2 %.
#[test]
fn force_driven_holder_presses_with_its_force() {
    let card = MaterialCard::load(&common::repo_path("tests/data/stiff-yarn-fabric.toml")).unwrap();
    let t = card.laminate.reference_thickness();
    let (force, end) = (50.0, 0.02);
    let blank_mass = card.density * t * 400.0;
    let holder = ToolMotion::Force {
        force: Vector3::new(0.0, 0.0, force),
        mass: 10.0 * blank_mass,
    };
    let tools = vec![
        RigidTool::new(
            "die",
            common::square_plate(t / 2.0, -1.0),
            ToolMotion::Fixed,
            0.2,
            t,
        )
        .unwrap(),
        RigidTool::new(
            "holder",
            common::square_plate(-t / 2.0 - 0.05, 1.0),
            holder,
            0.2,
            t,
        )
        .unwrap(),
    ];
    let model = common::free_sheet(&card, tools);
    let settings = SolverSettings {
        end_time: end,
        time_step_safety: 0.9,
        target_time_step: None,
        output_interval: end / 200.0,
        damping: 0.0,
        yarn_damping: 0.06,
    };
    let mut loads = DieLoad::default();
    solver::run(&model, &settings, &mut loads).unwrap();
    let late: Vec<f64> = loads
        .0
        .iter()
        .filter(|r| r.0 > end / 2.0)
        .map(|r| r.1)
        .collect();
    let mean = late.iter().sum::<f64>() / late.len() as f64;
    assert!(
        (mean / force - 1.0).abs() < 0.02,
        "die load {mean} N for {force} N"
    );
}
