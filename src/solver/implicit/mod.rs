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
pub mod linear;
mod supernodal;

use super::energy::Energies;
use super::explicit::{elastic_energy, positive_setting, Observer, SolverError, State};
use super::model::{Model, Motion};
use crate::contact::penalty::nodes_through_tools;
use crate::contact::potential::{penalty_stiffness, FrictionLag};
use crate::contact::{RigidTool, ToolMotion};
use assembly::{Evaluation, Evaluator, IncrementStart, Layout, NearLists, Tangent, Trial};
use linear::{Cholesky, Sparsified};
use nalgebra::{Matrix2, Vector3};
use std::time::Instant;

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

/// Solves `K d = rhs` for the tangent `K` in `values` (on `layout`'s pattern) by conjugate
/// gradients preconditioned with its factorisation on the membrane's stencil (docs/solver.md,
/// "Conjugate gradients on the membrane's stencil"); `None` where there is no
/// `preconditioner`, it is not positive definite, or the iterations do not converge within
/// [`CG_ITERATIONS`]: then the tangent is factorised.
fn iterative_solve(
    layout: &Layout,
    preconditioner: Option<&mut Preconditioner>,
    values: &[f64],
    rhs: &[f64],
    stats: &mut ImplicitStatistics,
) -> Option<Vec<f64>> {
    let p = preconditioner?;
    p.sparsified.values(values, &mut p.values);
    stats.preconditioner_factorisations += 1;
    p.cholesky
        .factorise(&p.sparsified.pattern, &p.values)
        .ok()?;
    let solved =
        p.cholesky
            .conjugate_gradients(&layout.pattern, values, rhs, CG_TOLERANCE, CG_ITERATIONS);
    let iterations = match &solved {
        Ok((_, iterations)) | Err((_, iterations)) => *iterations,
    };
    stats.cg_iterations += iterations;
    solved.ok().map(|(d, _)| d)
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
    let layout = layout(model, settings)?;
    let cholesky = Cholesky::analyse(&layout.pattern).map_err(SolverError::Settings)?;
    let preconditioner = Preconditioner::of(model, &layout, &cholesky, settings.iterative_from)
        .map_err(SolverError::Settings)?;
    let mut work = Workspace {
        cholesky,
        near: NearLists::default(),
        values: Vec::new(),
        preconditioner,
    };
    let evaluator = Evaluator {
        model,
        layout: &layout,
        exact: settings.exact_tangent,
        stick_slip: stick_slip(model, settings),
    };
    let mut state = rest_state(model);
    seat_force_driven_tools(model, &layout, &mut state);
    let n = model.mesh.nodes.len();
    let mut converged = Converged {
        strains: vec![Matrix2::identity(); model.elements.len()],
        friction: vec![vec![None; model.tools.len()]; n],
        previous_forces: vec![Vector3::zeros(); n],
        previous_reactions: vec![Vector3::zeros(); n],
        previous_contact: vec![Vector3::zeros(); n],
    };
    let max_increment = settings
        .max_increment
        .unwrap_or(settings.end_time / DEFAULT_INCREMENTS);
    let mut dt = 0.25 * max_increment;
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
                    model,
                    &layout,
                    &mut state,
                    &mut converged,
                    (evaluation, positions, translations),
                    step,
                );
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

/// Increments over the run at their largest where [`ImplicitSettings::max_increment`] is not
/// set, and of the stroke where `process.max_increment` is not **(choice)**: 0.5 mm on the
/// examples' 30 mm, where the hemisphere's 400 to 20,164 cells converge in 5 to 10 Newton
/// iterations an increment (docs/performance.md).
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
    let layout = layout(model, settings)?;
    let evaluator = Evaluator {
        model,
        layout: &layout,
        exact: settings.exact_tangent,
        stick_slip: stick_slip(model, settings),
    };
    let rest = rest_state(model);
    let strains = vec![Matrix2::identity(); model.elements.len()];
    let start = IncrementStart {
        positions: &rest.positions,
        strains: &strains,
        laminate_states: &rest.laminate_states,
        friction,
        velocities: &rest.velocities,
        masses: &rest.masses,
        dt,
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
    state.energies.elastic = elastic_energy(model, state)
        .map_err(|(element, e)| SolverError::Settings(format!("element {element}: {e}")))?;
    observer
        .record(model, state)
        .map_err(|source| SolverError::Output {
            time: state.time,
            source,
        })
}

/// The unknowns, pattern, contact springs and drag of `model`.
pub fn layout(model: &Model, settings: &ImplicitSettings) -> Result<Layout, SolverError> {
    let laminate = &model.laminate;
    let t0 = laminate.reference_thickness();
    let rest = crate::material::MembraneKinematics {
        c: Matrix2::identity(),
        c_dot: Matrix2::zeros(),
        temperature: model.temperature,
        fibres: Default::default(),
    };
    let wave = laminate
        .wave_modulus(&rest, &laminate.initial_state())
        .map_err(|e| SolverError::Settings(e.to_string()))?
        * t0;
    let shear = laminate
        .shear_modulus(model.temperature)
        .map_err(|e| SolverError::Settings(e.to_string()))?
        * t0;
    let n = model.mesh.nodes.len();
    let mut area = vec![0.0; n];
    let mut size = vec![f64::INFINITY; n];
    for e in &model.elements {
        for &a in e.nodes() {
            area[a] += e.area / e.nodes().len() as f64;
            size[a] = size[a].min(e.altitude);
        }
    }
    let penalty = (0..n)
        .map(|a| penalty_stiffness(settings.penalty_scale, wave, area[a], size[a]))
        .collect();
    let drag = (0..n)
        .map(|a| settings.stabilisation * shear.max(1e-12 * wave) * area[a] / (size[a] * size[a]))
        .collect();
    let mean_size = model.elements.iter().map(|e| e.area.sqrt()).sum::<f64>()
        / model.elements.len().max(1) as f64;
    let mut layout = Layout::new(model, penalty, drag);
    layout.force_floor = FORCE_FLOOR * shear.max(1e-12 * wave) * mean_size;
    layout.length_scale = mean_size;
    Ok(layout)
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

/// The elastic slip of friction's stick (mm) of `model`'s ply.
pub fn stick_slip(model: &Model, settings: &ImplicitSettings) -> f64 {
    settings.friction_stick * model.laminate.reference_thickness()
}

/// Bytes per stored entry of the sparse tangent and of its factor: a value and a row index.
const SPARSE_ENTRY_BYTES: f64 = 16.0;

/// The memory (bytes) the sparse tangent of `model` and its Cholesky factor take, fill-in
/// included, on the pattern and elimination order the run will use, with the preconditioner's
/// where the run uses one: what an implicit run needs beyond the arrays of the model and its
/// state.
pub fn sparse_memory(model: &Model) -> Result<f64, String> {
    let n = model.mesh.nodes.len();
    let layout = Layout::new(model, vec![0.0; n], vec![0.0; n]);
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
/// on 2 threads, the hemisphere's measured growth (docs/performance.md: 1.8 s on 400 cells,
/// 7 s on 1,600, 38 s on 5,041, 366 s on 20,164, in about 60 increments).
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
    let thickness = model.laminate.reference_thickness();
    let mut masses = vec![0.0; n];
    for e in &model.elements {
        for &a in e.nodes() {
            masses[a] += model.density * thickness * e.area / e.nodes().len() as f64;
        }
    }
    State::undeformed(
        model,
        masses,
        vec![model.density; model.elements.len()],
        0.0,
    )
}

/// Moves each force-driven tool along its force onto the blank, pressed into the contact
/// springs of the nodes it meets as deep as its force asks: off the blank the tool has nothing
/// to rest on, and at a gap of exactly zero the springs have no stiffness yet, so Newton's
/// method would have nothing to converge to.
fn seat_force_driven_tools(model: &Model, layout: &Layout, state: &mut State) {
    let offset = model.contact.offset;
    for (k, tool) in model.tools.iter().enumerate() {
        let ToolMotion::Force { force, .. } = &tool.motion else {
            continue;
        };
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
    let Ok((evaluation, x, translations, _)) = newton(
        evaluator,
        work,
        (state, converged),
        dt,
        held,
        settings,
        stats,
    ) else {
        return;
    };
    accept(
        model,
        evaluator.layout,
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
                    ToolMotion::Force { .. } => state.tool_velocities[k] * dt,
                }
        })
        .collect();
    (x, translations)
}

type Solved = (Evaluation, Vec<Vector3<f64>>, Vec<Vector3<f64>>, usize);

/// One increment of duration `dt`: Newton's method with friction lagged at the increment's
/// start and lagged again, as it converges, with the normal forces it reaches
/// ([`FRICTION_LAG_CHANGE`], at most [`FRICTION_PASSES`] times): a node that comes into contact
/// during the increment would otherwise slide it without friction, and the friction force
/// would lag the stroke by an increment.
fn increment(
    evaluator: &Evaluator,
    work: &mut Workspace,
    from: (&State, &Converged),
    dt: f64,
    settings: &ImplicitSettings,
    stats: &mut ImplicitStatistics,
) -> Result<Solved, NotConverged> {
    let guess = predictor(evaluator.model, from.0, dt);
    let solved = newton(evaluator, work, from, dt, guess, settings, stats)?;
    // the contact's own test sees the tools' triangles near each node only: a tool that moved
    // past a node in one increment is found by a full search
    let model = evaluator.model;
    let through = nodes_through_tools(&model.tools, &solved.2, &solved.1, &model.contact);
    if through > 0 {
        return Err(NotConverged {
            worst_nodes: Vec::new(),
            residuals: Vec::new(),
            reason: format!("{through} nodes passed through a tool in the increment"),
        });
    }
    Ok(solved)
}

/// Friction lagged again with the normal forces of the iterate `evaluation`, when they differ
/// from the lagged ones by more than [`FRICTION_LAG_CHANGE`] of their sum; the slip still
/// counts from the increment's start, along the start's tangent plane where there was one.
fn refined_lags(
    model: &Model,
    state: &State,
    lags: &[Vec<Option<FrictionLag>>],
    evaluation: &Evaluation,
    x: &[Vector3<f64>],
    translations: &[Vector3<f64>],
) -> Option<Vec<Vec<Option<FrictionLag>>>> {
    let mut change = 0.0;
    let mut total = 0.0;
    let mut refined = lags.to_vec();
    for (a, contact) in evaluation.contacts.iter().enumerate() {
        for (k, tool) in model.tools.iter().enumerate() {
            if tool.friction <= 0.0 {
                continue;
            }
            let limit = tool.friction * contact.normal_force.get(k).copied().unwrap_or(0.0);
            let lagged = lags[a][k].map_or(0.0, |l| l.limit);
            change += (limit - lagged).abs();
            total += limit;
            refined[a][k] = (limit > 0.0).then(|| match lags[a][k] {
                Some(lag) => FrictionLag { limit, ..lag },
                None => FrictionLag {
                    limit,
                    normal: lag_normal(tool, &(x[a] - translations[k])),
                    start: state.positions[a] - state.tool_translations[k],
                    carried: Vector3::zeros(),
                },
            });
        }
    }
    (change > FRICTION_LAG_CHANGE * total).then_some(refined)
}

/// The tool's normal at a node at `y` (relative to the tool) that friction is lagged with.
fn lag_normal(tool: &RigidTool, y: &Vector3<f64>) -> Vector3<f64> {
    // unit: a blended surface's normal is its distance's gradient, nearly so
    tool.nearest(y)
        .map_or(Vector3::z(), |p| p.direction_to(y).0.normalize())
}

/// Newton's method on one increment of `dt` from the converged `state`, beginning at `guess`
/// (positions and tool translations), friction lagged from the increment's start and then
/// from the normal forces reached once the residual is within [`LAG_REFRESH_BAND`] of its
/// tolerance.
fn newton(
    evaluator: &Evaluator,
    work: &mut Workspace,
    (state, converged): (&State, &Converged),
    dt: f64,
    guess: (Vec<Vector3<f64>>, Vec<Vector3<f64>>),
    settings: &ImplicitSettings,
    stats: &mut ImplicitStatistics,
) -> Result<Solved, NotConverged> {
    let mut lags = converged.friction.clone();
    let mut refreshes = 0;
    let model = evaluator.model;
    let layout = evaluator.layout;
    let (mut x, mut translations) = guess;
    let mut z = unknowns(layout, &x, &translations);
    let mut residuals = Vec::new();
    let mut projected = false;
    let fail =
        |residuals: Vec<f64>, evaluation: Option<&Evaluation>, reason: String| NotConverged {
            worst_nodes: evaluation.map_or(Vec::new(), |e| worst_nodes(layout, &e.residual)),
            residuals,
            reason,
        };
    let mut frozen: Option<Vec<Vec<bool>>> = None;
    let mut freezes = 0;
    let mut worst = Vec::new();
    // the accepted line-search probe, the residual where the next iteration starts, with the
    // contact set it was evaluated on
    let mut carried: Option<(Evaluation, Option<Vec<Vec<bool>>>)> = None;
    for iteration in 0..settings.max_iterations {
        stats.iterations += 1;
        let start = &IncrementStart {
            positions: &state.positions,
            strains: &converged.strains,
            laminate_states: &state.laminate_states,
            friction: &lags,
            velocities: &state.velocities,
            masses: &state.masses,
            dt,
        };
        // a solution on the frozen contact set, taken on the free set where it holds there
        let on_free = |x: &[Vector3<f64>],
                       translations: &[Vector3<f64>],
                       evaluation: &Evaluation,
                       scale: f64,
                       stats: &mut ImplicitStatistics,
                       residuals: &[f64]| {
            let tolerance = settings.tolerance * scale;
            on_free_set(
                evaluator,
                start,
                (x, translations),
                evaluation,
                tolerance,
                stats,
            )
            .map_err(|(k, e)| fail(residuals.to_vec(), None, format!("element {k}: {e}")))
        };
        let engaged = frozen.clone();
        work.near.refresh(model, &x, &translations);
        let trial = Trial {
            positions: &x,
            translations: &translations,
            engaged: engaged.as_deref(),
            near: Some(work.near.lists()),
        };
        let evaluation = match carried.take().filter(|(_, set)| *set == engaged) {
            Some((evaluation, _)) => evaluation,
            None => {
                let clock = Instant::now();
                let evaluation = evaluator
                    .residual(start, &trial)
                    .map_err(|(k, e)| fail(residuals.clone(), None, format!("element {k}: {e}")))?;
                stats.assembly_seconds += clock.elapsed().as_secs_f64();
                evaluation
            }
        };
        let norm = free_norm(layout, &evaluation.residual);
        if !norm.is_finite() {
            return Err(fail(
                residuals,
                None,
                "the forces at the trial are not finite numbers: a speed, load or stiffness of \
                 the model is beyond what double precision holds"
                    .into(),
            ));
        }
        residuals.push(norm);
        if iteration + 1 == settings.max_iterations {
            worst = worst_nodes(layout, &evaluation.residual);
        }
        let scale = force_scale(layout, &evaluation).max(layout.force_floor);
        if norm <= LAG_REFRESH_BAND * settings.tolerance * scale && refreshes < FRICTION_PASSES {
            if let Some(better) = refined_lags(model, state, &lags, &evaluation, &x, &translations)
            {
                lags = better;
                refreshes += 1;
                carried = None;
                // a new incremental problem: Newton's method starts over on it from here
                residuals.clear();
                frozen = None;
                freezes = 0;
                projected = false;
                continue;
            }
        }
        if norm <= settings.tolerance * scale {
            if evaluation.tunnelled > 0 {
                return Err(fail(
                    residuals,
                    Some(&evaluation),
                    format!(
                        "{} nodes came to rest behind a tool beyond the contact's reach",
                        evaluation.tunnelled
                    ),
                ));
            }
            if frozen.is_none() {
                return Ok((evaluation, x, translations, iteration + 1));
            }
            // solved on the frozen contact set: the solution if the set is the right one
            if let Some(free) = on_free(&x, &translations, &evaluation, scale, stats, &residuals)? {
                return Ok((free, x, translations, iteration + 1));
            }
            frozen = None;
            continue;
        }
        if frozen.is_none() && residuals.len() >= FREEZE_AFTER * (freezes + 1) {
            freezes += 1;
            frozen = Some(active_set(&evaluation));
        }
        let kind = if projected {
            Tangent::Projected
        } else {
            Tangent::Consistent
        };
        let descent = || -> Vec<f64> {
            evaluation
                .residual
                .iter()
                .zip(&layout.held)
                .map(|(r, &held)| if held { 0.0 } else { -r })
                .collect()
        };
        let mut factored = false;
        let mut iterated = None;
        for kind in [kind, Tangent::Projected] {
            let clock = Instant::now();
            evaluator
                .tangent(start, &trial, &evaluation, kind, &mut work.values)
                .map_err(|(k, e)| fail(residuals.clone(), None, format!("element {k}: {e}")))?;
            stats.assembly_seconds += clock.elapsed().as_secs_f64();
            let clock = Instant::now();
            iterated = iterative_solve(
                layout,
                work.preconditioner.as_mut(),
                &work.values,
                &descent(),
                stats,
            );
            if iterated.is_some() {
                stats.solve_seconds += clock.elapsed().as_secs_f64();
                factored = true;
                break;
            }
            factored = work
                .cholesky
                .factorise(&layout.pattern, &work.values)
                .is_ok();
            stats.factorisations += 1;
            stats.solve_seconds += clock.elapsed().as_secs_f64();
            if factored || projected {
                break;
            }
            projected = true;
            stats.projected += 1;
        }
        let values = &mut work.values;
        let clock = Instant::now();
        let mut shift = 1e-10;
        while !factored && shift < 1.0 {
            shift_diagonal(layout, values, shift);
            factored = work.cholesky.factorise(&layout.pattern, values).is_ok();
            stats.factorisations += 1;
            shift *= 100.0;
        }
        if !factored {
            return Err(fail(
                residuals,
                Some(&evaluation),
                "the tangent could not be factorised even when shifted".into(),
            ));
        }
        let mut direction = iterated.unwrap_or_else(|| {
            let mut direct = descent();
            work.cholesky.solve(&mut direct);
            direct
        });
        let correction = largest_free(layout, &direction);
        // the springs the correction enters, anticipated in the linear model (kept where the
        // correction still descends)
        let mut anticipated = Vec::new();
        let mut newton_direction = None;
        for _ in 0..ANTICIPATION_ROUNDS {
            let entries = contact_entry::entering(
                model,
                layout,
                &evaluation,
                (&x, &translations),
                frozen.as_deref(),
                &direction,
                &anticipated,
            );
            if entries.is_empty() {
                break;
            }
            contact_entry::add_springs(layout, &entries, &mut work.values);
            anticipated.extend(entries);
            let mut pushed = descent();
            contact_entry::add_pushes(layout, &anticipated, &mut pushed);
            let solved = match iterative_solve(
                layout,
                work.preconditioner.as_mut(),
                &work.values,
                &pushed,
                stats,
            ) {
                Some(solved) => solved,
                None => {
                    stats.factorisations += 1;
                    if work
                        .cholesky
                        .factorise(&layout.pattern, &work.values)
                        .is_err()
                    {
                        break;
                    }
                    work.cholesky.solve(&mut pushed);
                    pushed
                }
            };
            newton_direction.get_or_insert_with(|| direction.clone());
            direction = solved;
        }
        if let Some(newton) = newton_direction {
            if slope_along(layout, &direction, &evaluation.residual) >= 0.0 {
                direction = newton;
            }
        }
        stats.solve_seconds += clock.elapsed().as_secs_f64();
        // an increment that would be cut (stalled, or no step found) is solved if its
        // positions are settled: the residual floors where nodes rest at the edge of a
        // contact spring's reach
        let settled = correction <= CORRECTION_TOLERANCE * layout.length_scale
            && norm <= CORRECTION_RESIDUAL_SLACK * settings.tolerance * scale
            && evaluation.tunnelled == 0;
        let stalled = stalls(&residuals);
        // backtracking: a step is taken when it lowers the incremental potential by a share of
        // its slope (Armijo; on a positive definite tangent the direction always descends) or
        // the residual norm, whichever first: the potential alone stops deciding near the
        // solution, where its changes are at its rounding
        let slope = slope_along(layout, &direction, &evaluation.residual);
        // a force-driven tool moves at most a quarter of the contact's reach per step: its
        // potential -F u falls without bound once it has passed through the blank
        let tool_step = layout
            .tool_unknown
            .iter()
            .flatten()
            .map(|&u| direction[u].abs())
            .fold(0.0, f64::max);
        let reach = 0.25 * model.contact.max_penetration;
        let mut alpha: f64 = if tool_step > reach {
            reach / tool_step
        } else {
            1.0
        };
        let potential_decides =
            -slope > POTENTIAL_ROUNDING * evaluation.potential.abs().max(f64::MIN_POSITIVE);
        let mut accepted = false;
        // the last probe's step and potential, for the interpolated steps after the halvings
        let mut last_probe: Option<(f64, f64)> = None;
        // a stalled increment takes no step: it is settled or cut
        let attempts = if stalled {
            0
        } else {
            LINE_SEARCH_HALVINGS + LINE_SEARCH_INTERPOLATIONS
        };
        for attempt in 0..attempts {
            if attempt >= LINE_SEARCH_HALVINGS {
                match last_probe
                    .and_then(|(a, pi)| interpolated_step(a, pi - evaluation.potential, slope))
                {
                    Some(a) if potential_decides => alpha = a,
                    _ => break,
                }
            }
            let candidate: Vec<f64> = z
                .iter()
                .zip(&direction)
                .map(|(z, d)| z + alpha * d)
                .collect();
            let (cx, ct) = configuration(layout, &candidate, &x, &translations);
            let clock = Instant::now();
            let trial = Trial {
                positions: &cx,
                translations: &ct,
                engaged: frozen.as_deref(),
                near: Some(work.near.lists()),
            };
            let probe = evaluator.residual(start, &trial);
            stats.assembly_seconds += clock.elapsed().as_secs_f64();
            if let Ok(probe) = probe {
                let probe_norm = free_norm(layout, &probe.residual);
                let lowers_potential =
                    slope < 0.0 && probe.potential <= evaluation.potential + 1e-4 * alpha * slope;
                let lowers_residual = probe_norm <= (1.0 - 1e-4 * alpha) * norm;
                let lowers = if potential_decides {
                    lowers_potential
                } else {
                    lowers_residual
                };
                if probe_norm.is_finite() && lowers {
                    z = candidate;
                    x = cx;
                    translations = ct;
                    carried = Some((probe, frozen.clone()));
                    accepted = true;
                    break;
                }
                last_probe = probe
                    .potential
                    .is_finite()
                    .then_some((alpha, probe.potential));
            }
            alpha *= 0.5;
        }
        if !accepted {
            // at the rounding floor no step lowers the residual: the increment is solved
            let at_rounding = norm <= ROUNDING_FLOOR * scale
                || correction <= CORRECTION_FLOOR * layout.length_scale;
            if at_rounding && !stalled {
                return Ok((evaluation, x, translations, iteration + 1));
            }
            if settled && frozen.is_none() {
                return Ok((evaluation, x, translations, iteration + 1));
            }
            if settled {
                if let Some(free) =
                    on_free(&x, &translations, &evaluation, scale, stats, &residuals)?
                {
                    return Ok((free, x, translations, iteration + 1));
                }
            }
            if stalled {
                return Err(fail(
                    residuals,
                    Some(&evaluation),
                    format!(
                        "the residual fell by less than half over the last {STALL_WINDOW} \
                         iterations"
                    ),
                ));
            }
            if !projected {
                projected = true;
                stats.projected += 1;
                continue;
            }
            return Err(fail(
                residuals,
                Some(&evaluation),
                "the line search found no step that lowers the residual".into(),
            ));
        }
    }
    Err(NotConverged {
        worst_nodes: worst,
        reason: format!("no convergence in {} iterations", settings.max_iterations),
        residuals,
    })
}

/// Times a correction is solved again with the contact springs it enters, at most.
const ANTICIPATION_ROUNDS: usize = 3;

/// Relative residual `|K d + r| / |r|` to which conjugate gradients solve for a Newton
/// correction **(choice)**: Newton's method contracts only four to eight times per iteration
/// until near the solution (the yarns' slack band), which a correction this close does not
/// slow (on the 5,041-cell hemisphere 551 iterations against 562 with exact solves; docs/
/// performance.md).
const CG_TOLERANCE: f64 = 1e-2;

/// Conjugate-gradient iterations after which the tangent is factorised instead (measured on
/// the 5,041-cell hemisphere: about four a solve on average, 2,408 over 576 solves, growing
/// with the number of cells across the part; a few solves a run do not converge within this).
const CG_ITERATIONS: usize = 40;

/// Times an increment's friction is lagged again with the normal forces it reaches, at most.
const FRICTION_PASSES: usize = 2;

/// How close to converged (a multiple of the tolerance) the residual must be before friction
/// is lagged again with the normal forces reached: close enough that they are the increment's
/// to within the lag's own change threshold, early enough that the iterations still to come
/// converge the new problem (docs/solver.md, "Friction": 10 took an iteration more about every
/// third increment, 1,000 more iterations again).
const LAG_REFRESH_BAND: f64 = 100.0;

/// Change of the friction limits `mu lambda`, relative to their sum, above which friction is
/// lagged again with them and Newton's method goes on from there on the new problem.
const FRICTION_LAG_CHANGE: f64 = 0.002;

/// Iterations over which the residual must at least halve once the increment is this many
/// iterations old: slower, the increment is cut at once rather than after its last
/// iteration, as the shorter one converges in fewer iterations than the slow one would take.
const STALL_WINDOW: usize = 5;
const STALL_AFTER: usize = 10;

fn stalls(residuals: &[f64]) -> bool {
    let n = residuals.len();
    n >= STALL_AFTER && residuals[n - 1] > 0.5 * residuals[n - 1 - STALL_WINDOW]
}

/// The expected change of the potential, relative to the potential, below which the line
/// search judges a step by the residual instead: `Pi` sums terms whose rounding (about 1e-16
/// of each) then hides the change of the sum.
const POTENTIAL_ROUNDING: f64 = 1e-10;

/// Halvings of the step the line search tries before it gives up.
const LINE_SEARCH_HALVINGS: usize = 12;

/// Steps the line search tries after its halvings, each the minimum of the parabola through
/// the potential at the start (with its slope) and at the last step tried: where the tangent
/// does not see a contact spring that the step runs into (a node resting at the edge of its
/// reach), the potential rises along the Newton correction from a step far below the
/// halvings' last (measured on 20,164 elements: 3e-5, the halvings ending at 2.4e-4).
const LINE_SEARCH_INTERPOLATIONS: usize = 4;

/// The minimum of the parabola `slope a + c a^2` through the change `rise` of the potential at
/// the step `alpha`, kept within a tenth and a half of `alpha`; `None` where that is no
/// parabola opening upwards from a descent.
fn interpolated_step(alpha: f64, rise: f64, slope: f64) -> Option<f64> {
    let curvature = (rise - slope * alpha) / (alpha * alpha);
    (slope < 0.0 && curvature > 0.0)
        .then(|| (-slope / (2.0 * curvature)).clamp(0.1 * alpha, 0.5 * alpha))
}

/// Newton iterations after which the contact set (which node–tool springs act) is frozen for
/// the rest of the iterations, every so many again: a node whose equilibrium lies at the edge
/// of contact otherwise hops in and out of it from one iteration to the next and the residual
/// falls only slowly. Solved on the frozen set, the solution is checked on the free one.
const FREEZE_AFTER: usize = 5;

/// A residual, relative to the forces at play, that no step lowers is taken as converged below
/// this: the rounding of sums of forces up to a million times larger than the residual.
const ROUNDING_FLOOR: f64 = 1e-9;

/// A Newton correction, relative to the mean element size, at the rounding of the positions:
/// where no step lowers the residual and the full step would move no unknown farther, the
/// residual is what the forces' rounding leaves (stiff yarns over a slack sheet, forces of
/// 1e-6 N at the start of a virtual test) and the increment is solved.
const CORRECTION_FLOOR: f64 = 1e-9;

/// A full Newton correction, relative to the mean element size, below which an increment is
/// solved although its residual is above the tolerance, if within [`CORRECTION_RESIDUAL_SLACK`]
/// times it **(choice)**: where the forces at play are a thousandth of a newton (a flange that
/// only touches the die, no holder) the residual's tolerance asks for less than a micronewton,
/// which nodes at the edge of a contact spring's reach never give, while their positions are
/// settled to a millionth of the cells.
const CORRECTION_TOLERANCE: f64 = 1e-5;
const CORRECTION_RESIDUAL_SLACK: f64 = 100.0;

/// A solution on the frozen contact set, `frozen` its evaluation, taken on the free set: the
/// evaluation there when its residual is within `tolerance` (N), or when the springs the
/// frozen set held on pull no node from farther than [`CORRECTION_TOLERANCE`] of the cells
/// beyond their reach (then they only tell which side of the reach's edge a node at it lies,
/// to within what the positions are settled to); `None` otherwise.
fn on_free_set(
    evaluator: &Evaluator,
    start: &IncrementStart,
    (x, translations): (&[Vector3<f64>], &[Vector3<f64>]),
    frozen: &Evaluation,
    tolerance: f64,
    stats: &mut ImplicitStatistics,
) -> Result<Option<Evaluation>, (usize, crate::material::MaterialError)> {
    let layout = evaluator.layout;
    let free = Trial {
        positions: x,
        translations,
        engaged: None,
        near: None,
    };
    let clock = Instant::now();
    let unfrozen = evaluator.evaluate(start, &free, Tangent::None)?;
    stats.assembly_seconds += clock.elapsed().as_secs_f64();
    let pull = frozen
        .contacts
        .iter()
        .zip(&layout.penalty)
        .flat_map(|(c, k)| c.normal_force.iter().map(move |f| -f / k))
        .fold(0.0, f64::max);
    let settled = pull <= CORRECTION_TOLERANCE * layout.length_scale;
    Ok((settled || free_norm(layout, &unfrozen.residual) <= tolerance).then_some(unfrozen))
}

/// Which node–tool springs act in `evaluation` (`[node][tool]`): the contact set Newton's
/// method freezes.
fn active_set(evaluation: &Evaluation) -> Vec<Vec<bool>> {
    evaluation
        .contacts
        .iter()
        .map(|c| c.normal_force.iter().map(|&f| f != 0.0).collect())
        .collect()
}

/// `dPi/dalpha` along `direction` at `alpha = 0`: the free unknowns' `direction . residual`.
fn slope_along(layout: &Layout, direction: &[f64], residual: &[f64]) -> f64 {
    direction
        .iter()
        .zip(residual)
        .zip(&layout.held)
        .filter(|(_, &h)| !h)
        .map(|((d, r), _)| d * r)
        .sum()
}

/// The largest free component of `v`.
fn largest_free(layout: &Layout, v: &[f64]) -> f64 {
    v.iter()
        .zip(&layout.held)
        .filter(|(_, &h)| !h)
        .map(|(d, _)| d.abs())
        .fold(0.0, f64::max)
}

/// The unknowns of a configuration: node coordinates, then the tools' travel.
fn unknowns(layout: &Layout, x: &[Vector3<f64>], translations: &[Vector3<f64>]) -> Vec<f64> {
    let mut z: Vec<f64> = x.iter().flat_map(|p| [p.x, p.y, p.z]).collect();
    z.resize(layout.size, 0.0);
    for (k, unknown) in layout.tool_unknown.iter().enumerate() {
        if let (Some(u), Some((axis, _))) = (unknown, layout.tool_force[k]) {
            z[*u] = translations[k].dot(&axis);
        }
    }
    z
}

/// Node positions and tool translations from the unknowns; held coordinates and the other
/// tools stay where `x` and `translations` have them.
fn configuration(
    layout: &Layout,
    z: &[f64],
    x: &[Vector3<f64>],
    translations: &[Vector3<f64>],
) -> (Vec<Vector3<f64>>, Vec<Vector3<f64>>) {
    let positions = x
        .iter()
        .enumerate()
        .map(|(n, p)| {
            Vector3::from_fn(|d, _| {
                if layout.held[3 * n + d] {
                    p[d]
                } else {
                    z[3 * n + d]
                }
            })
        })
        .collect();
    let moved = translations
        .iter()
        .enumerate()
        .map(
            |(k, t)| match (layout.tool_unknown[k], layout.tool_force[k]) {
                (Some(u), Some((axis, _))) => t + axis * (z[u] - t.dot(&axis)),
                _ => *t,
            },
        )
        .collect();
    (positions, moved)
}

fn free_norm(layout: &Layout, residual: &[f64]) -> f64 {
    residual
        .iter()
        .zip(&layout.held)
        .filter(|(_, &h)| !h)
        .map(|(r, _)| r * r)
        .sum::<f64>()
        .sqrt()
}

/// The size of the forces at play: internal, contact and applied (N).
fn force_scale(layout: &Layout, e: &Evaluation) -> f64 {
    let internal: f64 = e.internal.iter().map(|f| f.norm_squared()).sum();
    let contact: f64 = e.contacts.iter().map(|c| c.force.norm_squared()).sum();
    let applied: f64 = layout.tool_force.iter().flatten().map(|(_, f)| f * f).sum();
    (internal + contact + applied).sqrt().max(1e-9)
}

fn shift_diagonal(layout: &Layout, values: &mut [f64], shift: f64) {
    let diagonal: Vec<usize> = (0..layout.size)
        .map(|i| layout.pattern.place(i, i).expect("diagonal"))
        .collect();
    let mean = diagonal.iter().map(|&p| values[p].abs()).sum::<f64>() / layout.size as f64;
    for (i, &p) in diagonal.iter().enumerate() {
        if !layout.held[i] {
            values[p] += shift * mean;
        }
    }
}

/// The five nodes with the largest residual force.
fn worst_nodes(layout: &Layout, residual: &[f64]) -> Vec<usize> {
    let mut nodes: Vec<(usize, f64)> = (0..layout.nodes)
        .map(|n| {
            let r: f64 = (0..3)
                .filter(|d| !layout.held[3 * n + d])
                .map(|d| residual[3 * n + d].powi(2))
                .sum();
            (n, r)
        })
        .collect();
    nodes.sort_by(|a, b| b.1.total_cmp(&a.1));
    nodes.into_iter().take(5).map(|(n, _)| n).collect()
}

/// Takes the converged increment into the state: positions, forces, contact, tools, energies
/// (trapezoidal work sums as in the explicit solver), and the friction lagged for the next.
fn accept(
    model: &Model,
    layout: &Layout,
    state: &mut State,
    converged: &mut Converged,
    (evaluation, x, translations): (Evaluation, Vec<Vector3<f64>>, Vec<Vector3<f64>>),
    dt: f64,
) {
    let (mut internal, mut external, mut tool) = (0.0, 0.0, 0.0);
    let (mut kinetic, mut dissipated) = (0.0, 0.0);
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
    state.energies.kinetic = kinetic;
    state.energies.internal_work += internal;
    state.energies.external_work += external + tool;
    state.energies.tool_work += tool;
    state.energies.damping += evaluation.drag_work + dissipated;
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

#[cfg(test)]
mod tests {
    use super::interpolated_step;

    /// Along a Newton correction the potential is `slope a + c a^2` where the tangent misses a
    /// stiffness the step runs into: the interpolated step is that parabola's minimum, from any
    /// step tried, kept within a tenth and a half of it.
    #[test]
    fn the_interpolated_step_is_the_minimum_of_the_parabola() {
        let (slope, c) = (-2.5e-4, 4.0);
        let minimum = -slope / (2.0 * c);
        let rise = |a: f64| slope * a + c * a * a;
        for alpha in [4.0 * minimum, 9.0 * minimum] {
            let step = interpolated_step(alpha, rise(alpha), slope).unwrap();
            assert!(
                (step - minimum).abs() < 1e-12 * minimum,
                "{step} against {minimum}"
            );
        }
        let far = 1e3 * minimum;
        assert_eq!(interpolated_step(far, rise(far), slope), Some(0.1 * far));
        let near = 1.2 * minimum;
        assert_eq!(interpolated_step(near, rise(near), slope), Some(0.5 * near));
        assert_eq!(interpolated_step(1.0, -1.0, 2.0), None, "no descent");
        assert_eq!(interpolated_step(1.0, -1.0, -0.5), None, "no minimum");
    }
}
