//! Ply–ply contact and friction as potentials of the node positions (docs/solver.md,
//! "Ply–ply contact"): what the implicit solver's Newton method needs, a force and its
//! derivative, over the node and the corners of the face it meets.
//!
//! Both parts are potentials `phi(y)` of one combination of positions `y = sum_m w_m x_m`: the
//! node with weight 1, the face's corners with minus their shares (barycentric coordinates).
//! The force on node `m` is `-w_m dphi/dy` and the Hessian's block `(m, l)` is
//! `w_m w_l d^2phi/dy^2`, so the forces of a pair sum to zero and its tangent is symmetric.
//!
//! - **Normal**: `1/2 k (g - g_m)^2` while the gap `g` between the plies' faces
//!   ([`Touch`]) is below a margin `g_m`, as with the tools ([`super::potential`]). Where the
//!   node is over the face, `dg/dx_a = n` and `dg/dx_m = -N_m n` exactly (the nearest point is
//!   a minimum over the face: its own motion along the face does not change the distance to
//!   first order), so the gradient is the explicit solver's force. The Hessian is its
//!   Gauss–Newton part `k n n^T` in `y`; what is left out, `k (g - g_m) d^2g/dx^2` (the turn of
//!   the face's normal as its corners move), is smaller by the overlap over a cell.
//! - **Friction**: the tools' elastic stick and Coulomb slip ([`super::potential`]) on the
//!   slip of the node over the material point of the other ply it was on at the increment's
//!   start: `y = x_a - sum_m N0_m x_m`, the shares `N0` and the limit lagged. The limit is the
//!   film's ([`FilmFriction::slip_limit`], model.md Eq. (F1)) at the normal force and slip
//!   speed lagged, as incremental-potential contact lags the normal force.

use super::ply_contact::{FilmFriction, Touch};
use super::potential::{stick_slip, FrictionLag};
use nalgebra::{Matrix3, Vector3};

/// A potential of `y = sum_m weights[m] x_{nodes[m]}`: its energy, gradient and Hessian in `y`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PairTerm {
    pub nodes: [usize; 4],
    pub weights: [f64; 4],
    pub energy: f64,
    /// `dphi/dy` (N).
    pub gradient: Vector3<f64>,
    /// `d^2phi/dy^2` (N/mm).
    pub hessian: Matrix3<f64>,
}

impl PairTerm {
    /// The force of the term on its `m`-th node (N).
    pub fn force(&self, m: usize) -> Vector3<f64> {
        -self.gradient * self.weights[m]
    }

    /// The Hessian's block of its nodes `(m, l)` (N/mm).
    pub fn block(&self, m: usize, l: usize) -> Matrix3<f64> {
        self.hessian * (self.weights[m] * self.weights[l])
    }
}

/// The node `a` and the corners of a face with their shares as a term's nodes and weights.
fn over(a: usize, corners: [usize; 3], shares: [f64; 3]) -> ([usize; 4], [f64; 4]) {
    (
        [a, corners[0], corners[1], corners[2]],
        [1.0, -shares[0], -shares[1], -shares[2]],
    )
}

/// The penalty of node `a` at `touch` with spring `k` (N/mm) and margin `margin` (mm); `None`
/// where the gap is at or beyond the margin.
pub fn normal_term(a: usize, touch: &Touch, k: f64, margin: f64) -> Option<PairTerm> {
    let gap = touch.gap - margin;
    if gap >= 0.0 {
        return None;
    }
    let (nodes, weights) = over(a, touch.corners, touch.shares);
    let n = touch.direction;
    Some(PairTerm {
        nodes,
        weights,
        energy: 0.5 * k * gap * gap,
        gradient: n * (k * gap),
        hessian: n * n.transpose() * k,
    })
}

/// The friction of a node over a neighbouring ply during an increment: what was lagged at its
/// start.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlyLag {
    /// Coulomb's part: its limit `min(mu lambda, tau_max A)`, the normal, start and carried
    /// force, in the node's position relative to the material point of the other ply it was
    /// over (`y = x_a - sum_m N0_m x_m`).
    pub friction: FrictionLag,
    /// The film's part: its drag per slip speed `c = F_film(v) / v` at the speed lagged
    /// (N·s/mm; `(eta_f / h_f) A` for a Newtonian film, whatever the speed) and the force it
    /// is capped at, `tau_max A - mu lambda` (N).
    pub drag: f64,
    pub drag_cap: f64,
    /// That point's face and its shares `N0`.
    pub corners: [usize; 3],
    pub shares: [f64; 3],
}

impl PlyLag {
    /// `y = x_a - sum_m N0_m x_m` at `positions`.
    pub fn relative(&self, a: usize, positions: &[Vector3<f64>]) -> Vector3<f64> {
        let (nodes, weights) = over(a, self.corners, self.shares);
        nodes
            .iter()
            .zip(weights)
            .map(|(&n, w)| positions[n] * w)
            .sum()
    }

    /// The slip since the increment's start, in the plane lagged (mm).
    pub fn slip(&self, a: usize, positions: &[Vector3<f64>]) -> Vector3<f64> {
        let s = self.relative(a, positions) - self.friction.start;
        let n = self.friction.normal;
        s - n * n.dot(&s)
    }
}

/// The friction of node `a` lagged in `lag` at `positions` over an increment of `dt` (s), with
/// the elastic slip `eps` (mm) of Coulomb's stick: the term, and Coulomb's part of its gradient
/// (the stick's memory for the next increment); `None` without friction.
pub fn friction_term(
    a: usize,
    lag: &PlyLag,
    positions: &[Vector3<f64>],
    (dt, eps): (f64, f64),
    with_hessian: bool,
) -> Option<(PairTerm, Vector3<f64>)> {
    if lag.friction.limit <= 0.0 && lag.drag <= 0.0 {
        return None;
    }
    let (nodes, weights) = over(a, lag.corners, lag.shares);
    let mut term = PairTerm {
        nodes,
        weights,
        energy: 0.0,
        gradient: Vector3::zeros(),
        hessian: Matrix3::zeros(),
    };
    let mut coulomb = Vector3::zeros();
    if lag.friction.limit > 0.0 {
        let part = stick_slip(
            &lag.friction,
            &lag.relative(a, positions),
            eps,
            with_hessian,
        );
        term.energy += part.energy;
        term.gradient += part.gradient;
        term.hessian += part.hessian;
        coulomb = part.gradient;
    }
    if lag.drag > 0.0 {
        let (energy, gradient, hessian) = film_drag(lag, &lag.slip(a, positions), dt);
        term.energy += energy;
        term.gradient += gradient;
        if with_hessian {
            term.hessian += hessian;
        }
    }
    Some((term, coulomb))
}

/// The film's drag over the increment's slip `s` (mm) in `dt` (s): the dissipation potential
/// `dt D(|s| / dt)` of the force `min(c v, F_cap)` along the slip (`D' = min(c v, F_cap)`), its
/// gradient and Hessian: `(c / dt) P0` while the film does not yield, `(F_cap / |s|)
/// (P0 - s s^T / |s|^2)` once it does. Implicit in the slip speed, as the drag is stiff: lagged,
/// its speed would swing from one increment to the next.
fn film_drag(lag: &PlyLag, s: &Vector3<f64>, dt: f64) -> (f64, Vector3<f64>, Matrix3<f64>) {
    let (c, cap) = (lag.drag, lag.drag_cap);
    let n = lag.friction.normal;
    let plane = Matrix3::identity() - n * n.transpose();
    let size = s.norm();
    if c * size / dt <= cap {
        let k = c / dt;
        (0.5 * k * size * size, s * k, plane * k)
    } else {
        let direction = s / size;
        let energy = cap * size - 0.5 * dt * cap * cap / c;
        let hessian = (plane - direction * direction.transpose()) * (cap / size);
        (energy, direction * cap, hessian)
    }
}

/// Slip speed below which the film's drag per speed is taken at this speed (mm/s) **(choice)**:
/// a drag per speed is a secant, which a node at rest does not define.
const SLOWEST_FILM: f64 = 1e-3;

/// The friction to lag for the next increment of node `a` over a neighbouring ply at
/// `positions`, where it touches at `touch` pressed with `normal_force` (N) and has slid at
/// `speed` (mm/s), `area` its share of the film (mm^2), `carried` Coulomb's tangential force it
/// carries (minus the friction force on it).
pub fn lag_at(
    (a, touch, positions): (usize, &Touch, &[Vector3<f64>]),
    law: &FilmFriction,
    (normal_force, speed, area): (f64, f64, f64),
    carried: Vector3<f64>,
) -> PlyLag {
    let coulomb = law.slip_limit(normal_force, 0.0, area);
    let (drag, drag_cap) = film_lag(law, (normal_force, speed, area));
    let mut lag = PlyLag {
        friction: FrictionLag {
            limit: coulomb,
            normal: touch.direction,
            start: Vector3::zeros(),
            carried,
        },
        drag,
        drag_cap,
        corners: touch.corners,
        shares: touch.shares,
    };
    lag.friction.start = lag.relative(a, positions);
    lag
}

/// The film's drag per speed at `speed` and the force it is capped at, for a node pressed with
/// `normal_force` (N) of film area `area` (mm^2): model.md Eq. (F1) less its Coulomb part.
pub fn film_lag(law: &FilmFriction, (normal_force, speed, area): (f64, f64, f64)) -> (f64, f64) {
    let v = speed.max(SLOWEST_FILM);
    let film = law.slip_limit(0.0, v, area);
    let cap = law.shear_cap * area - law.slip_limit(normal_force, 0.0, area);
    (film / v, cap.max(0.0))
}
