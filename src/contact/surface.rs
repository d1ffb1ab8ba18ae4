//! Rigid tool surfaces: triangulated, with outward normals facing the blank.

use nalgebra::{Matrix3, Vector3};
use std::collections::HashMap;

/// A triangulated rigid surface in its own frame (mm). Triangles are counter-clockwise seen
/// from the side the blank is on, so `(b - a) x (c - a)` points towards the blank.
#[derive(Clone, Debug, PartialEq)]
pub struct TriangleSurface {
    pub vertices: Vec<Vector3<f64>>,
    pub triangles: Vec<[usize; 3]>,
}

/// The point of a surface nearest to a query point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Projection {
    /// The nearest point.
    pub point: Vector3<f64>,
    /// Normal there, towards the blank's side: the facet's on a triangulated surface, unit;
    /// on a blended surface ([`super::blended_surface`]) the gradient of its distance, within
    /// a few per cent of unit, so that the contact's potential has the force it gives.
    pub normal: Vector3<f64>,
    /// What the nearest point lies on.
    pub on: Footing,
}

/// What a [`Projection`]'s point lies on: a facet of a triangulated surface, or a smooth
/// surface: a tool's exact one ([`super::swept_profile`]) or one blended over its facets
/// ([`super::blended_surface`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Footing {
    /// Triangle `k` of the surface.
    Facet(usize),
    /// A smooth surface, where the distance is `(x - point) . normal` and `turn` is the
    /// normal's derivative with respect to the query.
    Smooth { turn: Matrix3<f64> },
}

impl Projection {
    /// The direction from the surface to `x` and the signed distance along it. On a
    /// triangulated surface: the unit vector from the nearest point to `x` when `x` is on the
    /// blank's side, so that over an edge or a corner of a faceted convex tool the gap is the
    /// true distance, not its component along one facet's normal (which would read a node
    /// resting on a punch's ridge as a penetration of `t/2 (1 - cos)` of half the facet angle);
    /// the facet's normal when `x` is behind it. On an exact surface: its normal, on either
    /// side.
    pub fn direction_to(&self, x: &Vector3<f64>) -> (Vector3<f64>, f64) {
        let d = x - self.point;
        if matches!(self.on, Footing::Facet(_)) && self.in_front(x) {
            let distance = d.norm();
            (d / distance, distance)
        } else {
            (self.normal, d.dot(&self.normal))
        }
    }

    /// Whether `x` is on the blank's side of the surface (and off it): where, on a
    /// triangulated surface, [`Self::direction_to`] is the unit vector from the nearest point,
    /// not the facet's normal.
    pub fn in_front(&self, x: &Vector3<f64>) -> bool {
        let d = x - self.point;
        d.dot(&self.normal) > 0.0 && d.norm() > 0.0
    }
}

impl TriangleSurface {
    /// Unit normal of triangle `k`, towards the blank's side.
    pub fn normal(&self, k: usize) -> Vector3<f64> {
        let [a, b, c] = self.triangles[k].map(|i| self.vertices[i]);
        (b - a).cross(&(c - a)).normalize()
    }

    /// Smallest and largest corner of the axis-aligned box around the surface.
    pub fn bounds(&self) -> (Vector3<f64>, Vector3<f64>) {
        let mut lo = Vector3::repeat(f64::INFINITY);
        let mut hi = Vector3::repeat(f64::NEG_INFINITY);
        for v in &self.vertices {
            lo = lo.inf(v);
            hi = hi.sup(v);
        }
        (lo, hi)
    }
}

/// How a surface read from a file faces the blank.
#[derive(Clone, Debug, PartialEq)]
pub enum Facing {
    /// Its triangles' normals point towards the blank, as the contact needs.
    Towards,
    /// They all point away: the surface is to be used flipped.
    Away,
}

impl TriangleSurface {
    /// Whether neighbouring triangles agree on the orientation: every edge two triangles share
    /// is run through in opposite directions by them. Returns the first triangle that disagrees
    /// with a neighbour (or shares an edge with more than one other), with the edge.
    pub fn incoherent_triangle(&self) -> Option<(usize, [usize; 2])> {
        let mut directed: HashMap<[usize; 2], usize> = HashMap::new();
        for (k, t) in self.triangles.iter().enumerate() {
            for e in 0..3 {
                let edge = [t[e], t[(e + 1) % 3]];
                if directed.insert(edge, k).is_some() {
                    return Some((k, edge));
                }
            }
        }
        None
    }

    /// Area-weighted mean of `n . side` over the triangles: +1 when every normal points along
    /// `side`, -1 when every one points against it.
    pub fn mean_facing(&self, side: &Vector3<f64>) -> f64 {
        let (mut along, mut total) = (0.0, 0.0);
        for t in &self.triangles {
            let [a, b, c] = t.map(|i| self.vertices[i]);
            let n = (b - a).cross(&(c - a));
            along += n.dot(side);
            total += n.norm();
        }
        along / (total * side.norm())
    }

    /// Checks that the surface is coherently oriented and says whether its normals point to
    /// `blank_side` (the direction from the tool towards the blank), on the area-weighted mean.
    pub fn facing(&self, blank_side: &Vector3<f64>) -> Result<Facing, String> {
        if let Some((k, [a, b])) = self.incoherent_triangle() {
            return Err(format!(
                "triangle {k} runs its edge between vertices {a} and {b} the same way as another                  triangle (or a third triangle shares that edge): the surface's normals are not                  consistently oriented there"
            ));
        }
        Ok(if self.mean_facing(blank_side) >= 0.0 {
            Facing::Towards
        } else {
            Facing::Away
        })
    }

    /// The same surface with every triangle's orientation reversed.
    pub fn flipped(mut self) -> Self {
        for t in &mut self.triangles {
            t.swap(1, 2);
        }
        self
    }
}

/// Nearest point of triangle `(a, b, c)` to `p` (Ericson, Real-Time Collision Detection, 5.1.5).
pub fn closest_point_on_triangle(
    p: &Vector3<f64>,
    a: &Vector3<f64>,
    b: &Vector3<f64>,
    c: &Vector3<f64>,
) -> Vector3<f64> {
    closest_feature_on_triangle(p, a, b, c).0
}

/// Where on a triangle its point nearest to a query lies: what the distance's second
/// derivative depends on (the nearest point slides with the query over a face, along an edge,
/// not at all at a corner).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Feature {
    Vertex,
    /// An edge, with its unit direction.
    Edge(Vector3<f64>),
    Face,
}

/// [`closest_point_on_triangle`] and the [`Feature`] it lies on (Ericson, Real-Time Collision
/// Detection, 5.1.5).
pub fn closest_feature_on_triangle(
    p: &Vector3<f64>,
    a: &Vector3<f64>,
    b: &Vector3<f64>,
    c: &Vector3<f64>,
) -> (Vector3<f64>, Feature) {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(&ap);
    let d2 = ac.dot(&ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return (*a, Feature::Vertex);
    }
    let bp = p - b;
    let d3 = ab.dot(&bp);
    let d4 = ac.dot(&bp);
    if d3 >= 0.0 && d4 <= d3 {
        return (*b, Feature::Vertex);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return (a + ab * (d1 / (d1 - d3)), Feature::Edge(ab.normalize()));
    }
    let cp = p - c;
    let d5 = ab.dot(&cp);
    let d6 = ac.dot(&cp);
    if d6 >= 0.0 && d5 <= d6 {
        return (*c, Feature::Vertex);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return (a + ac * (d2 / (d2 - d6)), Feature::Edge(ac.normalize()));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let bc = c - b;
        return (
            b + bc * ((d4 - d3) / ((d4 - d3) + (d5 - d6))),
            Feature::Edge(bc.normalize()),
        );
    }
    let denom = 1.0 / (va + vb + vc);
    (a + ab * (vb * denom) + ac * (vc * denom), Feature::Face)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn over_an_edge_the_gap_is_the_distance() {
        // two facets meeting at a ridge along y, each tilted by 0.1 rad
        let (c, s) = (0.1f64.cos(), 0.1f64.sin());
        let left = Projection {
            point: Vector3::zeros(),
            normal: Vector3::new(-s, 0.0, c),
            on: Footing::Facet(0),
        };
        let above = Vector3::new(0.0, 0.0, 0.5);
        let (n, gap) = left.direction_to(&above);
        assert!((gap - 0.5).abs() < 1e-15 && (n - Vector3::z()).norm() < 1e-15);
        let behind = Vector3::new(0.0, 0.0, -0.5);
        let (n, gap) = left.direction_to(&behind);
        assert!((gap + 0.5 * c).abs() < 1e-15 && n == left.normal);
    }

    /// A unit square in z = 0 as two triangles, normals +z.
    fn square() -> TriangleSurface {
        TriangleSurface {
            vertices: vec![
                Vector3::zeros(),
                Vector3::x(),
                Vector3::new(1.0, 1.0, 0.0),
                Vector3::y(),
            ],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
        }
    }

    #[test]
    fn facing_and_flipping() {
        let up = square();
        assert_eq!(up.facing(&Vector3::z()), Ok(Facing::Towards));
        assert_eq!(up.facing(&-Vector3::z()), Ok(Facing::Away));
        assert!((up.mean_facing(&Vector3::z()) - 1.0).abs() < 1e-15);
        let down = up.flipped();
        assert!((down.mean_facing(&Vector3::z()) + 1.0).abs() < 1e-15);
        assert_eq!(down.facing(&-Vector3::z()), Ok(Facing::Towards));
    }

    #[test]
    fn an_incoherent_surface_is_refused_with_the_triangle() {
        let mut bad = square();
        bad.triangles[1] = [0, 3, 2];
        let e = bad.facing(&Vector3::z()).unwrap_err();
        assert!(
            e.starts_with("triangle 1 runs its edge between vertices"),
            "{e}"
        );
        assert!(square().incoherent_triangle().is_none());
    }

    #[test]
    fn closest_point_regions_of_a_triangle() {
        let (a, b, c) = (Vector3::zeros(), Vector3::x(), Vector3::y());
        let inside = closest_point_on_triangle(&Vector3::new(0.2, 0.3, 5.0), &a, &b, &c);
        assert!((inside - Vector3::new(0.2, 0.3, 0.0)).norm() < 1e-15);
        let corner = closest_point_on_triangle(&Vector3::new(-1.0, -1.0, 1.0), &a, &b, &c);
        assert!(corner.norm() < 1e-15);
        let edge = closest_point_on_triangle(&Vector3::new(1.0, 1.0, 0.0), &a, &b, &c);
        assert!((edge - Vector3::new(0.5, 0.5, 0.0)).norm() < 1e-15);
    }
}
