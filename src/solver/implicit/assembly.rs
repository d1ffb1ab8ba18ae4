//! The residual and tangent of the incremental problem at a trial configuration
//! (docs/solver.md, "Implicit"): membrane, hourglass and bending forces of the sheet, contact
//! and friction with the tools, the stabilising drag, assembled over the unknowns of the node
//! positions and of the force-driven tools' travel.
//!
//! Elements and patches are evaluated in parallel in chunks of fixed size and their entries
//! added in element order, so the sums do not depend on the thread count.

use super::linear::Pattern;
use crate::contact::potential::{pair_contact, FrictionLag, PairContact};
use crate::contact::{NodeContact, ToolLoad, ToolMotion};
use crate::material::laminate::BackwardEulerStep;
use crate::material::{LaminateState, MaterialError, MembraneResponse};
use crate::solver::model::{Model, Motion};
use nalgebra::{DMatrix, Matrix2, Matrix3, SymmetricEigen, Vector3};
use rayon::prelude::*;

/// Elements (or patches) per parallel chunk; fixed, so that sums do not depend on the threads.
const CHUNK: usize = 256;

/// What stays the same over a run: the unknowns, what is held, the pattern, the springs.
pub struct Layout {
    pub nodes: usize,
    /// Unknowns: three per node, then one per force-driven tool.
    pub size: usize,
    /// Per unknown: held by a constraint (its value prescribed).
    pub held: Vec<bool>,
    /// The unknown of each tool's travel along its force, if force-driven.
    pub tool_unknown: Vec<Option<usize>>,
    /// Unit axis and magnitude of each force-driven tool's force.
    pub tool_force: Vec<Option<(Vector3<f64>, f64)>>,
    pub pattern: Pattern,
    /// Contact spring of each node (N/mm).
    pub penalty: Vec<f64>,
    /// Stabilising drag of each node (N/mm over the increment's travel).
    pub drag: Vec<f64>,
    /// Drag of each force-driven tool's travel (N/mm).
    pub tool_drag: f64,
    /// Force below which a residual is converged whatever the forces at play (N), set by the
    /// solver.
    pub force_floor: f64,
    /// The mean element size (mm), the scale of a Newton correction at the rounding of the
    /// positions; set by the solver.
    pub length_scale: f64,
    /// Where each element's and each bending patch's entries are stored.
    elements: Vec<Scatter>,
    patches: Vec<Scatter>,
    /// Where each node's own 3x3 block is stored (contact, drag).
    diagonal: Vec<Scatter>,
}

impl Layout {
    pub fn new(model: &Model, penalty: Vec<f64>, drag: Vec<f64>) -> Self {
        let nodes = model.mesh.nodes.len();
        let mut tool_unknown = Vec::new();
        let mut tool_force = Vec::new();
        let mut size = 3 * nodes;
        for tool in &model.tools {
            match &tool.motion {
                ToolMotion::Force { force, .. } => {
                    tool_unknown.push(Some(size));
                    tool_force.push(Some((force.normalize(), force.norm())));
                    size += 1;
                }
                _ => {
                    tool_unknown.push(None);
                    tool_force.push(None);
                }
            }
        }
        let mut held = vec![false; size];
        for c in &model.constraints {
            let mask = match c.motion {
                Motion::Fixed | Motion::Velocity(_) => [true; 3],
                Motion::Components(m) => m,
            };
            for &n in &c.nodes {
                for d in 0..3 {
                    held[3 * n + d] |= mask[d];
                }
            }
        }
        let dofs = |nodes: &[usize]| -> Vec<usize> {
            nodes
                .iter()
                .flat_map(|&n| [3 * n, 3 * n + 1, 3 * n + 2])
                .collect()
        };
        let element_nodes: Vec<Vec<usize>> =
            model.elements.iter().map(|e| e.nodes().to_vec()).collect();
        let patch_nodes: Vec<Vec<usize>> = model.bending.as_ref().map_or(Vec::new(), |b| {
            b.patches.iter().map(|p| p.nodes.clone()).collect()
        });
        let mut groups: Vec<Vec<usize>> = element_nodes
            .iter()
            .chain(&patch_nodes)
            .map(|n| dofs(n))
            .collect();
        for unknown in tool_unknown.iter().flatten() {
            for n in 0..nodes {
                groups.push(vec![3 * n, 3 * n + 1, 3 * n + 2, *unknown]);
            }
        }
        let pattern = Pattern::from_groups(size, groups.iter().map(|g| &g[..]));
        let scatter = |nodes: &Vec<usize>| Scatter::new(&pattern, &held, nodes);
        let elements = element_nodes.iter().map(scatter).collect();
        let patches = patch_nodes.iter().map(scatter).collect();
        let diagonal = (0..nodes).map(|n| scatter(&vec![n])).collect();
        let tool_drag = 1e-9 * penalty.iter().sum::<f64>();
        Self {
            nodes,
            size,
            held,
            tool_unknown,
            tool_force,
            pattern,
            penalty,
            drag,
            tool_drag,
            force_floor: 0.0,
            length_scale: 0.0,
            elements,
            patches,
            diagonal,
        }
    }
}

/// The start of the increment: what the trial configuration is measured from.
pub struct IncrementStart<'a> {
    pub positions: &'a [Vector3<f64>],
    /// `C` of every element at the start.
    pub strains: &'a [Matrix2<f64>],
    pub laminate_states: &'a [LaminateState],
    /// Friction of each node on each tool (`[node][tool]`).
    pub friction: &'a [Vec<Option<FrictionLag>>],
    pub dt: f64,
}

/// How the tangent is formed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tangent {
    /// No tangent: the residual only (line search).
    None,
    /// The consistent tangent; bending, hourglass and contact exact or by their
    /// Gauss–Newton parts as set in [`Evaluator::exact`].
    Consistent,
    /// Every element's tangent made positive semi-definite (the material tangent's and the
    /// membrane resultant's negative eigenvalues set to zero, the Gauss–Newton parts of
    /// hourglass, bending and contact): a descent direction wherever the sheet buckles.
    Projected,
}

/// A trial configuration: node positions and each tool's translation, and where Newton's
/// method has frozen the contact set, which node–tool springs act (`[node][tool]`).
pub struct Trial<'a> {
    pub positions: &'a [Vector3<f64>],
    pub translations: &'a [Vector3<f64>],
    pub engaged: Option<&'a [Vec<bool>]>,
}

/// Everything evaluated at a trial configuration.
pub struct Evaluation {
    /// `dPi/dz` for every unknown (held ones included: there it is the reaction).
    pub residual: Vec<f64>,
    /// Lower triangle of the tangent on the layout's pattern (held rows and columns replaced
    /// by the identity), when asked for.
    pub matrix: Option<Vec<f64>>,
    /// Membrane, hourglass and bending forces per node (N).
    pub internal: Vec<Vector3<f64>>,
    pub responses: Vec<MembraneResponse>,
    pub states: Vec<LaminateState>,
    pub contacts: Vec<NodeContact>,
    pub loads: Vec<ToolLoad>,
    /// Work of the stabilising drag over the increment so far, `sum c |x - x_n|^2` (N·mm).
    pub drag_work: f64,
    /// The incremental potential `Pi` (N·mm) whose gradient is the residual.
    pub potential: f64,
    /// Node–tool pairs with the node behind the tool beyond the contact's reach.
    pub tunnelled: usize,
}

/// Evaluates the residual and tangent of a model.
pub struct Evaluator<'a> {
    pub model: &'a Model,
    pub layout: &'a Layout,
    /// The exact tangents of bending, hourglass and contact (the moments times the
    /// curvature's second derivative, the turn of the yarns and normal, the turn of the tool's
    /// normal over its edges), instead of their Gauss–Newton parts (which the projected
    /// tangent always takes).
    pub exact: bool,
    /// Regularising sliding speed of friction (mm/s): the slip `eps` of an increment is it
    /// times the increment's duration.
    pub slip_rate: f64,
}

/// One bending patch's forces on its nodes, its stiffness when asked for, and its energy.
type PatchShare = (Vec<Vector3<f64>>, Option<DMatrix<f64>>, f64);

/// One element's share.
struct ElementShare {
    forces: [Vector3<f64>; 4],
    potential: f64,
    stiffness: Option<[[Matrix3<f64>; 4]; 4]>,
    response: MembraneResponse,
    state: LaminateState,
}

impl Evaluator<'_> {
    pub fn evaluate(
        &self,
        start: &IncrementStart,
        trial: &Trial,
        tangent: Tangent,
    ) -> Result<Evaluation, (usize, MaterialError)> {
        let model = self.model;
        let layout = self.layout;
        let mut residual = vec![0.0; layout.size];
        let mut matrix = (tangent != Tangent::None).then(|| vec![0.0; layout.pattern.entries()]);
        let mut internal = vec![Vector3::zeros(); layout.nodes];
        let mut potential = 0.0;
        let mut responses = Vec::with_capacity(model.elements.len());
        let mut states = Vec::with_capacity(model.elements.len());
        for (c, chunk) in model.elements.chunks(CHUNK).enumerate() {
            let shares: Vec<Result<ElementShare, (usize, MaterialError)>> = chunk
                .par_iter()
                .enumerate()
                .map(|(i, _)| {
                    let k = c * CHUNK + i;
                    self.element(k, start, trial.positions, tangent)
                        .map_err(|e| (k, e))
                })
                .collect();
            for (i, share) in shares.into_iter().enumerate() {
                let share = share?;
                potential += share.potential;
                let scatter = &layout.elements[c * CHUNK + i];
                for (a, &n) in scatter.nodes.iter().enumerate() {
                    internal[n] += share.forces[a];
                }
                if let (Some(values), Some(k)) = (matrix.as_mut(), &share.stiffness) {
                    scatter.add(&layout.held, values, |a, b| k[a][b]);
                }
                responses.push(share.response);
                states.push(share.state);
            }
        }
        if let Some(bending) = &model.bending {
            let exact = self.exact;
            for (c, chunk) in bending.patches.chunks(CHUNK).enumerate() {
                let shares: Vec<PatchShare> = chunk
                    .par_iter()
                    .map(|patch| {
                        let mut f = vec![Vector3::zeros(); patch.nodes.len()];
                        let energy = bending.forces(patch, trial.positions, &mut f);
                        let k = (tangent != Tangent::None).then(|| {
                            bending.stiffness(
                                patch,
                                trial.positions,
                                exact && tangent == Tangent::Consistent,
                            )
                        });
                        (f, k, energy)
                    })
                    .collect();
                for (i, (f, k, energy)) in shares.into_iter().enumerate() {
                    potential += energy;
                    let scatter = &layout.patches[c * CHUNK + i];
                    for (a, &n) in scatter.nodes.iter().enumerate() {
                        internal[n] += f[a];
                    }
                    if let (Some(values), Some(k)) = (matrix.as_mut(), k) {
                        scatter.add(&layout.held, values, |a, b| {
                            k.fixed_view::<3, 3>(3 * a, 3 * b).into_owned()
                        });
                    }
                }
            }
        }
        for (n, f) in internal.iter().enumerate() {
            for d in 0..3 {
                residual[3 * n + d] += f[d];
            }
        }
        let (contacts, loads, contact_energy, tunnelled) =
            self.contact(start, trial, tangent, &mut residual, matrix.as_mut());
        potential += contact_energy;
        let mut drag_work = 0.0;
        for n in 0..layout.nodes {
            let travel = trial.positions[n] - start.positions[n];
            let c = layout.drag[n];
            drag_work += c * travel.norm_squared();
            potential += 0.5 * c * travel.norm_squared();
            for d in 0..3 {
                residual[3 * n + d] += c * travel[d];
            }
            if let Some(values) = matrix.as_mut() {
                layout.diagonal[n].add(&layout.held, values, |_, _| Matrix3::identity() * c);
            }
        }
        for (k, unknown) in layout.tool_unknown.iter().enumerate() {
            if let (Some(u), Some((axis, force))) = (unknown, layout.tool_force[k]) {
                residual[*u] -= force;
                potential -= force * trial.translations[k].dot(&axis);
                if let Some(values) = matrix.as_mut() {
                    values[layout.pattern.place(*u, *u).expect("tool diagonal")] +=
                        layout.tool_drag;
                }
            }
        }
        if let Some(values) = matrix.as_mut() {
            for (i, &held) in layout.held.iter().enumerate() {
                if held {
                    values[layout.pattern.place(i, i).expect("diagonal")] = 1.0;
                }
            }
        }
        Ok(Evaluation {
            residual,
            matrix,
            internal,
            responses,
            states,
            contacts,
            loads,
            drag_work,
            potential,
            tunnelled,
        })
    }

    /// Forces and tangent of element `k`.
    fn element(
        &self,
        k: usize,
        start: &IncrementStart,
        x: &[Vector3<f64>],
        tangent: Tangent,
    ) -> Result<ElementShare, MaterialError> {
        let model = self.model;
        let e = &model.elements[k];
        let f = e.gradient(x);
        let step = BackwardEulerStep {
            c: f.transpose() * f,
            c_start: start.strains[k],
            dt: start.dt,
            temperature: model.temperature,
            fibres: e.fibres,
        };
        let laminate = &model.laminate;
        let (response, state, d) = match tangent {
            Tangent::None => {
                let mut state = start.laminate_states[k].clone();
                let r =
                    laminate.membrane_response(&step.kinematics(&step.c), step.dt, &mut state)?;
                (r, state, None)
            }
            _ => {
                let (r, state, d) = laminate.step_tangent(&step, &start.laminate_states[k])?;
                (r, state, Some(0.5 * (d + d.transpose())))
            }
        };
        let mut forces = e.internal_forces(&f, &response.n);
        let hourglass = e.hourglass_forces(x, &f, &model.hourglass, &mut forces);
        let potential = e.area
            * laminate.incremental_potential(&step.kinematics(&step.c), &state, step.dt)?
            + hourglass;
        let stiffness = d.map(|d| {
            let (d, n) = match tangent {
                Tangent::Projected => (positive_part3(&d), positive_part2(&response.n)),
                _ => (d, response.n),
            };
            let mut k = e.stiffness(&f, &n, &d);
            if e.hourglass.is_some() {
                let exact = self.exact && tangent == Tangent::Consistent;
                let h = e.hourglass_stiffness(x, &model.hourglass, exact);
                for a in 0..4 {
                    for b in 0..4 {
                        k[a][b] += h[a][b];
                    }
                }
            }
            k
        });
        Ok(ElementShare {
            forces,
            potential,
            stiffness,
            response,
            state,
        })
    }

    /// Contact and friction of every node with every tool: adds to the residual and matrix,
    /// returns each node's contact, each tool's load, the pairs' energy and how many tunnelled.
    fn contact(
        &self,
        start: &IncrementStart,
        trial: &Trial,
        tangent: Tangent,
        residual: &mut [f64],
        mut matrix: Option<&mut Vec<f64>>,
    ) -> (Vec<NodeContact>, Vec<ToolLoad>, f64, usize) {
        let model = self.model;
        let layout = self.layout;
        let tools = model.tools.len();
        let exact = self.exact && tangent == Tangent::Consistent;
        let pairs: Vec<Vec<Option<PairContact>>> = (0..layout.nodes)
            .into_par_iter()
            .map(|n| {
                (0..tools)
                    .map(|k| {
                        let y = trial.positions[n] - trial.translations[k];
                        pair_contact(
                            &model.tools[k],
                            &y,
                            layout.penalty[n],
                            &model.contact,
                            start.friction[n][k].as_ref(),
                            (
                                self.slip_rate * start.dt,
                                exact,
                                trial.engaged.map(|e| e[n][k]),
                            ),
                        )
                    })
                    .collect()
            })
            .collect();
        let mut contacts = vec![NodeContact::default(); layout.nodes];
        let mut loads = vec![ToolLoad::default(); tools];
        let mut energy = 0.0;
        let mut tunnelled = 0;
        for (n, node_pairs) in pairs.iter().enumerate() {
            let contact = &mut contacts[n];
            contact.tangential = vec![Vector3::zeros(); tools];
            contact.normal_force = vec![0.0; tools];
            contact.near = vec![Default::default(); tools];
            for (k, pair) in node_pairs.iter().enumerate() {
                let Some(pair) = pair else { continue };
                tunnelled += usize::from(pair.tunnelled);
                energy += pair.energy;
                let force = -pair.gradient;
                contact.force += force;
                contact.tangential[k] = pair.tangential;
                contact.normal_force[k] = pair.normal_force;
                if pair.normal_force > 0.0 {
                    loads[k].normal_force += pair.normal_force;
                    loads[k].stiffness += layout.penalty[n];
                    loads[k].nodes_in_contact += 1;
                }
                loads[k].force -= force;
                for d in 0..3 {
                    residual[3 * n + d] += pair.gradient[d];
                }
                let hessian = match tangent {
                    Tangent::Projected => positive_part3(&pair.hessian),
                    _ => pair.hessian,
                };
                if let Some(values) = matrix.as_deref_mut() {
                    layout.diagonal[n].add(&layout.held, values, |_, _| hessian);
                }
                if let (Some(u), Some((axis, _))) = (layout.tool_unknown[k], layout.tool_force[k]) {
                    // the pair's potential depends on y = x - u axis
                    residual[u] -= axis.dot(&pair.gradient);
                    if let Some(values) = matrix.as_deref_mut() {
                        let coupling = -(hessian * axis);
                        for d in 0..3 {
                            let i = 3 * n + d;
                            if !layout.held[i] {
                                values[layout.pattern.place(u, i).expect("tool coupling")] +=
                                    coupling[d];
                            }
                        }
                        values[layout.pattern.place(u, u).expect("tool diagonal")] +=
                            axis.dot(&(hessian * axis));
                    }
                }
            }
        }
        (contacts, loads, energy, tunnelled)
    }
}

/// Where the lower-triangle entries of the 3x3 blocks of a group of nodes (an element, a
/// patch, one node) are stored, found once: for every pair `(a, b)` of its nodes with
/// `nodes[a] >= nodes[b]`, in that order, and every column `e` of the block, the place of its
/// first stored row ([`Scatter::SKIP`] where the column is held). A binary search per column
/// and block was the largest single cost of the assembly.
struct Scatter {
    nodes: Vec<usize>,
    places: Vec<u32>,
}

impl Scatter {
    const SKIP: u32 = u32::MAX;

    fn new(pattern: &Pattern, held: &[bool], nodes: &[usize]) -> Self {
        let mut places = Vec::new();
        for &na in nodes {
            for &nb in nodes {
                if na < nb {
                    continue;
                }
                for e in 0..3 {
                    let j = 3 * nb + e;
                    let first = if na == nb { e } else { 0 };
                    let place = pattern
                        .place(3 * na + first, j)
                        .filter(|_| !held[j])
                        .map_or(Self::SKIP, |p| {
                            u32::try_from(p).expect("fewer than 4e9 tangent entries")
                        });
                    places.push(place);
                }
            }
        }
        Self {
            nodes: nodes.to_vec(),
            places,
        }
    }

    /// Adds `block(a, b)`, the 3x3 block of local nodes `(a, b)`, for every pair of the
    /// group, skipping held rows and columns.
    fn add(&self, held: &[bool], values: &mut [f64], block: impl Fn(usize, usize) -> Matrix3<f64>) {
        let mut places = self.places.iter();
        for (a, &na) in self.nodes.iter().enumerate() {
            for (b, &nb) in self.nodes.iter().enumerate() {
                if na < nb {
                    continue;
                }
                let k = block(a, b);
                for e in 0..3 {
                    let start = *places.next().expect("a place per column");
                    if start == Self::SKIP {
                        continue;
                    }
                    let first = if na == nb { e } else { 0 };
                    for d in first..3 {
                        // rows of one node are stored one after the other in a column
                        if !held[3 * na + d] {
                            values[start as usize + (d - first)] += k[(d, e)];
                        }
                    }
                }
            }
        }
    }
}

/// A symmetric 3x3 matrix with its negative eigenvalues set to zero.
fn positive_part3(m: &Matrix3<f64>) -> Matrix3<f64> {
    let eigen = SymmetricEigen::new(0.5 * (m + m.transpose()));
    let clamped = eigen.eigenvalues.map(|v| v.max(0.0));
    eigen.eigenvectors * Matrix3::from_diagonal(&clamped) * eigen.eigenvectors.transpose()
}

/// A symmetric 2x2 matrix with its negative eigenvalues set to zero.
fn positive_part2(m: &Matrix2<f64>) -> Matrix2<f64> {
    let eigen = SymmetricEigen::new(0.5 * (m + m.transpose()));
    let clamped = eigen.eigenvalues.map(|v| v.max(0.0));
    eigen.eigenvectors * Matrix2::from_diagonal(&clamped) * eigen.eigenvectors.transpose()
}
