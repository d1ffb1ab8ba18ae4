//! Partly held nodes (`Motion::Components`): a symmetry plane. A ±45° strip pulled at both
//! ends and the half of it on one side of its mid-line, held along x on that line, must deform
//! alike: the half model's nodes follow the full model's within rounding, free to contract
//! across the pull on the symmetry line.

mod common;

use common::t300_card;
use nalgebra::Vector3;
use std::sync::Arc;
use thermostamp::mesh::{rectangle, DiagonalPattern, Mesh};
use thermostamp::solver::{self, Constraint, Model, Motion, Observer, SolverSettings, State};

struct Last(Option<State>);

impl Observer for Last {
    fn record(&mut self, _: &Model, state: &State) -> anyhow::Result<()> {
        self.0 = Some(state.clone());
        Ok(())
    }
}

const SPEED: f64 = 500.0;
const END: f64 = 2e-4;

/// The ends' nodes pulled apart along x at `SPEED`, free across the pull; `held` nodes (if
/// any) held along x and z.
fn run(mesh: Mesh, pulled: Vec<(String, Vec<usize>, f64)>, held: Option<Vec<usize>>) -> State {
    let mut constraints: Vec<Constraint> = pulled
        .into_iter()
        .map(|(name, nodes, sign)| Constraint {
            name,
            nodes,
            motion: Motion::Velocity(Arc::new(move |_, _| Vector3::new(sign * SPEED, 0.0, 0.0))),
        })
        .collect();
    if let Some(nodes) = held {
        constraints.push(Constraint {
            name: "symmetry".into(),
            nodes,
            motion: Motion::Components([true, false, true]),
        });
    }
    let card = t300_card();
    let laminate = card.laminate.time_scaled(f64::INFINITY);
    let angle = 0f64.to_radians();
    let warp = Vector3::new(angle.cos(), angle.sin(), 0.0);
    let model = Model::new(mesh, laminate, card.density, 300.0, warp, constraints).unwrap();
    let settings = SolverSettings {
        end_time: END,
        time_step_safety: 0.9,
        target_time_step: None,
        output_interval: END,
        damping: 0.0,
        yarn_damping: 0.0,
    };
    let mut last = Last(None);
    solver::run(&model, &settings, &mut last).unwrap();
    last.0.unwrap()
}

/// Nodes of `mesh` on the line x = `x`.
fn on_line(mesh: &Mesh, x: f64) -> Vec<usize> {
    (0..mesh.nodes.len())
        .filter(|&n| (mesh.nodes[n].x - x).abs() < 1e-9)
        .collect()
}

#[test]
fn a_symmetry_plane_gives_the_half_of_the_full_strip() {
    // 0/90° yarns and crossed cells: the strip is mirror-symmetric about its mid-line x = 0.
    // (A ±45° strip is too, but its near-free trellis modes amplify rounding within a few
    // hundred steps: its full model drifts from symmetry by 1e-3 of the pull by 0.5 % strain.)
    let full = rectangle(40.0, 10.0, 16, 4, DiagonalPattern::Crossed);
    let left = full.node_set("left").unwrap().to_vec();
    let right = full.node_set("right").unwrap().to_vec();
    let full_state = run(
        full.clone(),
        vec![("left".into(), left, -1.0), ("right".into(), right, 1.0)],
        None,
    );
    let stretch = SPEED * END;
    let mut asymmetry: f64 = 0.0;
    for (a, x0) in full.nodes.iter().enumerate() {
        let mirror = Vector3::new(-x0.x, x0.y, x0.z);
        let m = full
            .nodes
            .iter()
            .position(|y| (y - mirror).norm() < 1e-9)
            .unwrap();
        let (u, v) = (
            full_state.positions[a] - x0,
            full_state.positions[m] - mirror,
        );
        asymmetry = asymmetry.max((u - Vector3::new(-v.x, v.y, v.z)).norm());
    }
    assert!(
        asymmetry < 1e-9 * stretch,
        "the full model itself: {asymmetry}"
    );
    let mut half = rectangle(20.0, 10.0, 8, 4, DiagonalPattern::Crossed);
    for x in &mut half.nodes {
        x.x += 10.0;
    }
    let middle = on_line(&half, 0.0);
    let right = half.node_set("right").unwrap().to_vec();
    let half_state = run(
        half.clone(),
        vec![("right".into(), right, 1.0)],
        Some(middle.clone()),
    );
    let mut worst: f64 = 0.0;
    for (a, x0) in half.nodes.iter().enumerate() {
        let b = full
            .nodes
            .iter()
            .position(|y| (y - x0).norm() < 1e-9)
            .unwrap();
        let (u_half, u_full) = (
            half_state.positions[a] - x0,
            full_state.positions[b] - full.nodes[b],
        );
        worst = worst.max((u_half - u_full).norm());
    }
    println!("largest difference {worst:e} mm for a pull of {stretch} mm");
    assert!(worst < 1e-6 * stretch, "{worst}");
    // the symmetry line contracts across the pull: it is free along y
    let lateral: f64 = middle
        .iter()
        .map(|&n| (half_state.positions[n].y - half.nodes[n].y).abs())
        .fold(0.0, f64::max);
    assert!(lateral > 1e-4 * stretch, "{lateral}");
    assert!(middle
        .iter()
        .all(|&n| (half_state.positions[n].x).abs() < 1e-12));
}
