//! Closed plane polygons (the last vertex joins the first): area, winding, inside/outside,
//! distance to the edge, crossing edges, resampling and the mitre offset that adds the margin.

use nalgebra::Vector2;

/// A closed polygon: its vertices in order, the closing edge implied.
pub type Polygon = Vec<Vector2<f64>>;

/// Longest mitre of [`offset_mitre`], in margins: a sharp corner (turning by more than about
/// 150°) is clipped there instead of shooting a spike out (SVG's default miter limit).
pub const MITRE_LIMIT: f64 = 4.0;

/// The edges `(a, b)` in order, the closing one last.
pub fn edges(p: &[Vector2<f64>]) -> impl Iterator<Item = (Vector2<f64>, Vector2<f64>)> + '_ {
    (0..p.len()).map(move |k| (p[k], p[(k + 1) % p.len()]))
}

/// Signed area (mm²): positive for a counter-clockwise polygon (the shoelace formula).
pub fn signed_area(p: &[Vector2<f64>]) -> f64 {
    0.5 * edges(p).map(|(a, b)| a.x * b.y - a.y * b.x).sum::<f64>()
}

/// The length of the boundary (mm).
pub fn perimeter(p: &[Vector2<f64>]) -> f64 {
    edges(p).map(|(a, b)| (b - a).norm()).sum()
}

/// The area centroid (mm); the vertices' mean for a polygon without area.
pub fn centroid(p: &[Vector2<f64>]) -> Vector2<f64> {
    let area = signed_area(p);
    if area.abs() < f64::EPSILON {
        return p.iter().sum::<Vector2<f64>>() / p.len().max(1) as f64;
    }
    let sum: Vector2<f64> = edges(p)
        .map(|(a, b)| (a + b) * (a.x * b.y - a.y * b.x))
        .sum();
    sum / (6.0 * area)
}

/// The polygon counter-clockwise: reversed when it turns the other way. The offset and the
/// signed distance count "outward" from a counter-clockwise polygon.
pub fn counter_clockwise(mut p: Polygon) -> Polygon {
    if signed_area(&p) < 0.0 {
        p.reverse();
    }
    p
}

/// Whether `q` lies inside (crossing number: a horizontal ray from `q` crosses the boundary an
/// odd number of times); either winding.
pub fn contains(p: &[Vector2<f64>], q: &Vector2<f64>) -> bool {
    let mut inside = false;
    for (a, b) in edges(p) {
        if (a.y > q.y) != (b.y > q.y) {
            let x = a.x + (q.y - a.y) / (b.y - a.y) * (b.x - a.x);
            if q.x < x {
                inside = !inside;
            }
        }
    }
    inside
}

/// Distance (mm) from `q` to the segment `a b`.
pub fn segment_distance(q: &Vector2<f64>, a: &Vector2<f64>, b: &Vector2<f64>) -> f64 {
    let ab = b - a;
    let length2 = ab.norm_squared();
    let t = if length2 > 0.0 {
        ((q - a).dot(&ab) / length2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (q - (a + t * ab)).norm()
}

/// Distance (mm) from `q` to the boundary, positive inside and negative outside: how far
/// inside the blank's edge a point lies.
pub fn signed_distance(p: &[Vector2<f64>], q: &Vector2<f64>) -> f64 {
    let d = edges(p)
        .map(|(a, b)| segment_distance(q, &a, &b))
        .fold(f64::INFINITY, f64::min);
    if contains(p, q) {
        d
    } else {
        -d
    }
}

/// Whether the segments `a b` and `c d` cross or touch.
fn segments_meet(a: &Vector2<f64>, b: &Vector2<f64>, c: &Vector2<f64>, d: &Vector2<f64>) -> bool {
    let side = |p: &Vector2<f64>, q: &Vector2<f64>, r: &Vector2<f64>| {
        let v = (q - p).perp(&(r - p));
        // a point within rounding of the line counts as on it
        let scale = (q - p).norm() * (r - p).norm();
        if v.abs() <= 1e-12 * scale {
            0.0
        } else {
            v.signum()
        }
    };
    let within = |p: &Vector2<f64>, q: &Vector2<f64>, r: &Vector2<f64>| {
        r.x >= p.x.min(q.x) && r.x <= p.x.max(q.x) && r.y >= p.y.min(q.y) && r.y <= p.y.max(q.y)
    };
    let (d1, d2) = (side(c, d, a), side(c, d, b));
    let (d3, d4) = (side(a, b, c), side(a, b, d));
    if d1 * d2 < 0.0 && d3 * d4 < 0.0 {
        return true;
    }
    (d1 == 0.0 && within(c, d, a))
        || (d2 == 0.0 && within(c, d, b))
        || (d3 == 0.0 && within(a, b, c))
        || (d4 == 0.0 && within(a, b, d))
}

/// The first two edges (by their first vertex's index) that cross or touch, neighbours
/// excepted: `None` for a simple polygon. Every pair is tried (n² / 2): a trim line of a few
/// thousand points takes milliseconds.
pub fn first_crossing(p: &[Vector2<f64>]) -> Option<(usize, usize)> {
    let n = p.len();
    for i in 0..n {
        let (a, b) = (p[i], p[(i + 1) % n]);
        for j in i + 2..n {
            if i == 0 && j == n - 1 {
                continue; // the closing edge is the first one's neighbour
            }
            let (c, d) = (p[j], p[(j + 1) % n]);
            if segments_meet(&a, &b, &c, &d) {
                return Some((i, j));
            }
        }
    }
    None
}

/// The polygon with each edge cut into equal pieces no longer than `longest` (mm): a curve
/// given by a few corners is mapped point by point along its edges, not only at the corners.
pub fn resampled(p: &[Vector2<f64>], longest: f64) -> Polygon {
    let mut out = Vec::new();
    for (a, b) in edges(p) {
        let pieces = ((b - a).norm() / longest).ceil().max(1.0) as usize;
        out.extend((0..pieces).map(|k| a + (b - a) * (k as f64 / pieces as f64)));
    }
    out
}

/// The counter-clockwise polygon `p` moved outward by `margin` (mm), a mitre offset: each edge
/// moves `margin` along its outward normal and each vertex goes where its two moved edges meet,
/// along the bisector of their normals, `margin / cos(half the turn)` away, at most
/// [`MITRE_LIMIT`] margins. A square of side a gives the square of side a + 2 margin. Vertices
/// are moved independently: a margin larger than a concave feature folds the result (the caller
/// checks the blank it meshes). Coincident vertices are dropped first.
pub fn offset_mitre(p: &[Vector2<f64>], margin: f64) -> Polygon {
    let p = without_repeats(p);
    let n = p.len();
    let normal = |k: usize| {
        let e = p[(k + 1) % n] - p[k];
        Vector2::new(e.y, -e.x).normalize()
    };
    (0..n)
        .map(|k| {
            let (before, after) = (normal((k + n - 1) % n), normal(k));
            let sum = before + after;
            let along = if sum.norm() < 1e-9 {
                // the boundary turns back on itself: no bisector, move along one edge's normal
                before * margin
            } else {
                let bisector = sum.normalize();
                let stretch = (1.0 / bisector.dot(&after)).min(MITRE_LIMIT);
                bisector * (margin * stretch)
            };
            p[k] + along
        })
        .collect()
}

/// `p` without vertices that repeat the one before (the last compared with the first).
fn without_repeats(p: &[Vector2<f64>]) -> Polygon {
    let scale = p.iter().map(|v| v.norm()).fold(1.0, f64::max);
    let mut out: Polygon = Vec::with_capacity(p.len());
    for v in p {
        if out
            .last()
            .is_none_or(|last| (v - last).norm() > 1e-12 * scale)
        {
            out.push(*v);
        }
    }
    while out.len() > 1 && (out[0] - out[out.len() - 1]).norm() <= 1e-12 * scale {
        out.pop();
    }
    out
}

/// Whether every ray from `centre` crosses the boundary once, counter-clockwise: each edge
/// turns positively about it (the centre lies in the polygon's kernel). The blank's mesher
/// needs it.
pub fn star_shaped_about(p: &[Vector2<f64>], centre: &Vector2<f64>) -> bool {
    edges(p).all(|(a, b)| (a - centre).perp(&(b - centre)) > 0.0)
}

/// Where the ray from `centre` towards `direction` leaves the polygon: the farthest crossing
/// (mm from the centre along the unit direction); `None` if it crosses no edge.
pub fn ray_exit(
    p: &[Vector2<f64>],
    centre: &Vector2<f64>,
    direction: &Vector2<f64>,
) -> Option<f64> {
    let mut best: Option<f64> = None;
    for (a, b) in edges(p) {
        let e = b - a;
        let denominator = direction.perp(&e);
        if denominator.abs() < 1e-15 {
            continue;
        }
        let w = a - centre;
        let t = w.perp(&e) / denominator;
        let s = w.perp(direction) / denominator;
        if t >= 0.0 && (-1e-12..=1.0 + 1e-12).contains(&s) {
            best = Some(best.map_or(t, |b: f64| b.max(t)));
        }
    }
    best
}

/// Smallest distance (mm) from `q` to the boundary.
pub fn boundary_distance(p: &[Vector2<f64>], q: &Vector2<f64>) -> f64 {
    signed_distance(p, q).abs()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn square(a: f64) -> Polygon {
        let h = 0.5 * a;
        vec![
            Vector2::new(-h, -h),
            Vector2::new(h, -h),
            Vector2::new(h, h),
            Vector2::new(-h, h),
        ]
    }

    fn circle(r: f64, n: usize) -> Polygon {
        (0..n)
            .map(|k| {
                let t = 2.0 * PI * k as f64 / n as f64;
                Vector2::new(r * t.cos(), r * t.sin())
            })
            .collect()
    }

    #[test]
    fn a_square_offset_by_a_mitre_is_the_square_of_side_a_plus_two_margins() {
        let (a, m) = (30.0, 4.0);
        let out = offset_mitre(&square(a), m);
        assert!((signed_area(&out) - (a + 2.0 * m).powi(2)).abs() < 1e-9);
        // each corner at the corner of the bigger square
        assert!((out[2] - Vector2::new(19.0, 19.0)).norm() < 1e-12);
    }

    #[test]
    fn a_circle_offset_grows_its_radius_by_the_margin() {
        let out = offset_mitre(&circle(50.0, 720), 5.0);
        for v in &out {
            // vertices of the inscribed polygon: R + m / cos(pi / n)
            assert!((v.norm() - 55.0).abs() < 1e-3, "{}", v.norm());
        }
    }

    #[test]
    fn a_mitre_is_clipped_at_a_spike() {
        let spike = vec![
            Vector2::new(0.0, 0.0),
            Vector2::new(100.0, 0.0),
            Vector2::new(0.0, 1.0),
        ];
        let out = offset_mitre(&spike, 1.0);
        assert!((out[1] - spike[1]).norm() <= MITRE_LIMIT + 1e-12);
    }

    #[test]
    fn the_area_and_winding_of_a_square() {
        let s = square(2.0);
        assert!((signed_area(&s) - 4.0).abs() < 1e-15);
        let mut r = s.clone();
        r.reverse();
        assert!((signed_area(&r) + 4.0).abs() < 1e-15);
        assert!((signed_area(&counter_clockwise(r)) - 4.0).abs() < 1e-15);
        assert!((perimeter(&s) - 8.0).abs() < 1e-15);
        assert!(centroid(&s).norm() < 1e-15);
    }

    #[test]
    fn points_inside_and_outside_a_concave_polygon() {
        // an L: the notch at the top right is outside
        let l = vec![
            Vector2::new(0.0, 0.0),
            Vector2::new(2.0, 0.0),
            Vector2::new(2.0, 1.0),
            Vector2::new(1.0, 1.0),
            Vector2::new(1.0, 2.0),
            Vector2::new(0.0, 2.0),
        ];
        assert!(contains(&l, &Vector2::new(0.5, 0.5)));
        assert!(contains(&l, &Vector2::new(0.5, 1.5)));
        assert!(contains(&l, &Vector2::new(1.5, 0.5)));
        assert!(!contains(&l, &Vector2::new(1.5, 1.5)));
        assert!(!contains(&l, &Vector2::new(-0.1, 0.5)));
        assert!((signed_distance(&l, &Vector2::new(0.5, 0.25)) - 0.25).abs() < 1e-15);
        assert!((signed_distance(&l, &Vector2::new(1.5, 1.25)) + 0.25).abs() < 1e-15);
        assert!((boundary_distance(&l, &Vector2::new(1.5, 1.25)) - 0.25).abs() < 1e-15);
    }

    #[test]
    fn a_figure_eight_crosses_itself_and_a_square_does_not() {
        assert_eq!(first_crossing(&square(1.0)), None);
        let bow = vec![
            Vector2::new(0.0, 0.0),
            Vector2::new(1.0, 1.0),
            Vector2::new(1.0, 0.0),
            Vector2::new(0.0, 1.0),
        ];
        assert_eq!(first_crossing(&bow), Some((0, 2)));
    }

    #[test]
    fn resampling_keeps_the_corners_and_cuts_the_edges() {
        let r = resampled(&square(10.0), 3.0);
        assert_eq!(r.len(), 16);
        assert!((perimeter(&r) - 40.0).abs() < 1e-12);
        assert_eq!(r[0], Vector2::new(-5.0, -5.0));
        assert_eq!(r[4], Vector2::new(5.0, -5.0));
    }

    #[test]
    fn star_shape_and_rays_of_a_circle() {
        let c = circle(10.0, 64);
        assert!(star_shaped_about(&c, &Vector2::new(3.0, 0.0)));
        assert!(!star_shaped_about(&c, &Vector2::new(30.0, 0.0)));
        let d = ray_exit(&c, &Vector2::zeros(), &Vector2::new(0.6, 0.8)).unwrap();
        assert!(d <= 10.0 && d > 10.0 * (PI / 64.0).cos());
    }
}
