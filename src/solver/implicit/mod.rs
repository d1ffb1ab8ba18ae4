//! Quasi-static implicit solution of the sheet (docs/solver.md, "Implicit"): no inertia, the
//! tools and constraints moved at the physical speed in increments of time, each increment
//! solved by Newton's method on the full nonlinear problem.
//!
//! Per increment `t_n -> t_{n+1} = t_n + dt` the unknowns are the node positions and the
//! travel of the force-driven tools; the residual is the gradient of the incremental potential
//! `Pi = sum_e A0 w_e + bending + contact + friction + drag - F u`, the viscous matrix taking the
//! backward-Euler rate `Cdot = (C - C_n) / dt`. The drag `1/2 c |x - x_n|^2` (`c` a small
//! fraction of the sheet's shear stiffness per node) holds the rigid and zero-stiffness modes of
//! a sheet that nothing yet supports; its work is booked in [`Energies::damping`] and watched.
//!
//! Newton's direction comes from a sparse Cholesky factorisation of the tangent
//! ([`linear::Cholesky`]); where the consistent tangent is not positive definite (the sheet
//! buckling, a wrinkle forming), every element's tangent is projected to its positive
//! semi-definite part ([`assembly::Tangent::Projected`]) and the step is globalised by a
//! backtracking line search on the residual. The contact springs a correction enters are
//! anticipated in its linear model ([`contact_entry`]). An increment that does not converge is
//! cut; one that converges fast lets the next grow.

pub mod assembly;
pub mod contact_entry;
pub mod interply;
pub mod linear;
mod newton;
mod scatter;
mod supernodal;

use super::energy::Energies;
use super::error::{positive_setting, SolverError};
use super::heat;
use super::model::{rest_moduli, Model, Motion, Ply};
use super::observer::Observer;
use super::state::State;
use crate::contact::penalty::nodes_through_tools;
use crate::contact::ply_contact::PlyContact;
use crate::contact::potential::{penalty_stiffness, FrictionLag};
use crate::contact::{RigidTool, ToolMotion};
use assembly::{Evaluation, Evaluator, IncrementStart, Layout, NearLists, Tangent, Trial};
use interply::PlyLags;
use linear::{Cholesky, NotSolved, Sparsified};
use nalgebra::{Matrix2, Vector3};
use newton::{newton, Problem};

/// How to solve.
#[derive(Clone, Debug, PartialEq)]
pub struct ImplicitSettings {
    /// Process time to reach (s).
    pub end_time: f64,
    /// Time between two records (s): a record is made at the end of the first increment at or
    /// past each multiple of it; the records never shorten an increment.
    pub output_interval: f64,
    /// Largest increment (s); `None`: [`DEFAULT_INCREMENTS`] of them over the run.
    pub max_increment: Option<f64>,
    /// Residual norm below which an increment has converged, as a fraction of the norm of the
    /// internal and contact forces.
    pub tolerance: f64,
    /// Newton iterations after which an increment is cut.
    pub max_iterations: usize,
    /// Drag per node as a fraction of the sheet's in-plane shear stiffness `G t0`.
    pub stabilisation: f64,
    /// Elastic slip of friction's stick, as a fraction of the ply's thickness: a node
    /// starting from rest slides once it has slipped this far (docs/solver.md, "Friction").
    pub friction_stick: f64,
    /// Contact spring scale `s` of `k = s E t0 A / h^2`.
    pub penalty_scale: f64,
    /// The exact tangents of bending and contact (analytic) and of the hourglass control
    /// (central differences of its forces), the default; or their Gauss–Newton parts: on the
    /// hemisphere (measured with a 1e-4 slack band) the run then stalls at 9.4 mm of stroke
    /// where, exact, it reaches 25.3 mm (docs/solver.md).
    pub exact_tangent: bool,
    /// Entries of the tangent's factor from which the linear solves are made by conjugate
    /// gradients preconditioned on the membrane's stencil, where the model has bending
    /// patches (docs/solver.md, "Conjugate gradients on the membrane's stencil"): 0 always,
    /// `usize::MAX` never.
    pub iterative_from: usize,
}

impl ImplicitSettings {
    /// Defaults for a run to `end_time` recorded every `output_interval`.
    pub fn new(end_time: f64, output_interval: f64) -> Self {
        Self {
            end_time,
            output_interval,
            max_increment: None,
            tolerance: 1e-4,
            max_iterations: 25,
            stabilisation: 1e-4,
            friction_stick: FRICTION_STICK,
            penalty_scale: 0.1,
            exact_tangent: true,
            iterative_from: ITERATIVE_FACTOR_ENTRIES,
        }
    }
}

/// Counters and the time split of an implicit run.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ImplicitStatistics {
    pub increments: usize,
    pub cut_increments: usize,
    pub iterations: usize,
    /// Factorisations of the tangent, and of its preconditioner on the membrane's stencil.
    pub factorisations: usize,
    pub preconditioner_factorisations: usize,
    /// Conjugate-gradient iterations of the linear solves.
    pub cg_iterations: usize,
    /// Iterations that needed the projected tangent.
    pub projected: usize,
    /// Wall-clock seconds in assembly (elements, patches, contact), factorisation and solve.
    pub assembly_seconds: f64,
    pub solve_seconds: f64,
}

/// What the run keeps between increments besides the [`State`].
struct Converged {
    strains: Vec<Matrix2<f64>>,
    friction: Vec<Vec<Option<FrictionLag>>>,
    previous_forces: Vec<Vector3<f64>>,
    previous_reactions: Vec<Vector3<f64>>,
    previous_contact: Vec<Vector3<f64>>,
    previous_support: Vec<Vector3<f64>>,
    /// Friction of each node on the plies below and above it, lagged for the next increment,
    /// and the force of the plies on each node at the last one.
    ply_lags: PlyLags,
    previous_interply: Vec<Vector3<f64>>,
}

/// What Newton's method keeps from one iteration and increment to the next: the
/// factorisations on the run's pattern and on its preconditioner's, and the lists of the
/// tools' triangles near each node.
struct Workspace {
    cholesky: Cholesky,
    near: NearLists,
    /// The tangent's values, a buffer reused by every iteration.
    values: Vec<f64>,
    /// Where the linear solves are iterative, their preconditioner.
    preconditioner: Option<Preconditioner>,
}

impl Workspace {
    /// The symbolic factorisations of `layout`'s tangent and, where its solves are made
    /// iteratively, of its preconditioner.
    fn new(
        model: &Model,
        layout: &Layout,
        settings: &ImplicitSettings,
    ) -> Result<Self, SolverError> {
        let cholesky = Cholesky::analyse(&layout.pattern).map_err(SolverError::Settings)?;
        let preconditioner = Preconditioner::of(model, layout, &cholesky, settings.iterative_from)
            .map_err(SolverError::Settings)?;
        Ok(Self {
            cholesky,
            near: NearLists::default(),
            values: Vec::new(),
            preconditioner,
        })
    }

    /// Laid out again on `layout`, the lists of near triangles kept.
    fn relaid(
        self,
        model: &Model,
        layout: &Layout,
        settings: &ImplicitSettings,
    ) -> Result<Self, SolverError> {
        Ok(Self {
            near: self.near,
            ..Self::new(model, layout, settings)?
        })
    }
}

/// The tangent on the membrane's stencil: where its entries come from, its factorisation and
/// a buffer for its values.
struct Preconditioner {
    sparsified: Sparsified,
    cholesky: Cholesky,
    values: Vec<f64>,
}

impl Preconditioner {
    /// The preconditioner of `layout`'s linear solves, where they are made iteratively: where
    /// `model` has bending patches and the tangent's factor, `cholesky`'s, has `from` entries
    /// or more.
    fn of(
        model: &Model,
        layout: &Layout,
        cholesky: &Cholesky,
        from: usize,
    ) -> Result<Option<Self>, String> {
        if cholesky.factor_entries() < from {
            return Ok(None);
        }
        let Some(sparsified) = layout.membrane_preconditioner(model) else {
            return Ok(None);
        };
        Ok(Some(Self {
            cholesky: Cholesky::analyse(&sparsified.pattern)?,
            sparsified,
            values: Vec::new(),
        }))
    }
}

/// Why a linear solve was not made by conjugate gradients.
enum NotIterated {
    /// There is no preconditioner, or the iterations did not converge within
    /// [`CG_ITERATIONS`]: the tangent is to be factorised.
    Factorise,
    /// The tangent is not positive definite: the preconditioner on the membrane's stencil,
    /// which lies above it, is not, or a search direction has no positive curvature. Its
    /// factorisation would fail too.
    Indefinite,
}

/// Solves `K d = rhs` for the tangent `K` in `values` (on `layout`'s pattern) by conjugate
/// gradients preconditioned with its factorisation on the membrane's stencil (docs/solver.md,
/// "Conjugate gradients on the membrane's stencil"), or says why not.
fn iterative_solve(
    layout: &Layout,
    preconditioner: Option<&mut Preconditioner>,
    values: &[f64],
    rhs: &[f64],
    stats: &mut ImplicitStatistics,
) -> Result<Vec<f64>, NotIterated> {
    let p = preconditioner.ok_or(NotIterated::Factorise)?;
    p.sparsified.values(values, &mut p.values);
    stats.preconditioner_factorisations += 1;
    p.cholesky
        .factorise(&p.sparsified.pattern, &p.values)
        .map_err(|_| NotIterated::Indefinite)?;
    let solved =
        p.cholesky
            .conjugate_gradients(&layout.pattern, values, rhs, CG_TOLERANCE, CG_ITERATIONS);
    let iterations = match &solved {
        Ok((_, iterations)) | Err((_, iterations)) => *iterations,
    };
    stats.cg_iterations += iterations;
    match solved {
        Ok((d, _)) => Ok(d),
        Err((NotSolved::NotPositiveDefinite, _)) => Err(NotIterated::Indefinite),
        Err((NotSolved::Slow, _)) => Err(NotIterated::Factorise),
    }
}

/// Why an increment failed.
struct NotConverged {
    residuals: Vec<f64>,
    worst_nodes: Vec<usize>,
    reason: String,
}

/// Solves `model` quasi-statically to `settings.end_time`, reporting to `observer`; `stats`
/// counts the work done, also when the run stops early.
pub fn run(
    model: &Model,
    settings: &ImplicitSettings,
    observer: &mut dyn Observer,
    stats: &mut ImplicitStatistics,
) -> Result<State, SolverError> {
    check_settings(settings)?;
    let mut plies = model.ply_contact(IMPLICIT_PLY_MARGIN);
    let mut state = rest_state(model);
    heat::start(model, &mut state)?;
    let couplings = relist_plies(plies.as_mut(), &mut state, true);
    let mut layout = layout(model, settings, &couplings)?;
    let mut work = Workspace::new(model, &layout, settings)?;
    seat_force_driven_tools(model, &layout, &mut state);
    let n = model.mesh.nodes.len();
    let mut converged = Converged {
        strains: vec![Matrix2::identity(); model.elements.len()],
        friction: vec![vec![None; model.tools.len()]; n],
        previous_forces: vec![Vector3::zeros(); n],
        previous_reactions: vec![Vector3::zeros(); n],
        previous_contact: vec![Vector3::zeros(); n],
        previous_support: vec![Vector3::zeros(); n],
        ply_lags: vec![[None, None]; state.interply.len()],
        previous_interply: vec![Vector3::zeros(); n],
    };
    let max_increment = settings
        .max_increment
        .unwrap_or(settings.end_time / DEFAULT_INCREMENTS);
    let mut dt = 0.25 * max_increment;
    let evaluator = evaluator_of(model, &layout, settings, plies.as_ref());
    close_force_driven_tools(
        &evaluator,
        &mut work,
        (&mut state, &mut converged),
        settings.end_time,
        settings,
        stats,
    );
    observer
        .record(model, &state)
        .and_then(|()| observer.checkpoint(model, &state))
        .map_err(|source| SolverError::Output { time: 0.0, source })?;
    let min_increment = 1e-6 * settings.end_time;
    let mut next_output = settings.output_interval;
    let mut recorded = 0.0;
    while state.time < settings.end_time * (1.0 - 1e-12) {
        if observer.interrupted() {
            if state.time > recorded {
                record(model, &mut state, observer)?;
            }
            return Err(SolverError::Interrupted {
                step: state.step,
                time: state.time,
            });
        }
        if let Some(plies) = plies.as_mut() {
            plies.set_frictions(&state.interface_frictions);
        }
        let couplings = relist_plies(plies.as_mut(), &mut state, false);
        if !couplings.is_empty() {
            layout = self::layout(model, settings, &couplings)?;
            work = work.relaid(model, &layout, settings)?;
        }
        let evaluator = evaluator_of(model, &layout, settings, plies.as_ref());
        let step = dt.min(settings.end_time - state.time);
        let attempt = increment(
            &evaluator,
            &mut work,
            (&state, &converged),
            step,
            settings,
            stats,
        );
        match attempt {
            Ok((evaluation, positions, translations, iterations)) => {
                accept(
                    &evaluator,
                    &mut state,
                    &mut converged,
                    (evaluation, positions, translations),
                    step,
                );
                heat::advance(model, &mut state, step)?;
                stats.increments += 1;
                state.step = stats.increments;
                let reached_output = state.time >= next_output - 1e-9 * settings.output_interval;
                if reached_output || state.time >= settings.end_time * (1.0 - 1e-12) {
                    record(model, &mut state, observer)?;
                    recorded = state.time;
                    next_output = next_record_time(state.time, settings.output_interval);
                }
                if let Err(source) = observer.checkpoint(model, &state) {
                    if state.time > recorded {
                        record(model, &mut state, observer)?;
                    }
                    return Err(SolverError::Output {
                        time: state.time,
                        source,
                    });
                }
                observer.progress(&state);
                if iterations <= 6 {
                    dt = (dt * 1.5).min(max_increment);
                }
            }
            Err(failure) => {
                stats.cut_increments += 1;
                dt = 0.25 * step;
                if dt < min_increment {
                    // what was converged since the last record; nothing new if it is at hand
                    if state.time > recorded {
                        record(model, &mut state, observer)?;
                    }
                    return Err(SolverError::NotConverged {
                        increment: stats.increments + 1,
                        time: state.time,
                        increment_time: step,
                        reason: failure.reason,
                        residuals: failure.residuals,
                        worst_nodes: failure.worst_nodes,
                    });
                }
            }
        }
    }
    Ok(state)
}

/// The Verlet margin of the ply–ply contact's lists in the implicit solver, in mean cell sizes
/// **(choice)**: an increment moves a node a fraction of a cell, and each listing lays the
/// tangent's pattern out again, so the lists reach farther than the explicit solver's.
const IMPLICIT_PLY_MARGIN: f64 = 1.0;

/// The evaluator of `model` on `layout`, with the ply contact `plies`.
fn evaluator_of<'a>(
    model: &'a Model,
    layout: &'a Layout,
    settings: &ImplicitSettings,
    plies: Option<&'a PlyContact>,
) -> Evaluator<'a> {
    Evaluator {
        model,
        layout,
        exact: settings.exact_tangent,
        stick_slip: stick_slip(model, settings),
        plies,
    }
}

/// Lists the faces near each node of the plies again where a node has moved half their margin
/// (or `always`), into the state: the node pairs the tangent must then couple; none where the
/// lists still hold or the model has no interfaces.
fn relist_plies(
    plies: Option<&mut PlyContact>,
    state: &mut State,
    always: bool,
) -> Vec<[usize; 2]> {
    let Some(plies) = plies else {
        return Vec::new();
    };
    let relisted = plies.relist_if_moved(&state.positions, &mut state.interply);
    if relisted || always {
        plies.listed_pairs(&state.interply)
    } else {
        Vec::new()
    }
}

/// Increments over the run at their largest where [`ImplicitSettings::max_increment`] is not
/// set, and of the stroke where `process.max_increment` is not **(choice)**: 0.5 mm on the
/// examples' 30 mm, where the hemisphere's 400 to 20,164 cells converge in 5 to 10 Newton
/// iterations an increment (docs/dev/performance-history.md).
pub const DEFAULT_INCREMENTS: f64 = 60.0;

/// The first multiple of `interval` after `time`, by more than rounding: the next record
/// time once a record is made at `time`.
fn next_record_time(time: f64, interval: f64) -> f64 {
    let done = (time / interval + 1e-9).floor();
    (done + 1.0) * interval
}

/// The residual (every unknown, held ones included) and the consistent tangent (dense, held
/// rows and columns as the solver has them: identity) of the increment of duration `dt` from
/// the model at rest to `positions` (tools at `translations`): what the tangent checks compare
/// with differences of the residual. Friction lagged as given per node and tool.
pub fn residual_and_tangent(
    model: &Model,
    settings: &ImplicitSettings,
    (positions, translations): (&[Vector3<f64>], &[Vector3<f64>]),
    dt: f64,
    friction: &[Vec<Option<FrictionLag>>],
) -> Result<(Vec<f64>, nalgebra::DMatrix<f64>), SolverError> {
    let mut plies = model.ply_contact(IMPLICIT_PLY_MARGIN);
    let mut rest = rest_state(model);
    let mut at_trial = rest.clone();
    at_trial.positions = positions.to_vec();
    let couplings = relist_plies(plies.as_mut(), &mut at_trial, true);
    let layout = layout(model, settings, &couplings)?;
    let evaluator = evaluator_of(model, &layout, settings, plies.as_ref());
    rest.interply = at_trial.interply;
    let no_ply_friction = vec![[None, None]; rest.interply.len()];
    let faces = plies.as_ref().map_or(Vec::new(), |p| {
        interply::held_faces(p, &rest.interply, positions)
    });
    let strains = vec![Matrix2::identity(); model.elements.len()];
    let start = IncrementStart {
        positions: &rest.positions,
        strains: &strains,
        laminate_states: &rest.laminate_states,
        friction,
        velocities: &rest.velocities,
        masses: &rest.masses,
        dt,
        ply_lags: &no_ply_friction,
        ply_lists: &rest.interply,
        ply_faces: &faces,
        temperatures: &rest.temperatures,
        bending_rigidities: &rest.bending_rigidities,
        released: &rest.supports.released,
    };
    let trial = Trial {
        positions,
        translations,
        engaged: None,
        near: None,
    };
    let evaluation = evaluator
        .evaluate(&start, &trial, Tangent::Consistent)
        .map_err(|(k, e)| SolverError::Settings(format!("element {k}: {e}")))?;
    let values = evaluation.matrix.expect("tangent asked for");
    let n = layout.size;
    let mut dense = nalgebra::DMatrix::zeros(n, n);
    for j in 0..n {
        for i in j..n {
            if let Some(p) = layout.pattern.place(i, j) {
                dense[(i, j)] = values[p];
                dense[(j, i)] = values[p];
            }
        }
    }
    Ok((evaluation.residual, dense))
}

fn record(
    model: &Model,
    state: &mut State,
    observer: &mut dyn Observer,
) -> Result<(), SolverError> {
    state.energies.elastic = state
        .elastic_energy(model)
        .map_err(|(element, e)| SolverError::Settings(format!("element {element}: {e}")))?;
    observer
        .record(model, state)
        .map_err(|source| SolverError::Output {
            time: state.time,
            source,
        })
}

/// The unknowns, pattern, contact springs and drag of `model`, the ply–ply contact coupling
/// the node pairs `couplings`.
pub fn layout(
    model: &Model,
    settings: &ImplicitSettings,
    couplings: &[[usize; 2]],
) -> Result<Layout, SolverError> {
    let stiffness = model
        .plies
        .iter()
        .map(|ply| ply_stiffness(model, ply))
        .collect::<Result<Vec<_>, _>>()?;
    let n = model.mesh.nodes.len();
    let mut area = vec![0.0; n];
    let mut size = vec![f64::INFINITY; n];
    let mut ply_of_node = vec![0; n];
    for (p, ply) in model.plies.iter().enumerate() {
        for e in &model.elements[ply.elements.clone()] {
            for &a in e.nodes() {
                area[a] += e.area / e.nodes().len() as f64;
                size[a] = size[a].min(e.altitude);
                ply_of_node[a] = p;
            }
        }
    }
    let penalty = (0..n)
        .map(|a| {
            let wave = stiffness[ply_of_node[a]].0;
            penalty_stiffness(settings.penalty_scale, wave, area[a], size[a])
        })
        .collect();
    let drag = (0..n)
        .map(|a| {
            let (wave, shear) = stiffness[ply_of_node[a]];
            settings.stabilisation * shear.max(1e-12 * wave) * area[a] / (size[a] * size[a])
        })
        .collect();
    let mean_size = model.elements.iter().map(|e| e.area.sqrt()).sum::<f64>()
        / model.elements.len().max(1) as f64;
    let softest = stiffness
        .iter()
        .map(|&(wave, shear)| shear.max(1e-12 * wave))
        .fold(f64::INFINITY, f64::min);
    let mut layout = Layout::new(model, penalty, drag, couplings);
    layout.force_floor = FORCE_FLOOR * softest * mean_size;
    layout.length_scale = mean_size;
    Ok(layout)
}

/// `(E t0, G t0)` of a ply at rest (its hourglass moduli, whether or not its cells are
/// quadrilaterals): what scales its contact springs and its drag.
fn ply_stiffness(model: &Model, ply: &Ply) -> Result<(f64, f64), SolverError> {
    let rest = rest_moduli(&ply.laminate, model.temperature)
        .map_err(|e| SolverError::Settings(e.to_string()))?;
    Ok((rest.yarn, rest.shear))
}

/// Entries of the tangent's factor from which its linear solves are made by conjugate
/// gradients on the membrane's stencil rather than by factorising it **(choice, measured**
/// on the hemisphere, 2 threads: 400 cells, 3.0e5 entries, 2.4 s with against 1.7 s without;
/// 1,600 cells, 1.8e6 entries, 7.0 s against 8.6 s; 5,041 cells, 7.5e6, 38.5 s against 58.8 s):
/// below, the factor fits in the caches and a factorisation costs about what the iterations do.
const ITERATIVE_FACTOR_ENTRIES: usize = 1_000_000;

/// Elastic slip of friction's stick as a fraction of the ply's thickness **(choice)**: a
/// hundredth, 3 µm on the T300/PPS ply, below the slip of any node that slides within an
/// increment, and soft enough that Newton's method meets the stick's stiffness
/// `mu lambda / eps` without cutting increments (docs/solver.md, "Friction").
const FRICTION_STICK: f64 = 0.01;

/// The elastic slip of friction's stick (mm): a fraction of the thinnest ply.
pub fn stick_slip(model: &Model, settings: &ImplicitSettings) -> f64 {
    settings.friction_stick * model.thinnest_ply()
}

/// Bytes per stored entry of the sparse tangent and of its factor: a value and a row index.
const SPARSE_ENTRY_BYTES: f64 = 16.0;

/// The memory (bytes) the sparse tangent of `model` and its Cholesky factor take, fill-in
/// included, on the pattern and elimination order the run will use, with the preconditioner's
/// where the run uses one: what an implicit run needs beyond the arrays of the model and its
/// state.
pub fn sparse_memory(model: &Model) -> Result<f64, String> {
    let n = model.mesh.nodes.len();
    let mut rest = rest_state(model);
    let couplings = relist_plies(
        model.ply_contact(IMPLICIT_PLY_MARGIN).as_mut(),
        &mut rest,
        true,
    );
    let layout = Layout::new(model, vec![0.0; n], vec![0.0; n], &couplings);
    let cholesky = Cholesky::analyse(&layout.pattern)?;
    let mut entries = layout.pattern.entries() + cholesky.factor_entries();
    if let Some(p) = Preconditioner::of(model, &layout, &cholesky, ITERATIVE_FACTOR_ENTRIES)? {
        entries += p.sparsified.pattern.entries() + p.cholesky.factor_entries();
    }
    Ok(SPARSE_ENTRY_BYTES * entries as f64)
}

/// The memory (bytes) of the sparse tangent and its factor for a sheet of `nodes` nodes, from
/// the count alone, before the mesh is made: `b n (log2 n - c)` **(fit** of [`sparse_memory`]
/// on the hemisphere's quadrilaterals with bending, 441 to 40,401 nodes: within 4 %; nested
/// dissection's fill grows as `n log n` on a planar mesh). The count is what the key-based
/// estimate needs; [`sparse_memory`] is the exact figure, at the price of an ordering.
pub fn sparse_memory_of_size(nodes: f64) -> f64 {
    SPARSE_BYTES_PER_NODE_DOUBLING * nodes * (nodes.max(2.0).log2() - SPARSE_LOG_OFFSET).max(1.0)
}

/// `b` and `c` of [`sparse_memory_of_size`] (bytes, doublings).
const SPARSE_BYTES_PER_NODE_DOUBLING: f64 = 5200.0;
const SPARSE_LOG_OFFSET: f64 = 6.2;

/// The wall time (s) of an implicit forming run of `elements` cells in `increments` increments
/// on `threads` threads, good to a factor of about 3: `(1 + 38 (N / 5041)^1.6) increments / 60`
/// on 2 threads, the hemisphere's measured growth (docs/dev/performance-history.md: 1.8 s on
/// 400 cells, 7 s on 1,600, 38 s on 5,041, 366 s on 20,164, in about 60 increments).
pub fn wall_seconds_of_size(elements: f64, increments: f64, threads: usize) -> f64 {
    let on_two = 1.0 + 38.0 * (elements / 5041.0).powf(1.6);
    on_two * (increments / 60.0) * 2.0 / threads.max(1) as f64
}

/// The smallest force scale of the convergence test, as a fraction of `G t0 h` (the force that
/// shears an element of size `h` by one radian): before anything is loaded the residual is
/// measured against it, not against forces that are still zero.
const FORCE_FLOOR: f64 = 1e-3;

/// The model at rest at `t = 0`, with physical masses (they take no part: they are reported).
fn rest_state(model: &Model) -> State {
    let n = model.mesh.nodes.len();
    let mut masses = vec![0.0; n];
    for (k, e) in model.elements.iter().enumerate() {
        for &a in e.nodes() {
            masses[a] += model.density(k) * model.thickness(k) * e.area / e.nodes().len() as f64;
        }
    }
    let densities = (0..model.elements.len())
        .map(|k| model.density(k))
        .collect();
    State::undeformed(model, masses, densities, 0.0)
}

/// Moves each force-driven tool along its force onto the blank, pressed into the contact
/// springs of the nodes it meets as deep as its force asks: off the blank the tool has nothing
/// to rest on, and at a gap of exactly zero the springs have no stiffness yet, so Newton's
/// method would have nothing to converge to.
fn seat_force_driven_tools(model: &Model, layout: &Layout, state: &mut State) {
    for (k, tool) in model.tools.iter().enumerate() {
        let ToolMotion::Force { force, .. } = &tool.motion else {
            continue;
        };
        let offset = model.tool_contact(k).offset;
        let axis = force.normalize();
        for _ in 0..3 {
            let translation = state.tool_translations[k];
            let gap = state
                .positions
                .iter()
                .map(|x| tool.gap(&(x - translation), offset))
                .fold(f64::INFINITY, f64::min);
            if !gap.is_finite() || gap.abs() < 1e-9 {
                break;
            }
            state.tool_translations[k] += axis * gap;
        }
        let translation = state.tool_translations[k];
        let springs: f64 = state
            .positions
            .iter()
            .zip(&layout.penalty)
            .filter(|(x, _)| tool.gap(&(*x - translation), offset) < 1e-3 * offset)
            .map(|(_, k)| k)
            .sum();
        if springs > 0.0 {
            let depth = (force.norm() / springs).min(0.25 * model.contact.max_penetration);
            state.tool_translations[k] += axis * depth;
        }
    }
}

/// Closes the force-driven tools (a blank holder, seated on the blank) onto the blank before
/// the stroke starts, as a press closes its holder before the punch moves: one increment of
/// `dt` (the run's duration: the holder closes as slowly as the punch then forms, so that the
/// matrix's viscous stress of the closing has relaxed) with every prescribed motion held where
/// it is, the flange pressed into the die's
/// contact springs until the holder's force is carried. The clock, the velocities and the
/// energies then start from zero, so that the work of this closing, which goes into the
/// contact springs and no force of the forming does, is not booked against the blank's
/// energy balance. Where it does not converge the run starts from the seated tools as they
/// are, and its first increment closes them.
fn close_force_driven_tools(
    evaluator: &Evaluator,
    work: &mut Workspace,
    (state, converged): (&mut State, &mut Converged),
    dt: f64,
    settings: &ImplicitSettings,
    stats: &mut ImplicitStatistics,
) {
    let model = evaluator.model;
    let driven = |t: &RigidTool| matches!(t.motion, ToolMotion::Force { .. });
    if !model.tools.iter().any(driven) {
        return;
    }
    let held = (state.positions.clone(), state.tool_translations.clone());
    let closing = Problem {
        evaluator,
        state,
        converged,
        dt,
        settings,
    };
    let Ok((evaluation, x, translations, _)) = newton(&closing, work, held, stats) else {
        return;
    };
    accept(
        evaluator,
        state,
        converged,
        (evaluation, x, translations),
        dt,
    );
    stats.increments += 1;
    state.time = 0.0;
    state.energies = Energies::default();
    state.velocities.fill(Vector3::zeros());
    state.tool_velocities.fill(Vector3::zeros());
    state.tool_impulses.fill(Vector3::zeros());
}

/// The prescribed position of every node at `t` after an increment `dt` from `positions`, and
/// each tool's translation; free nodes extrapolated with their last velocity.
fn predictor(model: &Model, state: &State, dt: f64) -> (Vec<Vector3<f64>>, Vec<Vector3<f64>>) {
    let t_half = state.time + 0.5 * dt;
    let mut x: Vec<Vector3<f64>> = state
        .positions
        .iter()
        .zip(&state.velocities)
        .map(|(x, v)| x + v * dt)
        .collect();
    for c in &model.constraints {
        for &n in &c.nodes {
            let start = state.positions[n];
            x[n] = match &c.motion {
                Motion::Fixed => start,
                Motion::Velocity(field) => start + field(t_half, &model.mesh.nodes[n]) * dt,
                Motion::Components(mask) => {
                    Vector3::from_fn(|d, _| if mask[d] { start[d] } else { x[n][d] })
                }
            };
        }
    }
    let translations = model
        .tools
        .iter()
        .enumerate()
        .map(|(k, tool)| {
            state.tool_translations[k]
                + match &tool.motion {
                    ToolMotion::Fixed => Vector3::zeros(),
                    ToolMotion::Velocity(v) => v(t_half) * dt,
                    ToolMotion::Path(p) => p.mean_velocity(t_half, dt) * dt,
                    ToolMotion::Force { .. } => state.tool_velocities[k] * dt,
                }
        })
        .collect();
    (x, translations)
}

type Solved = (Evaluation, Vec<Vector3<f64>>, Vec<Vector3<f64>>, usize);

/// One increment of duration `dt` from the predictor ([`predictor`]): Newton's method
/// ([`newton::newton`]) with friction lagged at the increment's start and lagged again, as it
/// converges, with the normal forces it reaches: a node that comes into contact during the
/// increment would otherwise slide it without friction, and the friction force would lag the
/// stroke by an increment.
fn increment(
    evaluator: &Evaluator,
    work: &mut Workspace,
    (state, converged): (&State, &Converged),
    dt: f64,
    settings: &ImplicitSettings,
    stats: &mut ImplicitStatistics,
) -> Result<Solved, NotConverged> {
    let guess = predictor(evaluator.model, state, dt);
    let problem = Problem {
        evaluator,
        state,
        converged,
        dt,
        settings,
    };
    let solved = newton(&problem, work, guess, stats)?;
    // the contact's own test sees the tools' triangles near each node only: a tool that moved
    // past a node in one increment is found by a full search
    let model = evaluator.model;
    let through = nodes_through_tools(&model.tools, &solved.2, &solved.1, &model.tool_contacts());
    if through > 0 {
        return Err(NotConverged {
            worst_nodes: Vec::new(),
            residuals: Vec::new(),
            reason: format!("{through} nodes passed through a tool in the increment"),
        });
    }
    Ok(solved)
}

/// The tool's normal at a node at `y` (relative to the tool) that friction is lagged with.
fn lag_normal(tool: &RigidTool, y: &Vector3<f64>) -> Vector3<f64> {
    // unit: a blended surface's normal is its distance's gradient, nearly so
    tool.nearest(y)
        .map_or(Vector3::z(), |p| p.direction_to(y).0.normalize())
}

/// Relative residual `|K d + r| / |r|` to which conjugate gradients solve for a Newton
/// correction **(choice)**: Newton's method contracts only four to eight times per iteration
/// until near the solution (the yarns' slack band), which a correction this close does not
/// slow (on the 5,041-cell hemisphere 551 iterations against 562 with exact solves;
/// docs/dev/performance-history.md).
const CG_TOLERANCE: f64 = 1e-2;

/// Conjugate-gradient iterations after which the tangent is factorised instead **(choice,
/// measured** on the hemisphere: about four a solve on average on 5,041 cells, twelve on
/// 20,164, where a cap of 40 left 34 solves to the full factorisation, 944 MiB at the peak and
/// 630 s of CPU, and 200 none, 544 MiB and 597 s, the same part;
/// docs/dev/performance-history.md): an iteration costs far less than that factorisation,
/// whose factor is the run's largest array.
const CG_ITERATIONS: usize = 200;

/// Takes the converged increment into the state: positions, forces, contact, tools, energies
/// (trapezoidal work sums as in the explicit solver), and the friction lagged for the next.
fn accept(
    evaluator: &Evaluator,
    state: &mut State,
    converged: &mut Converged,
    (evaluation, x, translations): (Evaluation, Vec<Vector3<f64>>, Vec<Vector3<f64>>),
    dt: f64,
) {
    let (model, layout) = (evaluator.model, evaluator.layout);
    accept_interply(evaluator, state, converged, (&evaluation, &x), dt);
    let (mut internal, mut external, mut tool, mut support) = (0.0, 0.0, 0.0, 0.0);
    let (mut kinetic, mut dissipated) = (0.0, 0.0);
    let no_support = Vector3::zeros();
    for (a, x_a) in x.iter().enumerate() {
        let du = x_a - state.positions[a];
        let f_int = evaluation.internal[a];
        let f_contact = evaluation.contacts[a].force;
        // the support's force along the held directions: the residual there
        let reaction = Vector3::from_fn(|d, _| {
            if layout.held[3 * a + d] {
                evaluation.residual[3 * a + d]
            } else {
                0.0
            }
        });
        internal += 0.5 * (converged.previous_forces[a] + f_int).dot(&du);
        external += 0.5 * (converged.previous_reactions[a] + reaction).dot(&du);
        tool += 0.5 * (converged.previous_contact[a] + f_contact).dot(&du);
        let f_support = evaluation.supports.forces.get(a).unwrap_or(&no_support);
        support += 0.5 * (converged.previous_support[a] + f_support).dot(&du);
        if let Some(previous) = converged.previous_support.get_mut(a) {
            *previous = *f_support;
        }
        converged.previous_forces[a] = f_int;
        converged.previous_reactions[a] = reaction;
        converged.previous_contact[a] = f_contact;
        let v = du / dt;
        // backward Euler's inertia does the kinetic energy's change and dissipates the rest
        dissipated += 0.5 * state.masses[a] * (v - state.velocities[a]).norm_squared();
        kinetic += 0.5 * state.masses[a] * v.norm_squared();
        state.velocities[a] = v;
        state.reactions[a] = reaction;
    }
    for (k, t) in translations.iter().enumerate() {
        state.tool_velocities[k] = (t - state.tool_translations[k]) / dt;
        // trapezoidal, as the force is known at the increment's ends only: the end value alone
        // would read a rising force high by half its rise over the increment
        let force = 0.5 * (state.tool_loads[k].force + evaluation.loads[k].force);
        state.tool_impulses[k] += force * dt;
    }
    state.tool_translations = translations;
    for (k, e) in model.elements.iter().enumerate() {
        let f = e.gradient(&x);
        converged.strains[k] = f.transpose() * f;
    }
    for (a, contact) in evaluation.contacts.iter().enumerate() {
        for (k, tool) in model.tools.iter().enumerate() {
            let normal_force = contact.normal_force.get(k).copied().unwrap_or(0.0);
            converged.friction[a][k] = (normal_force > 0.0 && tool.friction > 0.0).then(|| {
                let y = x[a] - state.tool_translations[k];
                FrictionLag {
                    limit: tool.friction * normal_force,
                    normal: lag_normal(tool, &y),
                    start: y,
                    carried: -contact.tangential[k],
                }
            });
        }
    }
    state.positions = x;
    state.internal_forces = evaluation.internal;
    state.membrane = evaluation.responses;
    state.laminate_states = evaluation.states;
    state.contacts = evaluation.contacts;
    state.tool_loads = evaluation.loads;
    state.time_step = dt;
    state.time += dt;
    if !model.supports.is_empty() {
        state.supports.loads = evaluation.supports;
        let supports = &mut state.supports;
        model
            .supports
            .release(state.time, &supports.loads, &mut supports.released);
    }
    state.energies.kinetic = kinetic;
    state.energies.internal_work += internal;
    state.energies.external_work += external + tool + support;
    state.energies.tool_work += tool;
    state.energies.support_work += support;
    state.energies.damping += evaluation.drag_work + dissipated;
}

/// Takes the ply–ply contact of the converged increment into the state (forces, pressures,
/// slip) and its work into the energies, and lags friction for the next increment.
fn accept_interply(
    evaluator: &Evaluator,
    state: &mut State,
    converged: &mut Converged,
    (evaluation, x): (&Evaluation, &[Vector3<f64>]),
    dt: f64,
) {
    let (slips, lags) = {
        let kept = (&state.interply[..], &converged.ply_lags[..], &[][..]);
        let Some(plies) = evaluator.interply_over(kept, dt) else {
            return;
        };
        (
            plies.slips(x),
            plies.lags_after(&evaluation.interply, x, dt),
        )
    };
    let mut work = 0.0;
    for (a, (node, contact)) in state
        .interply
        .iter_mut()
        .zip(&evaluation.interply)
        .enumerate()
    {
        let du = x[a] - state.positions[a];
        work += 0.5 * (converged.previous_interply[a] + contact.force).dot(&du);
        converged.previous_interply[a] = contact.force;
        node.force = contact.force;
        for (side, (s, now)) in node.sides.iter_mut().zip(&contact.sides).enumerate() {
            s.normal_force = now.normal_force;
            s.tangential = now.tangential;
            s.slip += slips[a][side];
        }
    }
    converged.ply_lags = lags;
    state.energies.interply_work += work;
}

fn check_settings(s: &ImplicitSettings) -> Result<(), SolverError> {
    let positive = positive_setting;
    positive("end time", s.end_time)?;
    positive("output interval", s.output_interval)?;
    positive("tolerance", s.tolerance)?;
    positive("friction stick", s.friction_stick)?;
    positive("contact penalty scale", s.penalty_scale)?;
    if let Some(m) = s.max_increment {
        positive("largest increment", m)?;
    }
    if !(s.stabilisation.is_finite() && s.stabilisation >= 0.0) {
        return Err(SolverError::Settings(format!(
            "stabilisation = {} must be >= 0",
            s.stabilisation
        )));
    }
    if s.max_iterations == 0 {
        return Err(SolverError::Settings(
            "the Newton iterations per increment must be at least 1".into(),
        ));
    }
    Ok(())
}
