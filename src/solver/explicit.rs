//! Central-difference integration of the sheet (docs/model.md §6).
//!
//! Leapfrog with lumped mass: `a_n = -M^-1 f_int(x_n, v_{n-1/2})`,
//! `v_{n+1/2} = v_{n-1/2} + (dt_{n-1/2} + dt_{n+1/2})/2 a_n`, `x_{n+1} = x_n + dt_{n+1/2} v_{n+1/2}`.
//! The viscous matrix sees the rate from `v_{n-1/2}`, half a step behind, as usual in explicit
//! codes. Constrained nodes get their prescribed velocity at `t_{n+1/2}`; their reaction is
//! `R = f_int + m a`. The step is `safety x min_e(h_e / c_e)` with `h_e` the element length (`MembraneElement::altitude`)
//! and `c_e = sqrt(E_e / rho_e)` from the laminate's current wave modulus, re-evaluated every step,
//! times `sqrt(1 + xi^2) - xi` for the damping `xi` of the element's highest mode by the yarn
//! damping and the matrix viscosity (the critical step of a damped oscillator).

use super::checks::{self, CheckReport, CheckSettings};
use super::energy::Energies;
use super::error::{positive_setting, SolverError};
use super::heat;
use super::model::{Model, Motion};
use super::observer::Observer;
use super::state::State;
use super::yarn_damping::{step_reduction, yarn_damping_resultant};
use crate::contact::penalty::{self, Nodes};
use crate::contact::ply_contact::PlyNodes;
use crate::element::Bending;
use crate::material::{MaterialError, MembraneKinematics, StepModuli};
use crate::support::SupportsAt;
use nalgebra::Vector3;
use rayon::prelude::*;

/// How to integrate.
#[derive(Clone, Debug, PartialEq)]
pub struct SolverSettings {
    /// Simulated duration (s).
    pub end_time: f64,
    /// Fraction of the critical step actually taken.
    pub time_step_safety: f64,
    /// Mass scaling: elements whose stable step is below this get extra density so that it
    /// reaches it (s). `None`: physical mass.
    pub target_time_step: Option<f64>,
    /// Simulated time between two calls of [`Observer::record`] (s).
    pub output_interval: f64,
    /// Global mass-proportional damping `c` (1/s): a force `-c m v` on every free node. It
    /// damps the slow ringing of soft, mass-scaled sheets in quasi-static runs; what it removes
    /// is booked in [`Energies::damping`]. Zero: none.
    pub damping: f64,
    /// Linear viscosity on the yarn strain rates, as a fraction of critical damping of the
    /// element's highest yarn mode (see [`super::yarn_damping`]); 0.06 is a good default, as
    /// for the linear bulk viscosity of explicit codes. Zero: none.
    pub yarn_damping: f64,
}

/// What the element loop returns per element.
#[derive(Clone, Copy, Debug, Default)]
struct ElementResult {
    forces: [Vector3<f64>; 4],
    stable_step: f64,
    /// Power taken by the yarn-rate damping (N·mm/s).
    damping_power: f64,
}

/// Elements (or bending patches) around each node, for a race-free parallel gather of nodal
/// forces: entries `(item, place of the node in the item)`.
struct NodeElements {
    start: Vec<usize>,
    entries: Vec<(usize, usize)>,
}

impl NodeElements {
    /// From the node lists of the items on `nodes` nodes.
    fn new<'a>(nodes: usize, items: impl Iterator<Item = &'a [usize]> + Clone) -> Self {
        let mut count = vec![0usize; nodes + 1];
        for item in items.clone() {
            for &n in item {
                count[n + 1] += 1;
            }
        }
        for i in 1..count.len() {
            count[i] += count[i - 1];
        }
        let mut fill = count.clone();
        let mut entries = vec![(0, 0); count[count.len() - 1]];
        for (k, item) in items.enumerate() {
            for (local, &n) in item.iter().enumerate() {
                entries[fill[n]] = (k, local);
                fill[n] += 1;
            }
        }
        Self {
            start: count,
            entries,
        }
    }

    fn of(&self, node: usize) -> &[(usize, usize)] {
        &self.entries[self.start[node]..self.start[node + 1]]
    }
}

/// What step `n` needs from step `n - 1` for the trapezoidal work sums.
struct PreviousStep {
    forces: Vec<Vector3<f64>>,
    /// Contact forces of the tools on the nodes.
    contact: Vec<Vector3<f64>>,
    /// Contact forces of the neighbouring plies on the nodes.
    interply: Vec<Vector3<f64>>,
    /// Forces of gravity, the springs and the grippers on the nodes.
    support: Vec<Vector3<f64>>,
    reactions: Vec<Vector3<f64>>,
    /// `x_n - x_{n-1}`.
    increments: Vec<Vector3<f64>>,
    /// `dt_{n-1/2}`.
    time_step: f64,
}

/// Runs the explicit solver with the checks watching every record; returns the outcome and the
/// report.
/// A stop by a check is a [`SolverError::Check`].
pub fn run_checked(
    model: &Model,
    settings: &SolverSettings,
    check: CheckSettings,
    observer: &mut dyn Observer,
) -> (Result<State, SolverError>, CheckReport) {
    checks::watched(model, check, observer, |watched| {
        run(model, settings, watched)
    })
}

/// Integrates `model` to `settings.end_time`, reporting to `observer`. On an instability the
/// observer has already received everything recorded so far.
pub fn run(
    model: &Model,
    settings: &SolverSettings,
    observer: &mut dyn Observer,
) -> Result<State, SolverError> {
    check_settings(settings)?;
    let mut forces = InternalForces::new(model);
    let prescribed = prescribed_motion(model);
    let mut state = initial_state(model, settings)?;
    heat::start(model, &mut state)?;
    let mut heat_pending = 0.0;
    let zeros = vec![Vector3::zeros(); model.mesh.nodes.len()];
    let mut ply_contact = model.ply_contact(EXPLICIT_PLY_MARGIN);
    let mut previous = PreviousStep {
        forces: zeros.clone(),
        contact: zeros.clone(),
        interply: zeros.clone(),
        support: zeros.clone(),
        reactions: zeros.clone(),
        increments: zeros,
        time_step: 0.0,
    };
    let mut next_output = 0.0;
    let mut runaway_steps = 0;
    let physical_masses = model.physical_nodal_masses();
    let support_step = model.supports.stable_step(&state.masses);
    loop {
        let (stable_step, damping_power) =
            forces.evaluate(model, &mut state, previous.time_step, settings.yarn_damping)?;
        let full_step = settings.time_step_safety * stable_step.min(support_step);
        let dt = full_step.min(settings.end_time - state.time);
        if !model.tools.is_empty() {
            // the penalty follows the full step: a last step cut short to reach the end time
            // would otherwise stiffen it without bound
            tool_contact(model, &mut state, full_step);
        }
        support_loads(model, &mut state, &physical_masses);
        if let Some(plies) = &mut ply_contact {
            plies.set_frictions(&state.interface_frictions);
            let nodes = PlyNodes {
                positions: &state.positions,
                velocities: &state.velocities,
                masses: &state.masses,
            };
            plies.evaluate(nodes, full_step, &mut state.interply);
        }
        let last = state.time >= settings.end_time;
        let stop = observer.interrupted();
        if last || stop || state.time >= next_output - 1e-9 * settings.output_interval {
            state.energies.elastic = state
                .elastic_energy(model)
                .map_err(|(element, e)| unstable(&state, element, e.to_string()))?;
            observer
                .record(model, &state)
                .and_then(|()| observer.checkpoint(model, &state))
                .map_err(|source| SolverError::Output {
                    time: state.time,
                    source,
                })?;
            next_output += settings.output_interval;
        }
        if stop {
            return Err(SolverError::Interrupted {
                step: state.step,
                time: state.time,
            });
        }
        if last {
            return Ok(state);
        }
        heat_pending += dt;
        if heat_is_due(model, heat_pending, state.time + dt >= settings.end_time) {
            heat::advance(model, &mut state, heat_pending)?;
            heat_pending = 0.0;
        }
        state.energies.numerical_damping += damping_power * dt;
        advance(
            model,
            &prescribed,
            &mut state,
            (dt, settings.damping),
            &mut previous,
        );
        for (impulse, load) in state.tool_impulses.iter_mut().zip(&state.tool_loads) {
            *impulse += load.force * dt;
        }
        let supports = &mut state.supports;
        model
            .supports
            .release(state.time + dt, &supports.loads, &mut supports.released);
        if let Some(node) = state
            .positions
            .iter()
            .position(|x| !x.iter().all(|c| c.is_finite()))
        {
            let element = forces.adjacency.of(node).first().map_or(0, |&(e, _)| e);
            return Err(unstable(
                &state,
                element,
                format!("node {node} has a non-finite position"),
            ));
        }
        runaway_steps = if energy_runs_away(&state.energies) {
            runaway_steps + 1
        } else {
            0
        };
        if runaway_steps > RUNAWAY_STEPS {
            let element = fastest_element(model, &state);
            let reason = format!(
                "energy is being created: W_ext - W_int - E_kin - W_damp = {:.4e} N·mm (this \
                 element holds the fastest node; the time step may be too large for the material)",
                state.energies.balance()
            );
            return Err(unstable(&state, element, reason));
        }
        state.time_step = dt;
        state.time = if dt == settings.end_time - state.time {
            settings.end_time
        } else {
            state.time + dt
        };
        state.step += 1;
        if state.step.is_multiple_of(200) {
            observer.progress(&state);
        }
    }
}

/// Whether the heat equation is advanced now, `pending` seconds of the solver's time after it
/// last was: every step would cost more than the mechanics' step, so the contacts are sampled
/// once per [`crate::thermal::blank::HeatSettings::time_step`] of process time, and at the end.
fn heat_is_due(model: &Model, pending: f64, at_end: bool) -> bool {
    model
        .heat
        .as_ref()
        .is_some_and(|heat| at_end || pending * heat.time_scaling >= heat.blank.settings.time_step)
}

/// Step `n -> n+1` of every node: velocity (free, or prescribed at `t_{n+1/2}`), reaction,
/// kinetic energy at `t_n` and the work sums up to `t_n`, then the position.
fn advance(
    model: &Model,
    prescribed: &[Option<&Motion>],
    state: &mut State,
    (dt, damping): (f64, f64),
    previous: &mut PreviousStep,
) {
    let dt_mean = 0.5 * (previous.time_step + dt);
    let t_half = state.time + 0.5 * dt;
    let (mut kinetic, mut internal, mut external, mut damping_work) = (0.0, 0.0, 0.0, 0.0);
    let (mut tool, mut interply, mut support) = (0.0, 0.0, 0.0);
    // m (v_new - v_old)/dt + c m (v_new + v_old)/2 + f = 0, solved for v_new
    let half_damp = 0.5 * damping * dt_mean;
    for (a, motion) in prescribed.iter().enumerate() {
        let m = state.masses[a];
        let f_int = state.internal_forces[a];
        let f_contact = state.contacts[a].force;
        let f_ply = state.interply.get(a).map_or(Vector3::zeros(), |c| c.force);
        let f_support = state
            .supports
            .loads
            .forces
            .get(a)
            .copied()
            .unwrap_or_else(Vector3::zeros);
        let f = f_int - f_contact - f_ply - f_support;
        let v_old = state.velocities[a];
        let free = (v_old * (1.0 - half_damp) - f * (dt_mean / m)) / (1.0 + half_damp);
        let held = held_components(*motion);
        let v_new = match motion {
            Some(Motion::Velocity(field)) => field(t_half, &model.mesh.nodes[a]),
            _ => free.zip_map(&held, |v, h| if h { 0.0 } else { v }),
        };
        // The force the support puts on the node along the held directions.
        let reaction =
            (f + (v_new - v_old) * (m / dt_mean)).zip_map(&held, |r, h| if h { r } else { 0.0 });
        let v_mid = 0.5 * (v_old + v_new);
        kinetic += 0.5 * m * v_mid.norm_squared();
        let damped: f64 = v_mid
            .iter()
            .zip(&held)
            .filter(|(_, &h)| !h)
            .map(|(v, _)| v * v)
            .sum();
        damping_work += damping * m * damped * dt_mean;
        internal += 0.5 * (previous.forces[a] + f_int).dot(&previous.increments[a]);
        external += 0.5 * (previous.reactions[a] + reaction).dot(&previous.increments[a]);
        tool += 0.5 * (previous.contact[a] + f_contact).dot(&previous.increments[a]);
        interply += 0.5 * (previous.interply[a] + f_ply).dot(&previous.increments[a]);
        support += 0.5 * (previous.support[a] + f_support).dot(&previous.increments[a]);
        let increment = v_new * dt;
        state.velocities[a] = v_new;
        state.reactions[a] = reaction;
        state.positions[a] += increment;
        previous.forces[a] = f_int;
        previous.contact[a] = f_contact;
        previous.interply[a] = f_ply;
        previous.support[a] = f_support;
        previous.reactions[a] = reaction;
        previous.increments[a] = increment;
    }
    previous.time_step = dt;
    for (k, tool) in model.tools.iter().enumerate() {
        let (last, load) = (state.tool_velocities[k], &state.tool_loads[k]);
        state.tool_velocities[k] = tool.velocity(t_half, dt, last, load);
        state.tool_translations[k] += state.tool_velocities[k] * dt;
    }
    state.energies.kinetic = kinetic;
    state.energies.internal_work += internal;
    state.energies.external_work += external + tool + support;
    state.energies.tool_work += tool;
    state.energies.support_work += support;
    state.energies.interply_work += interply;
    state.energies.damping += damping_work;
}

/// The forces of gravity, the springs and the grippers on every node now (`support`), gravity
/// on the `physical` masses.
fn support_loads(model: &Model, state: &mut State, physical: &[f64]) {
    if model.supports.is_empty() {
        return;
    }
    let at = SupportsAt {
        translations: &state.tool_translations,
        released: &state.supports.released,
    };
    state.supports.loads = model.supports.loads(&state.positions, physical, at);
}

/// Contact forces of the tools on every node for the step `dt` about to be taken
/// (`contact::penalty`), and the loads on the tools.
fn tool_contact(model: &Model, state: &mut State, dt: f64) {
    let velocities: Vec<Vector3<f64>> = model
        .tools
        .iter()
        .enumerate()
        .map(|(k, t)| {
            let (last, load) = (state.tool_velocities[k], &state.tool_loads[k]);
            t.velocity(state.time + 0.5 * dt, dt, last, load)
        })
        .collect();
    let nodes = Nodes {
        positions: &state.positions,
        velocities: &state.velocities,
        masses: &state.masses,
    };
    state.tool_loads = penalty::evaluate(
        &model.tools,
        (&state.tool_translations, &velocities),
        nodes,
        dt,
        &model.tool_contacts(),
        &mut state.contacts,
    );
}

/// `f_int` at each node: the sum of its elements' and hinges' contributions, gathered node by
/// node so that threads never write to the same place.
fn gather_forces(forces: &InternalForces, nodal: &mut [Vector3<f64>]) {
    nodal.par_iter_mut().enumerate().for_each(|(node, f)| {
        let membrane: Vector3<f64> = forces
            .adjacency
            .of(node)
            .iter()
            .map(|&(e, local)| forces.results[e].forces[local])
            .sum();
        let bending: Vector3<f64> = forces
            .patch_adjacency
            .of(node)
            .iter()
            .map(|&(t, local)| forces.patch_forces[forces.patch_offsets[t] + local])
            .sum();
        *f = membrane + bending;
    });
}

/// An explicit run that goes unstable creates energy from nothing: the balance error grows
/// past the energy the machine put in. A stable run stays within a few per cent of it.
fn energy_runs_away(e: &Energies) -> bool {
    let scale = e.external_work.abs().max(e.internal_work.abs());
    scale > 0.0 && e.balance().abs() > RUNAWAY_BALANCE * scale + 1e-12
}

/// Energy balance error (fraction of the work put in) taken as a blow-up.
const RUNAWAY_BALANCE: f64 = 0.5;

/// The Verlet margin of the ply–ply contact's lists, in mean cell sizes **(choice)**: a step
/// moves a node far less than a cell, and the lists are made again once one moved half of it.
const EXPLICIT_PLY_MARGIN: f64 = 0.5;

/// Consecutive steps the balance must stay off before the run is stopped: in the first steps
/// the energies are tiny and the half-step offset of leapfrog velocities alone (kinetic energy
/// of the prescribed nodes at `t_0` taken from `v_{1/2}`) is of their size; a blow-up persists.
const RUNAWAY_STEPS: usize = 100;

/// The element around the node that moves fastest: where a blow-up starts.
fn fastest_element(model: &Model, state: &State) -> usize {
    let node = (0..state.velocities.len())
        .max_by(|&a, &b| {
            state.velocities[a]
                .norm()
                .total_cmp(&state.velocities[b].norm())
        })
        .unwrap_or(0);
    model
        .elements
        .iter()
        .position(|e| e.nodes().contains(&node))
        .unwrap_or(0)
}

fn check_settings(s: &SolverSettings) -> Result<(), SolverError> {
    let positive = positive_setting;
    positive("end time", s.end_time)?;
    positive("output interval", s.output_interval)?;
    positive("time-step safety factor", s.time_step_safety)?;
    if s.time_step_safety > 1.0 {
        return Err(SolverError::Settings(format!(
            "time-step safety factor {} must not exceed 1",
            s.time_step_safety
        )));
    }
    if let Some(target) = s.target_time_step {
        positive("target time step", target)?;
    }
    if !(s.yarn_damping.is_finite() && (0.0..1.0).contains(&s.yarn_damping)) {
        return Err(SolverError::Settings(format!(
            "yarn damping = {} must be in [0, 1)",
            s.yarn_damping
        )));
    }
    if !(s.damping.is_finite() && s.damping >= 0.0) {
        return Err(SolverError::Settings(format!(
            "damping = {} must be >= 0",
            s.damping
        )));
    }
    Ok(())
}

fn unstable(state: &State, element: usize, reason: String) -> SolverError {
    SolverError::Unstable {
        step: state.step,
        time: state.time,
        element,
        reason,
        kinetic: state.energies.kinetic,
        internal: state.energies.internal_work,
        external: state.energies.external_work,
    }
}

/// Which velocity components of a node the solver does not integrate: none of a free node's,
/// all of a fixed or driven node's, the marked ones of a partly held node.
fn held_components(motion: Option<&Motion>) -> Vector3<bool> {
    match motion {
        None => Vector3::repeat(false),
        Some(Motion::Fixed | Motion::Velocity(_)) => Vector3::repeat(true),
        Some(Motion::Components(held)) => Vector3::from(*held),
    }
}

/// Per node: `None` when free, else the constraint's motion.
fn prescribed_motion(model: &Model) -> Vec<Option<&Motion>> {
    let mut motion = vec![None; model.mesh.nodes.len()];
    for c in &model.constraints {
        for &n in &c.nodes {
            motion[n] = Some(&c.motion);
        }
    }
    motion
}

/// The internal-force pass of every step: the element loop (in parallel) and the race-free
/// gather of nodal forces. Public for benchmarks and tools that need forces at a given state.
pub struct InternalForces {
    adjacency: NodeElements,
    results: Vec<ElementResult>,
    patch_adjacency: NodeElements,
    /// Bending forces of every patch node, patch after patch, from `patch_offsets`.
    patch_forces: Vec<Vector3<f64>>,
    patch_offsets: Vec<usize>,
}

impl InternalForces {
    pub fn new(model: &Model) -> Self {
        let nodes = model.mesh.nodes.len();
        let patches = model.bending.as_ref().map_or(&[][..], |b| &b.patches[..]);
        let mut patch_offsets = vec![0];
        for t in patches {
            patch_offsets.push(patch_offsets[patch_offsets.len() - 1] + t.nodes.len());
        }
        Self {
            adjacency: NodeElements::new(nodes, model.elements.iter().map(|e| e.nodes())),
            results: vec![ElementResult::default(); model.elements.len()],
            patch_adjacency: NodeElements::new(nodes, patches.iter().map(|t| &t.nodes[..])),
            patch_forces: vec![Vector3::zeros(); patch_offsets[patch_offsets.len() - 1]],
            patch_offsets,
        }
    }

    /// Fills `state.internal_forces` and `state.membrane` at the current positions and
    /// velocities; `dt` is the step that led here, `yarn_damping` as in [`SolverSettings`].
    /// Returns the stable step and the power taken by the yarn-rate damping.
    pub fn evaluate(
        &mut self,
        model: &Model,
        state: &mut State,
        dt: f64,
        yarn_damping: f64,
    ) -> Result<(f64, f64), SolverError> {
        let (membrane_step, power) =
            element_loop(model, state, &mut self.results, (dt, yarn_damping))
                .map_err(|(element, e)| unstable(state, element, e.to_string()))?;
        let bending_step = match &model.bending {
            Some(bending) => bending_loop(
                model,
                bending,
                state,
                &mut self.patch_forces,
                &self.patch_offsets,
            ),
            None => f64::INFINITY,
        };
        gather_forces(self, &mut state.internal_forces);
        Ok((membrane_step.min(bending_step), power))
    }
}

/// Bending forces of every patch at the current positions (in parallel), and the smallest
/// stable step of the bending modes on the current element densities.
fn bending_loop(
    model: &Model,
    bending: &Bending,
    state: &State,
    forces: &mut [Vector3<f64>],
    offsets: &[usize],
) -> f64 {
    split_at_offsets(forces, offsets)
        .into_par_iter()
        .zip(bending.patches.par_iter())
        .zip(state.densities.par_iter())
        .enumerate()
        .map(|(k, ((f, t), rho))| {
            let b = state.bending_rigidity(t, k);
            bending.forces_with(t, b, &state.positions, f);
            bending.stable_step_with(t, b, rho * model.thickness(k))
        })
        .reduce(|| f64::INFINITY, f64::min)
}

/// `forces` cut into the consecutive pieces that `offsets` (starts, and the end) delimit.
fn split_at_offsets<'a>(
    mut forces: &'a mut [Vector3<f64>],
    offsets: &[usize],
) -> Vec<&'a mut [Vector3<f64>]> {
    offsets
        .windows(2)
        .map(|w| {
            let (piece, rest) = std::mem::take(&mut forces).split_at_mut(w[1] - w[0]);
            forces = rest;
            piece
        })
        .collect()
}

/// Stable step of the bending modes of each triangle on its density.
fn bending_steps(model: &Model, bending: &Bending, densities: &[f64]) -> Vec<f64> {
    bending
        .patches
        .iter()
        .zip(densities)
        .enumerate()
        .map(|(k, (t, rho))| bending.stable_step(t, rho * model.thickness(k)))
        .collect()
}

/// The rest state of an explicit run: lumped masses, and mass scaling from the stable step at
/// rest.
pub fn initial_state(model: &Model, settings: &SolverSettings) -> Result<State, SolverError> {
    let n_nodes = model.mesh.nodes.len();
    let mut densities: Vec<f64> = (0..model.elements.len())
        .map(|k| model.density(k))
        .collect();
    let mut added_mass = 0.0;
    let mut steps = Vec::with_capacity(model.elements.len());
    for (k, e) in model.elements.iter().enumerate() {
        let laminate = model.laminate(k);
        let kin = model.rest_kinematics(k);
        let modulus = laminate
            .wave_modulus(&kin, &laminate.initial_state())
            .map_err(|err| SolverError::Settings(format!("element {k}: {err}")))?;
        steps.push(e.altitude * (model.density(k) / modulus).sqrt());
    }
    if let Some(bending) = &model.bending {
        for (step, bending_step) in steps
            .iter_mut()
            .zip(bending_steps(model, bending, &densities))
        {
            *step = step.min(bending_step);
        }
    }
    for ((k, e), &step) in model.elements.iter().enumerate().zip(&steps) {
        if let Some(target) = settings.target_time_step {
            if step < target {
                densities[k] = model.density(k) * (target / step).powi(2);
                added_mass += (densities[k] - model.density(k)) * model.thickness(k) * e.area;
            }
        }
    }
    let mut masses = vec![0.0; n_nodes];
    for (k, (e, rho)) in model.elements.iter().zip(&densities).enumerate() {
        let share = rho * model.thickness(k) * e.area / e.nodes().len() as f64;
        for &n in e.nodes() {
            masses[n] += share;
        }
    }
    Ok(State::undeformed(model, masses, densities, added_mass))
}

/// Membrane forces of every element at the current positions (in parallel), the stable step
/// they allow and the power of the yarn-rate damping `xi`. `dt` is the duration of the step
/// that led here (for the thickness rate). The elements go in chunks of [`CHUNK`], each summed
/// in order and the chunks' sums added in order, so the power is the same on any thread
/// count; a failure is that of the lowest-numbered failing element.
fn element_loop(
    model: &Model,
    state: &mut State,
    results: &mut [ElementResult],
    (dt, xi): (f64, f64),
) -> Result<(f64, f64), (usize, MaterialError)> {
    let positions = &state.positions;
    let velocities = &state.velocities;
    let densities = &state.densities;
    let temperatures = &state.temperatures;
    let chunks: Vec<Result<(f64, f64), (usize, MaterialError)>> = results
        .par_chunks_mut(CHUNK)
        .zip(state.laminate_states.par_chunks_mut(CHUNK))
        .zip(state.membrane.par_chunks_mut(CHUNK))
        .enumerate()
        .map(|(c, ((results, lam_states), membranes))| {
            let mut chunk = (f64::INFINITY, 0.0);
            let items = results.iter_mut().zip(lam_states).zip(membranes);
            for (i, ((result, lam_state), membrane)) in items.enumerate() {
                let k = c * CHUNK + i;
                let e = &model.elements[k];
                let ply = model.ply_of(k);
                let (laminate, thickness) = (&ply.laminate, ply.laminate.reference_thickness());
                let f = e.gradient(positions);
                let f_dot = e.gradient(velocities);
                let temperature = model.element_temperature(temperatures, k);
                let kin = MembraneKinematics::from_deformation(&f, &f_dot, temperature, e.fibres);
                let response = laminate
                    .membrane_response(&kin, dt, lam_state)
                    .map_err(|err| (k, err))?;
                let StepModuli {
                    wave: modulus,
                    viscous: viscosity,
                } = laminate
                    .step_moduli(&kin, lam_state)
                    .map_err(|err| (k, err))?;
                *membrane = response;
                let element_step = e.altitude * (densities[k] / modulus).sqrt();
                let (n_damping, power) =
                    yarn_damping_resultant(&kin, xi, element_step, modulus, thickness);
                result.forces = e.internal_forces(&f, &(response.n + n_damping));
                e.hourglass_forces(positions, &f, &ply.hourglass, &mut result.forces);
                let xi_total = xi + material_damping_ratio(viscosity, modulus, element_step);
                result.stable_step = element_step * step_reduction(xi_total);
                result.damping_power = power * e.area;
                chunk = (
                    chunk.0.min(result.stable_step),
                    chunk.1 + result.damping_power,
                );
            }
            Ok(chunk)
        })
        .collect();
    chunks
        .into_iter()
        .try_fold((f64::INFINITY, 0.0), |(step, power), chunk| {
            let (chunk_step, chunk_power) = chunk?;
            Ok((step.min(chunk_step), power + chunk_power))
        })
}

/// Elements per chunk of the parallel sums: fixed, so that where the partial sums start does
/// not depend on the thread count (results bit for bit the same on any number of threads),
/// and large enough that the per-chunk bookkeeping costs nothing against the element work.
const CHUNK: usize = 256;

/// Fraction of critical damping that a material viscosity `eta` (MPa·s) gives the highest mode
/// of an element, `omega = 2 / dt_e`: `xi = eta omega / (2 E) = eta / (E dt_e)`. Heavily
/// viscous melts on fine meshes are limited by it, not by the wave speed.
fn material_damping_ratio(eta: f64, modulus: f64, element_step: f64) -> f64 {
    eta / (modulus * element_step)
}
