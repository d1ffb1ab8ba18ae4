//! Contact and friction between the plies of a layup in the implicit solver (docs/solver.md,
//! "Ply–ply contact"): each node against the faces of the plies below and above it (both
//! ways, as in the explicit solver, so the contact is symmetric), as the potentials of
//! [`crate::contact::ply_potential`], added to the residual and tangent over the node and the
//! face's corners.
//!
//! The faces near each node are those the ply contact lists ([`PlyContact`]); the tangent's
//! pattern couples each node with every corner of its listed faces, so it is laid out again
//! whenever the lists are made again (between increments, once a node has moved half their
//! margin). Every node's pairs are evaluated in parallel and their sums taken in node order:
//! the result does not depend on the thread count.

use super::linear::Pattern;
use super::scatter::Scatter;
use crate::contact::ply_contact::{InterplyNode, PlyContact, Touch};
use crate::contact::ply_potential::{
    film_lag, friction_term, lag_at, normal_term, PairTerm, PlyLag,
};
use crate::contact::potential::FrictionLag;
use nalgebra::Vector3;
use rayon::prelude::*;

/// A node's contact with its neighbouring plies at a trial configuration.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PlyNodeContact {
    /// The force of the neighbouring plies on the node: its own pairs' and its share, as a
    /// face's corner, of the other plies' nodes' (N).
    pub force: Vector3<f64>,
    /// Below (`[0]`) and above (`[1]`).
    pub sides: [PlySide; 2],
}

/// A node's own pair on one side.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PlySide {
    /// `k |g - g_m|` (N); zero apart.
    pub normal_force: f64,
    /// The friction force on the node (N), and Coulomb's part of it.
    pub tangential: Vector3<f64>,
    pub coulomb: Vector3<f64>,
    /// Where it touches (within the spring's margin).
    pub touch: Option<Touch>,
}

/// Lags of every node's friction on its two sides (`[node][side]`).
pub type PlyLags = Vec<[Option<PlyLag>; 2]>;

/// The triangle of the other ply each node is measured against on its two sides
/// (`[node][side]`), and whether over its face: held for an increment, so that the gap is
/// smooth while Newton's method converges (two plies meshed alike put every node over a
/// corner of the other's triangles, where the nearest one changes at the slightest motion).
pub type HeldFaces = Vec<[Option<HeldFace>; 2]>;

/// A triangle's corners, and whether the node is over its face.
pub type HeldFace = ([usize; 3], bool);

/// The triangles nearest to every node at `positions` among those listed in `lists`.
pub fn held_faces(
    contact: &PlyContact,
    lists: &[InterplyNode],
    positions: &[Vector3<f64>],
) -> HeldFaces {
    (0..lists.len())
        .into_par_iter()
        .map(|a| {
            [0, 1].map(|side| {
                let candidates = lists[a].sides[side].candidates();
                let t = contact.nearest(a, side, candidates, positions)?;
                Some((t.corners, t.over_face))
            })
        })
        .collect()
}

/// The ply–ply contact of one increment: the contact, its lists of near faces (the state's),
/// the friction lagged at the increment's start, the springs.
pub struct Interply<'a> {
    pub contact: &'a PlyContact,
    pub lists: &'a [InterplyNode],
    pub lags: &'a [[Option<PlyLag>; 2]],
    pub faces: &'a [[Option<HeldFace>; 2]],
    /// Each node's contact spring with the tools (N/mm); a ply–ply pair takes half of it, as
    /// both plies' nodes press on the other's faces.
    pub springs: &'a [f64],
    /// The spring's margin `g_m` (mm), friction's elastic slip (mm) and the increment (s).
    pub margin: f64,
    pub stick: f64,
    pub dt: f64,
}

/// The ply–ply contact at a trial configuration.
#[derive(Clone, Debug, Default)]
pub struct InterplyEvaluation {
    pub nodes: Vec<PlyNodeContact>,
    /// The pairs' potential (N·mm).
    pub energy: f64,
    /// Pairs with the node deeper in the other ply than the contact's reach.
    pub tunnelled: usize,
}

/// Node `a`'s pairs: its two sides, their terms and whether any went through.
struct NodePairs {
    sides: [PlySide; 2],
    terms: Vec<PairTerm>,
    tunnelled: usize,
}

impl Interply<'_> {
    /// Node `a`'s pairs with the plies across its two sides at `positions`.
    fn node_pairs(&self, a: usize, positions: &[Vector3<f64>], with_hessian: bool) -> NodePairs {
        let mut pairs = NodePairs {
            sides: [PlySide::default(); 2],
            terms: Vec::new(),
            tunnelled: 0,
        };
        for side in 0..2 {
            if self.contact.interface(a, side).is_none() {
                continue;
            }
            let touch = match self.faces.get(a).and_then(|f| f[side]) {
                Some(face) => self.contact.touch_on(a, side, face, positions),
                None => {
                    let candidates = self.lists[a].sides[side].candidates();
                    self.contact.nearest(a, side, candidates, positions)
                }
            };
            let k = 0.5 * self.springs[a];
            if let Some((t, term)) =
                touch.and_then(|t| Some((t, normal_term(a, &t, k, self.margin)?)))
            {
                pairs.sides[side].normal_force = -k * (t.gap - self.margin);
                pairs.sides[side].touch = Some(t);
                pairs.tunnelled += usize::from(t.gap <= -self.contact.max_penetration());
                pairs.terms.push(term);
            }
            let lag = self.lags.get(a).and_then(|l| l[side].as_ref());
            let slip = (self.dt, self.stick);
            if let Some((term, coulomb)) =
                lag.and_then(|l| friction_term(a, l, positions, slip, with_hessian))
            {
                pairs.sides[side].tangential = -term.gradient;
                pairs.sides[side].coulomb = -coulomb;
                pairs.terms.push(term);
            }
        }
        pairs
    }

    /// The pairs of every node at `positions`, their gradient added to `residual`.
    pub fn residual(&self, positions: &[Vector3<f64>], residual: &mut [f64]) -> InterplyEvaluation {
        let pairs: Vec<NodePairs> = (0..positions.len())
            .into_par_iter()
            .map(|a| self.node_pairs(a, positions, false))
            .collect();
        let mut out = InterplyEvaluation {
            nodes: vec![PlyNodeContact::default(); positions.len()],
            ..Default::default()
        };
        for (a, node) in pairs.into_iter().enumerate() {
            out.nodes[a].sides = node.sides;
            out.tunnelled += node.tunnelled;
            for term in &node.terms {
                out.energy += term.energy;
                for (m, &n) in term.nodes.iter().enumerate() {
                    let f = term.force(m);
                    out.nodes[n].force += f;
                    for d in 0..3 {
                        residual[3 * n + d] -= f[d];
                    }
                }
            }
        }
        out
    }

    /// Adds the pairs' Hessians at `positions` to the tangent `values` on `pattern` (held rows
    /// and columns skipped).
    pub fn add_tangent(
        &self,
        positions: &[Vector3<f64>],
        (pattern, held): (&Pattern, &[bool]),
        values: &mut [f64],
    ) {
        let terms: Vec<Vec<PairTerm>> = (0..positions.len())
            .into_par_iter()
            .map(|a| self.node_pairs(a, positions, true).terms)
            .collect();
        for term in terms.iter().flatten() {
            Scatter::new(pattern, held, &term.nodes).add(held, values, |m, l| term.block(m, l));
        }
    }

    /// The friction lagged again with the normal forces of a trial at `x` (`nodes`) and the
    /// slip speeds of the increment of `dt` from `start` so far, where the limits moved by more
    /// than `threshold` of their sum; `None` otherwise. A node that came into contact during
    /// the increment is anchored where it was at the start.
    pub fn refined_lags(
        &self,
        nodes: &[PlyNodeContact],
        (start, x, dt): (&[Vector3<f64>], &[Vector3<f64>], f64),
        threshold: f64,
    ) -> Option<PlyLags> {
        let (mut change, mut total) = (0.0, 0.0);
        let mut refined = self.lags.to_vec();
        for (a, node) in nodes.iter().enumerate() {
            for (side, now) in node.sides.iter().enumerate() {
                let Some(face) = self.contact.interface(a, side) else {
                    continue;
                };
                let lagged = self.lags[a][side];
                let speed = lagged.map_or(0.0, |l| l.slip(a, x).norm() / dt);
                let area = 0.5 * self.contact.area(a);
                let pressed = now.normal_force > 0.0;
                let force = |lag: &PlyLag| lag.friction.limit + lag.drag * speed;
                let before = lagged.map_or(0.0, |l| force(&l));
                let mut law = |anchor: PlyLag| {
                    let limit = face.friction.slip_limit(now.normal_force, 0.0, area);
                    let (drag, drag_cap) =
                        film_lag(&face.friction, (now.normal_force, speed, area));
                    let lag = PlyLag {
                        friction: FrictionLag {
                            limit,
                            ..anchor.friction
                        },
                        drag,
                        drag_cap,
                        ..anchor
                    };
                    change += (force(&lag) - before).abs();
                    total += force(&lag);
                    lag
                };
                refined[a][side] = match (lagged, pressed) {
                    (Some(l), true) => Some(law(l)),
                    (None, true) => {
                        let candidates = self.lists[a].sides[side].candidates();
                        let at_start = self.contact.nearest(a, side, candidates, start);
                        at_start.map(|t| {
                            law(lag_at(
                                (a, &t, start),
                                &face.friction,
                                (0.0, 0.0, area),
                                Vector3::zeros(),
                            ))
                        })
                    }
                    (Some(_), false) => {
                        change += before;
                        None
                    }
                    (None, false) => None,
                };
            }
        }
        (change > threshold * total).then_some(refined)
    }

    /// The slip of every node over the plies it was on, in the increment that ended at `x`
    /// (mm): zero where it touched none at the start.
    pub fn slips(&self, x: &[Vector3<f64>]) -> Vec<[f64; 2]> {
        self.lags
            .iter()
            .enumerate()
            .map(|(a, sides)| sides.map(|l| l.map_or(0.0, |l| l.slip(a, x).norm())))
            .collect()
    }

    /// The friction to lag for the increment after the one of `dt` that ended at `x` with the
    /// contacts `nodes`: anchored where each node touches, the limit at its normal force and
    /// slip speed, carrying its friction force.
    pub fn lags_after(&self, nodes: &[PlyNodeContact], x: &[Vector3<f64>], dt: f64) -> PlyLags {
        let slips = self.slips(x);
        nodes
            .iter()
            .enumerate()
            .map(|(a, node)| {
                [0, 1].map(|side| {
                    let now = &node.sides[side];
                    let touch = now.touch?;
                    let face = self.contact.interface(a, side)?;
                    let speed = slips[a][side] / dt;
                    Some(lag_at(
                        (a, &touch, x),
                        &face.friction,
                        (now.normal_force, speed, 0.5 * self.contact.area(a)),
                        -now.coulomb,
                    ))
                })
            })
            .collect()
    }
}
