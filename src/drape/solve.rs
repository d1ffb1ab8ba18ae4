//! The two geometric steps of the pin-jointed net (Mack & Taylor 1956; Van West et al. 1990):
//! stepping one cell along a generator, and completing a cell from three known corners.

use nalgebra::{Matrix2, Vector2, Vector3};

use super::surface::DrapeSurface;
use super::FailReason;

/// Newton iterations allowed for one node; a well-posed node converges in 4–6.
const MAX_NEWTON: usize = 60;
/// Step halvings allowed in the Newton line search.
const MAX_HALVINGS: usize = 40;
/// Bisection steps on a generator: 2^-80 of a cell is below round-off.
const MAX_BISECTIONS: usize = 80;
/// Converged when both |d² − cell²| are below this fraction of cell²: the edge length is then
/// exact to about half of it times the cell, far inside the 1e-9 mm asked of the tests.
const RESIDUAL_TOL: f64 = 1e-13;

/// The point of the surface above (x, y), or `None` outside its domain.
pub(crate) fn surface_point<S: DrapeSurface + ?Sized>(
    surface: &S,
    x: f64,
    y: f64,
) -> Option<Vector3<f64>> {
    let z = surface.height(x, y)?;
    z.is_finite().then(|| Vector3::new(x, y, z))
}

/// The next generator node: the point of the surface above the ray from `from` in the plan
/// direction `dir` (a unit vector in x-y) at chord distance `chord` from `from`.
///
/// Choice: the generator is the normal section, the surface curve whose plan view is the
/// straight ray; on a symmetry plane of the tool (an apex-centred 0/90 net on a dome, the axis
/// or circumference of a cylinder) this is also the geodesic. The plan distance t lies in
/// (0, chord] because a chord is never shorter than its plan projection, so bisection on
/// t ↦ |S(t) − S(0)|² − chord² cannot miss the first crossing when the surface is defined on
/// the whole interval. Returns `None` when the domain ends before the chord is reached.
pub(crate) fn step_along_generator<S: DrapeSurface + ?Sized>(
    surface: &S,
    from: Vector3<f64>,
    dir: Vector2<f64>,
    chord: f64,
) -> Option<Vector3<f64>> {
    let at = |t: f64| surface_point(surface, from.x + t * dir.x, from.y + t * dir.y);
    let excess = |p: Vector3<f64>| (p - from).norm_squared() - chord * chord;
    let mut hi = chord;
    if at(hi).is_none() {
        hi = last_defined_distance(&at, chord)?;
        if excess(at(hi)?) < 0.0 {
            return None;
        }
    }
    let mut lo = 0.0;
    for _ in 0..MAX_BISECTIONS {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        match at(mid) {
            Some(p) if excess(p) < 0.0 => lo = mid,
            Some(_) => hi = mid,
            None => return None,
        }
    }
    let (p_lo, p_hi) = (at(lo)?, at(hi)?);
    Some(if excess(p_lo).abs() < excess(p_hi).abs() {
        p_lo
    } else {
        p_hi
    })
}

/// The largest plan distance in (0, `limit`) at which the surface is still defined, found by
/// bisection (the domain is assumed convex along the ray, as for the bundled tools).
fn last_defined_distance(at: &impl Fn(f64) -> Option<Vector3<f64>>, limit: f64) -> Option<f64> {
    let (mut inside, mut outside) = (0.0, limit);
    for _ in 0..MAX_BISECTIONS {
        let mid = 0.5 * (inside + outside);
        if at(mid).is_some() {
            inside = mid;
        } else {
            outside = mid;
        }
    }
    (inside > 0.0).then_some(inside)
}

/// The fourth corner of a cell: the point P of the surface with |P − a| = |P − b| = `chord`,
/// on the far side of the edge a–b from the known diagonal corner `d`.
///
/// Newton's method on the two equations in (x, y), started from the parallelogram completion
/// a + b − d (exact on a plane, one iteration away on a smooth surface) with a backtracking
/// line search on the residual. The two circles on the surface meet twice, at `d` itself and
/// at the new node; the side test rejects a collapse onto `d` (a folded cell).
pub(crate) fn complete_cell<S: DrapeSurface + ?Sized>(
    surface: &S,
    a: Vector3<f64>,
    b: Vector3<f64>,
    d: Vector3<f64>,
    chord: f64,
) -> Result<Vector3<f64>, FailReason> {
    let eval = |xy: Vector2<f64>| {
        let p = surface_point(surface, xy.x, xy.y)?;
        let f = Vector2::new(
            (p - a).norm_squared() - chord * chord,
            (p - b).norm_squared() - chord * chord,
        );
        Some((p, f))
    };
    let tol = RESIDUAL_TOL * chord * chord;
    let mut xy = predictor(surface, a, b, d).ok_or(FailReason::OutsideDomain)?;
    let (mut p, mut f) = eval(xy).ok_or(FailReason::OutsideDomain)?;
    let mut saw_outside = false;
    for _ in 0..MAX_NEWTON {
        if f.amax() <= tol {
            return far_side(p, a, b, d);
        }
        let step = newton_step(surface, p, a, b, f)?;
        let mut accepted = false;
        let mut lambda = 1.0;
        for _ in 0..MAX_HALVINGS {
            match eval(xy + lambda * step) {
                Some((p_t, f_t)) if f_t.norm() < f.norm() => {
                    (xy, p, f) = (xy + lambda * step, p_t, f_t);
                    accepted = true;
                    break;
                }
                Some(_) => {}
                None => saw_outside = true,
            }
            lambda *= 0.5;
        }
        if !accepted {
            break;
        }
    }
    if f.amax() <= tol {
        return far_side(p, a, b, d);
    }
    Err(if saw_outside {
        FailReason::OutsideDomain
    } else {
        FailReason::NoSolution
    })
}

/// The parallelogram completion a + b − d in plan, pulled back towards the midpoint of a–b
/// when it falls outside the domain (near a rim).
fn predictor<S: DrapeSurface + ?Sized>(
    surface: &S,
    a: Vector3<f64>,
    b: Vector3<f64>,
    d: Vector3<f64>,
) -> Option<Vector2<f64>> {
    let mid = Vector2::new(0.5 * (a.x + b.x), 0.5 * (a.y + b.y));
    let outward = mid - Vector2::new(d.x, d.y);
    let mut scale = 1.0;
    for _ in 0..MAX_HALVINGS {
        let xy = mid + scale * outward;
        if surface.height(xy.x, xy.y).is_some() {
            return Some(xy);
        }
        scale *= 0.5;
    }
    None
}

/// The Newton correction δ solving J δ = −f, with J the plan derivative of
/// (|P − a|², |P − b|²) and P = (x, y, h(x, y)).
fn newton_step<S: DrapeSurface + ?Sized>(
    surface: &S,
    p: Vector3<f64>,
    a: Vector3<f64>,
    b: Vector3<f64>,
    f: Vector2<f64>,
) -> Result<Vector2<f64>, FailReason> {
    let (hx, hy) = surface
        .gradient(p.x, p.y)
        .filter(|(gx, gy)| gx.is_finite() && gy.is_finite())
        .ok_or(FailReason::OutsideDomain)?;
    let (ra, rb) = (p - a, p - b);
    let jac = 2.0
        * Matrix2::new(
            ra.x + ra.z * hx,
            ra.y + ra.z * hy,
            rb.x + rb.z * hx,
            rb.y + rb.z * hy,
        );
    let scale = jac.abs().max();
    if jac.determinant().abs() <= 1e-14 * scale * scale {
        return Err(FailReason::NoSolution);
    }
    let inverse = jac.try_inverse().ok_or(FailReason::NoSolution)?;
    Ok(-(inverse * f))
}

/// Accepts the converged point only beyond the midpoint of a–b as seen from `d`, i.e. the
/// root that is not `d` itself (for a parallelogram, P − m = m − d).
fn far_side(
    p: Vector3<f64>,
    a: Vector3<f64>,
    b: Vector3<f64>,
    d: Vector3<f64>,
) -> Result<Vector3<f64>, FailReason> {
    let m = 0.5 * (a + b);
    if (p - m).dot(&(m - d)) > 0.0 {
        Ok(p)
    } else {
        Err(FailReason::Folded)
    }
}
