//! The residual and tangent of the incremental problem at a trial configuration
//! (docs/solver.md, "Implicit"): membrane, hourglass and bending forces of the sheet, contact
//! and friction with the tools, the stabilising drag, assembled over the unknowns of the node
//! positions and of the force-driven tools' travel.
//!
//! Elements and patches are evaluated in parallel in chunks of fixed size and their entries
//! added in element order, so the sums do not depend on the thread count.

use super::interply::{HeldFace, Interply, PlyNodeContact};
use super::linear::{minimum_degree, nested_dissection, Pattern, Sparsified};
use super::scatter::Scatter;
use crate::contact::ply_contact::{InterplyNode, PlyContact};
use crate::contact::ply_potential::PlyLag;
use crate::contact::potential::{
    contact_margin, pair_contact, FrictionLag, PairContact, PairHessian, PairOptions,
};
use crate::contact::Projection;
use crate::contact::{NearTriangles, NodeContact, ToolLoad, ToolMotion};
use crate::element::bending::{BendingPatch, BendingRigidity};
use crate::material::laminate::BackwardEulerStep;
use crate::material::{LaminateState, LayerTemperatures, MaterialError, MembraneResponse};
use crate::solver::model::{Model, Motion};
use crate::support::{SupportLoads, SupportsAt};
use nalgebra::{DMatrix, Matrix2, Matrix3, Matrix3x2, SymmetricEigen, Vector3};
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
    /// Pairs of nodes of neighbouring plies the ply–ply contact may couple.
    couplings: Vec<Vec<usize>>,
    /// Each node's physical mass (tonne): what gravity pulls.
    pub physical_masses: Vec<f64>,
}

impl Layout {
    /// The layout of `model` with the tools' springs `penalty` and the drag `drag` per node,
    /// the ply–ply contact coupling the node pairs `couplings`.
    pub fn new(model: &Model, penalty: Vec<f64>, drag: Vec<f64>, couplings: &[[usize; 2]]) -> Self {
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
        let element_nodes: Vec<Vec<usize>> =
            model.elements.iter().map(|e| e.nodes().to_vec()).collect();
        let patch_nodes: Vec<Vec<usize>> = model.bending.as_ref().map_or(Vec::new(), |b| {
            b.patches.iter().map(|p| p.nodes.clone()).collect()
        });
        let couplings: Vec<Vec<usize>> = couplings.iter().map(|c| c.to_vec()).collect();
        let sets = [&element_nodes[..], &patch_nodes, &couplings];
        let groups = unknown_groups(nodes, &sets, &tool_unknown);
        let order = elimination_order(model, nodes, &sets, size);
        let pattern = Pattern::from_groups_in_order(size, groups.iter().map(|g| &g[..]), order);
        let scatter = |nodes: &Vec<usize>| Scatter::new(&pattern, &held, nodes);
        let elements = element_nodes.iter().map(scatter).collect();
        let patches = patch_nodes.iter().map(scatter).collect();
        let diagonal = (0..nodes).map(|n| scatter(&vec![n])).collect();
        let tool_drag = 1e-9 * penalty.iter().sum::<f64>();
        Self {
            physical_masses: model.physical_nodal_masses(),
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
            couplings,
        }
    }

    /// The tangent on the membrane's stencil of `model` (this layout's) and the ply–ply
    /// contact's couplings, the bending patches' farther couplings moved onto the diagonal: the preconditioner of the linear solves
    /// (docs/solver.md, "Conjugate gradients on the membrane's stencil"); `None` without
    /// bending patches, where the stencils are the same.
    pub fn membrane_preconditioner(&self, model: &Model) -> Option<Sparsified> {
        if self.patches.is_empty() {
            return None;
        }
        let element_nodes: Vec<Vec<usize>> =
            model.elements.iter().map(|e| e.nodes().to_vec()).collect();
        let sets = [&element_nodes[..], &self.couplings];
        let groups = unknown_groups(self.nodes, &sets, &self.tool_unknown);
        let order = elimination_order(model, self.nodes, &sets, self.size);
        let membrane =
            Pattern::from_groups_in_order(self.size, groups.iter().map(|g| &g[..]), order);
        Some(Sparsified::new(&self.pattern, membrane))
    }

    /// Adds `block(blocks[i], a, b)` of every group `groups[i]` to the tangent `values`, the
    /// stored places before [`Pattern::halfway`] on one thread and the others on another: each
    /// place takes its sums in the groups' order whichever thread runs it.
    fn add_side_by_side<T: Sync>(
        &self,
        groups: &[Scatter],
        blocks: &[T],
        values: &mut [f64],
        block: impl Fn(&T, usize, usize) -> Matrix3<f64> + Sync,
    ) {
        let halfway = self.pattern.halfway();
        let (low, high) = values.split_at_mut(halfway);
        let add = |part: &mut [f64], offset: usize| {
            for (group, k) in groups.iter().zip(blocks) {
                group.add_within(&self.held, part, offset, |a, b| block(k, a, b));
            }
        };
        rayon::join(|| add(low, 0), || add(high, halfway));
    }

    /// Adds to the tangent `values` the Hessian `hessian` of a potential of node `n` relative
    /// to tool `k` (`y = x_n - u_k`): on the node's block, and where the tool is force-driven
    /// on its coupling with the tool's travel and on the travel's own entry.
    pub fn add_pair_block(
        &self,
        values: &mut [f64],
        (n, k): (usize, usize),
        hessian: &Matrix3<f64>,
    ) {
        self.diagonal[n].add(&self.held, values, |_, _| *hessian);
        if let (Some(u), Some((axis, _))) = (self.tool_unknown[k], self.tool_force[k]) {
            let coupling = -(hessian * axis);
            for d in 0..3 {
                let i = 3 * n + d;
                if !self.held[i] {
                    values[self.pattern.place(u, i).expect("tool coupling")] += coupling[d];
                }
            }
            values[self.pattern.place(u, u).expect("tool diagonal")] += axis.dot(&(hessian * axis));
        }
    }
}

/// The unknowns coupled with one another in the tangent: those of the nodes of each set of
/// each of `sets` (elements, bending patches), then each force-driven tool's travel with the
/// unknowns of every node.
fn unknown_groups(
    nodes: usize,
    sets: &[&[Vec<usize>]],
    tool_unknown: &[Option<usize>],
) -> Vec<Vec<usize>> {
    let dofs = |set: &Vec<usize>| -> Vec<usize> {
        set.iter()
            .flat_map(|&n| [3 * n, 3 * n + 1, 3 * n + 2])
            .collect()
    };
    let mut groups: Vec<Vec<usize>> = sets.iter().flat_map(|s| s.iter().map(dofs)).collect();
    for unknown in tool_unknown.iter().flatten() {
        for n in 0..nodes {
            groups.push(vec![3 * n, 3 * n + 1, 3 * n + 2, *unknown]);
        }
    }
    groups
}

/// The order in which the factorisation eliminates the unknowns: node by node (a node's
/// three coordinates together), the nodes by approximate minimum degree or by geometric
/// nested dissection of the reference mesh, whichever gives the sparser factor (minimum
/// degree on small sheets; dissection from a few thousand nodes on, where its separators pay
/// off), then the tools' travel, coupled with every node.
fn elimination_order(
    model: &Model,
    nodes: usize,
    sets: &[&[Vec<usize>]],
    size: usize,
) -> Vec<usize> {
    let mut neighbours = vec![Vec::new(); nodes];
    for group in sets.iter().flat_map(|s| s.iter()) {
        for &a in group {
            neighbours[a].extend(group.iter().copied().filter(|&b| b != a));
        }
    }
    for around in &mut neighbours {
        around.sort_unstable();
        around.dedup();
    }
    let points: Vec<[f64; 3]> = model.mesh.nodes.iter().map(|p| [p.x, p.y, p.z]).collect();
    let expand = |node_order: Vec<usize>| -> Vec<usize> {
        let mut order: Vec<usize> = node_order
            .iter()
            .flat_map(|&n| [3 * n, 3 * n + 1, 3 * n + 2])
            .collect();
        order.extend(3 * nodes..size);
        order
    };
    let node_groups: Vec<Vec<usize>> = (0..nodes)
        .map(|n| {
            std::iter::once(n)
                .chain(neighbours[n].iter().copied())
                .collect()
        })
        .collect();
    let candidates = [
        minimum_degree(&neighbours).ok(),
        Some(nested_dissection(&points, &neighbours)),
    ];
    candidates
        .into_iter()
        .flatten()
        .map(|node_order| {
            let entries = Pattern::from_groups_in_order(
                nodes,
                node_groups.iter().map(|g| &g[..]),
                node_order.clone(),
            )
            .factor_entries()
            .unwrap_or(usize::MAX);
            (entries, node_order)
        })
        .min_by_key(|(entries, _)| *entries)
        .map_or_else(|| (0..size).collect(), |(_, node_order)| expand(node_order))
}

/// The start of the increment: what the trial configuration is measured from.
pub struct IncrementStart<'a> {
    pub positions: &'a [Vector3<f64>],
    /// `C` of every element at the start.
    pub strains: &'a [Matrix2<f64>],
    pub laminate_states: &'a [LaminateState],
    /// Friction of each node on each tool (`[node][tool]`).
    pub friction: &'a [Vec<Option<FrictionLag>>],
    /// Velocity of every node at the start (mm/s) and its mass (tonne): the inertia of
    /// backward Euler.
    pub velocities: &'a [Vector3<f64>],
    pub masses: &'a [f64],
    pub dt: f64,
    /// Friction of each node on the plies below and above it, and the faces listed near it
    /// (the state's; empty without interfaces).
    pub ply_lags: &'a [[Option<PlyLag>; 2]],
    pub ply_lists: &'a [InterplyNode],
    /// The triangle each node's ply–ply pairs are held on ([`super::interply::HeldFaces`]).
    pub ply_faces: &'a [[Option<HeldFace>; 2]],
    /// The temperature of each layer of each element over the increment (the state's at its
    /// start: the heat equation is advanced after the mechanics, docs/solver.md); empty in an
    /// isothermal run.
    pub temperatures: &'a [LayerTemperatures],
    /// The bending rigidity of each element at its temperature over the increment; empty where
    /// the patches' own hold (an isothermal run).
    pub bending_rigidities: &'a [BendingRigidity],
    /// Which grippers have let go (the state's at the increment's start).
    pub released: &'a [bool],
}

impl IncrementStart<'_> {
    /// The bending rigidity of patch `k` over the increment.
    fn bending_rigidity<'p>(&'p self, patch: &'p BendingPatch, k: usize) -> &'p BendingRigidity {
        self.bending_rigidities.get(k).unwrap_or(&patch.rigidity)
    }
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
    /// Lists of the triangles near each node made at a nearby configuration
    /// (`[node * tools + tool]`, [`NearLists`]), which the contact search reads instead of the
    /// tools' grids where the node is still within their margin.
    pub near: Option<&'a [NearTriangles]>,
}

/// The lists of near triangles of every node and tool (`[node * tools + tool]`), kept by
/// Newton's method between iterations and increments and made again for a node once it has
/// moved past their margin ([`RigidTool::refresh_near_list`]).
#[derive(Clone, Debug, Default)]
pub struct NearLists(Vec<NearTriangles>);

impl NearLists {
    /// Lists that serve at `positions` (tools at `translations`).
    pub fn refresh(
        &mut self,
        model: &Model,
        positions: &[Vector3<f64>],
        translations: &[Vector3<f64>],
    ) {
        let tools = model.tools.len();
        self.0
            .resize(positions.len() * tools, NearTriangles::default());
        self.0
            .par_chunks_mut(tools.max(1))
            .zip(positions)
            .for_each(|(lists, x)| {
                for (k, near) in lists.iter_mut().enumerate() {
                    model.tools[k].refresh_near_list(&(x - translations[k]), near);
                }
            });
    }

    pub fn lists(&self) -> &[NearTriangles] {
        &self.0
    }
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
    /// Each tool's point nearest to each node within the search radius
    /// (`[node * tools + tool]`), where the tangent at this trial reads it.
    pub nearest: Vec<Option<Projection>>,
    /// Work of the stabilising drag over the increment so far, `sum c |x - x_n|^2` (N·mm).
    pub drag_work: f64,
    /// The incremental potential `Pi` (N·mm) whose gradient is the residual.
    pub potential: f64,
    /// Node–tool pairs with the node behind the tool beyond the contact's reach, and
    /// ply–ply pairs with the node deeper in the other ply.
    pub tunnelled: usize,
    /// Each node's contact with its neighbouring plies (empty without interfaces).
    pub interply: Vec<PlyNodeContact>,
    /// Gravity's, the springs' and the grippers' forces (empty without supports).
    pub supports: SupportLoads,
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
    /// Elastic slip of friction's stick (mm): the slip at which a node starting from rest
    /// reaches Coulomb's limit.
    pub stick_slip: f64,
    /// The contact between the plies, where the model has interfaces.
    pub plies: Option<&'a PlyContact>,
}

/// One element's share of the residual.
struct ElementShare {
    forces: [Vector3<f64>; 4],
    potential: f64,
    response: MembraneResponse,
    state: LaminateState,
}

/// One element's stiffness, in 3x3 blocks of its nodes.
type ElementBlocks = [[Matrix3<f64>; 4]; 4];

/// What the ply–ply contact keeps over an increment: each node's lists, friction lags and held
/// faces.
type KeptContact<'a> = (
    &'a [InterplyNode],
    &'a [[Option<PlyLag>; 2]],
    &'a [[Option<HeldFace>; 2]],
);

impl Evaluator<'_> {
    /// The ply–ply contact of the increment from `start`, where the model has interfaces.
    pub fn interply<'s>(&'s self, start: &IncrementStart<'s>) -> Option<Interply<'s>> {
        let kept = (start.ply_lists, start.ply_lags, start.ply_faces);
        self.interply_over(kept, start.dt)
    }

    /// The ply–ply contact of an increment of `dt` over the node's `lists`, friction `lags`
    /// and held `faces` (none: each node's nearest), where the model has interfaces.
    pub fn interply_over<'s>(
        &'s self,
        (lists, lags, faces): KeptContact<'s>,
        dt: f64,
    ) -> Option<Interply<'s>> {
        Some(Interply {
            contact: self.plies?,
            lists,
            lags,
            faces,
            springs: &self.layout.penalty,
            margin: contact_margin(&self.model.contact),
            stick: self.stick_slip,
            dt,
        })
    }

    /// The residual at `trial` and, unless `tangent` is [`Tangent::None`], the tangent there.
    pub fn evaluate(
        &self,
        start: &IncrementStart,
        trial: &Trial,
        tangent: Tangent,
    ) -> Result<Evaluation, (usize, MaterialError)> {
        let mut evaluation = self.residual(start, trial)?;
        if tangent != Tangent::None {
            let mut values = Vec::new();
            self.tangent(start, trial, &evaluation, tangent, &mut values)?;
            evaluation.matrix = Some(values);
        }
        Ok(evaluation)
    }

    /// The residual, forces, contacts and potential at `trial`, without the tangent: what a
    /// line-search probe needs, and what [`Self::tangent`] builds on where Newton's method
    /// goes on from it.
    pub fn residual(
        &self,
        start: &IncrementStart,
        trial: &Trial,
    ) -> Result<Evaluation, (usize, MaterialError)> {
        let model = self.model;
        let layout = self.layout;
        let mut residual = vec![0.0; layout.size];
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
                    self.element(k, start, trial.positions).map_err(|e| (k, e))
                })
                .collect();
            for (i, share) in shares.into_iter().enumerate() {
                let share = share?;
                potential += share.potential;
                let scatter = &layout.elements[c * CHUNK + i];
                for (a, &n) in scatter.nodes.iter().enumerate() {
                    internal[n] += share.forces[a];
                }
                responses.push(share.response);
                states.push(share.state);
            }
        }
        if let Some(bending) = &model.bending {
            for (c, chunk) in bending.patches.chunks(CHUNK).enumerate() {
                let shares: Vec<(Vec<Vector3<f64>>, f64)> = chunk
                    .par_iter()
                    .enumerate()
                    .map(|(i, patch)| {
                        let b = start.bending_rigidity(patch, c * CHUNK + i);
                        let mut f = vec![Vector3::zeros(); patch.nodes.len()];
                        let energy = bending.forces_with(patch, b, trial.positions, &mut f);
                        (f, energy)
                    })
                    .collect();
                for (i, (f, energy)) in shares.into_iter().enumerate() {
                    potential += energy;
                    let scatter = &layout.patches[c * CHUNK + i];
                    for (a, &n) in scatter.nodes.iter().enumerate() {
                        internal[n] += f[a];
                    }
                }
            }
        }
        for (n, f) in internal.iter().enumerate() {
            for d in 0..3 {
                residual[3 * n + d] += f[d];
            }
        }
        let contact = self.contact(start, trial, &mut residual);
        potential += contact.energy;
        let plies = self
            .interply(start)
            .map(|plies| plies.residual(trial.positions, &mut residual))
            .unwrap_or_default();
        potential += plies.energy;
        let mut drag_work = 0.0;
        for n in 0..layout.nodes {
            let travel = trial.positions[n] - start.positions[n];
            let c = layout.drag[n];
            drag_work += c * travel.norm_squared();
            potential += 0.5 * c * travel.norm_squared();
            for d in 0..3 {
                residual[3 * n + d] += c * travel[d];
            }
        }
        let rate = 1.0 / (start.dt * start.dt);
        for n in 0..layout.nodes {
            let lead = trial.positions[n] - start.positions[n] - start.velocities[n] * start.dt;
            let m = start.masses[n] * rate;
            potential += 0.5 * m * lead.norm_squared();
            for d in 0..3 {
                residual[3 * n + d] += m * lead[d];
            }
        }
        for (k, unknown) in layout.tool_unknown.iter().enumerate() {
            if let (Some(u), Some((axis, force))) = (unknown, layout.tool_force[k]) {
                residual[*u] -= force;
                potential -= force * trial.translations[k].dot(&axis);
            }
        }
        let supports = self.supports(start, trial);
        potential += supports.potential;
        for (n, f) in supports.forces.iter().enumerate() {
            for d in 0..3 {
                residual[3 * n + d] -= f[d];
            }
        }
        Ok(Evaluation {
            supports,
            residual,
            matrix: None,
            internal,
            responses,
            states,
            contacts: contact.contacts,
            loads: contact.loads,
            nearest: contact.nearest,
            drag_work,
            potential,
            tunnelled: contact.tunnelled + plies.tunnelled,
            interply: plies.nodes,
        })
    }

    /// The lower triangle of the tangent of kind `kind` (not [`Tangent::None`]) at `trial`
    /// into `values` (a buffer kept by the caller: allocated anew, the tangent of a large
    /// sheet was page-faulted in at every iteration), whose residual is `evaluation`
    /// ([`Self::residual`]): the elements' responses and laminate states and the tools'
    /// nearest points are taken from it; held rows and columns are the identity.
    pub fn tangent(
        &self,
        start: &IncrementStart,
        trial: &Trial,
        evaluation: &Evaluation,
        kind: Tangent,
        values: &mut Vec<f64>,
    ) -> Result<(), (usize, MaterialError)> {
        let model = self.model;
        let layout = self.layout;
        let exact = self.exact && kind == Tangent::Consistent;
        values.clear();
        values.resize(layout.pattern.entries(), 0.0);
        let values = values.as_mut_slice();
        for (c, chunk) in model.elements.chunks(CHUNK).enumerate() {
            let blocks = chunk
                .par_iter()
                .enumerate()
                .map(|(i, _)| {
                    let k = c * CHUNK + i;
                    let at = (&evaluation.responses[k], &evaluation.states[k]);
                    self.element_stiffness(k, start, trial.positions, at, kind)
                        .map_err(|e| (k, e))
                })
                // collected in order first: the error named is the first element's on any
                // thread count
                .collect::<Vec<Result<ElementBlocks, _>>>()
                .into_iter()
                .collect::<Result<Vec<_>, _>>()?;
            let groups = &layout.elements[c * CHUNK..];
            layout.add_side_by_side(groups, &blocks, values, |k, a, b| k[a][b]);
        }
        if let Some(bending) = &model.bending {
            for (c, chunk) in bending.patches.chunks(CHUNK).enumerate() {
                let blocks: Vec<DMatrix<f64>> = chunk
                    .par_iter()
                    .enumerate()
                    .map(|(i, patch)| {
                        let b = start.bending_rigidity(patch, c * CHUNK + i);
                        bending.stiffness_with(patch, b, trial.positions, exact)
                    })
                    .collect();
                let groups = &layout.patches[c * CHUNK..];
                layout.add_side_by_side(groups, &blocks, values, |k, a, b| {
                    k.fixed_view::<3, 3>(3 * a, 3 * b).into_owned()
                });
            }
        }
        self.contact_tangent(start, trial, evaluation, kind, values);
        if let Some(plies) = self.interply(start) {
            plies.add_tangent(trial.positions, (&layout.pattern, &layout.held), values);
        }
        let rate = 1.0 / (start.dt * start.dt);
        for n in 0..layout.nodes {
            let c = layout.drag[n] + start.masses[n] * rate;
            layout.diagonal[n].add(&layout.held, values, |_, _| Matrix3::identity() * c);
        }
        for u in layout.tool_unknown.iter().flatten() {
            values[layout.pattern.place(*u, *u).expect("tool diagonal")] += layout.tool_drag;
        }
        let at = SupportsAt {
            translations: trial.translations,
            released: start.released,
        };
        for (n, block) in model.supports.stiffness(trial.positions, at) {
            layout.diagonal[n].add(&layout.held, values, |_, _| block);
        }
        for (i, &held) in layout.held.iter().enumerate() {
            if held {
                values[layout.pattern.place(i, i).expect("diagonal")] = 1.0;
            }
        }
        Ok(())
    }

    /// Gravity's, the springs' and the grippers' forces at `trial` (Eqs. (S1)–(S4)); none
    /// without supports.
    fn supports(&self, start: &IncrementStart, trial: &Trial) -> SupportLoads {
        let supports = &self.model.supports;
        if supports.is_empty() {
            return SupportLoads::default();
        }
        let at = SupportsAt {
            translations: trial.translations,
            released: start.released,
        };
        supports.loads(trial.positions, &self.layout.physical_masses, at)
    }

    /// Forces, potential and response of element `k`.
    fn element(
        &self,
        k: usize,
        start: &IncrementStart,
        x: &[Vector3<f64>],
    ) -> Result<ElementShare, MaterialError> {
        let model = self.model;
        let e = &model.elements[k];
        let f = e.gradient(x);
        let step = self.step(k, start, &f);
        let ply = model.ply_of(k);
        let laminate = &ply.laminate;
        let mut state = start.laminate_states[k].clone();
        let kin = step.kinematics(&step.c);
        let response = laminate.membrane_response(&kin, step.dt, &mut state)?;
        let mut forces = e.internal_forces(&f, &response.n);
        let hourglass = e.hourglass_forces(x, &f, &ply.hourglass, &mut forces);
        let potential = e.area * laminate.incremental_potential(&kin, &state, step.dt)? + hourglass;
        Ok(ElementShare {
            forces,
            potential,
            response,
            state,
        })
    }

    /// The backward-Euler step of element `k` from the increment's start to the deformation
    /// gradient `f`.
    fn step(&self, k: usize, start: &IncrementStart, f: &Matrix3x2<f64>) -> BackwardEulerStep {
        let e = &self.model.elements[k];
        BackwardEulerStep {
            c: f.transpose() * f,
            c_start: start.strains[k],
            dt: start.dt,
            temperature: self.model.element_temperature(start.temperatures, k),
            fibres: e.fibres,
        }
    }

    /// The stiffness blocks of element `k` at `x`, where its response and advanced laminate
    /// state are `(response, state)`.
    fn element_stiffness(
        &self,
        k: usize,
        start: &IncrementStart,
        x: &[Vector3<f64>],
        (response, state): (&MembraneResponse, &LaminateState),
        kind: Tangent,
    ) -> Result<ElementBlocks, MaterialError> {
        let model = self.model;
        let e = &model.elements[k];
        let f = e.gradient(x);
        let step = self.step(k, start, &f);
        let d = model
            .laminate(k)
            .advanced_step_tangent(&step, &start.laminate_states[k], state)?;
        let d = 0.5 * (d + d.transpose());
        let (d, n) = match kind {
            Tangent::Projected => (positive_part3(&d), positive_part2(&response.n)),
            _ => (d, response.n),
        };
        let mut blocks = e.stiffness(&f, &n, &d);
        if e.hourglass.is_some() {
            let exact = self.exact && kind == Tangent::Consistent;
            let h = e.hourglass_stiffness(x, model.hourglass(k), exact);
            for a in 0..4 {
                for b in 0..4 {
                    blocks[a][b] += h[a][b];
                }
            }
        }
        Ok(blocks)
    }

    /// The pair of node `n` and tool `k` at the trial, `nearest` the tool's point nearest to
    /// it, with the Hessian of kind `hessian`.
    fn pair(
        &self,
        (n, k): (usize, usize),
        start: &IncrementStart,
        trial: &Trial,
        nearest: Option<Projection>,
        hessian: PairHessian,
    ) -> Option<PairContact> {
        let y = trial.positions[n] - trial.translations[k];
        pair_contact(
            &self.model.tools[k],
            &y,
            nearest,
            self.layout.penalty[n],
            &self.model.tool_contact(k),
            start.friction[n][k].as_ref(),
            PairOptions {
                slip: self.stick_slip,
                hessian,
                engaged: trial.engaged.map(|e| e[n][k]),
            },
        )
    }

    /// Contact and friction of every node with every tool: adds to the residual and returns
    /// each node's contact, each tool's load, the pairs' energy and nearest points and how
    /// many tunnelled.
    fn contact(&self, start: &IncrementStart, trial: &Trial, residual: &mut [f64]) -> Contacts {
        let model = self.model;
        let layout = self.layout;
        let tools = model.tools.len();
        let pairs: Vec<Vec<(Option<Projection>, Option<PairContact>)>> = (0..layout.nodes)
            .into_par_iter()
            .map(|n| {
                (0..tools)
                    .map(|k| {
                        let y = trial.positions[n] - trial.translations[k];
                        let tool = &model.tools[k];
                        let nearest = match trial.near {
                            Some(lists) => tool.nearest_kept(&y, &lists[n * tools + k]),
                            None => tool.nearest(&y),
                        };
                        let pair = self.pair((n, k), start, trial, nearest, PairHessian::None);
                        (nearest, pair)
                    })
                    .collect()
            })
            .collect();
        let mut out = Contacts {
            contacts: vec![NodeContact::default(); layout.nodes],
            loads: vec![ToolLoad::default(); tools],
            nearest: Vec::with_capacity(layout.nodes * tools),
            energy: 0.0,
            tunnelled: 0,
        };
        for (n, node_pairs) in pairs.into_iter().enumerate() {
            let contact = &mut out.contacts[n];
            contact.tangential = vec![Vector3::zeros(); tools];
            contact.normal_force = vec![0.0; tools];
            contact.normals = vec![Vector3::zeros(); tools];
            contact.near = vec![Default::default(); tools];
            for (k, (nearest, pair)) in node_pairs.into_iter().enumerate() {
                out.nearest.push(nearest);
                let Some(pair) = pair else { continue };
                out.tunnelled += usize::from(pair.tunnelled);
                out.energy += pair.energy;
                let force = -pair.gradient;
                contact.force += force;
                contact.tangential[k] = pair.tangential;
                contact.normal_force[k] = pair.normal_force;
                contact.normals[k] = pair.normal;
                let load = &mut out.loads[k];
                if pair.normal_force > 0.0 {
                    load.normal_force += pair.normal_force;
                    load.stiffness += layout.penalty[n];
                    load.nodes_in_contact += 1;
                }
                load.force -= force;
                for d in 0..3 {
                    residual[3 * n + d] += pair.gradient[d];
                }
                if let (Some(u), Some((axis, _))) = (layout.tool_unknown[k], layout.tool_force[k]) {
                    // the pair's potential depends on y = x - u axis
                    residual[u] -= axis.dot(&pair.gradient);
                }
            }
        }
        out
    }

    /// The pairs' Hessians at the trial of `evaluation`, added to the tangent `values`: each
    /// node's own block and its coupling with a force-driven tool's travel.
    fn contact_tangent(
        &self,
        start: &IncrementStart,
        trial: &Trial,
        evaluation: &Evaluation,
        kind: Tangent,
        values: &mut [f64],
    ) {
        let layout = self.layout;
        let tools = self.model.tools.len();
        let hessian_kind = if self.exact && kind == Tangent::Consistent {
            PairHessian::Exact
        } else {
            PairHessian::GaussNewton
        };
        let hessians: Vec<Vec<Option<Matrix3<f64>>>> = (0..layout.nodes)
            .into_par_iter()
            .map(|n| {
                (0..tools)
                    .map(|k| {
                        let nearest = evaluation.nearest[n * tools + k];
                        let pair = self.pair((n, k), start, trial, nearest, hessian_kind);
                        pair.map(|pair| match kind {
                            Tangent::Projected => positive_part3(&pair.hessian),
                            _ => pair.hessian,
                        })
                    })
                    .collect()
            })
            .collect();
        for (n, node_hessians) in hessians.into_iter().enumerate() {
            for (k, hessian) in node_hessians.into_iter().enumerate() {
                if let Some(hessian) = hessian {
                    layout.add_pair_block(values, (n, k), &hessian);
                }
            }
        }
    }
}

/// What the contact of a trial gives: per node, per tool, the pairs' energy, each pair's
/// nearest point (`[node * tools + tool]`), and how many pairs tunnelled.
struct Contacts {
    contacts: Vec<NodeContact>,
    loads: Vec<ToolLoad>,
    nearest: Vec<Option<Projection>>,
    energy: f64,
    tunnelled: usize,
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
