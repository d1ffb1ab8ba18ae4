//! Kinematic draping: the pin-jointed ("fishnet") net, a quick preview of how a woven fabric
//! covers a tool before a forming simulation.
//!
//! Method (Mack & Taylor 1956; Van West, Pipes & Keefe 1990; Long & Rudd 1994): the fabric is
//! a net of inextensible warp and weft yarns, pinned at their crossings and free to rotate
//! there, so the only way it can follow a doubly curved surface is by in-plane shear of its
//! cells. Every cell side keeps its length `cell` (as a chord on the surface).
//!
//! 1. From the start point two *generators* are walked along the warp and weft, in both
//!    senses, a node every chord `cell` (`solve::step_along_generator` states the choice of
//!    curve: the normal section).
//! 2. Each quadrant is filled cell by cell: the fourth corner of a cell is the point of the
//!    surface at chord `cell` from its two known neighbours, on the far side from the known
//!    diagonal corner (Newton in (x, y) from the parallelogram completion).
//! 3. It stops at the domain of the surface, at `max_cells` per direction, or where no node
//!    exists; [`DrapeReport`] says what was placed and what failed.
//!
//! The result has shear angles per cell and per node ([`DrapeResult`]). No mechanics: the net
//! ignores fabric stiffness, friction and the blank holder, so it is a preview, not a forming
//! prediction. Units: mm, angles in degrees.

mod result;
mod solve;
mod surface;

use nalgebra::{Vector2, Vector3};

pub use result::{CellShear, DrapeResult};
pub use surface::{
    finite_difference_gradient, Cylinder, DoubleDome, DrapeSurface, Hemisphere, Plane,
};

/// Largest `max_cells` accepted: (2n+1)² nodes are stored, about 128 MB at this bound.
pub const MAX_CELLS_LIMIT: usize = 1000;

/// What to drape: the net and where it starts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DrapeParams {
    /// Cell side in the undeformed fabric (mm), > 0.
    pub cell: f64,
    /// Start point (x0, y0) in plan (mm); must lie in the surface's domain.
    pub start: (f64, f64),
    /// Plan angle of the warp from the x axis (degrees); the weft starts at +90° from it in
    /// the tangent plane at the start point (+90° in plan where that plane is horizontal).
    pub warp_angle_deg: f64,
    /// Cells per direction from the start (1..=[`MAX_CELLS_LIMIT`]): indices run −n..=n.
    pub max_cells: usize,
}

/// Why a node could not be placed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FailReason {
    /// The node would lie outside the surface's domain (a generator reached the edge, or
    /// Newton left the domain).
    OutsideDomain,
    /// Newton did not converge, or the two chord conditions became parallel (cell locked flat).
    NoSolution,
    /// The only root found was on the near side of the cell: the net would fold over.
    Folded,
}

/// One node that was attempted and not placed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NodeFailure {
    /// Warp index.
    pub i: i64,
    /// Weft index.
    pub j: i64,
    /// Why.
    pub reason: FailReason,
}

/// Counts of the drape: every node of the (2n+1)² grid is placed, failed or unreached (a
/// neighbour it needs is missing).
#[derive(Debug, Clone, PartialEq)]
pub struct DrapeReport {
    /// Nodes placed, the start point included.
    pub placed: usize,
    /// Nodes attempted and not placed.
    pub failures: Vec<NodeFailure>,
    /// Nodes never attempted because a neighbour was missing.
    pub unreached: usize,
}

/// Drapes a pin-jointed net of square cells over `surface` (see the module documentation).
///
/// Errors (never panics) on a non-positive or non-finite `cell`, a non-finite start point or
/// warp angle, a `max_cells` outside 1..=[`MAX_CELLS_LIMIT`], or a start point outside the
/// surface's domain or where it has no finite slope; the message names the parameter.
pub fn drape<S: DrapeSurface + ?Sized>(
    surface: &S,
    params: &DrapeParams,
) -> Result<DrapeResult, String> {
    let origin = validate(surface, params)?;
    let mut grid = Grid::new(params.max_cells);
    let mut failures = Vec::new();
    grid.set(0, 0, origin);
    let (warp, weft) = generator_directions(surface, origin, params.warp_angle_deg)?;
    for (dir, step) in [
        (warp, (1, 0)),
        (-warp, (-1, 0)),
        (weft, (0, 1)),
        (-weft, (0, -1)),
    ] {
        walk_generator(surface, params.cell, &mut grid, dir, step, &mut failures);
    }
    for (si, sj) in [(1, 1), (-1, 1), (-1, -1), (1, -1)] {
        fill_quadrant(surface, params.cell, &mut grid, (si, sj), &mut failures);
    }
    Ok(DrapeResult::new(
        params.cell,
        params.max_cells,
        grid.nodes,
        failures,
    ))
}

/// Checks the parameters and returns the start node on the surface.
fn validate<S: DrapeSurface + ?Sized>(
    surface: &S,
    params: &DrapeParams,
) -> Result<Vector3<f64>, String> {
    if !(params.cell.is_finite() && params.cell > 0.0) {
        return Err(format!(
            "cell must be a finite size > 0 mm, got {}",
            params.cell
        ));
    }
    let (x0, y0) = params.start;
    if !(x0.is_finite() && y0.is_finite()) {
        return Err(format!("start must be a finite point, got ({x0}, {y0})"));
    }
    if !params.warp_angle_deg.is_finite() {
        return Err(format!(
            "warp_angle_deg must be finite, got {}",
            params.warp_angle_deg
        ));
    }
    if params.max_cells == 0 || params.max_cells > MAX_CELLS_LIMIT {
        return Err(format!(
            "max_cells must be in 1..={MAX_CELLS_LIMIT}, got {}",
            params.max_cells
        ));
    }
    solve::surface_point(surface, x0, y0)
        .ok_or_else(|| format!("start ({x0}, {y0}) is outside the surface's domain"))
}

/// Plan directions of the warp and weft generators.
///
/// Choice: the warp leaves the start point at `warp_angle_deg` in plan; the weft leaves at
/// +90° from it *in the tangent plane* at the start point (n × t_warp), so the fabric starts
/// unsheared there even on an inclined tool. Where the tangent plane is horizontal (apex of a
/// dome, top line of a cylinder) this is simply +90° in plan.
fn generator_directions<S: DrapeSurface + ?Sized>(
    surface: &S,
    origin: Vector3<f64>,
    warp_angle_deg: f64,
) -> Result<(Vector2<f64>, Vector2<f64>), String> {
    let no_slope = || {
        format!(
            "start ({}, {}) has no finite surface slope (vertical tangent plane)",
            origin.x, origin.y
        )
    };
    let (hx, hy) = surface
        .gradient(origin.x, origin.y)
        .filter(|(gx, gy)| gx.is_finite() && gy.is_finite())
        .ok_or_else(no_slope)?;
    let theta = warp_angle_deg.to_radians();
    let warp = Vector2::new(theta.cos(), theta.sin());
    let warp_tangent = Vector3::new(warp.x, warp.y, hx * warp.x + hy * warp.y);
    let normal = Vector3::new(-hx, -hy, 1.0);
    let weft_tangent = normal.cross(&warp_tangent);
    let weft = Vector2::new(weft_tangent.x, weft_tangent.y)
        .try_normalize(0.0)
        .ok_or_else(no_slope)?;
    Ok((warp, weft))
}

/// The (2n+1)² node grid being filled, indexed by (i, j) in −n..=n.
struct Grid {
    n: i64,
    nodes: Vec<Option<Vector3<f64>>>,
}

impl Grid {
    fn new(n: usize) -> Self {
        let side = 2 * n + 1;
        Self {
            n: n as i64,
            nodes: vec![None; side * side],
        }
    }

    fn index(&self, i: i64, j: i64) -> usize {
        ((i + self.n) * (2 * self.n + 1) + (j + self.n)) as usize
    }

    fn get(&self, i: i64, j: i64) -> Option<Vector3<f64>> {
        self.nodes[self.index(i, j)]
    }

    fn set(&mut self, i: i64, j: i64, p: Vector3<f64>) {
        let k = self.index(i, j);
        self.nodes[k] = Some(p);
    }
}

/// Places the generator nodes k·step, k = 1..=n, from the start along plan direction `dir`,
/// until the surface's domain ends (one failure recorded there).
fn walk_generator<S: DrapeSurface + ?Sized>(
    surface: &S,
    cell: f64,
    grid: &mut Grid,
    dir: Vector2<f64>,
    step: (i64, i64),
    failures: &mut Vec<NodeFailure>,
) {
    for k in 1..=grid.n {
        let Some(from) = grid.get((k - 1) * step.0, (k - 1) * step.1) else {
            return;
        };
        let (i, j) = (k * step.0, k * step.1);
        match solve::step_along_generator(surface, from, dir, cell) {
            Some(p) => grid.set(i, j, p),
            None => {
                failures.push(NodeFailure {
                    i,
                    j,
                    reason: FailReason::OutsideDomain,
                });
                return;
            }
        }
    }
}

/// Fills the quadrant with signs (si, sj) row by row away from the generators, so both
/// neighbours (i − si, j) and (i, j − sj) and the diagonal corner are known when (i, j) is
/// solved; nodes with a missing neighbour stay unreached.
fn fill_quadrant<S: DrapeSurface + ?Sized>(
    surface: &S,
    cell: f64,
    grid: &mut Grid,
    (si, sj): (i64, i64),
    failures: &mut Vec<NodeFailure>,
) {
    for a in 1..=grid.n {
        for b in 1..=grid.n {
            let (i, j) = (si * a, sj * b);
            let (Some(pa), Some(pb), Some(pd)) = (
                grid.get(i - si, j),
                grid.get(i, j - sj),
                grid.get(i - si, j - sj),
            ) else {
                continue;
            };
            match solve::complete_cell(surface, pa, pb, pd, cell) {
                Ok(p) => grid.set(i, j, p),
                Err(reason) => failures.push(NodeFailure { i, j, reason }),
            }
        }
    }
}
