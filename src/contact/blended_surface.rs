//! A smooth surface over a triangulated tool: the facets' planes blended by moving least
//! squares (docs/model.md §6, "Blended tool surfaces").
//!
//! The contact of a tool read from a file sees, instead of its facets, the zero level of
//!
//! ```text
//! phi(y) = sum_k w_k(y) f_k(y) / sum_k w_k(y),   f_k(y) = n_k . (y - a_k),
//! w_k(y) = W(d_k(y)^2 / h^2),                   W(r) = (1 - r)^3 for r < 1, 0 beyond,
//! ```
//!
//! `f_k` the signed distance of `y` from facet `k`'s plane (unit normal `n_k`, corner `a_k`),
//! `d_k` the distance from `y` to the facet itself and `h` the blend's support
//! ([`BlendedSurface::support`]): the facets' planes blended by weights that fall smoothly to
//! zero at a distance `h` from each facet (Shen, O'Brien and Shewchuk, "Interpolating and
//! approximating implicit surfaces from polygon soup", 2004, with compactly supported weights).
//! `d_k^2` is continuously differentiable in `y` (its gradient is `2 (y - p_k)`, `p_k` the
//! facet's nearest point), so `phi` is, and the contact normal `grad phi` is continuous across
//! the facets' edges. Where every facet within `h` lies in one plane (a flat face, however its
//! triangles are cut), `phi` is that plane's distance exactly.
//!
//! The contact uses `phi` as the node's distance from the tool: the potential `1/2 k (phi -
//! c)^2` has the gradient `k (phi - c) grad phi` and the Hessian `k grad phi grad phi^T +
//! k (phi - c) hess phi`, both given here in closed form; `grad phi` is within a few per cent
//! of a unit vector (exactly one on a flat face).

use super::surface::{closest_feature_on_triangle, Feature, TriangleSurface};
use nalgebra::{Matrix3, Vector3};
use std::collections::HashMap;

/// The blend of a triangulated surface's planes: the support `h` and the open edges of each
/// facet; the facets stay with the tool.
#[derive(Clone, Debug, PartialEq)]
pub struct BlendedSurface {
    support: f64,
    /// Per facet, its edges that no other facet shares (the rim of an open surface): a point
    /// on the edge and the unit normal of the wall through it, in the facet's plane, away from
    /// the facet.
    open_edges: Vec<Vec<(Vector3<f64>, Vector3<f64>)>>,
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
        Self::with_support(surface, crease_spacing(surface).unwrap_or(least).max(least))
    }

    /// The blend over `surface` with the given support `h` (mm).
    pub fn with_support(surface: &TriangleSurface, support: f64) -> Self {
        let mut open_edges = vec![Vec::new(); surface.triangles.len()];
        let mut edges: Vec<_> = shared_edges(surface).into_iter().collect();
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
        Self {
            support,
            open_edges,
        }
    }

    /// `h` (mm): how far from a facet its plane still counts.
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
        // sums of w, of w f, and their gradients and Hessians
        let (mut s, mut ds, mut hs) = (0.0, Vector3::zeros(), Matrix3::zeros());
        let (mut f, mut df, mut hf) = (0.0, Vector3::zeros(), Matrix3::zeros());
        for &k in triangles {
            let [a, b, c] = surface.triangles[k].map(|i| surface.vertices[i]);
            let (p, feature) = closest_feature_on_triangle(y, &a, &b, &c);
            let r = (y - p).norm_squared() / h2;
            if r >= 1.0 {
                continue;
            }
            let n = (b - a).cross(&(c - a)).normalize();
            let (w, dw, hw) = weight(
                r,
                &((y - p) * (2.0 / h2)),
                &(feature_hessian(feature, &n) / h2),
            );
            let (plane, dplane, hplane) = self.facet_distance(surface, k, y, &p);
            s += w;
            ds += dw;
            hs += hw;
            f += w * plane;
            df += dw * plane + dplane * w;
            hf += hw * plane + dw * dplane.transpose() + dplane * dw.transpose() + hplane * w;
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
    /// Facet `k`'s signed distance `f_k` at `y`, its gradient and Hessian: that of its plane
    /// (a corner `a`, normal `n`), `n . (y - a)`; but where the facet's point `p` nearest to
    /// `y` lies on an open edge of the facet and `y` is past it (the rim of a holder's hole),
    /// that of the tool ending there in a wall square to the facet: with `g > 0` the distance
    /// past the wall (its normal `m`), `sqrt(f^2 + g^2)` in front of the plane (the distance
    /// to the edge, `f` where `g` reaches 0), `g` behind it (as the exact surfaces do beyond a
    /// rim, docs/model.md §6). A sheet sagging into a holder's hole below its top is then
    /// beside the holder, not inside it.
    pub fn facet_distance(
        &self,
        surface: &TriangleSurface,
        k: usize,
        y: &Vector3<f64>,
        p: &Vector3<f64>,
    ) -> (f64, Vector3<f64>, Matrix3<f64>) {
        let n = surface.normal(k);
        let f = n.dot(&(y - surface.vertices[surface.triangles[k][0]]));
        let on_edge = |(e, m): &&(Vector3<f64>, Vector3<f64>)| {
            m.dot(&(p - e)) >= -ON_EDGE * (1.0 + (p - e).norm())
        };
        let past = self.open_edges[k]
            .iter()
            .filter(on_edge)
            .map(|(e, m)| (m.dot(&(y - e)), m))
            .max_by(|x, y| x.0.total_cmp(&y.0));
        match past {
            Some((g, m)) if g > 0.0 && f > 0.0 => {
                let rho = f.hypot(g);
                let direction = (n * f + m * g) / rho;
                let across = n * n.transpose() + m * m.transpose();
                (
                    rho,
                    direction,
                    (across - direction * direction.transpose()) / rho,
                )
            }
            Some((g, m)) if g > 0.0 => (g, *m, Matrix3::zeros()),
            _ => (f, n, Matrix3::zeros()),
        }
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
pub fn crease_spacing(surface: &TriangleSurface) -> Option<f64> {
    let mut spacings: Vec<f64> = shared_edges(surface)
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
        hemisphere_die, hemisphere_punch, DieShape, ProfilePiece,
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
    /// them (where the contact acts): the distance within twice the facets' largest sagitta
    /// `L^2 / 8 R` (`L` the longest edge, `R` the smallest radius of curvature; the facets' own
    /// error is one sagitta), the normal within half the largest angle between neighbouring
    /// facets (the facets' own error is that angle).
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
                    let [r, z] = on_piece(piece, f);
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
                distance_error < 2.0 * sagitta,
                "{distance_error} against {sagitta}"
            );
            assert!(angle_error < 0.5 * widest, "{angle_error} against {widest}");
        }
    }

    /// The point of a profile piece at the fraction `f` of its length.
    fn on_piece(piece: &ProfilePiece, f: f64) -> [f64; 2] {
        match *piece {
            ProfilePiece::Line { from, to } => [
                from[0] + f * (to[0] - from[0]),
                from[1] + f * (to[1] - from[1]),
            ],
            ProfilePiece::Arc {
                centre,
                radius,
                from,
                to,
            } => {
                let a = from + f * (to - from);
                [centre[0] + radius * a.cos(), centre[1] + radius * a.sin()]
            }
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
        let mut sharing: HashMap<[usize; 2], Vec<usize>> = HashMap::new();
        for (k, t) in surface.triangles.iter().enumerate() {
            for e in 0..3 {
                let (i, j) = (t[e], t[(e + 1) % 3]);
                sharing.entry([i.min(j), i.max(j)]).or_default().push(k);
            }
        }
        sharing
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
