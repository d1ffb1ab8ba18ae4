//! Contact and friction of the quasi-static solver as potentials of the node's position
//! (docs/solver.md, "Implicit"): what Newton's method needs, a force and its derivative.
//!
//! - **Normal**: the penalty energy `1/2 k (g - g_m)^2` while the gap `g = d - t/2` is below a
//!   small margin `g_m` ([`contact_margin`]; `d` the signed distance of the node from the tool,
//!   as in [`super::penalty`]), so the tool pushes with `-k (g - g_m) n`. The spring is that of the explicit solver without its mass:
//!   `k = s m / dt^2` with `dt = h / c` is `s E t0 A / h^2` for a node of area `A` on elements of
//!   size `h` and wave modulus `E` ([`penalty_stiffness`]).
//! - **Friction**: Coulomb's law with an elastic stick, as the explicit solver has it
//!   ([`super::penalty`]), written as a potential of the slip with the normal force `lambda`
//!   and the tangent plane (normal `n0`) of the start of the increment lagged, as
//!   incremental-potential contact lags them. The tangential force `q` carried from the last
//!   increment (minus the friction force on the node) plus the stick's `k s`, with
//!   `s = P0 (y - y0)` the slip since the increment started (`P0 = I - n0 n0^T`, `y` the node
//!   relative to the tool) and `k = mu lambda / eps`, is the trial `z = P0 (q + k s)`; the
//!   force is its return to Coulomb's disc, `P(z) = z` within `|z| <= mu lambda` (stick) and
//!   `mu lambda z / |z|` beyond (slip). `P` is the gradient of the convex
//!   `phi(z) = |z|^2 / 2k` (stick), `(mu lambda |z| - (mu lambda)^2 / 2) / k` (slip)
//!   (docs/solver.md, "Friction"). The force depends on the path of slip, not on how it is cut
//!   into increments nor on how fast it is run: a node sliding steadily carries exactly
//!   `mu lambda`, whatever the punch speed and the increment.

use super::penalty::ContactSettings;
use super::rigid_tool::RigidTool;
use super::surface::{Feature, Footing, Projection};
use nalgebra::{Matrix3, Vector3};

/// The friction of a node on one tool during an increment: what was lagged at its start.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrictionLag {
    /// `mu lambda` (N): the Coulomb limit of the tangential force.
    pub limit: f64,
    /// Tool normal at the start (unit).
    pub normal: Vector3<f64>,
    /// The node's position relative to the tool at the start (mm).
    pub start: Vector3<f64>,
    /// The tangential force carried from the last increment (N): minus the friction force on
    /// the node there, the stick's memory.
    pub carried: Vector3<f64>,
}

/// A node's contact with one tool at a trial position: the gradient and Hessian of its
/// potential with respect to the node's position relative to the tool, and the forces.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PairContact {
    pub energy: f64,
    /// `dPi/dy` (N): minus the force of the tool on the node.
    pub gradient: Vector3<f64>,
    /// `d^2 Pi / dy^2` (N/mm).
    pub hessian: Matrix3<f64>,
    /// `k |g|` (N), zero when not touching.
    pub normal_force: f64,
    /// Unit normal of the tool at the node (zero when not touching).
    pub normal: Vector3<f64>,
    /// Friction force on the node (N).
    pub tangential: Vector3<f64>,
    /// The node lies behind the tool beyond the contact's reach (`max_penetration`). The
    /// spring still pushes it back (a cut-off would make the potential jump there, and a step
    /// through it would be a descent), but an increment may not end so.
    pub tunnelled: bool,
}

/// `s E t0 A / h^2`: the explicit solver's contact spring `s m / dt^2` at the stable step of
/// an element of size `h` (N/mm).
pub fn penalty_stiffness(scale: f64, wave_stiffness: f64, area: f64, size: f64) -> f64 {
    scale * wave_stiffness * area / (size * size)
}

/// How a pair's contact is evaluated: the elastic slip of friction's stick (mm), which
/// Hessian, and whether Newton's method has frozen the pair's spring on or off.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PairOptions {
    /// `eps`: the slip at which a node starting from rest reaches Coulomb's limit.
    pub slip: f64,
    pub hessian: PairHessian,
    /// `Some(true)` holds the spring on even where the node has left the margin (then it
    /// pulls), as Newton's method does when it freezes the contact set to stop a node
    /// chattering in and out of contact; otherwise the gap decides.
    pub engaged: Option<bool>,
}

/// Which second derivative of a pair's potential is formed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PairHessian {
    /// None: the residual alone (a line-search probe).
    None,
    /// `Pi''(g) n n^T` for the normal part, its positive semi-definite part.
    GaussNewton,
    /// With the turn of the normal over the tool's edges and corners ([`normal_hessian`]).
    Exact,
}

/// The potential of a node at `y` (relative to the tool's translation) against `tool`, whose
/// point nearest to `y` within the search radius is `nearest` ([`RigidTool::nearest`]), with
/// contact spring `stiffness` and friction lagged in `friction`. `None` when the node neither
/// touches the tool nor rubs on it.
pub fn pair_contact(
    tool: &RigidTool,
    y: &Vector3<f64>,
    nearest: Option<Projection>,
    stiffness: f64,
    settings: &ContactSettings,
    friction: Option<&FrictionLag>,
    options: PairOptions,
) -> Option<PairContact> {
    let PairOptions {
        slip,
        hessian,
        engaged,
    } = options;
    let normal = nearest.and_then(|p| normal_part(p, y, stiffness, settings, engaged));
    let rub = friction.filter(|f| f.limit > 0.0);
    if normal.is_none() && rub.is_none() {
        return None;
    }
    let mut pair = PairContact {
        tunnelled: nearest.is_some_and(|p| tunnelled(p, y, settings)),
        ..Default::default()
    };
    if let (Some((energy, gradient, n, force, curvature)), Some(p)) = (normal, nearest) {
        pair.energy = energy;
        pair.gradient = gradient;
        pair.normal = n.normalize();
        pair.normal_force = force;
        pair.hessian = match hessian {
            PairHessian::None => Matrix3::zeros(),
            PairHessian::GaussNewton => n * n.transpose() * curvature,
            PairHessian::Exact => normal_hessian(tool, p, y, stiffness, settings),
        };
    }
    if let Some(f) = rub {
        let friction = stick_slip(f, y, slip, hessian != PairHessian::None);
        pair.energy += friction.energy;
        pair.gradient += friction.gradient;
        pair.tangential = -friction.gradient;
        pair.hessian += friction.hessian;
    }
    Some(pair)
}

/// The friction part of a pair's potential: energy (N·mm, zero where the increment starts),
/// gradient (N) and Hessian (N/mm).
pub(crate) struct FrictionPart {
    pub energy: f64,
    pub gradient: Vector3<f64>,
    pub hessian: Matrix3<f64>,
}

/// Coulomb's friction with an elastic stick of slip `eps` at `y` (module docs): the trial
/// force `z = P0 (q + k s)` returned to the disc of radius `mu lambda`. Its Hessian is `k P0`
/// in the stick and `k (mu lambda / |z|) (P0 - z z^T / |z|^2)` in the slip: the slope of the
/// force along the slip drops to zero as the node starts sliding (a kink Newton's method meets
/// as it meets the contact's).
pub(crate) fn stick_slip(
    f: &FrictionLag,
    y: &Vector3<f64>,
    eps: f64,
    with_hessian: bool,
) -> FrictionPart {
    let radius = f.limit;
    let k = radius / eps;
    let projector = Matrix3::identity() - f.normal * f.normal.transpose();
    let carried = projector * f.carried;
    let z = carried + projector * (y - f.start) * k;
    let phi = |z: &Vector3<f64>| {
        let size = z.norm();
        if size <= radius {
            0.5 * size * size / k
        } else {
            (radius * size - 0.5 * radius * radius) / k
        }
    };
    let size = z.norm();
    let (gradient, hessian) = if size <= radius {
        (z, projector * k)
    } else {
        let direction = z / size;
        let slide = projector - direction * direction.transpose();
        (direction * radius, slide * (k * radius / size))
    };
    FrictionPart {
        energy: phi(&z) - phi(&carried),
        gradient,
        hessian: if with_hessian {
            hessian
        } else {
            Matrix3::zeros()
        },
    }
}

/// The penalty at a node: energy, gradient, unit normal, normal force, and the potential's
/// second derivative in the gap.
type NormalPart = (f64, Vector3<f64>, Vector3<f64>, f64, f64);

/// The [`NormalPart`] at `y` of the spring to `p`, the point of the tool nearest to `y`;
/// `None` out of contact. The penalty `1/2 k (g - g_m)^2` while the gap `g` is below the
/// margin `g_m` ([`contact_margin`]).
fn normal_part(
    p: Projection,
    y: &Vector3<f64>,
    stiffness: f64,
    settings: &ContactSettings,
    engaged: Option<bool>,
) -> Option<NormalPart> {
    let (n, distance) = p.direction_to(y);
    let gap = distance - settings.offset - contact_margin(settings);
    if gap >= 0.0 && engaged != Some(true) {
        return None;
    }
    let k = stiffness;
    Some((0.5 * k * gap * gap, n * (k * gap), n, -k * gap, k))
}

/// Whether the node at `y` lies behind the tool deeper than the contact reaches.
fn tunnelled(p: Projection, y: &Vector3<f64>, settings: &ContactSettings) -> bool {
    let gap = p.direction_to(y).1 - settings.offset - contact_margin(settings);
    gap <= -settings.max_penetration
}

/// The margin `g_m` by which the contact spring reaches beyond the blank's face: a tenth of
/// the contact offset **(choice)**. Blank and tools start touching (gap zero); with the spring
/// already engaged there, Newton's method sees the tool a node is pressed against (a die under
/// the flange the holder pushes down) instead of no stiffness until the node has passed it. The
/// price is that the faces rest `g_m` off the tool, 5 % of the ply's thickness.
pub fn contact_margin(settings: &ContactSettings) -> f64 {
    0.1 * settings.offset
}

/// `d^2/dy^2` of the spring `1/2 k (g - g_m)^2` to `p`, the point of the tool nearest to `y`:
/// `k n n^T + k (g - g_m) dn/dy`. On an exact surface `dn/dy` is its turn (the surface's
/// curvature seen from `y`). On a triangulated one, in front of a face the normal is the face's
/// and does not turn; in front of an edge or a corner it is `(y - p) / |y - p|`, which turns as
/// `y` moves across the edge (`(I - n n^T - t t^T) / |y - p|`, `t` along the edge) or in any
/// direction about the corner (`(I - n n^T) / |y - p|`); behind the tool it is the face's.
fn normal_hessian(
    tool: &RigidTool,
    p: Projection,
    y: &Vector3<f64>,
    stiffness: f64,
    settings: &ContactSettings,
) -> Matrix3<f64> {
    let (n, distance) = p.direction_to(y);
    let k = stiffness;
    let spring = n * n.transpose() * k;
    let gap = distance - settings.offset - contact_margin(settings);
    let triangle = match p.on {
        Footing::Smooth { turn } => return spring + turn * (k * gap),
        Footing::Facet(triangle) => triangle,
    };
    if !p.in_front(y) {
        return spring;
    }
    let turn = match tool.feature_on(triangle, y) {
        Feature::Face => return spring,
        Feature::Edge(t) => Matrix3::identity() - n * n.transpose() - t * t.transpose(),
        Feature::Vertex => Matrix3::identity() - n * n.transpose(),
    };
    spring + turn * (k * gap / distance)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::{hemisphere_punch, ToolMotion};

    fn punch() -> RigidTool {
        let surface = hemisphere_punch(20.0, 1.0).unwrap();
        RigidTool::new("punch", surface, ToolMotion::Fixed, 0.3, 1.0).unwrap()
    }

    fn options(slip: f64, hessian: PairHessian) -> PairOptions {
        PairOptions {
            slip,
            hessian,
            engaged: None,
        }
    }

    /// The pair at `z` on `tool` with friction lagged as `lag`, its regularising slip `slip`,
    /// and the exact Hessian.
    fn exact_pair(tool: &RigidTool, z: Vector3<f64>, lag: &FrictionLag, slip: f64) -> PairContact {
        pair_contact(
            tool,
            &z,
            tool.nearest(&z),
            500.0,
            &SETTINGS,
            Some(lag),
            options(slip, PairHessian::Exact),
        )
        .unwrap()
    }

    /// Friction lagged at `y` in front of `tool`: the tangent plane of its nearest point there,
    /// a start beside `y` and a carried force, with a limit of 3 N.
    fn lag_in_front(tool: &RigidTool, y: Vector3<f64>) -> FrictionLag {
        FrictionLag {
            limit: 3.0,
            normal: tool.nearest(&y).unwrap().normal.normalize(),
            start: y + Vector3::new(0.02, -0.01, 0.0),
            carried: Vector3::new(0.5, 1.0, -0.3),
        }
    }

    const SETTINGS: ContactSettings = ContactSettings {
        offset: 0.25,
        penalty_scale: 0.1,
        max_penetration: 0.5,
    };

    /// The pair at `y` touches, its gradient is the central difference of its energy and its
    /// Hessian that of its gradient (case `k` in the messages).
    fn assert_derivatives(k: usize, y: Vector3<f64>, at: impl Fn(Vector3<f64>) -> PairContact) {
        let pair = at(y);
        assert!(pair.normal_force > 0.0, "{k}: touching");
        let h = 1e-6;
        for d in 0..3 {
            let mut step = Vector3::zeros();
            step[d] = h;
            let (plus, minus) = (at(y + step), at(y - step));
            let slope = (plus.energy - minus.energy) / (2.0 * h);
            assert!(
                (slope - pair.gradient[d]).abs() < 1e-5 * pair.gradient.norm(),
                "{k} {d}: {slope} against {}",
                pair.gradient[d]
            );
            let column = (plus.gradient - minus.gradient) / (2.0 * h);
            let error = (column - pair.hessian.column(d)).norm();
            assert!(error < 1e-4 * pair.hessian.norm(), "{k} {d}: {error}");
        }
    }

    /// The gradient is the derivative of the energy and the Hessian that of the gradient,
    /// friction included, at points touching a faceted cap.
    #[test]
    fn gradient_and_hessian_are_the_derivatives_of_the_potential() {
        let tool = punch();
        let lag = FrictionLag {
            limit: 3.0,
            normal: Vector3::new(0.1, 0.2, 1.0).normalize(),
            start: Vector3::new(2.0, 1.0, 0.0),
            carried: Vector3::zeros(),
        };
        // in front of a face, of an edge and of a corner of the faceted cap (centre z = -20)
        let [a, b, c] = tool.surface.triangles[0].map(|i| tool.surface.vertices[i]);
        let centre = Vector3::new(0.0, 0.0, -20.0);
        let off = |q: Vector3<f64>| q + (q - centre).normalize() * 0.2;
        let points = [off((a + b + c) / 3.0), off(0.5 * (a + b)), off(a)];
        let features: Vec<Feature> = points
            .iter()
            .map(|y| match tool.nearest(y).unwrap().on {
                Footing::Facet(k) => tool.feature_on(k, y),
                Footing::Smooth { .. } => unreachable!("a triangulated tool"),
            })
            .collect();
        assert!(matches!(features[0], Feature::Face), "{features:?}");
        assert!(matches!(features[1], Feature::Edge(_)), "{features:?}");
        assert!(matches!(features[2], Feature::Vertex), "{features:?}");
        // eps 0.01 mm: the node slides; 1e3 mm: it sticks, with and without a carried force
        let carried = [Vector3::zeros(), Vector3::new(-0.4, 0.9, 0.2)];
        for (k, &y) in points.iter().enumerate() {
            for (eps, carried) in [0.01, 1e3]
                .into_iter()
                .flat_map(|e| carried.map(|c| (e, c)))
            {
                let lag = FrictionLag { carried, ..lag };
                let at = |z: Vector3<f64>| exact_pair(&tool, z, &lag, eps);
                let force = at(y).tangential.norm();
                assert_eq!(force >= lag.limit * (1.0 - 1e-12), eps < 1.0, "{k} {eps}");
                assert_derivatives(k, y, at);
            }
        }
    }

    /// The same on the exact surfaces of a die (plate, fillet, wall) and of a holder (its
    /// plate and, beyond its inner rim, the rim's edge), with friction.
    #[test]
    fn on_exact_surfaces_gradient_and_hessian_are_the_derivatives_of_the_potential() {
        use crate::contact::{
            double_dome_die, double_dome_die_shape, double_dome_holder_shape, DieShape,
        };
        let shape = DieShape {
            opening_radius: 12.0,
            fillet_radius: 5.0,
            outer_radius: 40.0,
            depth: 20.0,
        };
        let die = RigidTool::new(
            "die",
            double_dome_die(8.0, &shape, 2.0).unwrap(),
            ToolMotion::Fixed,
            0.3,
            1.0,
        )
        .unwrap()
        .with_exact_surface(double_dome_die_shape(8.0, &shape).unwrap().lifted(0.25));
        let holder = RigidTool::new(
            "holder",
            crate::contact::double_dome_holder(8.0, 15.0, 40.0, 2.0).unwrap(),
            ToolMotion::Fixed,
            0.3,
            1.0,
        )
        .unwrap()
        .with_exact_surface(
            double_dome_holder_shape(8.0, 15.0, 40.0)
                .unwrap()
                .lifted(-0.25),
        );
        let cases = [
            (&die, Vector3::new(20.0, 6.0, 0.1)),
            (&die, Vector3::new(3.0, 13.05, 1.2)),
            (&die, Vector3::new(-11.0, 10.5, 0.9)),
            (&die, Vector3::new(2.0, 12.3, 8.0)),
            (&holder, Vector3::new(4.0, 20.0, 0.1)),
            (&holder, Vector3::new(-6.0, 14.8, 0.1)),
            (&holder, Vector3::new(-10.0, 14.5, 0.1)),
        ];
        for (k, (tool, rough)) in cases.into_iter().enumerate() {
            // 0.15 mm in front of the surface: inside the spring's reach
            let foot = tool.exact_surface().unwrap().nearest(&rough);
            let y = foot.point + foot.normal * 0.15;
            let lag = lag_in_front(tool, y);
            let at = |z: Vector3<f64>| exact_pair(tool, z, &lag, 0.01);
            assert_derivatives(k, y, at);
        }
    }

    /// The same on the surfaces blended over a die's facets (docs/model.md §6, "Blended tool
    /// surfaces"): over its plate, fillet and wall, with friction.
    #[test]
    fn on_blended_surfaces_gradient_and_hessian_are_the_derivatives_of_the_potential() {
        let die = crate::contact::hemisphere_die(12.0, 5.0, 40.0, 20.0, 1.5).unwrap();
        let tool = RigidTool::new("die", die, ToolMotion::Fixed, 0.3, 1.0)
            .unwrap()
            .with_blended_surface();
        for (k, y) in [
            Vector3::new(25.0, 3.0, -0.15),
            Vector3::new(14.1, 1.3, 1.2),
            Vector3::new(-10.0, 7.3, 3.1),
            Vector3::new(0.4, -11.85, 9.0),
        ]
        .into_iter()
        .enumerate()
        {
            let lag = lag_in_front(&tool, y);
            let at = |z: Vector3<f64>| exact_pair(&tool, z, &lag, 0.01);
            assert!(matches!(
                tool.nearest(&y).unwrap().on,
                Footing::Smooth { .. }
            ));
            assert_derivatives(k, y, at);
        }
    }

    /// Deeper than the contact's reach the spring goes on pushing, `k |g - g_m|` along the
    /// normal, and the pair says it has tunnelled; within the reach it does not.
    #[test]
    fn the_spring_holds_beyond_the_reach_and_says_so() {
        let tool = punch();
        let k = 500.0;
        let margin = contact_margin(&SETTINGS);
        for depth in [0.1, 0.4, 0.6, 0.9] {
            // the cap's top at z = 0 is a vertex of the faceted surface; 0.3 mm off it
            let y = Vector3::new(0.3, 0.0, SETTINGS.offset - depth);
            let p = tool.nearest(&y).unwrap();
            let (n, distance) = p.direction_to(&y);
            let gap = distance - SETTINGS.offset - margin;
            let pair = pair_contact(
                &tool,
                &y,
                Some(p),
                k,
                &SETTINGS,
                None,
                options(0.01, PairHessian::GaussNewton),
            )
            .unwrap();
            assert!((pair.normal_force + k * gap).abs() < 1e-9, "{depth}");
            assert!((pair.gradient - n * (k * gap)).norm() < 1e-9, "{depth}");
            assert_eq!(pair.tunnelled, gap <= -SETTINGS.max_penetration, "{depth}");
        }
    }

    /// Past a slip of many `eps`, the friction force is `mu lambda` against the slip.
    #[test]
    fn sliding_friction_is_coulombs() {
        let tool = punch();
        let lag = FrictionLag {
            limit: 2.0,
            normal: Vector3::z(),
            start: Vector3::new(0.0, 0.0, 0.2),
            carried: Vector3::zeros(),
        };
        let y = Vector3::new(1.0, 0.0, 0.2);
        let pair = pair_contact(
            &tool,
            &y,
            tool.nearest(&y),
            500.0,
            &SETTINGS,
            Some(&lag),
            options(1e-3, PairHessian::GaussNewton),
        )
        .unwrap();
        assert!((pair.tangential + Vector3::x() * 2.0).norm() < 2.0 * 1e-6);
        let stuck = Vector3::new(1e-5, 0.0, 0.2);
        let pair = pair_contact(
            &tool,
            &stuck,
            tool.nearest(&stuck),
            500.0,
            &SETTINGS,
            Some(&lag),
            options(1e-3, PairHessian::GaussNewton),
        )
        .unwrap();
        assert!(pair.tangential.norm() < 0.02 * 2.0, "sticks below eps");
    }

    /// The friction after a slip `total` made in `pieces` increments, each starting from the
    /// last one's force, on the flat top of a plate.
    fn after_slip(
        total: Vector3<f64>,
        pieces: usize,
        eps: f64,
        carried: Vector3<f64>,
    ) -> Vector3<f64> {
        let tool = punch();
        let start = Vector3::new(0.0, 0.0, 0.2);
        let mut lag = FrictionLag {
            limit: 2.0,
            normal: Vector3::z(),
            start,
            carried,
        };
        let mut force = -carried;
        for i in 1..=pieces {
            let y = start + total * (i as f64 / pieces as f64);
            let pair = pair_contact(
                &tool,
                &y,
                tool.nearest(&y),
                500.0,
                &SETTINGS,
                Some(&lag),
                options(eps, PairHessian::None),
            )
            .unwrap();
            force = pair.tangential;
            lag = FrictionLag {
                start: y,
                carried: -force,
                ..lag
            };
        }
        force
    }

    /// Cut into 1, 10 or 1,000 increments, the same slip gives the same friction force:
    /// exactly Coulomb's `mu lambda` once it passes `eps`, the stick's `mu lambda s / eps`
    /// below it. Without the carried force (each increment's stick starting from zero, as a
    /// regularisation by the increment's slip alone does) the force would fall with the
    /// increment's length.
    #[test]
    fn friction_does_not_depend_on_how_the_slip_is_cut() {
        let eps = 1e-3;
        for (total, expected) in [(0.05, 2.0), (4e-4, 2.0 * 0.4)] {
            for pieces in [1, 10, 1000] {
                let force = after_slip(Vector3::x() * total, pieces, eps, Vector3::zeros());
                assert!(
                    (force + Vector3::x() * expected).norm() < 1e-9 * expected,
                    "{total} mm in {pieces}: {force}"
                );
            }
        }
    }

    /// A node that slid one way carries Coulomb's force; sliding back, its force turns through
    /// the stick: half after `eps / 2` of slip back, zero after `eps`, `mu lambda` the other
    /// way after `2 eps`.
    #[test]
    fn the_stick_remembers_the_slip_before() {
        let eps = 1e-3;
        let slid = after_slip(Vector3::x() * 0.05, 20, eps, Vector3::zeros());
        assert!((slid + Vector3::x() * 2.0).norm() < 1e-9);
        let back = |s: f64| after_slip(-Vector3::x() * s, 7, eps, -slid);
        assert!((back(0.5 * eps) + Vector3::x() * 1.0).norm() < 1e-9);
        assert!(back(eps).norm() < 1e-9, "{}", back(eps));
        assert!((back(3.0 * eps) - Vector3::x() * 2.0).norm() < 1e-9);
    }
}
