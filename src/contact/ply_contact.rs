//! Penalty contact between neighbouring plies of a layup, with friction through the molten
//! film between them (docs/model.md §6, "Ply–ply contact"); the explicit solver's.
//!
//! Each node of a ply meets the faces of the ply below and of the ply above it (both ways, so
//! the contact is symmetric): the cells cut into triangles, the nearest point `p` of the nearest
//! triangle, its unit normal `n` (the plies' cells run counter-clockwise about the same side, so
//! `n` points from the lower ply to the upper one). The gap between the two mid-surfaces less
//! half of each ply's thickness is
//!
//! `g = s (x - p) . n - (t_a + t_b) / 2`, `s = +1` for a node of the upper ply, `-1` of the lower,
//!
//! and where `g < 0` the node is pushed back with `f_n = -k g` along `s n`, `k = s_p m / (2 dt^2)`
//! (half the tools' spring of LS-DYNA's soft constraint: the node and the face both move), and
//! the face's three nodes take the opposite force in the shares `N_i` of `p` (its barycentric
//! coordinates), so the pair's forces sum to zero.
//!
//! Friction is carried as with the tools (elastic stick, then a slip limit), on the velocity
//! of the node relative to the face's point, `v - sum N_i v_i`, with the film's slip limit
//!
//! `F_t <= min(mu f_n + eta_f(v_t / h_f) (|v_t| / h_f) A, tau_max A)` (model.md Eq. (F1)),
//!
//! `A` half the node's share of its ply's area (the nodes of both plies carry the film between
//! them): Coulomb friction plus the viscous shear of a film of thickness `h_f`, its viscosity
//! `eta_f` constant or falling with the shear rate, capped at the film's yield `tau_max`
//! ([`FilmFriction`], in `contact::film_friction`).
//!
//! The faces near each node are listed within the contact's reach plus a margin and listed
//! again once any node has moved half the margin (a Verlet list), from a uniform grid.

pub use super::film_friction::{FilmFriction, FilmViscosity};
use super::surface::{closest_feature_on_triangle, Feature};
use nalgebra::Vector3;
use rayon::prelude::*;
use std::collections::HashMap;
use std::ops::Range;

/// Two plies that touch: `upper` lies on the side of `lower` its cells' normals point to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlyInterface {
    pub lower: usize,
    pub upper: usize,
    pub friction: FilmFriction,
}

/// One ply as the contact sees it.
#[derive(Clone, Debug)]
pub struct PlySurface {
    pub nodes: Range<usize>,
    /// Its cells cut into triangles (a quadrilateral `abcd` into `abc` and `acd`), in the
    /// model's node numbering, counter-clockwise about the side the upper plies lie on.
    pub triangles: Vec<[usize; 3]>,
    /// Half its thickness (mm).
    pub half_thickness: f64,
}

/// What one node carries across one of its two sides.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SideContact {
    /// Tangential force carried from the last step (N).
    pub tangential: Vector3<f64>,
    /// Normal force (N); 0 when apart.
    pub normal_force: f64,
    /// How far the node has slid over the other ply while touching it, `int |v_t| dt` (mm).
    pub slip: f64,
    /// Triangles of the other ply near the node (indices into its `triangles`).
    candidates: Vec<u32>,
}

impl SideContact {
    /// The triangles of the other ply listed near the node.
    pub fn candidates(&self) -> &[u32] {
        &self.candidates
    }
}

/// A node's contact with its neighbouring plies: the force they put on it (its own contacts
/// and its share of the contacts of the other ply's nodes on its faces), and its side below
/// (`sides[0]`, against the ply under it) and above (`sides[1]`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct InterplyNode {
    pub force: Vector3<f64>,
    pub sides: [SideContact; 2],
}

impl InterplyNode {
    /// How far the node has slid over its neighbours (mm): the farther of its two sides.
    pub fn slip(&self) -> f64 {
        self.sides.iter().map(|s| s.slip).fold(0.0, f64::max)
    }
}

/// The contact between the plies of a layup and what it keeps from step to step.
#[derive(Clone, Debug)]
pub struct PlyContact {
    plies: Vec<PlySurface>,
    /// Per ply, the interface below it and the one above it (indices into `interfaces`).
    neighbours: Vec<[Option<usize>; 2]>,
    interfaces: Vec<PlyInterface>,
    /// Per node: its ply and its share of the ply's area (mm^2).
    node_ply: Vec<usize>,
    areas: Vec<f64>,
    /// `s_p` of the penalty, and the depth beyond which a node went through (mm).
    penalty_scale: f64,
    max_penetration: f64,
    /// The Verlet margin (mm) and the positions the lists were made at.
    margin: f64,
    listed_at: Vec<Vector3<f64>>,
}

/// The nodes' state in one contact evaluation.
#[derive(Clone, Copy, Debug)]
pub struct PlyNodes<'a> {
    pub positions: &'a [Vector3<f64>],
    pub velocities: &'a [Vector3<f64>],
    pub masses: &'a [f64],
}

/// One node's contact on one side, before it is gathered: the force on the node and the face
/// corners' shares of its opposite.
struct Push {
    node: usize,
    force: Vector3<f64>,
    corners: [usize; 3],
    shares: [f64; 3],
}

impl PlyContact {
    /// The contact of `plies` across `interfaces`, `areas` each node's share of its ply's area
    /// (mm^2), `margin` the Verlet margin (mm, about half a cell).
    pub fn new(
        plies: Vec<PlySurface>,
        interfaces: Vec<PlyInterface>,
        areas: Vec<f64>,
        (penalty_scale, max_penetration, margin): (f64, f64, f64),
    ) -> Self {
        let mut neighbours = vec![[None, None]; plies.len()];
        for (i, face) in interfaces.iter().enumerate() {
            neighbours[face.upper][0] = Some(i);
            neighbours[face.lower][1] = Some(i);
        }
        let mut node_ply = vec![0; areas.len()];
        for (p, ply) in plies.iter().enumerate() {
            node_ply[ply.nodes.clone()].fill(p);
        }
        Self {
            plies,
            neighbours,
            interfaces,
            node_ply,
            areas,
            penalty_scale,
            max_penetration,
            margin,
            listed_at: Vec::new(),
        }
    }

    /// Each interface's friction replaced by `frictions` (in the order of the interfaces): a
    /// non-isothermal run's, at the interfaces' temperatures now.
    pub fn set_frictions(&mut self, frictions: &[FilmFriction]) {
        for (face, friction) in self.interfaces.iter_mut().zip(frictions) {
            face.friction = *friction;
        }
    }

    /// The ply across side `side` (0 below, 1 above) of ply `p`, and the interface.
    fn across(&self, p: usize, side: usize) -> Option<(usize, &PlyInterface)> {
        let face = &self.interfaces[self.neighbours[p][side]?];
        Some((if side == 0 { face.lower } else { face.upper }, face))
    }

    /// The forces of the plies on one another for the step `dt` about to be taken, into
    /// `contacts` (one per node). Every node is evaluated in parallel and the forces gathered
    /// in node order, so the result does not depend on the thread count.
    pub fn evaluate(&mut self, nodes: PlyNodes, dt: f64, contacts: &mut [InterplyNode]) {
        if self.needs_listing(nodes.positions) {
            self.list_candidates(nodes.positions, contacts);
        }
        let this = &*self;
        let pushes: Vec<[Option<Push>; 2]> = contacts
            .par_iter_mut()
            .enumerate()
            .map(|(a, contact)| this.node_pushes(a, nodes, dt, contact))
            .collect();
        for contact in contacts.iter_mut() {
            contact.force = Vector3::zeros();
        }
        for push in pushes.iter().flatten().flatten() {
            contacts[push.node].force += push.force;
            for (&c, &share) in push.corners.iter().zip(&push.shares) {
                contacts[c].force -= push.force * share;
            }
        }
    }

    /// Lists the faces near every node again where a node has moved half the margin since they
    /// were made (into `contacts`); whether they were.
    pub fn relist_if_moved(
        &mut self,
        positions: &[Vector3<f64>],
        contacts: &mut [InterplyNode],
    ) -> bool {
        let moved = self.needs_listing(positions);
        if moved {
            self.list_candidates(positions, contacts);
        }
        moved
    }

    /// The overlap of two plies beyond which a node went through (mm).
    pub fn max_penetration(&self) -> f64 {
        self.max_penetration
    }

    /// Each node's share of its ply's area (mm^2).
    pub fn area(&self, a: usize) -> f64 {
        self.areas[a]
    }

    /// The interface across side `side` (0 below, 1 above) of node `a`'s ply, if any.
    pub fn interface(&self, a: usize, side: usize) -> Option<&PlyInterface> {
        self.across(self.node_ply[a], side).map(|(_, face)| face)
    }

    /// The node pairs the contact may couple while the lists hold: each node with every
    /// corner of the triangles listed near it.
    pub fn listed_pairs(&self, contacts: &[InterplyNode]) -> Vec<[usize; 2]> {
        let mut pairs = Vec::new();
        for (a, contact) in contacts.iter().enumerate() {
            let p = self.node_ply[a];
            for (side, s) in contact.sides.iter().enumerate() {
                let Some((other, _)) = self.across(p, side) else {
                    continue;
                };
                let triangles = &self.plies[other].triangles;
                let mut corners: Vec<usize> = s
                    .candidates
                    .iter()
                    .flat_map(|&t| triangles[t as usize])
                    .collect();
                corners.sort_unstable();
                corners.dedup();
                pairs.extend(corners.into_iter().map(|c| [a, c]));
            }
        }
        pairs
    }

    /// Whether a node has moved half the margin since the lists were made.
    fn needs_listing(&self, positions: &[Vector3<f64>]) -> bool {
        self.listed_at.len() != positions.len()
            || positions
                .par_iter()
                .zip(&self.listed_at)
                .any(|(x, y)| (x - y).norm() > 0.5 * self.margin)
    }

    /// Lists for every node the triangles of its neighbouring plies within the reach plus the
    /// margin.
    fn list_candidates(&mut self, positions: &[Vector3<f64>], contacts: &mut [InterplyNode]) {
        let thickest = self
            .plies
            .iter()
            .map(|p| p.half_thickness)
            .fold(0.0, f64::max);
        let reach = 2.0 * thickest + self.max_penetration + self.margin;
        let grids: Vec<TriangleGrid> = self
            .plies
            .iter()
            .map(|p| TriangleGrid::new(&p.triangles, positions, reach))
            .collect();
        let this = &*self;
        contacts
            .par_iter_mut()
            .enumerate()
            .for_each(|(a, contact)| {
                let p = this.node_ply[a];
                for (side, s) in contact.sides.iter_mut().enumerate() {
                    s.candidates.clear();
                    if let Some((other, _)) = this.across(p, side) {
                        grids[other].near(&positions[a], reach, &mut s.candidates);
                    }
                }
            });
        self.listed_at = positions.to_vec();
    }

    /// The contacts of node `a` on its two sides.
    fn node_pushes(
        &self,
        a: usize,
        nodes: PlyNodes,
        dt: f64,
        contact: &mut InterplyNode,
    ) -> [Option<Push>; 2] {
        let p = self.node_ply[a];
        let mut pushes = [None, None];
        for (side, (s, push)) in contact.sides.iter_mut().zip(&mut pushes).enumerate() {
            let found = self.across(p, side).and_then(|(_, face)| {
                let touch = self.touch(a, side, &s.candidates, nodes)?;
                Some((touch, face))
            });
            let Some((touch, face)) = found else {
                s.tangential = Vector3::zeros();
                s.normal_force = 0.0;
                continue;
            };
            let stiffness = 0.5 * self.penalty_scale * nodes.masses[a] / (dt * dt);
            let normal_force = -stiffness * touch.gap;
            let relative = nodes.velocities[a]
                - touch
                    .corners
                    .iter()
                    .zip(&touch.shares)
                    .map(|(&c, &w)| nodes.velocities[c] * w)
                    .sum::<Vector3<f64>>();
            let n = touch.direction;
            let slip = relative - n * relative.dot(&n);
            let carried = s.tangential - n * s.tangential.dot(&n);
            let trial = carried - slip * (stiffness * dt);
            // both plies' nodes press on the other's faces: each takes half its area's film
            let limit = face
                .friction
                .slip_limit(normal_force, slip.norm(), 0.5 * self.areas[a]);
            let tangential = if trial.norm() > limit {
                trial * (limit / trial.norm())
            } else {
                trial
            };
            s.tangential = tangential;
            s.normal_force = normal_force;
            s.slip += slip.norm() * dt;
            *push = Some(Push {
                node: a,
                force: n * normal_force + tangential,
                corners: touch.corners,
                shares: touch.shares,
            });
        }
        pushes
    }

    /// Where node `a` presses into the ply across `side`: [`Self::nearest`], within the reach
    /// of the penalty (not beyond `max_penetration`, where the node went through).
    fn touch(&self, a: usize, side: usize, candidates: &[u32], nodes: PlyNodes) -> Option<Touch> {
        self.nearest(a, side, candidates, nodes.positions)
            .filter(|t| t.gap < 0.0 && t.gap > -self.max_penetration)
    }

    /// The nearest point to node `a` on the ply across `side` among its listed triangles
    /// `candidates`, with the gap between the two plies' faces there: over a face the height
    /// of the node above it, off it (beyond the ply's edge, or over a convex fold) the distance
    /// to the nearest edge or corner, and only from the node's own side (`None` from the other,
    /// or without a ply across).
    pub fn nearest(
        &self,
        a: usize,
        side: usize,
        candidates: &[u32],
        positions: &[Vector3<f64>],
    ) -> Option<Touch> {
        let p = self.node_ply[a];
        let (other, _) = self.across(p, side)?;
        let x = positions[a];
        let triangles = &self.plies[other].triangles;
        let (best, (_, feature)) = candidates
            .iter()
            .map(|&t| {
                let [i, j, k] = triangles[t as usize];
                let (pi, pj, pk) = (positions[i], positions[j], positions[k]);
                (t as usize, closest_feature_on_triangle(&x, &pi, &pj, &pk))
            })
            .min_by(|(_, (p, _)), (_, (q, _))| {
                (p - x).norm_squared().total_cmp(&(q - x).norm_squared())
            })?;
        let over_face = matches!(feature, Feature::Face);
        self.touch_on(a, side, (triangles[best], over_face), positions)
    }

    /// [`Self::nearest`] on the one triangle `corners` of the ply across `side`: over its face
    /// (`over_face`), the height of node `a` above the triangle's plane, wherever the node has
    /// slid to over it (so the gap is smooth while the triangle is held); otherwise the distance
    /// to its nearest edge or corner, from the node's own side only.
    pub fn touch_on(
        &self,
        a: usize,
        side: usize,
        (corners, over_face): ([usize; 3], bool),
        positions: &[Vector3<f64>],
    ) -> Option<Touch> {
        let p = self.node_ply[a];
        let (other, _) = self.across(p, side)?;
        let x = positions[a];
        let sign = if side == 0 { 1.0 } else { -1.0 };
        let offset = self.plies[p].half_thickness + self.plies[other].half_thickness;
        let [pi, pj, pk] = corners.map(|c| positions[c]);
        let normal = (pj - pi).cross(&(pk - pi)).normalize() * sign;
        let (point, feature) = match over_face {
            true => (x - normal * (x - pi).dot(&normal), Feature::Face),
            false => closest_feature_on_triangle(&x, &pi, &pj, &pk),
        };
        let apart = x - point;
        let height = apart.dot(&normal);
        // over a face the gap is the height; off it (beyond the ply's edge, or over a convex
        // fold) the distance to the nearest edge or corner, and only from the node's own side
        let (gap, direction) = match feature {
            Feature::Face => (height - offset, normal),
            _ if height > 0.0 => (apart.norm() - offset, apart.normalize()),
            _ => return None,
        };
        Some(Touch {
            gap,
            direction,
            corners,
            shares: barycentric(&point, [&pi, &pj, &pk]),
            over_face: matches!(feature, Feature::Face),
        })
    }
}

/// Node `a` over the faces of a neighbouring ply: the gap between the two plies' faces there
/// (mm, negative where they overlap; the gradient of the gap in the node's position is
/// `direction`, in a corner's position `-share direction`), the triangle's corners and the
/// nearest point's barycentric coordinates in it (outside `[0, 1]` where the node has slid
/// beyond a triangle held over its plane).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Touch {
    pub gap: f64,
    /// Unit, from the face towards the node's side.
    pub direction: Vector3<f64>,
    pub corners: [usize; 3],
    pub shares: [f64; 3],
    /// Whether the nearest point lies within the triangle's face (not on an edge or corner).
    pub over_face: bool,
}

/// The barycentric coordinates of `p` (on the triangle) in triangle `[a, b, c]`.
fn barycentric(p: &Vector3<f64>, [a, b, c]: [&Vector3<f64>; 3]) -> [f64; 3] {
    let (v0, v1, v2) = (b - a, c - a, p - a);
    let (d00, d01, d11) = (v0.dot(&v0), v0.dot(&v1), v1.dot(&v1));
    let (d20, d21) = (v2.dot(&v0), v2.dot(&v1));
    let det = d00 * d11 - d01 * d01;
    let v = (d11 * d20 - d01 * d21) / det;
    let w = (d00 * d21 - d01 * d20) / det;
    [1.0 - v - w, v, w]
}

/// Triangles binned by the cells of a uniform grid their bounding boxes overlap.
struct TriangleGrid {
    size: f64,
    bins: HashMap<[i64; 3], Vec<u32>>,
    boxes: Vec<(Vector3<f64>, Vector3<f64>)>,
}

impl TriangleGrid {
    fn new(triangles: &[[usize; 3]], positions: &[Vector3<f64>], reach: f64) -> Self {
        let boxes: Vec<(Vector3<f64>, Vector3<f64>)> = triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|n| positions[n]);
                (a.inf(&b).inf(&c), a.sup(&b).sup(&c))
            })
            .collect();
        let largest = boxes
            .iter()
            .map(|(lo, hi)| (hi - lo).max())
            .fold(0.0, f64::max);
        let size = largest.max(reach).max(1e-9);
        let mut bins: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
        for (t, (lo, hi)) in boxes.iter().enumerate() {
            let (from, to) = (cell_of(lo, size), cell_of(hi, size));
            for i in from[0]..=to[0] {
                for j in from[1]..=to[1] {
                    for k in from[2]..=to[2] {
                        bins.entry([i, j, k]).or_default().push(t as u32);
                    }
                }
            }
        }
        Self { size, bins, boxes }
    }

    /// The triangles whose bounding box, grown by `reach`, holds `x`, in ascending order.
    fn near(&self, x: &Vector3<f64>, reach: f64, out: &mut Vec<u32>) {
        let grow = Vector3::repeat(reach);
        let (from, to) = (
            cell_of(&(x - grow), self.size),
            cell_of(&(x + grow), self.size),
        );
        for i in from[0]..=to[0] {
            for j in from[1]..=to[1] {
                for k in from[2]..=to[2] {
                    for &t in self.bins.get(&[i, j, k]).into_iter().flatten() {
                        let (lo, hi) = &self.boxes[t as usize];
                        let inside = (0..3).all(|d| x[d] >= lo[d] - reach && x[d] <= hi[d] + reach);
                        if inside {
                            out.push(t);
                        }
                    }
                }
            }
        }
        out.sort_unstable();
        out.dedup();
    }
}

fn cell_of(x: &Vector3<f64>, size: f64) -> [i64; 3] {
    [0, 1, 2].map(|d| (x[d] / size).floor() as i64)
}
