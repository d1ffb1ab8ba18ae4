//! Contact and friction between plies (docs/model.md §6, "Ply–ply contact") against the
//! friction law: a ply pulled out from between two plies pressed together by a force `N`.
//! The outer plies are held in their plane and pressed between a fixed floor and a plate
//! driven by `N` (both frictionless); the middle ply, longer than they are, is pulled along x
//! by its end. Once it slides, the pull is the friction of its two faces: `2 mu N` for Coulomb
//! friction, `2 (eta_f / h_f) v A` for the film alone (`A` the overlap's area), `2 tau_max A`
//! once the film yields.

mod common;

use common::{square_plate, t300_card};
use nalgebra::Vector3;
use std::sync::Arc;
use thermostamp::contact::ply_contact::{FilmFriction, PlyInterface};
use thermostamp::contact::{ContactSettings, RigidTool, ToolMotion};
use thermostamp::io::sheet_frame::sheet_frame;
use thermostamp::io::vtk::{Field, FieldData};
use thermostamp::material::MaterialCard;
use thermostamp::mesh::{rectangle, DiagonalPattern};
use thermostamp::solver::implicit::{self, ImplicitSettings, ImplicitStatistics};
use thermostamp::solver::model::PlySheet;
use thermostamp::solver::{explicit, Constraint, Model, Motion, Observer, SolverSettings, State};

/// The press force (N), the outer plies' size (mm), the pull's ramp and duration (s).
const PRESS: f64 = 20.0;
const OUTER: (f64, f64) = (30.0, 20.0);
const RAMP: f64 = 0.01;
const END: f64 = 0.05;

/// A strip of `card` of `width` x 20 mm at height `z`, centred on `x0`.
fn strip(card: &MaterialCard, width: f64, (x0, z): (f64, f64), name: &str) -> PlySheet {
    let mut mesh = rectangle(
        width,
        OUTER.1,
        (width / 2.5) as usize,
        8,
        DiagonalPattern::Quad,
    );
    for x in &mut mesh.nodes {
        x.x += x0;
        x.z = z;
    }
    PlySheet {
        name: name.into(),
        mesh,
        laminate: card.laminate.clone(),
        density: card.density,
        warp_direction: Vector3::x(),
    }
}

/// The three plies, the floor and the plate, `friction` on both interfaces; the middle ply's
/// end pulled at `speed` (mm/s) after a ramp.
fn pull_out(friction: FilmFriction, speed: f64) -> Model {
    let card = t300_card();
    let t = card.laminate.reference_thickness();
    let sheets = vec![
        strip(&card, OUTER.0, (0.0, 0.0), "bottom"),
        strip(&card, 50.0, (8.0, t), "middle"),
        strip(&card, OUTER.0, (0.0, 2.0 * t), "top"),
    ];
    let counts: Vec<usize> = sheets.iter().map(|s| s.mesh.nodes.len()).collect();
    let (first_middle, first_top) = (counts[0], counts[0] + counts[1]);
    let right: Vec<usize> = sheets[1]
        .mesh
        .node_set("right")
        .unwrap()
        .iter()
        .map(|n| n + first_middle)
        .collect();
    let outer: Vec<usize> = (0..counts[0])
        .chain(first_top..first_top + counts[2])
        .collect();
    let constraints = vec![
        Constraint {
            name: "outer plies in their plane".into(),
            nodes: outer,
            motion: Motion::Components([true, true, false]),
        },
        Constraint {
            name: "pulled end".into(),
            nodes: right,
            motion: Motion::Velocity(Arc::new(move |time, _| {
                Vector3::new(speed * (time / RAMP).min(1.0), 0.0, 0.0)
            })),
        },
    ];
    let floor = RigidTool::new(
        "floor",
        square_plate(-t / 2.0, 1.0),
        ToolMotion::Fixed,
        0.0,
        t,
    )
    .unwrap();
    let plate = RigidTool::new(
        "plate",
        square_plate(2.5 * t, -1.0),
        ToolMotion::Force {
            force: Vector3::new(0.0, 0.0, -PRESS),
            mass: 1e-6,
        },
        0.0,
        t,
    )
    .unwrap();
    let contact = ContactSettings {
        offset: t / 2.0,
        penalty_scale: 0.1,
        max_penetration: t,
    };
    let interfaces = vec![
        PlyInterface {
            lower: 0,
            upper: 1,
            friction,
        },
        PlyInterface {
            lower: 1,
            upper: 2,
            friction,
        },
    ];
    Model::layup(sheets, 300.0, constraints)
        .unwrap()
        .with_tools(vec![floor, plate], contact)
        .with_interfaces(interfaces)
        .unwrap()
}

/// The pull (N, along x) at each record after the ramp and the slip's start, and the deepest a
/// node went into a neighbouring ply (mm) over the run.
struct Pull {
    model_pulled: Vec<usize>,
    forces: Vec<f64>,
    deepest: f64,
    last: Option<State>,
}

impl Observer for Pull {
    fn record(&mut self, model: &Model, state: &State) -> anyhow::Result<()> {
        if state.time > 3.0 * RAMP {
            let force: f64 = self
                .model_pulled
                .iter()
                .map(|&n| state.reactions[n].x)
                .sum();
            self.forces.push(force);
        }
        let t = model.plies[0].laminate.reference_thickness();
        let (bottom, middle) = (&model.plies[0].nodes, &model.plies[1].nodes);
        let lowest_middle = state.positions[middle.clone()]
            .iter()
            .map(|x| x.z)
            .fold(f64::INFINITY, f64::min);
        let highest_bottom = state.positions[bottom.clone()]
            .iter()
            .map(|x| x.z)
            .fold(f64::NEG_INFINITY, f64::max);
        self.deepest = self.deepest.max(t - (lowest_middle - highest_bottom));
        self.last = Some(state.clone());
        Ok(())
    }
}

/// Which solver runs the pull-out.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Solver {
    Explicit,
    Implicit,
}

/// The mean pull after the slip has set in (N), the deepest penetration (mm) and the end state.
fn pulled(friction: FilmFriction, speed: f64) -> (f64, f64, State, Model) {
    pulled_until(friction, speed, END, Solver::Explicit)
}

/// [`pulled`] over `end` (s) of the run, by `solver`.
fn pulled_until(
    friction: FilmFriction,
    speed: f64,
    end: f64,
    solver: Solver,
) -> (f64, f64, State, Model) {
    let model = pull_out(friction, speed);
    let mut pull = Pull {
        model_pulled: model.constraints[1].nodes.clone(),
        forces: Vec::new(),
        deepest: 0.0,
        last: None,
    };
    match solver {
        Solver::Explicit => {
            let settings = SolverSettings {
                end_time: end,
                time_step_safety: 0.9,
                target_time_step: Some(3e-6),
                output_interval: END / 60.0,
                damping: 0.0,
                yarn_damping: 0.06,
            };
            common::on_the_pool(|| explicit::run(&model, &settings, &mut pull)).unwrap();
        }
        Solver::Implicit => {
            let mut settings = ImplicitSettings::new(end, END / 60.0);
            settings.max_increment = Some(END / 60.0);
            let mut stats = ImplicitStatistics::default();
            common::on_the_pool(|| implicit::run(&model, &settings, &mut pull, &mut stats))
                .unwrap();
        }
    }
    let mean = pull.forces.iter().sum::<f64>() / pull.forces.len() as f64;
    eprintln!(
        "pull {mean:.4} N (records {:?}), deepest {:.4} mm",
        pull.forces
            .iter()
            .map(|f| (f * 1e3).round() / 1e3)
            .collect::<Vec<_>>(),
        pull.deepest
    );
    (mean, pull.deepest, pull.last.unwrap(), model)
}

/// The Coulomb pull-out (mu = 0.2 at 10 mm/s) on `threads` threads.
fn coulomb_pull_out(threads: usize) -> (f64, f64, State, Model) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| pulled(FilmFriction::coulomb(0.2), 10.0))
}

/// The Coulomb pull-out on two threads, run once for the two tests that check it.
fn coulomb_on_two_threads() -> &'static (f64, f64, State, Model) {
    static RUN: std::sync::OnceLock<(f64, f64, State, Model)> = std::sync::OnceLock::new();
    RUN.get_or_init(|| coulomb_pull_out(2))
}

#[test]
fn coulomb_pull_out_needs_twice_mu_times_the_press_force() {
    let mu = 0.2;
    let (pull, deepest, state, model) = coulomb_on_two_threads();
    let (pull, deepest) = (*pull, *deepest);
    let expected = 2.0 * mu * PRESS;
    assert!(
        (pull / expected - 1.0).abs() < 0.02,
        "pull {pull} N against 2 mu N = {expected} N"
    );
    let t = model.plies[0].laminate.reference_thickness();
    assert!(deepest < 0.1 * t, "a node {deepest} mm into its neighbour");
    // the friction's work: the pull over the middle ply's slip, less what the contact springs
    // hold (a few ten-thousandths of a millimetre deep)
    let e = &state.energies;
    let slip = 10.0 * (END - RAMP / 2.0);
    let dissipated = -e.interply_work;
    eprintln!(
        "energies {e:?}; friction work {dissipated} N·mm, 2 mu N slip {}",
        expected * slip
    );
    assert!(
        (dissipated / (expected * slip) - 1.0).abs() < 0.03,
        "friction dissipated {dissipated} N·mm over a slip of {slip} mm"
    );
    assert!(e.balance_error() < 0.01, "energy balance {e:?}");
    plies_in_the_frame(model, state, slip);
}

/// The frame a layup writes: each cell's ply, the plies' pressure on each node carrying both
/// interfaces' press force (each counted once from each side), and the slip of the nodes
/// that touched all along (the middle ply's over the outer plies, theirs under it).
fn plies_in_the_frame(model: &Model, state: &State, slip: f64) {
    let frame = sheet_frame(model, state).unwrap();
    let scalar = |fields: &[Field], name: &str| -> Vec<f64> {
        match &fields.iter().find(|f| f.name == name).unwrap().data {
            FieldData::Scalar(v) => v.clone(),
            _ => panic!("{name} is not a scalar"),
        }
    };
    let ply = scalar(&frame.cell_data, "ply");
    assert_eq!(ply[0], 1.0);
    assert_eq!(ply[model.plies[2].elements.start], 3.0);
    let pressure = scalar(&frame.point_data, "interply_pressure");
    let pressed: f64 = pressure
        .iter()
        .zip(model.nodal_areas())
        .map(|(p, a)| p * a)
        .sum();
    assert!(
        (pressed / (2.0 * PRESS) - 1.0).abs() < 0.02,
        "the plies press {pressed} N on one another"
    );
    let slid = scalar(&frame.point_data, "interply_slip");
    let most = slid.iter().copied().fold(0.0, f64::max);
    assert!((most / slip - 1.0).abs() < 0.05, "slid {most} mm of {slip}");
}

/// The Coulomb pull-out on one thread and on two, over the whole run (the two-thread run is
/// the one [`coulomb_pull_out_needs_twice_mu_times_the_press_force`] checks): the same bits;
/// and the implicit solver's, once sliding.
#[test]
fn a_layup_runs_the_same_on_any_thread_count() {
    // the one-thread run beside the shared two-thread one
    let ((.., one, _), (.., two, _)) = common::both(|| coulomb_pull_out(1), coulomb_on_two_threads);
    same_state(&one, two);
    let implicit = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let law = FilmFriction::coulomb(0.2);
        pool.install(|| pulled_until(law, 10.0, 4.0 * RAMP, Solver::Implicit).2)
    };
    same_state(&implicit(1), &implicit(2));
}

fn same_state(one: &State, two: &State) {
    assert_eq!(one.positions, two.positions);
    assert_eq!(one.reactions, two.reactions);
    assert_eq!(one.interply, two.interply);
    assert_eq!(one.energies, two.energies);
}

/// A Newtonian film and no Coulomb term: the pull is the film's drag, `2 (eta_f / h_f) v A`,
/// in proportion to the speed (the drag counts the nodes over the other ply's faces, so it
/// steps as a column of them crosses an edge of the outer plies: within 2 % of the law, and
/// twice the speed gives twice the pull within 1 %).
#[test]
fn the_film_drags_in_proportion_to_the_speed() {
    let film = FilmFriction::newtonian(0.0, 5e-3, f64::INFINITY);
    let area = OUTER.0 * OUTER.1;
    // the two runs side by side
    let speeds = vec![5.0, 10.0];
    let pulls = common::side_by_side(speeds.clone(), |speed| pulled(film, speed).0);
    for (&speed, &pull) in speeds.iter().zip(&pulls) {
        let expected = 2.0 * film.film * speed * area;
        assert!(
            (pull / expected - 1.0).abs() < 0.02,
            "at {speed} mm/s: pull {pull} N against 2 eta v A / h = {expected} N"
        );
    }
    assert!((pulls[1] / pulls[0] - 2.0).abs() < 0.02, "{pulls:?}");
}

/// A shear-thinning (Cross) film and no Coulomb term: the pull is `2 tau(v) A` with Cross's
/// `tau(v) = (eta_0 / h) v / (1 + ((eta_0 / h) v / tau_star)^(1-n))` (docs/model.md Eq. (F3)),
/// within 2 % at two speeds: 8.27 N and 12.05 N, where a Newtonian film of the same `eta_0`
/// would pull 15 N and 30 N; by either solver (the implicit one takes the film's drag per
/// speed at the speed lagged, refined as the increment converges).
#[test]
fn a_shear_thinning_film_drags_as_its_law_says() {
    let (film, n, tau_star) = (5e-3, 0.4, 5e-3);
    let law = FilmFriction::cross(0.0, (film * 0.01, n, tau_star), 0.01, f64::INFINITY);
    let area = OUTER.0 * OUTER.1;
    for speed in [5.0, 10.0] {
        let newtonian = film * speed;
        let tau = newtonian / (1.0 + (newtonian / tau_star).powf(1.0 - n));
        let expected = 2.0 * tau * area;
        for solver in [Solver::Explicit, Solver::Implicit] {
            let (pull, ..) = pulled_until(law, speed, END, solver);
            assert!(
                (pull / expected - 1.0).abs() < 0.02,
                "{solver:?} at {speed} mm/s: pull {pull} N against 2 tau(v) A = {expected} N"
            );
        }
    }
}

/// The film's yield caps the shear it carries, however fast the ply is pulled: at 10 mm/s the
/// film alone would drag 60 N, its yield allows 12 N (within 5 %: the nodes over the faces step
/// as above).
#[test]
fn the_film_yields_at_its_cap() {
    let film = FilmFriction::newtonian(0.0, 5e-3, 0.01);
    let area = OUTER.0 * OUTER.1;
    let (pull, ..) = pulled(film, 10.0);
    let expected = 2.0 * film.shear_cap * area;
    assert!(
        (pull / expected - 1.0).abs() < 0.05,
        "pull {pull} N against 2 tau_max A = {expected} N"
    );
}

/// The implicit solver's pull-out: Coulomb's `2 mu N` within 2 %, no node deeper than a tenth
/// of a ply, the friction's work booked.
#[test]
fn the_implicit_solver_pulls_out_as_the_law_says() {
    let mu = 0.2;
    let (pull, deepest, state, model) =
        pulled_until(FilmFriction::coulomb(mu), 10.0, END, Solver::Implicit);
    let expected = 2.0 * mu * PRESS;
    assert!(
        (pull / expected - 1.0).abs() < 0.02,
        "implicit: pull {pull} N against 2 mu N = {expected} N"
    );
    let t = model.plies[0].laminate.reference_thickness();
    assert!(deepest < 0.1 * t, "a node {deepest} mm into its neighbour");
    let e = &state.energies;
    let slip = 10.0 * (END - RAMP / 2.0);
    let dissipated = -e.interply_work;
    assert!(
        (dissipated / (expected * slip) - 1.0).abs() < 0.03,
        "friction dissipated {dissipated} N·mm over a slip of {slip} mm: {e:?}"
    );
    plies_in_the_frame(&model, &state, slip);
}

/// The film's drag in the implicit solver: in proportion to the speed within 2 % of the law,
/// and its cap within 5 %.
#[test]
fn the_implicit_solver_drags_the_film_as_the_law_says() {
    let film = FilmFriction::newtonian(0.0, 5e-3, f64::INFINITY);
    let area = OUTER.0 * OUTER.1;
    for speed in [5.0, 10.0] {
        let (pull, ..) = pulled_until(film, speed, END, Solver::Implicit);
        let expected = 2.0 * film.film * speed * area;
        assert!(
            (pull / expected - 1.0).abs() < 0.02,
            "implicit at {speed} mm/s: pull {pull} N against 2 eta v A / h = {expected} N"
        );
    }
    let capped = FilmFriction {
        shear_cap: 0.01,
        ..film
    };
    let (pull, ..) = pulled_until(capped, 10.0, END, Solver::Implicit);
    let expected = 2.0 * capped.shear_cap * area;
    assert!(
        (pull / expected - 1.0).abs() < 0.05,
        "implicit: pull {pull} N against 2 tau_max A = {expected} N"
    );
}
