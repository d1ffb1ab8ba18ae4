//! The exact surface of a built-in tool (docs/model.md §6, "Exact tool surfaces"): a profile of
//! straight lines and circular arcs in the meridian half-plane `(r, z)`, swept around the
//! stroke axis or around the ridge segment `|x| <= half_length`, `y = 0` of the double dome
//! (`r` is then the distance from that segment in the blank's plane).
//!
//! Contact against the triangulated tool sees an edge between two facets as a ridge of zero
//! radius: a node sliding over it turns its normal through the facets' angle within a
//! fraction of a millimetre, and Newton's method can cycle there. The exact surface is smooth
//! (tangent-continuous where its profile is), so the nearest point, the normal and the normal's
//! turn (the surface's curvature) all vary continuously with the node. The triangulation still
//! bounds the tool for the run's checks and its memory estimate.

use nalgebra::{Matrix3, Vector3};

/// One piece of a profile, in the direction whose left normal `(-z', r')` faces the blank.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ProfilePiece {
    /// A straight line from `from` to `to`, `(r, z)` in mm.
    Line { from: [f64; 2], to: [f64; 2] },
    /// A circular arc about `centre` of `radius`, from the angle `from` to the angle `to`
    /// (rad, measured from `+r` towards `+z`; less than a full turn apart).
    Arc {
        centre: [f64; 2],
        radius: f64,
        from: f64,
        to: f64,
    },
}

impl ProfilePiece {
    /// The point `(r, z)` at the fraction `f` of the piece (of its length along a line, of its
    /// angle along an arc).
    pub fn point_at(&self, f: f64) -> [f64; 2] {
        match *self {
            ProfilePiece::Line { from, to } => [
                from[0] + f * (to[0] - from[0]),
                from[1] + f * (to[1] - from[1]),
            ],
            ProfilePiece::Arc {
                centre,
                radius,
                from,
                to,
            } => on_circle(centre, radius, from + f * (to - from)),
        }
    }
}

/// The point of a smooth surface nearest to a query, with what the contact needs of it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    pub point: Vector3<f64>,
    /// Unit normal, towards the blank's side; in front of the surface it is the direction from
    /// `point` to the query.
    pub normal: Vector3<f64>,
    /// Signed distance of the query along `normal`.
    pub distance: f64,
    /// `d normal / d query`: how the normal turns as the query moves (symmetric; its
    /// eigenvalues are `kappa / (1 + kappa d)` for the principal curvatures `kappa`).
    pub turn: Matrix3<f64>,
}

/// A tool's exact surface: a profile swept around an axis or a ridge segment, lifted by `lift`
/// along `z`.
#[derive(Clone, Debug, PartialEq)]
pub struct SweptProfile {
    pieces: Vec<ProfilePiece>,
    half_length: f64,
    lift: f64,
}

/// Below this distance (mm) from the axis or ridge a query is on it: its radial direction is
/// then any horizontal one.
const ON_AXIS: f64 = 1e-12;

/// The nearest point of one profile piece to a point of the meridian plane.
#[derive(Clone, Copy, Debug)]
struct PieceFoot {
    point: [f64; 2],
    /// Unit left normal of the piece there.
    normal: [f64; 2],
    /// Curvature in the meridian plane, positive where the surface bends away from the blank
    /// (convex seen from it).
    curvature: f64,
    /// Which end of the piece holds the nearest point, where it is clamped to one.
    end: Option<PieceEnd>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum PieceEnd {
    Start,
    Finish,
}

impl ProfilePiece {
    /// Where the piece starts.
    pub fn start(&self) -> [f64; 2] {
        match *self {
            ProfilePiece::Line { from, .. } => from,
            ProfilePiece::Arc {
                centre,
                radius,
                from,
                ..
            } => on_circle(centre, radius, from),
        }
    }

    /// Where the piece ends.
    pub fn finish(&self) -> [f64; 2] {
        match *self {
            ProfilePiece::Line { to, .. } => to,
            ProfilePiece::Arc {
                centre, radius, to, ..
            } => on_circle(centre, radius, to),
        }
    }

    fn foot(&self, q: [f64; 2]) -> PieceFoot {
        match *self {
            ProfilePiece::Line { from, to } => line_foot(from, to, q),
            ProfilePiece::Arc {
                centre,
                radius,
                from,
                to,
            } => arc_foot(centre, radius, (from, to), q),
        }
    }
}

/// The point of the circle at `angle`, coordinates within rounding of zero made zero: an arc
/// from 90° starts on the axis (`r = 0`), not 6e-17 off it.
fn on_circle(c: [f64; 2], radius: f64, angle: f64) -> [f64; 2] {
    let snap = |v: f64| if v.abs() < 1e-12 * radius { 0.0 } else { v };
    [
        snap(c[0] + radius * angle.cos()),
        snap(c[1] + radius * angle.sin()),
    ]
}

fn line_foot(a: [f64; 2], b: [f64; 2], q: [f64; 2]) -> PieceFoot {
    let ab = [b[0] - a[0], b[1] - a[1]];
    let length = ab[0].hypot(ab[1]);
    let t = [ab[0] / length, ab[1] / length];
    let along = (q[0] - a[0]) * t[0] + (q[1] - a[1]) * t[1];
    let (s, end) = if along <= 0.0 {
        (0.0, Some(PieceEnd::Start))
    } else if along >= length {
        (length, Some(PieceEnd::Finish))
    } else {
        (along, None)
    };
    PieceFoot {
        point: [a[0] + s * t[0], a[1] + s * t[1]],
        normal: [-t[1], t[0]],
        curvature: 0.0,
        end,
    }
}

/// The arc's nearest point: on the ray from the centre through `q` where that ray crosses the
/// arc, the nearer end otherwise. Travelling with `s = sign(to - from)`, the left normal at
/// angle `a` is `-s (cos a, sin a)`: away from the centre (a convex arc) when `s < 0`.
fn arc_foot(c: [f64; 2], radius: f64, (from, to): (f64, f64), q: [f64; 2]) -> PieceFoot {
    let s = (to - from).signum();
    let (lo, hi) = (from.min(to), from.max(to));
    let angle = (q[1] - c[1]).atan2(q[0] - c[0]);
    let unwrapped = lo + (angle - lo).rem_euclid(std::f64::consts::TAU);
    let (a, end) = if unwrapped <= hi {
        (unwrapped, None)
    } else {
        let d2 = |x: f64| {
            let p = on_circle(c, radius, x);
            (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)
        };
        let at_from = d2(from) <= d2(to);
        let end = if at_from {
            PieceEnd::Start
        } else {
            PieceEnd::Finish
        };
        (if at_from { from } else { to }, Some(end))
    };
    PieceFoot {
        point: on_circle(c, radius, a),
        normal: [-s * a.cos(), -s * a.sin()],
        curvature: -s / radius,
        end,
    }
}

impl SweptProfile {
    /// A profile of `pieces`, each starting where the one before it ends, swept around the
    /// ridge segment of `half_length` (the axis when zero).
    pub fn new(pieces: Vec<ProfilePiece>, half_length: f64) -> Self {
        Self {
            pieces,
            half_length,
            lift: 0.0,
        }
    }

    /// The same surface moved by `dz` along the stroke axis.
    pub fn lifted(mut self, dz: f64) -> Self {
        self.lift += dz;
        self
    }

    pub fn pieces(&self) -> &[ProfilePiece] {
        &self.pieces
    }

    pub fn half_length(&self) -> f64 {
        self.half_length
    }

    /// The point of the surface nearest to `y`, its normal, the signed distance and the
    /// normal's turn.
    ///
    /// Beyond an end of the profile that lies off the axis (the rim of a holder's hole) the
    /// surface ends in an edge, a circle: in front of it the normal is the direction from the
    /// edge, turning by `1 / d` across it, as over a faceted tool's edge.
    pub fn nearest(&self, y: &Vector3<f64>) -> SurfacePoint {
        let (base, radial, r) = self.meridian_frame(y);
        let q = [r, y.z - self.lift];
        let (index, foot) = self.nearest_foot(q);
        let edge = self
            .profile_end(index, foot.end)
            .is_some_and(|e| e[0] > 0.0);
        let to_q = [q[0] - foot.point[0], q[1] - foot.point[1]];
        let ahead = to_q[0] * foot.normal[0] + to_q[1] * foot.normal[1];
        let gap = to_q[0].hypot(to_q[1]);
        let (normal2, distance, meridian_turn) = match edge {
            true if ahead > 0.0 && gap > 0.0 => ([to_q[0] / gap, to_q[1] / gap], gap, 1.0 / gap),
            true => beside_the_edge(to_q, foot.normal, ahead),
            false => {
                let k = foot.curvature;
                (foot.normal, ahead, k / (1.0 + k * ahead))
            }
        };
        let lift = Vector3::new(0.0, 0.0, self.lift);
        let in_space = |v: [f64; 2]| radial * v[0] + Vector3::z() * v[1];
        let normal = in_space(normal2);
        let tangent = in_space([normal2[1], -normal2[0]]);
        let turn = tangent * tangent.transpose() * meridian_turn
            + self.hoop_turn(y, (&radial, r), normal2[0], meridian_turn);
        SurfacePoint {
            point: base + lift + in_space(foot.point),
            normal,
            distance,
            turn,
        }
    }

    /// The nearest point of the ridge segment (or axis) to `y` in the blank's plane, the unit
    /// horizontal direction from it to `y` and the distance `r` along it.
    fn meridian_frame(&self, y: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>, f64) {
        let l = self.half_length;
        let base = Vector3::new(y.x.clamp(-l, l), 0.0, 0.0);
        let w = Vector3::new(y.x - base.x, y.y, 0.0);
        let r = w.norm();
        let radial = if r > ON_AXIS {
            w / r
        } else if l > 0.0 {
            Vector3::y()
        } else {
            Vector3::x()
        };
        (base, radial, r)
    }

    fn nearest_foot(&self, q: [f64; 2]) -> (usize, PieceFoot) {
        let squared = |f: &PieceFoot| (f.point[0] - q[0]).powi(2) + (f.point[1] - q[1]).powi(2);
        self.pieces
            .iter()
            .map(|p| p.foot(q))
            .enumerate()
            .min_by(|a, b| squared(&a.1).total_cmp(&squared(&b.1)))
            .expect("a profile has pieces")
    }

    /// The profile's own end at piece `index`'s clamped `end`, if that is one (not a joint
    /// between two pieces).
    fn profile_end(&self, index: usize, end: Option<PieceEnd>) -> Option<[f64; 2]> {
        match end? {
            PieceEnd::Start if index == 0 => Some(self.pieces[0].start()),
            PieceEnd::Finish if index + 1 == self.pieces.len() => Some(self.pieces[index].finish()),
            _ => None,
        }
    }

    /// How the normal turns as `y` moves around the axis (or a cap of the ridge): by
    /// `n_r / r` along the circle through `y`, `n_r` the normal's radial component; not at all
    /// along the ridge's straight sides. On the axis itself every horizontal direction is such
    /// a circle's, and the normal (vertical there) turns as in the meridian.
    fn hoop_turn(
        &self,
        y: &Vector3<f64>,
        (radial, r): (&Vector3<f64>, f64),
        normal_r: f64,
        meridian_turn: f64,
    ) -> Matrix3<f64> {
        if self.half_length > 0.0 && y.x.abs() < self.half_length {
            return Matrix3::zeros();
        }
        let hoop = Vector3::z().cross(radial);
        let rate = if r > ON_AXIS {
            normal_r / r
        } else {
            meridian_turn
        };
        hoop * hoop.transpose() * rate
    }
}

/// Behind the surface's level but past its edge (a point in a holder's hole, below its top)
/// the point is beside the tool, not in it: the tool ends there in a wall through the edge,
/// square to the surface, and the distance is the one to that wall, along the surface's
/// outward tangent at the edge. It meets the edge's own distance where `ahead = 0`. Taken as
/// the surface's level instead, a sheet sagging into the hole a millimetre from the rim would
/// be deep inside the tool, pushed by hundreds of newtons.
fn beside_the_edge(to_q: [f64; 2], normal: [f64; 2], ahead: f64) -> ([f64; 2], f64, f64) {
    let along = [to_q[0] - ahead * normal[0], to_q[1] - ahead * normal[1]];
    let past = along[0].hypot(along[1]);
    if past > 0.0 {
        ([along[0] / past, along[1] / past], past, 0.0)
    } else {
        (normal, ahead, 0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::{FRAC_PI_2, PI};

    /// A hemispherical cap of radius 10 (apex at the origin) on a skirt down to z = -15.
    fn punch() -> SweptProfile {
        SweptProfile::new(
            vec![
                ProfilePiece::Arc {
                    centre: [0.0, -10.0],
                    radius: 10.0,
                    from: FRAC_PI_2,
                    to: 0.0,
                },
                ProfilePiece::Line {
                    from: [10.0, -10.0],
                    to: [10.0, -15.0],
                },
            ],
            0.0,
        )
    }

    /// A die plate from r = 30 in to 17, a fillet of radius 5 about (12 + 5, 5), a wall up.
    fn die(half_length: f64) -> SweptProfile {
        SweptProfile::new(
            vec![
                ProfilePiece::Line {
                    from: [30.0, 0.0],
                    to: [17.0, 0.0],
                },
                ProfilePiece::Arc {
                    centre: [17.0, 5.0],
                    radius: 5.0,
                    from: -FRAC_PI_2,
                    to: -PI,
                },
                ProfilePiece::Line {
                    from: [12.0, 5.0],
                    to: [12.0, 20.0],
                },
            ],
            half_length,
        )
    }

    /// On a sphere the distance, normal and turn are those of the sphere: `|y - c| - R`,
    /// `(y - c) / |y - c|`, `(I - n n^T) / |y - c|`, the pole included.
    #[test]
    fn a_cap_is_a_sphere() {
        let shape = punch();
        let centre = Vector3::new(0.0, 0.0, -10.0);
        for y in [
            Vector3::new(0.0, 0.0, 0.3),
            Vector3::new(3.0, -4.0, -1.0),
            Vector3::new(-6.0, 2.0, -4.0),
            Vector3::new(1.0, 1.0, -0.5),
        ] {
            let foot = shape.nearest(&y);
            let from_centre = y - centre;
            let n = from_centre.normalize();
            assert!(
                (foot.distance - (from_centre.norm() - 10.0)).abs() < 1e-12,
                "{y}"
            );
            assert!((foot.normal - n).norm() < 1e-12, "{y}");
            assert!((foot.point - (centre + n * 10.0)).norm() < 1e-12, "{y}");
            let turn = (Matrix3::identity() - n * n.transpose()) / from_centre.norm();
            assert!((foot.turn - turn).norm() < 1e-12, "{y}: {}", foot.turn);
        }
    }

    /// The turn is the derivative of the normal, and the normal that of the distance, over the
    /// die's plate, fillet and wall, around the axis and along the ridge of a double dome, and
    /// beyond the plate's rim.
    #[test]
    fn the_turn_is_the_normals_derivative() {
        let points = [
            (0.0, Vector3::new(20.0, 3.0, -0.4)),
            (0.0, Vector3::new(14.0, 3.0, 1.0)),
            (0.0, Vector3::new(12.0, 5.0, 1.0)),
            (0.0, Vector3::new(10.0, -6.0, 9.0)),
            (8.0, Vector3::new(3.0, 15.5, 0.5)),
            (8.0, Vector3::new(-12.0, 13.0, 1.5)),
            (8.0, Vector3::new(3.0, 13.0, 1.0)),
            (8.0, Vector3::new(-12.0, 12.0, 0.8)),
            (0.0, Vector3::new(0.0, 31.0, -0.5)),
        ];
        for (half_length, y) in points {
            the_normal_and_turn_are_derivatives(&die(half_length), &y);
        }
    }

    /// The normal at `y` is the distance's gradient (central differences) and the turn the
    /// normal's, symmetric and tangent to the surface.
    fn the_normal_and_turn_are_derivatives(shape: &SweptProfile, y: &Vector3<f64>) {
        let foot = shape.nearest(y);
        let h = 1e-6;
        for d in 0..3 {
            let mut step = Vector3::zeros();
            step[d] = h;
            let (plus, minus) = (shape.nearest(&(y + step)), shape.nearest(&(y - step)));
            let slope = (plus.distance - minus.distance) / (2.0 * h);
            assert!((slope - foot.normal[d]).abs() < 1e-7, "{y} {d}");
            let column = (plus.normal - minus.normal) / (2.0 * h);
            let error = (column - foot.turn.column(d)).norm();
            assert!(error < 1e-6, "{y} {d}: {error}, {}", foot.turn);
        }
        assert!((foot.turn - foot.turn.transpose()).norm() < 1e-12);
        assert!((foot.turn * foot.normal).norm() < 1e-12, "{y}");
    }

    /// A holder's plate, `10 <= r <= 30` in `z = 0`, normal `+z`, around a ridge of
    /// `half_length`.
    fn holder(half_length: f64) -> SweptProfile {
        SweptProfile::new(
            vec![ProfilePiece::Line {
                from: [10.0, 0.0],
                to: [30.0, 0.0],
            }],
            half_length,
        )
    }

    /// In the holder's hole below its top, a point is beside the holder, not in it: its
    /// distance is the one to the hole's wall (`10 - r`), its normal points away from the
    /// wall, and the two agree with the edge's own where the point is level with the top;
    /// above the plate and behind it the plate's distance holds.
    #[test]
    fn below_the_top_in_a_holders_hole_the_distance_is_to_the_wall() {
        let shape = holder(0.0);
        let beside = shape.nearest(&Vector3::new(0.0, -8.64, -0.155));
        assert!(
            (beside.distance - 1.36).abs() < 1e-12,
            "{}",
            beside.distance
        );
        assert!((beside.normal - Vector3::new(0.0, 1.0, 0.0)).norm() < 1e-12);
        let level = shape.nearest(&Vector3::new(0.0, -8.64, 0.0));
        assert!((level.distance - 1.36).abs() < 1e-12);
        assert!((level.normal - beside.normal).norm() < 1e-12);
        let on_plate = shape.nearest(&Vector3::new(0.0, -12.0, -0.155));
        assert!((on_plate.distance + 0.155).abs() < 1e-12);
        assert!((on_plate.normal - Vector3::z()).norm() < 1e-12);
        for (half_length, y) in [
            (0.0, Vector3::new(3.0, -8.0, -0.4)),
            (0.0, Vector3::new(6.0, 7.0, -2.0)),
            (8.0, Vector3::new(2.0, 9.0, -0.3)),
            (8.0, Vector3::new(-11.0, -5.0, -0.6)),
        ] {
            let shape = holder(half_length);
            let foot = shape.nearest(&y);
            assert!(foot.distance > 0.0, "{y}: {}", foot.distance);
            assert_eq!(foot.normal.z, 0.0, "{y}");
            the_normal_and_turn_are_derivatives(&shape, &y);
        }
    }

    /// The nearest point is that of a dense sampling of the surface, and off the axis the
    /// distance is the least distance to it.
    #[test]
    fn the_nearest_point_is_the_nearest_of_a_dense_sampling() {
        let shape = die(8.0);
        let y = Vector3::new(9.0, 12.9, 1.0);
        let foot = shape.nearest(&y);
        let mut best = f64::INFINITY;
        for piece in shape.pieces() {
            for i in 0..=2000 {
                let f = i as f64 / 2000.0;
                let [r, z] = piece.point_at(f);
                for j in 0..=200 {
                    let a = -FRAC_PI_2 + PI * j as f64 / 200.0;
                    let p = Vector3::new(8.0 + r * a.cos(), r * a.sin(), z);
                    best = best.min((y - p).norm());
                }
            }
        }
        assert!(foot.distance > 0.0);
        assert!(
            (foot.distance - best).abs() < 2e-3,
            "{} against {best}",
            foot.distance
        );
        assert!(((y - foot.point).norm() - foot.distance).abs() < 1e-12);
    }
}
