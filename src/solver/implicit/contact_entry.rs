//! Contact springs a Newton correction is about to enter, anticipated in its linear model
//! (docs/solver.md, "Implicit", "Entering contact").
//!
//! A node outside a tool spring's reach has no spring in the tangent, so a correction that
//! pushes it towards the tool carries it through the spring's edge as if nothing were there.
//! The spring (hundreds of times the sheet's stiffness) then makes the full step useless: the
//! line search can only take a step so short that the node barely enters, every other node
//! moves by that same small fraction of its correction, and the increment crawls until it is
//! cut. As the active-set methods of contact do, the pairs the correction carries into their
//! spring are given it in the linear model, `1/2 k (g + n . dy)^2` about the node's present
//! gap `g` beyond the spring's edge, and the correction is solved again.

use super::assembly::{Evaluation, Layout};
use crate::contact::potential::contact_margin;
use crate::solver::model::Model;
use nalgebra::Vector3;

/// How deep into a spring's reach a correction must carry a node for its spring to be
/// anticipated, as a fraction of the contact margin **(choice)**: shallower entries the line
/// search takes in its stride (their spring's force is at most that fraction of the margin's).
const ENTRY_DEPTH: f64 = 0.01;

/// A node–tool pair the correction carries into the tool's spring.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Entry {
    pub node: usize,
    pub tool: usize,
    /// The tool's normal at the node.
    pub normal: Vector3<f64>,
    /// How far the node is outside the spring's reach (mm, positive).
    pub gap: f64,
}

/// The pairs that `direction` (a correction of the unknowns at `x`, `translations`) carries
/// from outside a tool's spring deeper than [`ENTRY_DEPTH`] into it, along the tool's normal at
/// the node; not those the frozen contact set `engaged` holds on, nor those in `known`.
pub fn entering(
    model: &Model,
    layout: &Layout,
    evaluation: &Evaluation,
    (x, translations): (&[Vector3<f64>], &[Vector3<f64>]),
    engaged: Option<&[Vec<bool>]>,
    direction: &[f64],
    known: &[Entry],
) -> Vec<Entry> {
    let tools = model.tools.len();
    let settings = model.tool_contacts();
    let tool_steps: Vec<Vector3<f64>> = (0..tools)
        .map(|k| match (layout.tool_unknown[k], layout.tool_force[k]) {
            (Some(u), Some((axis, _))) => axis * direction[u],
            _ => Vector3::zeros(),
        })
        .collect();
    let mut entries = Vec::new();
    for (a, position) in x.iter().enumerate() {
        for (k, translation) in translations.iter().enumerate() {
            let Some(p) = evaluation.nearest[a * tools + k] else {
                continue;
            };
            if engaged.is_some_and(|e| e[a][k]) || known.iter().any(|e| (e.node, e.tool) == (a, k))
            {
                continue;
            }
            let (normal, distance) = p.direction_to(&(position - translation));
            let margin = contact_margin(&settings[k]);
            let gap = distance - settings[k].offset - margin;
            if gap < 0.0 {
                continue; // in the spring: the tangent has it
            }
            let step = Vector3::from_fn(|d, _| direction[3 * a + d]) - tool_steps[k];
            if gap + normal.dot(&step) < -ENTRY_DEPTH * margin {
                entries.push(Entry {
                    node: a,
                    tool: k,
                    normal,
                    gap,
                });
            }
        }
    }
    entries
}

/// Gives the tangent `values` (on the layout's pattern) the springs of `entries`,
/// `k n n^T`, `k` the node's spring.
pub fn add_springs(layout: &Layout, entries: &[Entry], values: &mut [f64]) {
    for e in entries {
        let k = layout.penalty[e.node];
        layout.add_pair_block(
            values,
            (e.node, e.tool),
            &(e.normal * e.normal.transpose() * k),
        );
    }
}

/// Adds to `rhs` (minus the residual) the springs' pull towards their own edge in the linear
/// model: `-k g n` on the node (and its opposite along a force-driven tool's axis).
pub fn add_pushes(layout: &Layout, entries: &[Entry], rhs: &mut [f64]) {
    for e in entries {
        let push = e.normal * (layout.penalty[e.node] * e.gap);
        for d in 0..3 {
            if !layout.held[3 * e.node + d] {
                rhs[3 * e.node + d] -= push[d];
            }
        }
        if let (Some(u), Some((axis, _))) = (layout.tool_unknown[e.tool], layout.tool_force[e.tool])
        {
            rhs[u] += axis.dot(&push);
        }
    }
}
