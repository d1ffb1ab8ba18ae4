//! A blank of several plies (`Model::layup`): each ply is its own sheet with its own card and
//! orientation, numbered one after the other. Plies that do not touch must move exactly as each
//! would alone, in both solvers: what one ply's element reads of its material, mass, hourglass
//! and bending is its own ply's, never the first ply's.

mod common;

use common::t300_card;
use nalgebra::Vector3;
use thermostamp::element::BendingRigidity;
use thermostamp::material::MaterialCard;
use thermostamp::mesh::{rectangle, DiagonalPattern, Mesh};
use thermostamp::solver::implicit::{self, ImplicitSettings, ImplicitStatistics};
use thermostamp::solver::model::{ModelError, PlySheet};
use thermostamp::solver::{explicit, Constraint, Model, Motion, Observer, SolverSettings, State};

struct Last(Option<State>);

impl Observer for Last {
    fn record(&mut self, _: &Model, state: &State) -> anyhow::Result<()> {
        self.0 = Some(state.clone());
        Ok(())
    }
}

/// Pull speed of the top edges (mm/s) and the run's duration (s): 1 mm of pull.
const SPEED: f64 = 2.0;
const END: f64 = 0.5;

/// A 20 x 40 mm strip of quadrilaterals lifted to `z`, warp at `angle` degrees from x.
fn strip(card: &MaterialCard, z: f64, angle: f64, name: &str) -> PlySheet {
    let mut mesh = rectangle(20.0, 40.0, 4, 8, DiagonalPattern::Quad);
    for x in &mut mesh.nodes {
        x.z = z;
    }
    let a = angle.to_radians();
    PlySheet {
        name: name.into(),
        mesh,
        laminate: card.laminate.clone(),
        density: card.density,
        warp_direction: Vector3::new(a.cos(), a.sin(), 0.0),
    }
}

/// The strip's bottom edge held, its top edge pulled along y; node numbers from `first`.
fn clamps(mesh: &Mesh, first: usize, name: &str) -> Vec<Constraint> {
    let shifted = |set: &str| -> Vec<usize> {
        let nodes = mesh.node_set(set).unwrap();
        nodes.iter().map(|n| n + first).collect()
    };
    vec![
        Constraint {
            name: format!("{name} bottom"),
            nodes: shifted("bottom"),
            motion: Motion::Fixed,
        },
        Constraint {
            name: format!("{name} top"),
            nodes: shifted("top"),
            motion: Motion::Velocity(std::sync::Arc::new(|_, _| Vector3::new(0.0, SPEED, 0.0))),
        },
    ]
}

/// Each sheet alone, and all of them as one layup, with bending of each ply's `rigidity`.
fn alone_and_together(sheets: &[PlySheet], rigidity: &[BendingRigidity]) -> (Vec<Model>, Model) {
    let alone = sheets
        .iter()
        .zip(rigidity)
        .map(|(s, &r)| {
            let c = clamps(&s.mesh, 0, &s.name);
            Model::layup(vec![s.clone()], 300.0, c)
                .unwrap()
                .with_bending(r)
                .unwrap()
        })
        .collect();
    let mut constraints = Vec::new();
    let mut first = 0;
    for s in sheets {
        constraints.extend(clamps(&s.mesh, first, &s.name));
        first += s.mesh.nodes.len();
    }
    let together = Model::layup(sheets.to_vec(), 300.0, constraints)
        .unwrap()
        .with_ply_bending(rigidity)
        .unwrap();
    (alone, together)
}

/// Newton's tolerance of the implicit runs: each ply of the layup converges with the other's
/// residual in the same norm, so the runs agree to about this fraction of the motion.
const TOLERANCE: f64 = 1e-8;

fn implicit_run(model: &Model) -> State {
    let mut settings = ImplicitSettings::new(END, END / 4.0);
    settings.tolerance = TOLERANCE;
    let mut last = Last(None);
    implicit::run(
        model,
        &settings,
        &mut last,
        &mut ImplicitStatistics::default(),
    )
    .unwrap();
    last.0.unwrap()
}

fn explicit_run(model: &Model) -> State {
    let settings = SolverSettings {
        end_time: 0.02,
        time_step_safety: 0.9,
        target_time_step: None,
        output_interval: 0.01,
        damping: 0.0,
        yarn_damping: 0.06,
    };
    let mut last = Last(None);
    explicit::run(model, &settings, &mut last).unwrap();
    last.0.unwrap()
}

/// Largest distance between the layup's nodes of ply `p` and the same ply run alone (mm), and
/// the largest displacement of that ply alone.
fn difference(together: &State, model: &Model, p: usize, alone: &State) -> (f64, f64) {
    let range = model.plies[p].nodes.clone();
    let reference = &model.mesh.nodes[range.clone()];
    let mut worst: f64 = 0.0;
    let mut moved: f64 = 0.0;
    for ((x, y), x0) in together.positions[range]
        .iter()
        .zip(&alone.positions)
        .zip(reference)
    {
        worst = worst.max((x - y).norm());
        moved = moved.max((y - x0).norm());
    }
    (worst, moved)
}

/// Two strips 10 mm apart, one at 0°, one at 45° of a card with its matrix's viscosity divided by
/// ten and a third of the density, each with its own bending: pulled 1 mm, each moves as it does alone,
/// to a millionth (Newton converged to 1e-8); and the two strips alone differ by far more, so the
/// check would see one ply taking the other's material.
#[test]
fn separate_plies_move_as_each_alone_implicit() {
    let card = t300_card();
    let mut soft = card.clone();
    soft.laminate = soft.laminate.time_scaled(10.0);
    soft.density /= 3.0;
    let sheets = [strip(&card, 0.0, 0.0, "a"), strip(&soft, 10.0, 45.0, "b")];
    let rigidity = [
        BendingRigidity {
            warp: 0.5,
            weft: 0.5,
        },
        BendingRigidity {
            warp: 0.05,
            weft: 0.02,
        },
    ];
    let (alone, together) = alone_and_together(&sheets, &rigidity);
    assert_eq!(together.plies.len(), 2);
    assert_eq!(together.ply_of(together.elements.len() - 1).name, "b");
    // the three runs side by side
    let mut runs = common::side_by_side(alone.iter().chain([&together]).collect(), implicit_run);
    let both = runs.pop().unwrap();
    for (p, run) in runs.iter().enumerate() {
        let (worst, moved) = difference(&both, &together, p, run);
        eprintln!("ply {p}: {worst:.3e} mm off its run alone, which moved {moved:.3} mm");
        assert!(moved > 0.9, "ply {p} moved {moved} mm");
        assert!(worst < 1e-6 * moved, "ply {p}: {worst} mm");
    }
    let shifted = Vector3::new(0.0, 0.0, 10.0);
    let apart = runs[0]
        .positions
        .iter()
        .zip(&runs[1].positions)
        .map(|(a, b)| (a + shifted - b).norm())
        .fold(0.0, f64::max);
    eprintln!("the two plies alone differ by {apart:.3e} mm");
    assert!(apart > 1e-2, "{apart}");
}

/// The same in the explicit solver, whose nodal masses and stable step are each ply's own: the
/// layup's positions equal each ply's alone to rounding, the mass of each ply is its own.
#[test]
fn separate_plies_move_as_each_alone_explicit() {
    let card = t300_card();
    let mut light = card.clone();
    light.density /= 4.0;
    let sheets = [strip(&card, 0.0, 0.0, "a"), strip(&light, 10.0, 30.0, "b")];
    let rigidity = [BendingRigidity {
        warp: 0.2,
        weft: 0.2,
    }; 2];
    let (alone, together) = alone_and_together(&sheets, &rigidity);
    // the three runs side by side
    let mut runs = common::side_by_side(alone.iter().chain([&together]).collect(), explicit_run);
    let both = runs.pop().unwrap();
    for (p, run) in runs.iter().enumerate() {
        let ply = &together.plies[p];
        let mass: f64 = both.masses[ply.nodes.clone()].iter().sum();
        let alone_mass: f64 = run.masses.iter().sum();
        assert!((mass / alone_mass - 1.0).abs() < 1e-12, "ply {p}");
        let (worst, moved) = difference(&both, &together, p, run);
        eprintln!("ply {p}: {worst:.3e} mm off its run alone, which moved {moved:.3} mm");
        assert!(moved > 1e-3, "ply {p} moved {moved} mm");
        assert!(worst < 1e-9 * moved.max(1.0), "ply {p}: {worst} mm");
    }
    let masses: Vec<f64> = runs.iter().map(|r| r.masses.iter().sum()).collect();
    assert!((masses[0] / masses[1] - 4.0).abs() < 1e-9, "{masses:?}");
}

/// A layup's mesh: each ply's nodes, cells and sets after the ones before, its sets named
/// `ply/set`.
#[test]
fn a_layup_numbers_its_plies_one_after_the_other() {
    let card = t300_card();
    let sheets = vec![strip(&card, 0.0, 0.0, "a"), strip(&card, 1.0, 90.0, "b")];
    let (nodes, cells) = (sheets[0].mesh.nodes.len(), sheets[0].mesh.cells.len());
    let model = Model::layup(sheets.clone(), 300.0, vec![]).unwrap();
    assert_eq!(model.plies[1].nodes, nodes..2 * nodes);
    assert_eq!(model.plies[1].elements, cells..2 * cells);
    let top_b = model.mesh.node_set("b/top").unwrap();
    let top = sheets[1].mesh.node_set("top").unwrap();
    assert_eq!(top_b, top.iter().map(|n| n + nodes).collect::<Vec<_>>());
    for (k, e) in model.elements.iter().enumerate() {
        let ply = model.ply_of(k);
        assert!(
            e.nodes().iter().all(|n| ply.nodes.contains(n)),
            "element {k}"
        );
    }
    // the second ply's warp runs along y
    let warp = model.elements[cells].basis * model.elements[cells].fibres.warp.xy();
    assert!((warp.y.abs() - 1.0).abs() < 1e-12, "{warp}");
}

/// Bad layups are refused with the ply named.
#[test]
fn bad_layups_are_refused() {
    let card = t300_card();
    assert_eq!(
        Model::layup(vec![], 300.0, vec![]).unwrap_err(),
        ModelError::NoPly
    );
    let mut light = strip(&card, 1.0, 0.0, "b");
    light.density = -1.0;
    let e = Model::layup(vec![strip(&card, 0.0, 0.0, "a"), light], 300.0, vec![]).unwrap_err();
    assert!(e.to_string().contains("ply 'b'"), "{e}");
}
