//! Penalty node-to-surface contact with regularised Coulomb friction (docs/model.md §6).
//!
//! A blank node at `x` meets a tool when its gap to the tool's surface, offset by half the
//! blank's thickness, is negative: `g = (x - p) . n - t/2 < 0` with `p` the nearest point of the
//! surface and `n` the unit vector from `p` to `x` (the facet's normal, towards the blank, when
//! `x` is behind the facet; see `Projection::direction_to`). The tool then pushes it back with
//! `f_n = -k g n`, `k = s m / dt^2` for a node of mass `m` (the soft constraint of LS-DYNA:
//! with `s < 1` the contact spring `sqrt(k/m) dt = sqrt(s)` stays within the stable step of
//! central differences whatever the tool, so contact never shortens the step).
//!
//! Friction is regularised Coulomb, an elastic stick with the same stiffness and a slip
//! limit: the tangential force carried from the last step, projected on the current tangent
//! plane, is decreased by `k v_t dt` (`v_t` the tangential velocity of the node relative to the
//! tool), then scaled back to `mu |f_n|` if it exceeds it (slip). In sliding the friction force
//! is therefore exactly `mu |f_n|` against the slip direction; in sticking, below it.

use super::rigid_tool::{NearTriangles, RigidTool, ToolMotion};
use nalgebra::Vector3;
use rayon::prelude::*;

/// How the contact is computed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactSettings {
    /// Distance from the blank's mid-surface to its contact faces (mm): half its thickness.
    pub offset: f64,
    /// `s` of the penalty `k = s m / dt^2`, in (0, 1).
    pub penalty_scale: f64,
    /// Penetrations deeper than this (mm) are not contact but a node that went through or
    /// lies behind the tool (the far side of a thin tool), and are ignored.
    pub max_penetration: f64,
}

/// What a node does with the tools: its contact force, and per tool the tangential force it
/// carries, its normal force (0 when not touching) and the triangles near it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NodeContact {
    pub force: Vector3<f64>,
    pub tangential: Vec<Vector3<f64>>,
    pub normal_force: Vec<f64>,
    /// Per tool, the unit normal of its surface at the node, towards the node (zero when not
    /// touching): the side of the blank the tool is on.
    pub normals: Vec<Vector3<f64>>,
    pub near: Vec<NearTriangles>,
}

/// The force of the blank on one tool (N), and how many nodes touch it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ToolLoad {
    pub force: Vector3<f64>,
    /// Sum of the normal forces `|f_n|` (N).
    pub normal_force: f64,
    /// Sum of the contact springs `k` of the nodes touching the tool (N/mm): what a
    /// force-driven tool rests on.
    pub stiffness: f64,
    pub nodes_in_contact: usize,
}

/// The nodes in a contact evaluation: positions (mm), velocities (mm/s), lumped masses (t).
#[derive(Clone, Copy, Debug)]
pub struct Nodes<'a> {
    pub positions: &'a [Vector3<f64>],
    pub velocities: &'a [Vector3<f64>],
    pub masses: &'a [f64],
}

/// Nodes at `positions` behind a moving tool's surface (the tools at `translations`) deeper
/// than the contact's reach (`max_penetration`): the penalty no longer holds them, so they went
/// through the tool. Only the nodes inside the tool's bounding box, grown by three such depths
/// (a flat holder's box is flat), are searched, a full search each; fixed tools do not move
/// into the blank. `contact` is each tool's ([`crate::solver::Model::tool_contacts`]).
pub fn nodes_through_tools(
    tools: &[RigidTool],
    translations: &[Vector3<f64>],
    positions: &[Vector3<f64>],
    contact: &[ContactSettings],
) -> usize {
    let moving = tools
        .iter()
        .zip(translations)
        .zip(contact)
        .filter(|((tool, _), _)| !matches!(tool.motion, ToolMotion::Fixed))
        .map(|((tool, shift), settings)| {
            let (lo, hi) = tool.surface.bounds();
            let margin = Vector3::repeat(3.0 * settings.max_penetration);
            (tool, shift, settings, lo - margin, hi + margin)
        })
        .collect::<Vec<_>>();
    positions
        .par_iter()
        .filter(|x| {
            moving.iter().any(|(tool, shift, settings, lo, hi)| {
                let local = *x - *shift;
                let inside = (0..3).all(|d| local[d] >= lo[d] && local[d] <= hi[d]);
                inside && tool.gap(&local, settings.offset) < -settings.max_penetration
            })
        })
        .count()
}

/// One node's kinematics.
#[derive(Clone, Copy, Debug)]
struct NodeMotion {
    position: Vector3<f64>,
    velocity: Vector3<f64>,
    mass: f64,
}

/// Contact forces on every node for the step `dt` about to be taken, from the tools placed at
/// `translations` and moving at `tool_velocities`, `settings` each tool's; updates `contacts`
/// (one per node) and returns the load on each tool. The nodes go in parallel in chunks of [`NODE_CHUNK`], each
/// summed in node order and the chunks' loads added in order: the loads drive the holder and
/// give the punch force, so their rounding must not depend on the thread count.
pub fn evaluate(
    tools: &[RigidTool],
    (translations, tool_velocities): (&[Vector3<f64>], &[Vector3<f64>]),
    nodes: Nodes,
    dt: f64,
    settings: &[ContactSettings],
    contacts: &mut [NodeContact],
) -> Vec<ToolLoad> {
    let chunks: Vec<Vec<ToolLoad>> = contacts
        .par_chunks_mut(NODE_CHUNK)
        .enumerate()
        .map(|(c, chunk)| {
            let mut loads = vec![ToolLoad::default(); tools.len()];
            for (i, contact) in chunk.iter_mut().enumerate() {
                let a = c * NODE_CHUNK + i;
                let node = &NodeMotion {
                    position: nodes.positions[a],
                    velocity: nodes.velocities[a],
                    mass: nodes.masses[a],
                };
                node_contact(
                    tools,
                    (translations, tool_velocities),
                    node,
                    dt,
                    settings,
                    contact,
                    &mut loads,
                );
            }
            loads
        })
        .collect();
    let mut total = vec![ToolLoad::default(); tools.len()];
    for chunk in chunks {
        for (x, y) in total.iter_mut().zip(chunk) {
            x.force += y.force;
            x.normal_force += y.normal_force;
            x.stiffness += y.stiffness;
            x.nodes_in_contact += y.nodes_in_contact;
        }
    }
    total
}

/// Nodes per chunk of the parallel load sums: fixed, so that the sums do not depend on the
/// thread count.
const NODE_CHUNK: usize = 256;

/// The contact of one node with every tool: updates `contact` and adds the node's share to
/// `loads` (one per tool).
fn node_contact(
    tools: &[RigidTool],
    (translations, tool_velocities): (&[Vector3<f64>], &[Vector3<f64>]),
    node: &NodeMotion,
    dt: f64,
    settings: &[ContactSettings],
    contact: &mut NodeContact,
    loads: &mut [ToolLoad],
) {
    contact.force = Vector3::zeros();
    contact.tangential.resize(tools.len(), Vector3::zeros());
    contact.normal_force.resize(tools.len(), 0.0);
    contact.normals.resize(tools.len(), Vector3::zeros());
    contact.near.resize(tools.len(), NearTriangles::default());
    for (k, tool) in tools.iter().enumerate() {
        let moving = (translations[k], tool_velocities[k]);
        let f = node_tool_force(tool, moving, node, dt, &settings[k], contact, k);
        contact.force += f;
        if contact.normal_force[k] > 0.0 {
            loads[k].force -= f;
            loads[k].normal_force += contact.normal_force[k];
            loads[k].stiffness += penalty_stiffness(node.mass, dt, &settings[k]);
            loads[k].nodes_in_contact += 1;
        }
    }
}

/// The contact spring `k = s m / dt^2` of a node of mass `m` (N/mm).
fn penalty_stiffness(mass: f64, dt: f64, settings: &ContactSettings) -> f64 {
    settings.penalty_scale * mass / (dt * dt)
}

/// The force of tool `k` on one node; records the node's tangential and normal force.
fn node_tool_force(
    tool: &RigidTool,
    (translation, tool_velocity): (Vector3<f64>, Vector3<f64>),
    node: &NodeMotion,
    dt: f64,
    settings: &ContactSettings,
    contact: &mut NodeContact,
    k: usize,
) -> Vector3<f64> {
    let local = node.position - translation;
    let gap = tool.nearest_listed(&local, &mut contact.near[k]).map(|p| {
        let (normal, distance) = p.direction_to(&local);
        // unit: a blended surface's is its distance's gradient, nearly so
        (normal.normalize(), distance - settings.offset)
    });
    let (normal, gap) = match gap {
        Some((n, g)) if g < 0.0 && g > -settings.max_penetration => (n, g),
        _ => {
            contact.tangential[k] = Vector3::zeros();
            contact.normal_force[k] = 0.0;
            contact.normals[k] = Vector3::zeros();
            return Vector3::zeros();
        }
    };
    let stiffness = penalty_stiffness(node.mass, dt, settings);
    let normal_force = -stiffness * gap;
    let slip_velocity = {
        let relative = node.velocity - tool_velocity;
        relative - normal * relative.dot(&normal)
    };
    let carried = contact.tangential[k] - normal * contact.tangential[k].dot(&normal);
    let trial = carried - slip_velocity * (stiffness * dt);
    let limit = tool.friction * normal_force;
    let tangential = if trial.norm() > limit {
        trial * (limit / trial.norm())
    } else {
        trial
    };
    contact.tangential[k] = tangential;
    contact.normal_force[k] = normal_force;
    contact.normals[k] = normal;
    normal * normal_force + tangential
}
