//! A rigid tool in a run: its surface, how it moves, its friction, and a grid over its
//! triangles for the nearest-point search.
//!
//! In a run a node moves a tiny fraction of a millimetre per step relative to a tool, so each
//! node keeps the few triangles near it between steps ([`NearTriangles`], a Verlet list): every
//! triangle within `search_radius + margin` of where the list was made. Until the node has moved
//! `margin` from there, no other triangle can come within the search radius, and a step reads
//! the list instead of the grid.

use super::blended_surface::BlendedSurface;
use super::penalty::ToolLoad;
use super::surface::{
    closest_feature_on_triangle, closest_point_on_triangle, Feature, Footing, Projection,
    TriangleSurface,
};
use super::swept_profile::SweptProfile;
use super::tool_path::ToolPath;
use nalgebra::Vector3;
use std::collections::HashMap;
use std::sync::Arc;

/// Velocity of a tool (mm/s) at time `t`; tools translate, they do not turn.
pub type ToolVelocity = Arc<dyn Fn(f64) -> Vector3<f64> + Send + Sync>;

/// How a tool moves.
#[derive(Clone)]
pub enum ToolMotion {
    Fixed,
    /// Prescribed velocity history.
    Velocity(ToolVelocity),
    /// Moved along a path: each step translates it by exactly the path's travel over the step.
    Path(Arc<ToolPath>),
    /// Pushed by a constant `force` (N), free to move along it, resisted by the blank only: a
    /// blank holder under its blank-holder force. `mass` (tonne) is the tool's inertia in the
    /// simulation; the blank's mass or more keeps the tool stable on the contact springs. Its
    /// motion is critically damped on those springs, as a press cushion is: undamped, the tool
    /// rings on the flange (the holder force swinging between 0 and twice its value) and pumps
    /// kinetic energy into the blank.
    Force {
        force: Vector3<f64>,
        mass: f64,
    },
}

impl std::fmt::Debug for ToolMotion {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ToolMotion::Fixed => write!(f, "Fixed"),
            ToolMotion::Velocity(_) => write!(f, "Velocity(..)"),
            ToolMotion::Path(p) => write!(f, "Path({p:?})"),
            ToolMotion::Force { force, mass } => {
                write!(f, "Force {{ force: {force:?}, mass: {mass} }}")
            }
        }
    }
}

/// A rigid tool: surface (in its own frame, placed at the origin of the run), motion and the
/// Coulomb friction coefficient between it and the blank.
#[derive(Clone, Debug)]
pub struct RigidTool {
    pub name: String,
    pub surface: TriangleSurface,
    pub motion: ToolMotion,
    pub friction: f64,
    /// The exact surface the triangles approximate, where it is known (the built-in tools):
    /// contact then projects onto it; the triangles bound the tool for the run's checks.
    exact: Option<SweptProfile>,
    /// The smooth surface blended over the triangles, for a tool without an exact one (read
    /// from a file): contact then sees it instead of the facets (see [`super::blended_surface`]).
    blend: Option<BlendedSurface>,
    search_radius: f64,
    grid: SurfaceGrid,
    /// Centre and radius of a sphere around each triangle, for the full search of [`Self::gap`].
    spheres: Vec<(Vector3<f64>, f64)>,
}

impl RigidTool {
    /// `search_radius` (mm): how far from the surface a node is still looked up; the contact
    /// offset (half the blank's thickness) plus the largest penetration expected.
    pub fn new(
        name: &str,
        surface: TriangleSurface,
        motion: ToolMotion,
        friction: f64,
        search_radius: f64,
    ) -> Result<Self, String> {
        if !(friction.is_finite() && friction >= 0.0) {
            return Err(format!("tool '{name}': friction = {friction} must be >= 0"));
        }
        if surface.triangles.is_empty() {
            return Err(format!("tool '{name}': the surface has no triangles"));
        }
        if !(search_radius.is_finite() && search_radius > 0.0) {
            return Err(format!(
                "tool '{name}': search radius = {search_radius} must be > 0"
            ));
        }
        if let ToolMotion::Force { force, mass } = &motion {
            if !(force.iter().all(|c| c.is_finite()) && force.norm() > 0.0) {
                return Err(format!(
                    "tool '{name}': the driving force must be finite and not zero"
                ));
            }
            if !(mass.is_finite() && *mass > 0.0) {
                return Err(format!("tool '{name}': mass = {mass} must be > 0"));
            }
        }
        let grid = SurfaceGrid::new(&surface, reach(&search_radius, None));
        let spheres = surface
            .triangles
            .iter()
            .map(|t| {
                let corners = t.map(|i| surface.vertices[i]);
                let centre = (corners[0] + corners[1] + corners[2]) / 3.0;
                let radius = corners
                    .iter()
                    .map(|c| (c - centre).norm())
                    .fold(0.0, f64::max);
                (centre, radius)
            })
            .collect();
        Ok(Self {
            name: name.into(),
            surface,
            motion,
            friction,
            exact: None,
            blend: None,
            search_radius,
            grid,
            spheres,
        })
    }

    /// The tool with the exact surface its triangles were made from: contact projects onto it
    /// (see [`super::swept_profile`]).
    pub fn with_exact_surface(mut self, exact: SweptProfile) -> Self {
        self.exact = Some(exact);
        self
    }

    /// The tool whose contact sees the smooth surface blended over its triangles
    /// ([`super::blended_surface`]) instead of the bare facets, whose normal jumps at their
    /// edges.
    pub fn with_blended_surface(mut self) -> Self {
        let blend = BlendedSurface::new(&self.surface, self.search_radius);
        self.grid = SurfaceGrid::new(&self.surface, reach(&self.search_radius, Some(&blend)));
        self.blend = Some(blend);
        self
    }

    /// The same tool moved by `by` (mm) before the run starts: a built-in tool keeps its exact
    /// surface where it moves along `z` (its axis), and is blended over its triangles
    /// otherwise.
    pub fn moved(&self, by: Vector3<f64>) -> Result<Self, String> {
        let surface = TriangleSurface {
            vertices: self.surface.vertices.iter().map(|v| v + by).collect(),
            triangles: self.surface.triangles.clone(),
        };
        let tool = RigidTool::new(
            &self.name,
            surface,
            self.motion.clone(),
            self.friction,
            self.search_radius,
        )?;
        Ok(match (&self.exact, &self.blend) {
            (Some(exact), _) if by.x == 0.0 && by.y == 0.0 => {
                tool.with_exact_surface(exact.clone().lifted(by.z))
            }
            (Some(_), _) | (None, Some(_)) => tool.with_blended_surface(),
            (None, None) => tool,
        })
    }

    /// The blended surface, where the tool has one.
    pub fn blended_surface(&self) -> Option<&BlendedSurface> {
        self.blend.as_ref()
    }

    /// How far from a node the triangles it needs lie: the search radius, or the blend's
    /// support where that is longer.
    fn reach(&self) -> f64 {
        reach(&self.search_radius, self.blend.as_ref())
    }

    /// The vertices of the tool's triangulation where the tool stands after moving by
    /// `translation` (the surface is kept where the tool starts).
    pub fn vertices_at(
        &self,
        translation: Vector3<f64>,
    ) -> impl Iterator<Item = Vector3<f64>> + '_ {
        self.surface.vertices.iter().map(move |v| v + translation)
    }

    /// The exact surface, where the tool has one.
    pub fn exact_surface(&self) -> Option<&SweptProfile> {
        self.exact.as_ref()
    }

    /// The nearest point of the exact surface, when the tool has one.
    fn exact_nearest(&self, p: &Vector3<f64>) -> Option<Option<Projection>> {
        let exact = self.exact.as_ref()?;
        let foot = exact.nearest(p);
        Some(
            (foot.distance.abs() <= self.search_radius).then_some(Projection {
                point: foot.point,
                normal: foot.normal,
                on: Footing::Smooth { turn: foot.turn },
            }),
        )
    }

    /// The blended surface's point for `y` from the `triangles` near it, when the tool has a
    /// blend ([`super::blended_surface`]): `Some(None)` when `y` is farther from it than the
    /// search radius. The projection carries the blend's value, gradient and Hessian so that
    /// [`Projection::direction_to`] gives `(grad phi, phi)` at `y` and its turn is `hess phi`:
    /// `point = y - phi grad phi / |grad phi|^2`, `normal = grad phi` (nearly unit).
    fn blended_nearest(&self, p: &Vector3<f64>, triangles: &[usize]) -> Option<Option<Projection>> {
        let blend = self.blend.as_ref()?;
        let field = blend.distance(&self.surface, triangles, p);
        Some(
            field
                .filter(|f| f.value.abs() <= self.search_radius)
                .map(|f| Projection {
                    point: p - f.gradient * (f.value / f.gradient.norm_squared()),
                    normal: f.gradient,
                    on: Footing::Smooth { turn: f.hessian },
                }),
        )
    }

    /// The tool's velocity at `t` for a step `dt`, from its velocity `last` over the last step
    /// and the `load` of the blank on it (used by a force-driven tool only).
    pub fn velocity(&self, t: f64, dt: f64, last: Vector3<f64>, load: &ToolLoad) -> Vector3<f64> {
        match &self.motion {
            ToolMotion::Fixed => Vector3::zeros(),
            ToolMotion::Velocity(v) => v(t),
            ToolMotion::Path(p) => p.mean_velocity(t, dt),
            ToolMotion::Force { force, mass } => {
                // only along the applied force: a holder slides along the stroke axis
                let axis = force.normalize();
                let accelerating = (force + load.force).dot(&axis) / mass;
                // critical damping 2 sqrt(k m) of the tool on the contact springs, taken
                // implicitly so that it never limits the step
                let damping = 2.0 * (load.stiffness * mass).sqrt();
                let v = (last.dot(&axis) + accelerating * dt) / (1.0 + damping * dt / mass);
                axis * v
            }
        }
    }

    /// The nearest point of the surface to `p` (in the tool's frame), if it is within the search
    /// radius; `None` when no triangle is that near.
    pub fn nearest(&self, p: &Vector3<f64>) -> Option<Projection> {
        if let Some(exact) = self.exact_nearest(p) {
            return exact;
        }
        let candidates = self.grid.candidates(p).map_or(&[][..], Vec::as_slice);
        if let Some(blended) = self.blended_nearest(p, candidates) {
            return blended;
        }
        self.nearest_among(p, candidates)
    }

    /// [`Self::nearest`] for a node that keeps its list of near triangles between calls: the
    /// list is made again only when the node has moved `margin` since it was made.
    pub fn nearest_listed(&self, p: &Vector3<f64>, near: &mut NearTriangles) -> Option<Projection> {
        if let Some(exact) = self.exact_nearest(p) {
            return exact;
        }
        self.refresh_near_list(p, near);
        if let Some(blended) = self.blended_nearest(p, &near.triangles) {
            return blended;
        }
        self.nearest_among(p, &near.triangles)
    }

    /// [`Self::nearest`] from a list of near triangles made earlier ([`Self::near_list`]) when
    /// `p` is within its margin of where it was made, by the grid otherwise: the same
    /// triangles are looked at either way, the list's are fewer.
    pub fn nearest_kept(&self, p: &Vector3<f64>, near: &NearTriangles) -> Option<Projection> {
        if let Some(exact) = self.exact_nearest(p) {
            return exact;
        }
        let margin = list_margin(self.search_radius);
        match near.anchor {
            Some(a) if (p - a).norm_squared() < margin * margin => self
                .blended_nearest(p, &near.triangles)
                .unwrap_or_else(|| self.nearest_among(p, &near.triangles)),
            _ => self.nearest(p),
        }
    }

    /// Makes `near` the list of the triangles near `p`, unless it was made within its margin
    /// of `p` and still serves there.
    pub fn refresh_near_list(&self, p: &Vector3<f64>, near: &mut NearTriangles) {
        let margin = list_margin(self.search_radius);
        if self.exact.is_none()
            && near
                .anchor
                .is_none_or(|a| (p - a).norm_squared() >= margin * margin)
        {
            self.list_near_triangles(p, near);
        }
    }

    fn list_near_triangles(&self, p: &Vector3<f64>, near: &mut NearTriangles) {
        let reach = self.reach();
        near.anchor = Some(*p);
        near.triangles.clear();
        if let Some(candidates) = self.grid.candidates(p) {
            near.triangles.extend(
                candidates
                    .iter()
                    .filter(|&&k| (p - self.closest_on(k, p)).norm_squared() <= reach * reach),
            );
        }
    }

    fn nearest_among(&self, p: &Vector3<f64>, triangles: &[usize]) -> Option<Projection> {
        triangles
            .iter()
            .map(|&k| {
                let point = self.closest_on(k, p);
                (k, point, (p - point).norm_squared())
            })
            .filter(|x| x.2 <= self.search_radius * self.search_radius)
            .min_by(|x, y| x.2.total_cmp(&y.2))
            .map(|(triangle, point, _)| Projection {
                point,
                normal: self.surface.normal(triangle),
                on: Footing::Facet(triangle),
            })
    }

    /// The [`Feature`] of triangle `k` that holds its point nearest to `p`.
    pub fn feature_on(&self, k: usize, p: &Vector3<f64>) -> Feature {
        let [a, b, c] = self.surface.triangles[k].map(|i| self.surface.vertices[i]);
        closest_feature_on_triangle(p, &a, &b, &c).1
    }

    fn closest_on(&self, k: usize, p: &Vector3<f64>) -> Vector3<f64> {
        let [a, b, c] = self.surface.triangles[k].map(|i| self.surface.vertices[i]);
        closest_point_on_triangle(p, &a, &b, &c)
    }
}

/// How far from a node the triangles of a list or a grid cell reach: the search radius (or
/// the blend's support, where that is longer) and the margin a node may move before its list
/// is made again.
fn reach(search_radius: &f64, blend: Option<&BlendedSurface>) -> f64 {
    let needed = blend.map_or(*search_radius, |b| b.support().max(*search_radius));
    needed + list_margin(*search_radius)
}

/// How far (mm) a node may move relative to a tool before its list of near triangles is made
/// again: the search radius itself **(choice)**. A larger margin lists more triangles, a smaller
/// one lists them more often; both are cheap next to a grid lookup every step.
fn list_margin(search_radius: f64) -> f64 {
    search_radius
}

/// The triangles of one tool near one node, kept between steps by the node (see the module
/// documentation). Starts empty: the first query makes it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NearTriangles {
    /// Where the node was (in the tool's frame) when the list was made.
    anchor: Option<Vector3<f64>>,
    triangles: Vec<usize>,
}

impl RigidTool {
    /// Signed gap of a blank face to the surface, for output: the signed distance of `p` (in the
    /// tool's frame) to the nearest point of the whole surface (`Projection::direction_to`),
    /// less `offset`.
    /// Within the search radius the grid lists every triangle that can be the nearest; beyond
    /// it, a full search (for frames and checks, not for every step).
    pub fn gap(&self, p: &Vector3<f64>, offset: f64) -> f64 {
        if let Some(exact) = &self.exact {
            return exact.nearest(p).distance - offset;
        }
        if let Some(near) = self.nearest(p) {
            return near.direction_to(p).1 - offset;
        }
        // beyond the search radius, the blend where a facet is within its support (the
        // grid lists those), the nearest facet beyond that
        if let Some(Some(far)) = self.blend.as_ref().map(|b| {
            let candidates = self.grid.candidates(p).map_or(&[][..], Vec::as_slice);
            b.distance(&self.surface, candidates, p)
        }) {
            return far.value - offset;
        }
        // a triangle whose bounding sphere is farther than the best so far cannot be nearer
        let mut best: Option<(usize, Vector3<f64>, f64)> = None;
        for (k, (centre, radius)) in self.spheres.iter().enumerate() {
            let reach = ((p - centre).norm() - radius).max(0.0);
            if best.is_some_and(|b| reach * reach >= b.2) {
                continue;
            }
            let q = self.closest_on(k, p);
            let d2 = (p - q).norm_squared();
            if best.is_none_or(|b| d2 < b.2) {
                best = Some((k, q, d2));
            }
        }
        best.map_or(f64::INFINITY, |(k, q, _)| {
            if let Some(blend) = &self.blend {
                // as the blend's facets are: beside an open edge, not behind it
                return blend.facet_distance(k, p, &q).0 - offset;
            }
            let nearest = Projection {
                point: q,
                normal: self.surface.normal(k),
                on: Footing::Facet(k),
            };
            nearest.direction_to(p).1 - offset
        })
    }
}

/// A uniform grid over the surface: each cell lists the triangles whose bounding box, grown
/// by the search radius, overlaps it. A query reads one cell.
#[derive(Clone, Debug)]
struct SurfaceGrid {
    /// Corners of the surface's box grown by the search radius.
    origin: Vector3<f64>,
    end: Vector3<f64>,
    cell: f64,
    cells: HashMap<[i64; 3], Vec<usize>>,
}

impl SurfaceGrid {
    fn new(surface: &TriangleSurface, radius: f64) -> Self {
        let (lo, hi) = surface.bounds();
        let mean_edge = mean_edge_length(surface);
        // cells about the size of a triangle (and of the search radius), so that a cell
        // holds a handful of triangles
        let cell = mean_edge.max(radius).max(1e-9);
        let origin = lo - Vector3::repeat(radius);
        let mut cells: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
        for (k, t) in surface.triangles.iter().enumerate() {
            let corners = t.map(|i| surface.vertices[i]);
            let mut a = corners[0];
            let mut b = corners[0];
            for c in &corners[1..] {
                a = a.inf(c);
                b = b.sup(c);
            }
            let index = |p: Vector3<f64>| -> [i64; 3] {
                std::array::from_fn(|d| ((p[d] - origin[d]) / cell).floor() as i64)
            };
            let (i0, i1) = (
                index(a - Vector3::repeat(radius)),
                index(b + Vector3::repeat(radius)),
            );
            for x in i0[0]..=i1[0] {
                for y in i0[1]..=i1[1] {
                    for z in i0[2]..=i1[2] {
                        cells.entry([x, y, z]).or_default().push(k);
                    }
                }
            }
        }
        Self {
            origin,
            end: hi + Vector3::repeat(radius),
            cell,
            cells,
        }
    }

    fn candidates(&self, p: &Vector3<f64>) -> Option<&Vec<usize>> {
        // most nodes are far from most tools: out of the grid's box, no hashing at all
        if (0..3).any(|d| p[d] < self.origin[d] || p[d] > self.end[d]) {
            return None;
        }
        let key: [i64; 3] =
            std::array::from_fn(|d| ((p[d] - self.origin[d]) / self.cell).floor() as i64);
        self.cells.get(&key)
    }
}

fn mean_edge_length(surface: &TriangleSurface) -> f64 {
    let total: f64 = surface
        .triangles
        .iter()
        .map(|t| (surface.vertices[t[1]] - surface.vertices[t[0]]).norm())
        .sum();
    total / surface.triangles.len() as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    fn floor() -> TriangleSurface {
        TriangleSurface {
            vertices: vec![
                Vector3::new(-1.0, -1.0, 0.0),
                Vector3::new(1.0, -1.0, 0.0),
                Vector3::new(1.0, 1.0, 0.0),
                Vector3::new(-1.0, 1.0, 0.0),
            ],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
        }
    }

    #[test]
    fn nearest_within_the_search_radius_and_gap_anywhere() {
        let tool = RigidTool::new("floor", floor(), ToolMotion::Fixed, 0.1, 0.5).unwrap();
        let near = tool.nearest(&Vector3::new(0.3, -0.2, 0.2)).unwrap();
        assert!((near.point - Vector3::new(0.3, -0.2, 0.0)).norm() < 1e-15);
        assert!((near.normal - Vector3::z()).norm() < 1e-15);
        assert!(tool.nearest(&Vector3::new(0.3, -0.2, 3.0)).is_none());
        assert!((tool.gap(&Vector3::new(0.3, -0.2, 3.0), 0.15) - 2.85).abs() < 1e-12);
        assert!((tool.gap(&Vector3::new(0.0, 0.0, -0.1), 0.15) + 0.25).abs() < 1e-12);
    }

    #[test]
    fn a_kept_list_finds_what_the_grid_finds_along_a_path() {
        let punch = crate::contact::hemisphere_punch(10.0, 1.0).unwrap();
        let tool = RigidTool::new("punch", punch, ToolMotion::Fixed, 0.1, 0.3).unwrap();
        let mut near = NearTriangles::default();
        let mut touching = 0;
        // a spiral hugging the cap, 0.05 mm per step, in and out of the search radius
        for i in 0..4000 {
            let s = i as f64 * 0.05;
            let (theta, phi) = (s / 40.0, s / 7.0);
            let r = 10.0 + 0.3 * (s / 3.0).sin();
            let p = Vector3::new(0.0, 0.0, -10.0)
                + Vector3::new(
                    theta.sin() * phi.cos(),
                    theta.sin() * phi.sin(),
                    theta.cos(),
                ) * r;
            let listed = tool.nearest_listed(&p, &mut near);
            assert_eq!(listed, tool.nearest(&p), "step {i}");
            if let Some(q) = listed {
                touching += 1;
                let full = q.direction_to(&p).1;
                assert!((tool.gap(&p, 0.0) - full).abs() < 1e-12, "step {i}");
            }
        }
        assert!(touching > 1000 && touching < 4000, "{touching}");
    }

    /// The gap, by the grid near the surface and by the pruned search beyond it, is that of
    /// the nearest of all triangles, on points inside the search radius and far outside it.
    #[test]
    fn gap_is_that_of_the_nearest_of_all_triangles() {
        let punch = crate::contact::hemisphere_punch(10.0, 1.0).unwrap();
        let tool = RigidTool::new("punch", punch, ToolMotion::Fixed, 0.1, 0.3).unwrap();
        for i in 0..600 {
            let s = i as f64 * 0.37;
            let r = 10.0 + 3.0 * (s / 5.0).sin();
            let p = Vector3::new(0.0, 0.0, -10.0)
                + Vector3::new(
                    (s / 90.0).sin() * (s / 7.0).cos(),
                    (s / 90.0).sin() * (s / 7.0).sin(),
                    (s / 90.0).cos(),
                ) * r;
            let nearest = (0..tool.surface.triangles.len())
                .map(|k| (k, tool.closest_on(k, &p)))
                .min_by(|a, b| {
                    (p - a.1)
                        .norm_squared()
                        .total_cmp(&(p - b.1).norm_squared())
                })
                .unwrap();
            let exhaustive = Projection {
                point: nearest.1,
                normal: tool.surface.normal(nearest.0),
                on: Footing::Facet(nearest.0),
            }
            .direction_to(&p)
            .1;
            assert!(
                (tool.gap(&p, 0.0) - exhaustive).abs() < 1e-12,
                "point {i}: {p:?}"
            );
        }
    }

    #[test]
    fn bad_tools_are_refused_with_their_name() {
        let e = RigidTool::new("die", floor(), ToolMotion::Fixed, -0.1, 0.5).unwrap_err();
        assert!(e.contains("die") && e.contains("friction"));
        let holder = ToolMotion::Force {
            force: Vector3::zeros(),
            mass: 1.0,
        };
        let e = RigidTool::new("holder", floor(), holder, 0.1, 0.5).unwrap_err();
        assert!(e.contains("holder") && e.contains("force"));
    }
}
