//! Newton's method on one increment of the implicit solver (docs/solver.md, "Implicit"): where
//! the iteration stands ([`Iterate`]) and its phases, each a function: the residual at the
//! iterate ([`Iterate::evaluate`]), friction lagged again with the normal forces reached
//! ([`Iterate::relag_friction`]), the convergence test ([`Iterate::at_tolerance`]), the contact
//! set frozen ([`Iterate::freeze_contact_set`]), the Newton direction ([`newton_direction`]:
//! the tangent, its linear solve, the contact springs the correction enters), the line search
//! ([`Iterate::line_search`]) and what follows when it finds no step ([`Iterate::without_step`]).

use super::assembly::{Evaluation, Evaluator, IncrementStart, Layout, Tangent, Trial};
use super::interply::{held_faces, HeldFaces, PlyLags};
use super::{contact_entry, iterative_solve, lag_normal, NotIterated};
use super::{Converged, ImplicitSettings, ImplicitStatistics, NotConverged, Solved, Workspace};
use crate::contact::potential::FrictionLag;
use crate::solver::state::State;
use nalgebra::Vector3;
use std::time::Instant;

/// One increment's problem: the model's evaluator, the converged state it starts from, its
/// duration `dt` (s) and the solver's settings.
pub(super) struct Problem<'a> {
    pub evaluator: &'a Evaluator<'a>,
    pub state: &'a State,
    pub converged: &'a Converged,
    pub dt: f64,
    pub settings: &'a ImplicitSettings,
}

/// Which node–tool springs act (`[node][tool]`).
type ContactSet = Vec<Vec<bool>>;

/// Where Newton's method stands within an increment.
struct Iterate {
    /// Node positions and tool translations, and the unknowns they give.
    x: Vec<Vector3<f64>>,
    translations: Vec<Vector3<f64>>,
    z: Vec<f64>,
    /// Friction of each node on each tool, lagged for this increment's problem, and how often
    /// it was lagged again with the normal forces reached.
    lags: Vec<Vec<Option<FrictionLag>>>,
    /// The same of each node on the plies below and above it, and the triangles its ply–ply
    /// contact is held on over the increment: those nearest at its start (a node that slides
    /// past one meanwhile is measured from its plane, a difference of the slip times the angle
    /// between neighbouring faces; taking the nearest again there restarted Newton's method on
    /// most increments, 3,432 iterations against 2,647 on the two-ply hemisphere, the same
    /// part).
    ply_lags: PlyLags,
    ply_faces: HeldFaces,
    refreshes: usize,
    /// Residual norms (N) since the problem was last set.
    residuals: Vec<f64>,
    /// Whether the element tangents are projected to their positive semi-definite parts.
    projected: bool,
    /// The contact set held fixed, and how often it was frozen.
    frozen: Option<ContactSet>,
    freezes: usize,
    /// The line search's accepted probe, the residual where the next iteration starts, with
    /// the contact set it was evaluated on.
    carried: Option<(Evaluation, Option<ContactSet>)>,
}

/// A Newton correction: the step of the unknowns, and the largest free component of the
/// tangent's own solve (before the contact springs it enters were anticipated).
struct Direction {
    step: Vec<f64>,
    correction: f64,
}

/// Newton's method on one increment of `problem`, beginning at `guess` (positions and tool
/// translations), friction lagged from the increment's start and then from the normal forces
/// reached once the residual is within [`LAG_REFRESH_BAND`] of its tolerance.
pub(super) fn newton(
    problem: &Problem,
    work: &mut Workspace,
    guess: (Vec<Vector3<f64>>, Vec<Vector3<f64>>),
    stats: &mut ImplicitStatistics,
) -> Result<Solved, NotConverged> {
    let settings = problem.settings;
    let layout = problem.evaluator.layout;
    let mut it = Iterate::new(problem, guess);
    let mut worst = Vec::new();
    for iteration in 0..settings.max_iterations {
        stats.iterations += 1;
        let evaluation = it.evaluate(problem, work, stats)?;
        let norm = free_norm(layout, &evaluation.residual);
        if !norm.is_finite() {
            return Err(it.failure(
                Vec::new(),
                "the forces at the trial are not finite numbers: a speed, load or stiffness of \
                 the model is beyond what double precision holds",
            ));
        }
        it.residuals.push(norm);
        if iteration + 1 == settings.max_iterations {
            worst = worst_nodes(layout, &evaluation.residual);
        }
        let scale = force_scale(layout, &evaluation).max(layout.force_floor);
        if it.relag_friction(problem, &evaluation, norm, scale) {
            continue;
        }
        let done = |solved: Evaluation, it: Iterate| (solved, it.x, it.translations, iteration + 1);
        if norm <= settings.tolerance * scale {
            match it.at_tolerance(problem, evaluation, scale, stats)? {
                Ok(solved) => return Ok(done(solved, it)),
                Err(()) => continue,
            }
        }
        // the tangent is formed on the contact set the residual was evaluated on
        let engaged = it.frozen.clone();
        it.freeze_contact_set(&evaluation);
        let direction = newton_direction(problem, work, &mut it, (&evaluation, &engaged), stats)?;
        let stalled = stalls(&it.residuals);
        // a stalled increment takes no step: it is settled or cut
        if !stalled && it.line_search(problem, work, &evaluation, &direction.step, norm, stats) {
            continue;
        }
        let judged = Judged {
            norm,
            scale,
            correction: direction.correction,
            stalled,
        };
        if let Some(solved) = it.without_step(problem, evaluation, judged, stats)? {
            return Ok(done(solved, it));
        }
    }
    Err(NotConverged {
        worst_nodes: worst,
        reason: format!("no convergence in {} iterations", settings.max_iterations),
        residuals: it.residuals,
    })
}

/// What an iteration whose line search found no step is judged on: the residual's norm and
/// the forces at play (N), the correction's largest free component (mm), and whether the
/// residual stalls.
struct Judged {
    norm: f64,
    scale: f64,
    correction: f64,
    stalled: bool,
}

impl Iterate {
    fn new(problem: &Problem, (x, translations): (Vec<Vector3<f64>>, Vec<Vector3<f64>>)) -> Self {
        Self {
            z: unknowns(problem.evaluator.layout, &x, &translations),
            x,
            translations,
            lags: problem.converged.friction.clone(),
            ply_lags: problem.converged.ply_lags.clone(),
            ply_faces: problem.evaluator.plies.map_or(Vec::new(), |p| {
                held_faces(p, &problem.state.interply, &problem.state.positions)
            }),
            refreshes: 0,
            residuals: Vec::new(),
            projected: false,
            frozen: None,
            freezes: 0,
            carried: None,
        }
    }

    /// The increment's start as the assembly reads it, with the friction lagged now.
    fn start<'s>(&'s self, problem: &'s Problem) -> IncrementStart<'s> {
        let (state, converged) = (problem.state, problem.converged);
        IncrementStart {
            positions: &state.positions,
            strains: &converged.strains,
            laminate_states: &state.laminate_states,
            friction: &self.lags,
            velocities: &state.velocities,
            masses: &state.masses,
            dt: problem.dt,
            ply_lags: &self.ply_lags,
            ply_lists: &state.interply,
            ply_faces: &self.ply_faces,
            temperatures: &state.temperatures,
            bending_rigidities: &state.bending_rigidities,
            released: &state.supports.released,
        }
    }

    /// Why the increment failed, with the residuals so far and the nodes where the residual is
    /// largest (`worst`, [`worst_nodes`]; none where no residual was formed).
    fn failure(&self, worst: Vec<usize>, reason: impl Into<String>) -> NotConverged {
        NotConverged {
            worst_nodes: worst,
            residuals: self.residuals.clone(),
            reason: reason.into(),
        }
    }

    /// The residual at the iterate: the line search's accepted probe where it was made on the
    /// contact set that holds now, evaluated afresh otherwise.
    fn evaluate(
        &mut self,
        problem: &Problem,
        work: &mut Workspace,
        stats: &mut ImplicitStatistics,
    ) -> Result<Evaluation, NotConverged> {
        let evaluator = problem.evaluator;
        work.near
            .refresh(evaluator.model, &self.x, &self.translations);
        if let Some((evaluation, _)) = self.carried.take().filter(|(_, s)| *s == self.frozen) {
            return Ok(evaluation);
        }
        let trial = Trial {
            positions: &self.x,
            translations: &self.translations,
            engaged: self.frozen.as_deref(),
            near: Some(work.near.lists()),
        };
        let clock = Instant::now();
        let evaluation = evaluator
            .residual(&self.start(problem), &trial)
            .map_err(|(k, e)| self.failure(Vec::new(), format!("element {k}: {e}")))?;
        stats.assembly_seconds += clock.elapsed().as_secs_f64();
        Ok(evaluation)
    }

    /// Friction lagged again with the normal forces of `evaluation` once the residual's `norm`
    /// is within [`LAG_REFRESH_BAND`] times its tolerance (of the forces at play, `scale`) and
    /// they moved ([`refined_lags`]), at most [`FRICTION_PASSES`] times: a new incremental
    /// problem, which Newton's method starts over on from here. Whether it was.
    fn relag_friction(
        &mut self,
        problem: &Problem,
        evaluation: &Evaluation,
        norm: f64,
        scale: f64,
    ) -> bool {
        let band = LAG_REFRESH_BAND * problem.settings.tolerance * scale;
        if norm > band || self.refreshes >= FRICTION_PASSES {
            return false;
        }
        let model = problem.evaluator.model;
        let tools = refined_lags(
            model,
            problem.state,
            &self.lags,
            evaluation,
            (&self.x, &self.translations),
        );
        let plies = problem
            .evaluator
            .interply(&self.start(problem))
            .and_then(|plies| {
                let motion = (&problem.state.positions[..], &self.x[..], problem.dt);
                plies.refined_lags(&evaluation.interply, motion, FRICTION_LAG_CHANGE)
            });
        if tools.is_none() && plies.is_none() {
            return false;
        }
        if let Some(better) = tools {
            self.lags = better;
        }
        if let Some(better) = plies {
            self.ply_lags = better;
        }
        self.refreshes += 1;
        self.carried = None;
        self.residuals.clear();
        self.frozen = None;
        self.freezes = 0;
        self.projected = false;
        true
    }

    /// The residual is within its tolerance: the increment's solution (`Ok`), unless a node
    /// rests behind a tool beyond the contact's reach (the increment fails) or the solution on
    /// the frozen contact set does not hold on the free one (`Err(())`: the set is thawed and
    /// the iterations go on).
    fn at_tolerance(
        &mut self,
        problem: &Problem,
        evaluation: Evaluation,
        scale: f64,
        stats: &mut ImplicitStatistics,
    ) -> Result<Result<Evaluation, ()>, NotConverged> {
        if evaluation.tunnelled > 0 {
            return Err(self.failure(
                worst_nodes(problem.evaluator.layout, &evaluation.residual),
                format!(
                    "{} nodes came to rest behind a tool beyond the contact's reach",
                    evaluation.tunnelled
                ),
            ));
        }
        if self.frozen.is_none() {
            return Ok(Ok(evaluation));
        }
        if let Some(free) = self.on_free(problem, &evaluation, scale, stats)? {
            return Ok(Ok(free));
        }
        self.frozen = None;
        Ok(Err(()))
    }

    /// [`on_free_set`] at the iterate, with the tolerance of forces `scale`.
    fn on_free(
        &self,
        problem: &Problem,
        evaluation: &Evaluation,
        scale: f64,
        stats: &mut ImplicitStatistics,
    ) -> Result<Option<Evaluation>, NotConverged> {
        on_free_set(
            problem.evaluator,
            &self.start(problem),
            (&self.x, &self.translations),
            evaluation,
            problem.settings.tolerance * scale,
            stats,
        )
        .map_err(|(k, e)| self.failure(Vec::new(), format!("element {k}: {e}")))
    }

    /// After [`FREEZE_AFTER`] iterations (and as many again after each thaw) the contact set of
    /// `evaluation` is held for the rest of the iterations.
    fn freeze_contact_set(&mut self, evaluation: &Evaluation) {
        if self.frozen.is_none() && self.residuals.len() >= FREEZE_AFTER * (self.freezes + 1) {
            self.freezes += 1;
            self.frozen = Some(active_set(evaluation));
        }
    }

    /// Backtracking along `direction` from the iterate (residual `evaluation`, of norm `norm`):
    /// a step is taken when it lowers the incremental potential by a share of its slope
    /// (Armijo; on a positive definite tangent the direction always descends) or the residual
    /// norm, whichever decides (the potential stops deciding near the solution, where its
    /// changes are at its rounding); after [`LINE_SEARCH_HALVINGS`] halvings, steps at the
    /// minimum of the parabola through the last probe. Whether a step was taken: the iterate
    /// moved there, the probe carried to the next iteration.
    fn line_search(
        &mut self,
        problem: &Problem,
        work: &Workspace,
        evaluation: &Evaluation,
        direction: &[f64],
        norm: f64,
        stats: &mut ImplicitStatistics,
    ) -> bool {
        let layout = problem.evaluator.layout;
        let slope = slope_along(layout, direction, &evaluation.residual);
        let mut alpha = tool_step_limit(problem, direction);
        let potential_decides =
            -slope > POTENTIAL_ROUNDING * evaluation.potential.abs().max(f64::MIN_POSITIVE);
        // the last probe's step and potential, for the interpolated steps after the halvings
        let mut last_probe: Option<(f64, f64)> = None;
        for attempt in 0..LINE_SEARCH_HALVINGS + LINE_SEARCH_INTERPOLATIONS {
            if attempt >= LINE_SEARCH_HALVINGS {
                match last_probe
                    .and_then(|(a, pi)| interpolated_step(a, pi - evaluation.potential, slope))
                {
                    Some(a) if potential_decides => alpha = a,
                    _ => break,
                }
            }
            let candidate: Vec<f64> = self
                .z
                .iter()
                .zip(direction)
                .map(|(z, d)| z + alpha * d)
                .collect();
            let (cx, ct) = configuration(layout, &candidate, &self.x, &self.translations);
            let trial = Trial {
                positions: &cx,
                translations: &ct,
                engaged: self.frozen.as_deref(),
                near: Some(work.near.lists()),
            };
            let clock = Instant::now();
            let probe = problem.evaluator.residual(&self.start(problem), &trial);
            stats.assembly_seconds += clock.elapsed().as_secs_f64();
            if let Ok(probe) = probe {
                let probe_norm = free_norm(layout, &probe.residual);
                let lowers = if potential_decides {
                    slope < 0.0 && probe.potential <= evaluation.potential + 1e-4 * alpha * slope
                } else {
                    probe_norm <= (1.0 - 1e-4 * alpha) * norm
                };
                if probe_norm.is_finite() && lowers {
                    self.z = candidate;
                    self.x = cx;
                    self.translations = ct;
                    self.carried = Some((probe, self.frozen.clone()));
                    return true;
                }
                last_probe = probe
                    .potential
                    .is_finite()
                    .then_some((alpha, probe.potential));
            }
            alpha *= 0.5;
        }
        false
    }

    /// No step lowers the residual: the increment is solved where the residual is at its
    /// rounding floor or the positions are settled ([`CORRECTION_TOLERANCE`], on the free
    /// contact set); otherwise the tangent is projected and the iterations go on (`None`), or,
    /// projected already or stalled, the increment fails.
    fn without_step(
        &mut self,
        problem: &Problem,
        evaluation: Evaluation,
        judged: Judged,
        stats: &mut ImplicitStatistics,
    ) -> Result<Option<Evaluation>, NotConverged> {
        let layout = problem.evaluator.layout;
        let tolerance = problem.settings.tolerance;
        let Judged {
            norm,
            scale,
            correction,
            stalled,
        } = judged;
        let at_rounding =
            norm <= ROUNDING_FLOOR * scale || correction <= CORRECTION_FLOOR * layout.length_scale;
        if at_rounding && !stalled {
            return Ok(Some(evaluation));
        }
        // the residual floors where nodes rest at the edge of a contact spring's reach
        let settled = correction <= CORRECTION_TOLERANCE * layout.length_scale
            && norm <= CORRECTION_RESIDUAL_SLACK * tolerance * scale
            && evaluation.tunnelled == 0;
        if settled && self.frozen.is_none() {
            return Ok(Some(evaluation));
        }
        if settled {
            if let Some(free) = self.on_free(problem, &evaluation, scale, stats)? {
                return Ok(Some(free));
            }
        }
        if stalled {
            return Err(self.failure(
                worst_nodes(problem.evaluator.layout, &evaluation.residual),
                format!(
                    "the residual fell by less than half over the last {STALL_WINDOW} iterations"
                ),
            ));
        }
        if !self.projected {
            self.projected = true;
            stats.projected += 1;
            return Ok(None);
        }
        Err(self.failure(
            worst_nodes(layout, &evaluation.residual),
            "the line search found no step that lowers the residual",
        ))
    }
}

/// The Newton correction at the iterate `it` (residual `evaluation`, made on the contact set
/// `engaged`): the tangent solved ([`solve_tangent`]), then solved again with the contact
/// springs the correction enters anticipated ([`anticipate_contact_entries`]).
fn newton_direction(
    problem: &Problem,
    work: &mut Workspace,
    it: &mut Iterate,
    (evaluation, engaged): (&Evaluation, &Option<ContactSet>),
    stats: &mut ImplicitStatistics,
) -> Result<Direction, NotConverged> {
    let layout = problem.evaluator.layout;
    let descent = descent(layout, evaluation);
    let step = solve_tangent(problem, work, it, (evaluation, engaged), &descent, stats)?;
    let correction = largest_free(layout, &step);
    let clock = Instant::now();
    let step = anticipate_contact_entries(problem, work, it, evaluation, &descent, step, stats);
    stats.solve_seconds += clock.elapsed().as_secs_f64();
    Ok(Direction { step, correction })
}

/// `-r` on the free unknowns, zero on the held ones: the right-hand side of a correction.
fn descent(layout: &Layout, evaluation: &Evaluation) -> Vec<f64> {
    evaluation
        .residual
        .iter()
        .zip(&layout.held)
        .map(|(r, &held)| if held { 0.0 } else { -r })
        .collect()
}

/// `K d = descent` for the tangent `K` at the iterate (on the contact set `engaged`): the
/// consistent tangent, or where it is not positive definite the projected one (from then on for
/// the increment), by conjugate gradients where the run has a preconditioner and they converge,
/// else by the tangent's factorisation (not tried where the preconditioner or the conjugate
/// gradients showed the tangent indefinite: it would fail), its diagonal shifted where even the
/// projected tangent does not factorise. The tangent's values stay in `work.values` and, where
/// factorised, its factor in `work.cholesky`, for the anticipation's solves.
fn solve_tangent(
    problem: &Problem,
    work: &mut Workspace,
    it: &mut Iterate,
    (evaluation, engaged): (&Evaluation, &Option<ContactSet>),
    descent: &[f64],
    stats: &mut ImplicitStatistics,
) -> Result<Vec<f64>, NotConverged> {
    let evaluator = problem.evaluator;
    let layout = evaluator.layout;
    let first = if it.projected {
        Tangent::Projected
    } else {
        Tangent::Consistent
    };
    let mut factored = false;
    for kind in [first, Tangent::Projected] {
        let clock = Instant::now();
        let trial = Trial {
            positions: &it.x,
            translations: &it.translations,
            engaged: engaged.as_deref(),
            near: Some(work.near.lists()),
        };
        evaluator
            .tangent(
                &it.start(problem),
                &trial,
                evaluation,
                kind,
                &mut work.values,
            )
            .map_err(|(k, e)| it.failure(Vec::new(), format!("element {k}: {e}")))?;
        stats.assembly_seconds += clock.elapsed().as_secs_f64();
        let clock = Instant::now();
        match iterative_solve(
            layout,
            work.preconditioner.as_mut(),
            &work.values,
            descent,
            stats,
        ) {
            Ok(solved) => {
                stats.solve_seconds += clock.elapsed().as_secs_f64();
                return Ok(solved);
            }
            // factorising it would fail too: on to the projected tangent
            Err(NotIterated::Indefinite) => {}
            Err(NotIterated::Factorise) => {
                factored = work
                    .cholesky
                    .factorise(&layout.pattern, &work.values)
                    .is_ok();
                stats.factorisations += 1;
            }
        }
        stats.solve_seconds += clock.elapsed().as_secs_f64();
        if factored || it.projected {
            break;
        }
        it.projected = true;
        stats.projected += 1;
    }
    let clock = Instant::now();
    let mut shift = 1e-10;
    while !factored && shift < 1.0 {
        shift_diagonal(layout, &mut work.values, shift);
        factored = work
            .cholesky
            .factorise(&layout.pattern, &work.values)
            .is_ok();
        stats.factorisations += 1;
        shift *= 100.0;
    }
    if !factored {
        return Err(it.failure(
            worst_nodes(layout, &evaluation.residual),
            "the tangent could not be factorised even when shifted",
        ));
    }
    let mut direct = descent.to_vec();
    work.cholesky.solve(&mut direct);
    stats.solve_seconds += clock.elapsed().as_secs_f64();
    Ok(direct)
}

/// The correction `step` solved again, up to [`ANTICIPATION_ROUNDS`] times, with the contact
/// springs it enters added to the tangent and their pushes to the right-hand side
/// ([`contact_entry`]); kept where it still descends, the tangent's own correction otherwise.
fn anticipate_contact_entries(
    problem: &Problem,
    work: &mut Workspace,
    it: &Iterate,
    evaluation: &Evaluation,
    descent: &[f64],
    step: Vec<f64>,
    stats: &mut ImplicitStatistics,
) -> Vec<f64> {
    let model = problem.evaluator.model;
    let layout = problem.evaluator.layout;
    let mut direction = step;
    let mut anticipated = Vec::new();
    let mut newton_direction = None;
    for _ in 0..ANTICIPATION_ROUNDS {
        let entries = contact_entry::entering(
            model,
            layout,
            evaluation,
            (&it.x, &it.translations),
            it.frozen.as_deref(),
            &direction,
            &anticipated,
        );
        if entries.is_empty() {
            break;
        }
        contact_entry::add_springs(layout, &entries, &mut work.values);
        anticipated.extend(entries);
        let mut pushed = descent.to_vec();
        contact_entry::add_pushes(layout, &anticipated, &mut pushed);
        let solved = match iterative_solve(
            layout,
            work.preconditioner.as_mut(),
            &work.values,
            &pushed,
            stats,
        ) {
            Ok(solved) => solved,
            Err(NotIterated::Indefinite) => break,
            Err(NotIterated::Factorise) => {
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
    match newton_direction {
        Some(newton) if slope_along(layout, &direction, &evaluation.residual) >= 0.0 => newton,
        _ => direction,
    }
}

/// The line search's first step: 1, or less so that a force-driven tool moves at most a
/// quarter of the contact's reach (its potential `-F u` falls without bound once it has
/// passed through the blank).
fn tool_step_limit(problem: &Problem, direction: &[f64]) -> f64 {
    let layout = problem.evaluator.layout;
    let tool_step = layout
        .tool_unknown
        .iter()
        .flatten()
        .map(|&u| direction[u].abs())
        .fold(0.0, f64::max);
    let reach = 0.25 * problem.evaluator.model.contact.max_penetration;
    if tool_step > reach {
        reach / tool_step
    } else {
        1.0
    }
}

/// Friction lagged again with the normal forces of the iterate `evaluation` (at `x`, tools at
/// `translations`), when they differ from the lagged ones by more than
/// [`FRICTION_LAG_CHANGE`] of their sum; the slip still counts from the increment's start,
/// along the start's tangent plane where there was one.
fn refined_lags(
    model: &crate::solver::Model,
    state: &State,
    lags: &[Vec<Option<FrictionLag>>],
    evaluation: &Evaluation,
    (x, translations): (&[Vector3<f64>], &[Vector3<f64>]),
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

/// Times a correction is solved again with the contact springs it enters, at most.
const ANTICIPATION_ROUNDS: usize = 3;

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

/// Which node–tool springs act in `evaluation`: the contact set Newton's method freezes.
fn active_set(evaluation: &Evaluation) -> ContactSet {
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
    let contact: f64 = e
        .contacts
        .iter()
        .map(|c| c.force.norm_squared())
        .sum::<f64>()
        + e.interply
            .iter()
            .map(|c| c.force.norm_squared())
            .sum::<f64>();
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
