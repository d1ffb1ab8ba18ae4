//! A smooth surface over a triangulated tool: curved patches over its facets blended by
//! moving least squares (docs/model.md §6, "Blended tool surfaces").
//!
//! The contact of a tool read from a file sees, instead of its facets, the zero level of
//!
//! ```text
//! phi(y) = sum_k w_k(y) q_k(y) / sum_k w_k(y),   q_k(y) = n_k . (y - o_k) - s_k(u_k(y)),
//! w_k(y) = W(d_k(y)^2 / h^2),                   W(r) = (1 - r)^3 for r < 1, 0 beyond,
//! ```
//!
//! `q_k` the height of `y` above facet `k`'s patch: its plane (unit normal `n_k`, centroid
//! `o_k`) lifted by the quadratic `s_k(u) = lift + slope . u + u^T K u / 2` of the in-plane
//! point `u`, which passes through the facet's corners and bends as the surface's normals
//! there say ([`Patch`], [`corner_normals`]); `d_k` the distance from `y` to the facet itself
//! and `h` the blend's support ([`BlendedSurface::support`]). Facets' planes alone blended so
//! (Shen, O'Brien and Shewchuk, "Interpolating and approximating implicit surfaces from
//! polygon soup", 2004, with compactly supported weights) stand proud of a convex face by
//! about `h^2 / 6R`, most where a flat face meets a fillet; the patches follow the curve and
//! leave a flat face tangentially, so a flat face stays flat up to its edge. `d_k^2` is
//! continuously differentiable in `y` (its gradient is `2 (y - p_k)`, `p_k` the facet's nearest
//! point), so `phi` is, and the contact normal `grad phi` is continuous across the facets'
//! edges. Where every facet within `h` lies in one plane (a flat face, however its triangles
//! are cut), `phi` is that plane's distance exactly.
//!
//! The contact uses `phi` as the node's distance from the tool: the potential `1/2 k (phi -
//! c)^2` has the gradient `k (phi - c) grad phi` and the Hessian `k grad phi grad phi^T +
//! k (phi - c) hess phi`, both given here in closed form; `grad phi` is within a few per cent
//! of a unit vector (exactly one on a flat face).

use super::surface::{closest_feature_on_triangle, Feature, TriangleSurface};
use nalgebra::{Matrix2, Matrix2x3, Matrix3, Vector2, Vector3};
use std::collections::HashMap;

/// The blend of a triangulated surface's patches: the support `h`, the open edges and the
/// curved patch of each facet; the facets stay with the tool.
#[derive(Clone, Debug, PartialEq)]
pub struct BlendedSurface {
    support: f64,
    /// Per facet, its edges that no other facet shares (the rim of an open surface): a point
    /// on the edge and the unit normal of the wall through it, in the facet's plane, away from
    /// the facet.
    open_edges: Vec<Vec<(Vector3<f64>, Vector3<f64>)>>,
    /// Per facet, the curved patch it stands for ([`Patch`]).
    patches: Vec<Patch>,
}

/// A facet's curved patch (docs/model.md §6, "Blended tool surfaces"): over the facet's plane
/// (centroid `o`, unit normal `n`, in-plane axes the rows of `axes`) the height
/// `s(u) = lift + slope . u + u^T K u / 2` of the surface at the in-plane point `u = axes (y -
/// o)`, fitted through the facet's three corners and to the normals the surface has there
/// ([`corner_normals`]). A flat face's facets get `s = 0`, their plane.
#[derive(Clone, Debug, PartialEq)]
struct Patch {
    normal: Vector3<f64>,
    origin: Vector3<f64>,
    axes: Matrix2x3<f64>,
    lift: f64,
    slope: Vector2<f64>,
    curvature: Matrix2<f64>,
}

/// The blended distance at a point: `phi`, its gradient and its Hessian.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlendedDistance {
    /// `phi` (mm): zero on the smooth surface, positive on the blank's side.
    pub value: f64,
    /// `grad phi`: the surface's normal (towards the blank), nearly unit.
    pub gradient: Vector3<f64>,
    /// `hess phi` (1/mm): how the normal turns as the point moves.
    pub hessian: Matrix3<f64>,
}

/// The largest angle (rad) between two facets that a curved face's triangulation puts across
/// one edge, 45° **(choice)**: a coarser crease is a sharp edge of the tool, and its triangles
/// do not tell how far apart a smooth face's kinks are.
const LARGEST_SMOOTH_CREASE: f64 = std::f64::consts::FRAC_PI_4;

/// How near (relative) a facet's nearest point must lie to the line of an edge to be on it:
/// rounding.
const ON_EDGE: f64 = 1e-9;

/// The smallest angle (rad) taken as a crease at all, 0.1°: below it two facets lie in one
/// plane up to the rounding of a CAD export.
const SMALLEST_CREASE: f64 = 1.745e-3;

impl BlendedSurface {
    /// The blend over `surface` with the support `h` of its creases ([`crease_spacing`]), at
    /// least `least` (mm; a tool's search radius, so that every point the contact looks at has
    /// a facet within the support).
    pub fn new(surface: &TriangleSurface, least: f64) -> Self {
        let surface = &welded(surface);
        let edges = shared_edges(surface);
        let support = crease_spacing(surface, &edges).unwrap_or(least).max(least);
        Self::over(surface, edges, support)
    }

    /// The blend over `surface` with the given support `h` (mm).
    pub fn with_support(surface: &TriangleSurface, support: f64) -> Self {
        let surface = &welded(surface);
        Self::over(surface, shared_edges(surface), support)
    }

    /// The blend over a [`welded`] surface whose edges are `edges` ([`shared_edges`]).
    fn over(
        surface: &TriangleSurface,
        edges: HashMap<[usize; 2], Vec<usize>>,
        support: f64,
    ) -> Self {
        let mut open_edges = vec![Vec::new(); surface.triangles.len()];
        let mut edges: Vec<_> = edges.into_iter().collect();
        // in a fixed order, whatever the map's
        edges.sort_unstable_by_key(|e| e.0);
        for ([i, j], facets) in edges {
            let &[k] = facets.as_slice() else {
                continue;
            };
            let (a, b) = (surface.vertices[i], surface.vertices[j]);
            let far = surface.vertices[far_corner(surface, k, [i, j])];
            let wall = surface.normal(k).cross(&(b - a)).normalize();
            let away = if wall.dot(&(far - a)) > 0.0 {
                -wall
            } else {
                wall
            };
            open_edges[k].push((a, away));
        }
        let normals = corner_normals(surface);
        let patches = (0..surface.triangles.len())
            .map(|k| Patch::fit(surface, k, &normals[k]))
            .collect();
        Self {
            support,
            open_edges,
            patches,
        }
    }

    /// `h` (mm): how far from a facet its patch still counts.
    pub fn support(&self) -> f64 {
        self.support
    }

    /// `phi`, its gradient and Hessian at `y` from the `triangles` of `surface` (those within
    /// the support of `y`, in any superset; summed in the order given). `None` when no facet
    /// lies within the support.
    pub fn distance(
        &self,
        surface: &TriangleSurface,
        triangles: &[usize],
        y: &Vector3<f64>,
    ) -> Option<BlendedDistance> {
        let h2 = self.support * self.support;
        // sums of w, of w q, and their gradients and Hessians
        let (mut s, mut ds, mut hs) = (0.0, Vector3::zeros(), Matrix3::zeros());
        let (mut f, mut df, mut hf) = (0.0, Vector3::zeros(), Matrix3::zeros());
        for &k in triangles {
            let [a, b, c] = surface.triangles[k].map(|i| surface.vertices[i]);
            let (p, feature) = closest_feature_on_triangle(y, &a, &b, &c);
            let r = (y - p).norm_squared() / h2;
            if r >= 1.0 {
                continue;
            }
            let (w, dw, hw) = weight(
                r,
                &((y - p) * (2.0 / h2)),
                &(feature_hessian(feature, &self.patches[k].normal) / h2),
            );
            let (q, dq, hq) = self.facet_distance(k, y, &p);
            s += w;
            ds += dw;
            hs += hw;
            f += w * q;
            df += dw * q + dq * w;
            hf += hw * q + dw * dq.transpose() + dq * dw.transpose() + hq * w;
        }
        if s <= 0.0 {
            return None;
        }
        // phi s = F: differentiated once and twice
        let value = f / s;
        let gradient = (df - ds * value) / s;
        let hessian = (hf - hs * value - gradient * ds.transpose() - ds * gradient.transpose()) / s;
        Some(BlendedDistance {
            value,
            gradient,
            hessian,
        })
    }
}

impl BlendedSurface {
    /// Facet `k`'s signed distance `q_k` at `y`, its gradient and Hessian: the height above
    /// its patch ([`Patch::distance`]); but where the facet's point `p` nearest to `y` lies on
    /// an open edge of the facet and `y` is past it (the rim of a holder's hole), that of the
    /// tool ending there in a wall square to the facet: with `g > 0` the distance past the
    /// wall (its normal `m`), `sqrt(q^2 + g^2)` in front of the patch (the distance to the
    /// edge, `q` where `g` reaches 0), `g` behind it (as the exact surfaces do beyond a rim,
    /// docs/model.md §6). A sheet sagging into a holder's hole below its top is then beside
    /// the holder, not inside it.
    pub fn facet_distance(
        &self,
        k: usize,
        y: &Vector3<f64>,
        p: &Vector3<f64>,
    ) -> (f64, Vector3<f64>, Matrix3<f64>) {
        let (q, dq, hq) = self.patches[k].distance(y);
        let on_edge = |(e, m): &&(Vector3<f64>, Vector3<f64>)| {
            m.dot(&(p - e)) >= -ON_EDGE * (1.0 + (p - e).norm())
        };
        let past = self.open_edges[k]
            .iter()
            .filter(on_edge)
            .map(|(e, m)| (m.dot(&(y - e)), m))
            .max_by(|x, y| x.0.total_cmp(&y.0));
        match past {
            Some((g, m)) if g > 0.0 && q > 0.0 => {
                // rho = sqrt(q^2 + g^2), g linear in y
                let rho = q.hypot(g);
                let direction = (dq * q + m * g) / rho;
                let across = dq * dq.transpose() + hq * q + m * m.transpose();
                (
                    rho,
                    direction,
                    (across - direction * direction.transpose()) / rho,
                )
            }
            Some((g, m)) if g > 0.0 => (g, *m, Matrix3::zeros()),
            _ => (q, dq, hq),
        }
    }
}

impl Patch {
    /// Facet `k`'s patch through its corners, whose normals there are `normals` (unit, in the
    /// facet's corner order): the curvature `K` fitted by least squares to the change of the
    /// height's slope along the three edges (a normal `m` is the slope `-(a . m) / (n . m)`
    /// along an axis `a`), then `lift` and `slope` so that the patch passes through the three
    /// corners.
    fn fit(surface: &TriangleSurface, k: usize, normals: &[Vector3<f64>; 3]) -> Self {
        let corners = surface.triangles[k].map(|i| surface.vertices[i]);
        let n = surface.normal(k);
        let origin = (corners[0] + corners[1] + corners[2]) / 3.0;
        let e1 = (corners[1] - corners[0]).normalize();
        let e2 = n.cross(&e1);
        let axes = Matrix2x3::from_rows(&[e1.transpose(), e2.transpose()]);
        let u = corners.map(|c| axes * (c - origin));
        let slope_at = normals.map(|m| -(axes * m) / n.dot(&m));
        let mut normal_matrix = Matrix3::zeros();
        let mut right = Vector3::zeros();
        for (i, j) in [(0, 1), (1, 2), (2, 0)] {
            let d = u[j] - u[i];
            let change = slope_at[j] - slope_at[i];
            // K d = change, unknowns (K11, K12, K22)
            for (row, value) in [
                (Vector3::new(d.x, d.y, 0.0), change.x),
                (Vector3::new(0.0, d.x, d.y), change.y),
            ] {
                normal_matrix += row * row.transpose();
                right += row * value;
            }
        }
        let [k11, k12, k22] = normal_matrix
            .cholesky()
            .map_or([0.0; 3], |c| c.solve(&right).into());
        let curvature = Matrix2::new(k11, k12, k12, k22);
        let corner_rows = Matrix3::from_rows(&u.map(|u| nalgebra::RowVector3::new(1.0, u.x, u.y)));
        let heights = Vector3::from(u.map(|u| -0.5 * u.dot(&(curvature * u))));
        let [lift, s1, s2] = corner_rows
            .lu()
            .solve(&heights)
            .map_or([0.0; 3], Into::into);
        Self {
            normal: n,
            origin,
            axes,
            lift,
            slope: Vector2::new(s1, s2),
            curvature,
        }
    }

    /// The height of `y` above the patch along the facet's normal `n`, `n . (y - o) - s(u)`,
    /// with its gradient `n - A^T (slope + K u)` and Hessian `-A^T K A` (`A` the axes).
    fn distance(&self, y: &Vector3<f64>) -> (f64, Vector3<f64>, Matrix3<f64>) {
        let n = &self.normal;
        let r = y - self.origin;
        let u = self.axes * r;
        let slope = self.slope + self.curvature * u;
        let height = self.lift + self.slope.dot(&u) + 0.5 * u.dot(&(self.curvature * u));
        (
            n.dot(&r) - height,
            n - self.axes.transpose() * slope,
            -(self.axes.transpose() * self.curvature * self.axes),
        )
    }
}

/// The angle a coplanar group of facets must make around a vertex for the vertex to lie on
/// the edge of a flat face, or inside it (150°, **choice**): a flat face's edge gives 180°, a
/// strip of planar quadrilaterals over a curved face at most about 90° (one quadrilateral's
/// corner).
const FLAT_FACE_CORNER: f64 = 150.0 * std::f64::consts::PI / 180.0;

/// The largest angle (rad) between two facets of one flat face, 1e-4 **(choice)**: the
/// rounding of a CAD export's single-precision corners tilts a millimetre's facet by about
/// 1e-5; the facets around a vertex of a curved face differ by 1e-3 and more (a row of 1 mm
/// facets around a 5 mm fillet's start, tilted 6° and turned 1.3° about the axis from each
/// other, by 1.4e-3).
const COPLANAR: f64 = 1e-4;

/// Per facet, the surface's normal at its three corners as that facet sees it: where the
/// vertex lies on a flat face or on its edge (a group of facets within [`COPLANAR`] of
/// each other making at least [`FLAT_FACE_CORNER`] around it), that face's normal, so that a
/// fillet meeting a flat face leaves it tangentially and the flat face stays flat; elsewhere
/// the average of the normals of the facets around the vertex weighted by their corners'
/// angles. Either way only facets within [`LARGEST_SMOOTH_CREASE`] of the facet count: a
/// sharper edge is the tool's own.
fn corner_normals(surface: &TriangleSurface) -> Vec<[Vector3<f64>; 3]> {
    let normals: Vec<_> = (0..surface.triangles.len())
        .map(|k| surface.normal(k))
        .collect();
    let mut around: Vec<Vec<(usize, f64)>> = vec![Vec::new(); surface.vertices.len()];
    for (k, t) in surface.triangles.iter().enumerate() {
        for corner in 0..3 {
            let [v, a, b] =
                [t[corner], t[(corner + 1) % 3], t[(corner + 2) % 3]].map(|i| surface.vertices[i]);
            around[t[corner]].push((k, (a - v).angle(&(b - v))));
        }
    }
    let within = |m: &Vector3<f64>, l: &Vector3<f64>, angle: f64| m.dot(l) >= angle.cos();
    surface
        .triangles
        .iter()
        .enumerate()
        .map(|(k, t)| {
            t.map(|v| {
                let smooth: Vec<_> = around[v]
                    .iter()
                    .filter(|(l, _)| within(&normals[k], &normals[*l], LARGEST_SMOOTH_CREASE))
                    .collect();
                let flat_angle = |m: &Vector3<f64>| {
                    smooth
                        .iter()
                        .filter(|(l, _)| within(m, &normals[*l], COPLANAR))
                        .map(|(_, angle)| angle)
                        .sum::<f64>()
                };
                let own = flat_angle(&normals[k]);
                let flat = smooth
                    .iter()
                    .map(|(l, _)| (flat_angle(&normals[*l]), *l))
                    .filter(|(angle, _)| *angle >= FLAT_FACE_CORNER)
                    .max_by(|x, y| x.0.total_cmp(&y.0));
                match flat {
                    _ if own >= FLAT_FACE_CORNER => normals[k],
                    Some((_, l)) => normals[l],
                    None => smooth
                        .iter()
                        .map(|(l, angle)| normals[*l] * *angle)
                        .sum::<Vector3<f64>>()
                        .normalize(),
                }
            })
        })
        .collect()
}

/// How near (relative to the surface's size) two corners must lie to be one vertex, 1e-9
/// **(choice)**: a file written from a swept or patched model may give a vertex on a seam
/// twice, a few 1e-15 mm apart, which would open a crack between the facets on either side.
const WELD: f64 = 1e-9;

/// `surface` with its triangles' corners that lie within [`WELD`] of each other made one
/// vertex (the first of them), so that facets meet across every edge they share in space.
/// Facets keep their index.
fn welded(surface: &TriangleSurface) -> TriangleSurface {
    let (low, high) = surface.bounds();
    let cell = WELD * (high - low).norm().max(f64::MIN_POSITIVE);
    let mut first: HashMap<[i64; 3], usize> = HashMap::new();
    let same: Vec<usize> = surface
        .vertices
        .iter()
        .enumerate()
        .map(|(i, v)| {
            let key = [v.x, v.y, v.z].map(|c| (c / cell).round() as i64);
            *first.entry(key).or_insert(i)
        })
        .collect();
    let triangles = surface
        .triangles
        .iter()
        .map(|t| {
            let w = t.map(|i| same[i]);
            let distinct = w[0] != w[1] && w[1] != w[2] && w[2] != w[0];
            if distinct {
                w
            } else {
                *t
            }
        })
        .collect();
    TriangleSurface {
        vertices: surface.vertices.clone(),
        triangles,
    }
}

/// Every edge of the surface (its two vertices, the smaller first) with the facets sharing it.
fn shared_edges(surface: &TriangleSurface) -> HashMap<[usize; 2], Vec<usize>> {
    let mut sharing: HashMap<[usize; 2], Vec<usize>> = HashMap::new();
    for (k, t) in surface.triangles.iter().enumerate() {
        for e in 0..3 {
            let (i, j) = (t[e], t[(e + 1) % 3]);
            sharing.entry([i.min(j), i.max(j)]).or_default().push(k);
        }
    }
    sharing
}

/// Triangle `k`'s corner off its edge `[i, j]`.
fn far_corner(surface: &TriangleSurface, k: usize, [i, j]: [usize; 2]) -> usize {
    surface.triangles[k]
        .into_iter()
        .find(|&v| v != i && v != j)
        .expect("a triangle has a corner off each edge")
}

/// `W(r) = (1 - r)^3` at `r = d^2 / h^2` with `grad r` and `hess r`, and its gradient and
/// Hessian by the chain rule: `W' grad r` and `W'' grad r grad r^T + W' hess r`. `W` and its
/// first two derivatives vanish at `r = 1`, so the blend is smooth where a facet leaves it.
fn weight(r: f64, dr: &Vector3<f64>, hr: &Matrix3<f64>) -> (f64, Vector3<f64>, Matrix3<f64>) {
    let u = 1.0 - r;
    let (w, w1, w2) = (u * u * u, -3.0 * u * u, 6.0 * u);
    (w, dr * w1, dr * dr.transpose() * w2 + hr * w1)
}

/// `hess d^2 / 2` for the distance to a facet of normal `n`, by where its nearest point lies:
/// `n n^T` over the face (only the height above the plane changes), `I - t t^T` over an edge
/// of direction `t`, `I` at a corner. Multiplied by 2 it is `hess d^2`.
fn feature_hessian(feature: Feature, n: &Vector3<f64>) -> Matrix3<f64> {
    2.0 * match feature {
        Feature::Face => n * n.transpose(),
        Feature::Edge(t) => Matrix3::identity() - t * t.transpose(),
        Feature::Vertex => Matrix3::identity(),
    }
}

/// How far apart the kinks of the surface's curved faces lie (mm), the blend's support
/// **(choice)**: over every edge two facets share at an angle between [`SMALLEST_CREASE`] and
/// [`LARGEST_SMOOTH_CREASE`], the nearer of the two facets' far corners from the edge (the
/// smaller altitude onto it), and of those the median. A normal blended over that distance
/// turns through a crease's angle across the facets on either side, as the curved face it
/// approximates does; a support as long as the long thin facets of a flat face beside a
/// fillet would round the fillet's neighbourhood far more. `None` where the surface has no
/// such crease (flat, or only sharp edges).
fn crease_spacing(
    surface: &TriangleSurface,
    edges: &HashMap<[usize; 2], Vec<usize>>,
) -> Option<f64> {
    let mut spacings: Vec<f64> = edges
        .iter()
        .filter_map(|(&[i, j], facets)| {
            let &[k, l] = facets.as_slice() else {
                return None;
            };
            let angle = surface
                .normal(k)
                .dot(&surface.normal(l))
                .clamp(-1.0, 1.0)
                .acos();
            (SMALLEST_CREASE..=LARGEST_SMOOTH_CREASE)
                .contains(&angle)
                .then(|| altitude(surface, k, [i, j]).min(altitude(surface, l, [i, j])))
        })
        .collect();
    if spacings.is_empty() {
        return None;
    }
    spacings.sort_by(f64::total_cmp);
    Some(spacings[spacings.len() / 2])
}

/// The distance of triangle `k`'s corner off the edge `[i, j]` from that edge's line.
fn altitude(surface: &TriangleSurface, k: usize, [i, j]: [usize; 2]) -> f64 {
    let (a, b, c) = (
        surface.vertices[i],
        surface.vertices[j],
        surface.vertices[far_corner(surface, k, [i, j])],
    );
    (b - a).cross(&(c - a)).norm() / (b - a).norm()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::{
        double_dome_die, double_dome_die_shape, double_dome_punch, double_dome_punch_shape,
        hemisphere_die, hemisphere_punch, DieShape,
    };
    use std::f64::consts::PI;

    fn all(surface: &TriangleSurface) -> Vec<usize> {
        (0..surface.triangles.len()).collect()
    }

    /// A flat square cut into long thin triangles and a fan: the blend is the plane.
    #[test]
    fn on_a_flat_face_the_blend_is_the_plane() {
        let mut vertices = vec![Vector3::new(0.0, 0.0, 2.0)];
        let n = 40;
        for i in 0..n {
            let a = 2.0 * PI * i as f64 / n as f64;
            let r = if i % 2 == 0 { 30.0 } else { 3.0 };
            vertices.push(Vector3::new(r * a.cos(), r * a.sin(), 2.0));
        }
        let triangles = (0..n).map(|i| [0, 1 + i, 1 + (i + 1) % n]).collect();
        let surface = TriangleSurface {
            vertices,
            triangles,
        };
        let blend = BlendedSurface::with_support(&surface, 5.0);
        for y in [
            Vector3::new(0.3, -0.7, 2.4),
            Vector3::new(2.5, 0.1, 1.9),
            Vector3::new(-1.0, 1.0, 3.0),
        ] {
            let d = blend.distance(&surface, &all(&surface), &y).unwrap();
            assert!((d.value - (y.z - 2.0)).abs() < 1e-12, "{y}: {}", d.value);
            assert!((d.gradient - Vector3::z()).norm() < 1e-12, "{y}");
            assert!(d.hessian.norm() < 1e-12, "{y}");
        }
    }

    /// Past the inner rim of a flat holder (an open edge), below its top, a point is beside
    /// the holder, not in it; above the top, no nearer than the plane; over the plate, at its
    /// height.
    #[test]
    fn past_an_open_edge_the_tool_ends_in_a_wall() {
        let holder = crate::contact::blank_holder(20.0, 60.0, 2.0).unwrap();
        let blend = BlendedSurface::new(&holder, 0.3);
        let at = |y: Vector3<f64>| blend.distance(&holder, &all(&holder), &y).unwrap();
        // the rim is a polygon inscribed in r = 20: distances within its sagitta; beside the
        // rim the facets that touch it at a corner only still count with their plane
        // (-0.1 here), so the value lies between that and the wall's 0.2, outside the tool
        let beside = at(Vector3::new(19.8, 0.0, -0.1));
        assert!(
            beside.value > 0.0 && beside.value < 0.21,
            "{}",
            beside.value
        );
        let above = at(Vector3::new(19.8, 0.0, 0.15));
        // likewise between the plane's 0.15 and the rim's 0.25
        assert!(above.value > 0.15 && above.value < 0.26, "{}", above.value);
        let over = at(Vector3::new(30.0, 1.0, 0.2));
        assert!((over.value - 0.2).abs() < 1e-12, "{}", over.value);
    }

    /// The gradient is the derivative of the value and the Hessian that of the gradient
    /// (central differences), over faces, edges and corners of a faceted cap and a die's
    /// fillet.
    #[test]
    fn gradient_and_hessian_are_the_derivatives_of_the_blend() {
        let punch = hemisphere_punch(20.0, 2.0).unwrap();
        let die = hemisphere_die(12.0, 5.0, 40.0, 20.0, 1.5).unwrap();
        let mut points = Vec::new();
        for (surface, lift) in [(&punch, 0.3), (&die, 0.4)] {
            for k in (0..surface.triangles.len()).step_by(37).take(12) {
                let [a, b, c] = surface.triangles[k].map(|i| surface.vertices[i]);
                let n = surface.normal(k);
                // a face's centre, near an edge, near a corner: off the boundaries between
                // the regions of a facet's nearest point, where hess d^2 jumps
                for q in [
                    (a + b + c) / 3.0,
                    a * 0.47 + b * 0.47 + c * 0.06,
                    a * 0.96 + b * 0.02 + c * 0.02,
                ] {
                    points.push((surface, q + n * lift));
                }
            }
        }
        // past the die's open edges, in front of its patches: the top of its wall (r = 12,
        // up to z = 20) and its outer rim (r = 40)
        for around in [0.3f64, 2.1, 4.4] {
            let (c, s) = (around.cos(), around.sin());
            points.push((&die, Vector3::new(11.7 * c, 11.7 * s, 20.3)));
            points.push((&die, Vector3::new(40.3 * c, 40.3 * s, -0.2)));
        }
        let blends = [
            BlendedSurface::with_support(&punch, 2.5),
            BlendedSurface::with_support(&die, 2.5),
        ];
        for (i, (surface, y)) in points.into_iter().enumerate() {
            let blend = &blends[usize::from(std::ptr::eq(surface, &die))];
            let at = |z: Vector3<f64>| blend.distance(surface, &all(surface), &z).unwrap();
            let d = at(y);
            let h = 1e-6;
            for j in 0..3 {
                let mut step = Vector3::zeros();
                step[j] = h;
                let (plus, minus) = (at(y + step), at(y - step));
                let slope = (plus.value - minus.value) / (2.0 * h);
                assert!((slope - d.gradient[j]).abs() < 1e-7, "{i} {j}");
                let column = (plus.gradient - minus.gradient) / (2.0 * h);
                let error = (column - d.hessian.column(j)).norm();
                assert!(error < 1e-5 * (1.0 + d.hessian.norm()), "{i} {j}: {error}");
            }
            assert!((d.hessian - d.hessian.transpose()).norm() < 1e-12);
        }
    }

    /// The blend of the facets of the tutorial's hemisphere punch and die (examples/
    /// hemisphere.toml: punch radius 40, die opening 42 with a 5 mm fillet, 3 mm facets)
    /// against the exact surfaces they were cut from, at points 0.1 to 0.5 mm in front of
    /// them (where the contact acts): the distance within half the facets' largest sagitta
    /// `L^2 / 8 R` (`L` the longest edge, `R` the smallest radius of curvature; the facets' own
    /// error is one sagitta), the normal within 0.35 of the largest angle between neighbouring
    /// facets (the facets' own error is that angle). Measured: 0.36 and 0.11 of the sagitta,
    /// 0.29 and 0.22 of the angle.
    #[test]
    fn the_blend_of_the_built_in_tools_is_near_their_exact_surfaces() {
        let resolution = 3.0;
        let die = DieShape {
            opening_radius: 42.0,
            fillet_radius: 5.0,
            outer_radius: 90.0,
            depth: 45.0,
        };
        let cases = [
            (
                double_dome_punch(0.0, 40.0, 40.0, resolution).unwrap(),
                double_dome_punch_shape(0.0, 40.0, 40.0).unwrap(),
                40.0,
            ),
            (
                double_dome_die(0.0, &die, resolution).unwrap(),
                double_dome_die_shape(0.0, &die).unwrap(),
                5.0,
            ),
        ];
        for (surface, exact, radius) in cases {
            let longest = longest_edge(&surface);
            let sagitta = longest * longest / (8.0 * radius);
            let widest = largest_crease(&surface);
            let blend = BlendedSurface::new(&surface, 1.0);
            let (mut distance_error, mut angle_error) = (0.0f64, 0.0f64);
            let pieces = exact.pieces().len();
            for (index, piece) in exact.pieces().iter().enumerate() {
                // away from the open ends of the surface (the die's outer rim, the top of its
                // wall, the foot of the punch's skirt), where it stops, not curves
                let from = if index == 0 && pieces == 3 { 0.8 } else { 0.0 };
                let to = if index + 1 == pieces { 0.5 } else { 1.0 };
                for i in 0..=400 {
                    let f = from + (to - from) * i as f64 / 400.0;
                    let [r, z] = piece.point_at(f);
                    let around = 2.0 * PI * (i as f64 * 0.618_034).fract();
                    let rough = Vector3::new(r * around.cos(), r * around.sin(), z);
                    let foot = exact.nearest(&rough);
                    let off = 0.1 + 0.4 * (i as f64 * 0.381_966).fract();
                    let y = foot.point + foot.normal * off;
                    let truth = exact.nearest(&y);
                    let d = blend.distance(&surface, &all(&surface), &y).unwrap();
                    distance_error = distance_error.max((d.value - truth.distance).abs());
                    let cos = d.gradient.normalize().dot(&truth.normal).clamp(-1.0, 1.0);
                    angle_error = angle_error.max(cos.acos());
                }
            }
            eprintln!(
                "R {radius}: distance error {distance_error:.4} mm (sagitta {sagitta:.4}), \
                 normal {:.3}° (largest crease {:.3}°), support {:.3} mm",
                angle_error.to_degrees(),
                widest.to_degrees(),
                blend.support()
            );
            assert!(
                distance_error < 0.5 * sagitta,
                "{distance_error} against {sagitta}"
            );
            assert!(
                angle_error < 0.35 * widest,
                "{angle_error} against {widest}"
            );
        }
    }

    /// Over the die's plate, in front of it by half a ply, the blend stands proud of the plate
    /// by at most a thousandth of the facets' size (measured: 1e-16 mm on 1 mm facets, 1.3e-3
    /// mm on 3 mm facets, where a blend of the facets' planes stood 0.1 mm proud): the
    /// fillet's patches leave the plate tangentially (their corners on the plate's edge take
    /// its normal), so a holder whose rim sits at the fillet's start presses the sheet on a
    /// flat plate, not on a ridge. Beyond the support from the fillet it is the plate exactly.
    #[test]
    fn a_flat_face_meeting_a_fillet_stays_flat() {
        for resolution in [1.0, 3.0] {
            let die = hemisphere_die(42.0, 5.0, 90.0, 45.0, resolution).unwrap();
            let blend = BlendedSurface::new(&die, 0.3);
            let (mut lowest, mut beyond) = (f64::INFINITY, 0.0f64);
            for i in 0..2000 {
                let r = 47.0 + 13.0 * i as f64 / 2000.0;
                let around = 2.0 * PI * (i as f64 * 0.618_034).fract();
                let y = Vector3::new(r * around.cos(), r * around.sin(), -0.155);
                let d = blend.distance(&die, &all(&die), &y).unwrap();
                lowest = lowest.min(d.value - 0.155);
                if r > 47.0 + 2.0 * blend.support() {
                    beyond = beyond.max((d.value - 0.155).abs());
                }
            }
            assert!(
                lowest > -1e-3 * resolution,
                "{resolution} mm facets: {lowest} mm proud"
            );
            assert!(
                beyond < 1e-12,
                "{resolution} mm facets: {beyond} mm off the plate"
            );
        }
    }

    /// A surface whose facets each carry their own copies of their corners, some a few
    /// 1e-15 mm apart (a seam written twice), blends as the same surface with its corners
    /// shared: the facets meet across their edges either way.
    #[test]
    fn corners_written_twice_are_welded() {
        let shared = hemisphere_punch(20.0, 2.0).unwrap();
        let mut soup = TriangleSurface {
            vertices: Vec::new(),
            triangles: Vec::new(),
        };
        for (k, t) in shared.triangles.iter().enumerate() {
            let first = soup.vertices.len();
            for (c, &v) in t.iter().enumerate() {
                let jitter = if (k + c) % 3 == 0 { 4e-15 } else { 0.0 };
                soup.vertices
                    .push(shared.vertices[v] + Vector3::new(jitter, -jitter, 0.0));
            }
            soup.triangles.push([first, first + 1, first + 2]);
        }
        let (a, b) = (
            BlendedSurface::new(&shared, 0.3),
            BlendedSurface::new(&soup, 0.3),
        );
        assert!((a.support() - b.support()).abs() < 1e-12);
        for i in 0..50 {
            let around = 2.0 * PI * (i as f64 * 0.618_034).fract();
            let up = 0.3 + 0.6 * (i as f64 * 0.381_966).fract();
            let y = Vector3::new(
                21.0 * up.sin() * around.cos(),
                21.0 * up.sin() * around.sin(),
                21.0 * up.cos() - 20.0,
            );
            let (p, q) = (
                a.distance(&shared, &all(&shared), &y).unwrap(),
                b.distance(&soup, &all(&soup), &y).unwrap(),
            );
            assert!(
                (p.value - q.value).abs() < 1e-9,
                "{y}: {} {}",
                p.value,
                q.value
            );
            assert!((p.gradient - q.gradient).norm() < 1e-9, "{y}");
        }
    }

    fn longest_edge(surface: &TriangleSurface) -> f64 {
        surface
            .triangles
            .iter()
            .flat_map(|t| {
                (0..3).map(|e| (surface.vertices[t[e]] - surface.vertices[t[(e + 1) % 3]]).norm())
            })
            .fold(0.0, f64::max)
    }

    /// The largest angle between the normals of two facets sharing an edge.
    fn largest_crease(surface: &TriangleSurface) -> f64 {
        shared_edges(surface)
            .values()
            .filter(|f| f.len() == 2)
            .map(|f| {
                surface
                    .normal(f[0])
                    .dot(&surface.normal(f[1]))
                    .clamp(-1.0, 1.0)
                    .acos()
            })
            .fold(0.0, f64::max)
    }
}
