//! Surfaces a fabric is draped on, written as height fields z = h(x, y).
//!
//! A height field is enough for the punch shapes a kinematic drape is used for (domes, boxes,
//! channels seen from above), and it turns the search for a node into two unknowns (x, y)
//! instead of three with a constraint.

/// A tool surface z = h(x, y) (mm).
///
/// `height` returns `None` outside the surface's domain; the drape stops there. `gradient`
/// has a central finite-difference default, so a new surface only needs `height`; override it
/// when a closed form exists (it is used only in the Newton Jacobian, so its accuracy sets the
/// convergence rate, not the accuracy of the nodes).
pub trait DrapeSurface {
    /// Height z at (x, y), or `None` outside the domain.
    fn height(&self, x: f64, y: f64) -> Option<f64>;

    /// (dz/dx, dz/dy) at (x, y), or `None` where the height field has no finite slope.
    fn gradient(&self, x: f64, y: f64) -> Option<(f64, f64)> {
        finite_difference_gradient(self, x, y)
    }
}

/// Central differences, one-sided next to the domain's edge, with a step relative to the
/// coordinates (truncation and round-off errors both stay near 1e-10 for mm-sized tools).
pub fn finite_difference_gradient<S: DrapeSurface + ?Sized>(
    surface: &S,
    x: f64,
    y: f64,
) -> Option<(f64, f64)> {
    let step = 1e-6 * (1.0 + x.abs() + y.abs());
    let h0 = surface.height(x, y)?;
    let dx = one_slope(
        surface.height(x + step, y),
        surface.height(x - step, y),
        h0,
        step,
    )?;
    let dy = one_slope(
        surface.height(x, y + step),
        surface.height(x, y - step),
        h0,
        step,
    )?;
    Some((dx, dy))
}

/// The slope from the heights one step ahead and behind, central when both exist.
fn one_slope(ahead: Option<f64>, behind: Option<f64>, here: f64, step: f64) -> Option<f64> {
    match (ahead, behind) {
        (Some(a), Some(b)) => Some((a - b) / (2.0 * step)),
        (Some(a), None) => Some((a - here) / step),
        (None, Some(b)) => Some((here - b) / step),
        (None, None) => None,
    }
}

/// The plane z = z0 + slope_x·x + slope_y·y, defined everywhere.
///
/// A plane is developable and flat, so a draped net stays square: the reference case.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Plane {
    /// Height at the origin (mm).
    pub z0: f64,
    /// dz/dx.
    pub slope_x: f64,
    /// dz/dy.
    pub slope_y: f64,
}

impl DrapeSurface for Plane {
    fn height(&self, x: f64, y: f64) -> Option<f64> {
        let z = self.z0 + self.slope_x * x + self.slope_y * y;
        z.is_finite().then_some(z)
    }

    fn gradient(&self, x: f64, y: f64) -> Option<(f64, f64)> {
        self.height(x, y).map(|_| (self.slope_x, self.slope_y))
    }
}

/// The upper half of a sphere of radius R with its apex at the origin:
/// z = sqrt(R² − x² − y²) − R, so z = 0 at the apex and z = −R on the rim r = R.
///
/// Choice: the domain is the dome only (r ≤ R); outside it `height` is `None`, so the drape
/// stops at the rim instead of running onto a flange that a real tool would have to define.
/// A non-positive or non-finite radius makes an empty surface (every height `None`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hemisphere {
    /// Sphere radius R (mm).
    pub radius: f64,
}

impl DrapeSurface for Hemisphere {
    fn height(&self, x: f64, y: f64) -> Option<f64> {
        circle_sag(self.radius, x * x + y * y)
    }

    fn gradient(&self, x: f64, y: f64) -> Option<(f64, f64)> {
        let w = circle_half_chord(self.radius, x * x + y * y)?;
        Some((-x / w, -y / w))
    }
}

/// The upper half of a circular cylinder of radius R with its axis along x and its top line on
/// the x axis: z = sqrt(R² − y²) − R on |y| ≤ R, `None` beyond (as for [`Hemisphere`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cylinder {
    /// Cylinder radius R (mm).
    pub radius: f64,
}

impl DrapeSurface for Cylinder {
    fn height(&self, x: f64, y: f64) -> Option<f64> {
        if !x.is_finite() {
            return None;
        }
        circle_sag(self.radius, y * y)
    }

    fn gradient(&self, x: f64, y: f64) -> Option<(f64, f64)> {
        if !x.is_finite() {
            return None;
        }
        let w = circle_half_chord(self.radius, y * y)?;
        Some((0.0, -y / w))
    }
}

/// The crown of the double-dome punch (`contact::tools::double_dome_punch`): the points at
/// distance R above the ridge segment |x| ≤ L, y = 0, z = −R, seen from above:
/// z = sqrt(R² − d²) − R with d the distance of (x, y) from the ridge, `None` beyond d = R.
/// A cylinder along x between two quarter spheres; L = 0 is the [`Hemisphere`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DoubleDome {
    /// Dome radius R (mm).
    pub radius: f64,
    /// Half-length L of the ridge (mm).
    pub half_length: f64,
}

impl DoubleDome {
    /// Offset from the nearest ridge point along x: 0 over the cylinder.
    fn beyond_ridge(&self, x: f64) -> f64 {
        x.signum() * (x.abs() - self.half_length).max(0.0)
    }
}

impl DrapeSurface for DoubleDome {
    fn height(&self, x: f64, y: f64) -> Option<f64> {
        if !x.is_finite() {
            return None;
        }
        let dx = self.beyond_ridge(x);
        circle_sag(self.radius, dx * dx + y * y)
    }

    fn gradient(&self, x: f64, y: f64) -> Option<(f64, f64)> {
        if !x.is_finite() {
            return None;
        }
        let dx = self.beyond_ridge(x);
        let w = circle_half_chord(self.radius, dx * dx + y * y)?;
        Some((-dx / w, -y / w))
    }
}

/// z = sqrt(R² − r²) − R written as −r² / (sqrt(R² − r²) + R), which keeps full relative
/// precision near the apex where the plain difference cancels.
fn circle_sag(radius: f64, r2: f64) -> Option<f64> {
    if !(radius > 0.0 && radius.is_finite() && r2 <= radius * radius) {
        return None;
    }
    Some(-r2 / ((radius * radius - r2).sqrt() + radius))
}

/// sqrt(R² − r²), strictly positive where the slope is finite.
fn circle_half_chord(radius: f64, r2: f64) -> Option<f64> {
    circle_sag(radius, r2)?;
    let w = (radius * radius - r2).sqrt();
    (w > 0.0).then_some(w)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn double_dome_is_a_cylinder_between_two_hemispheres() {
        let (r, l) = (20.0, 15.0);
        let dome = DoubleDome {
            radius: r,
            half_length: l,
        };
        let (sphere, cylinder) = (Hemisphere { radius: r }, Cylinder { radius: r });
        for &(x, y) in &[
            (0.0f64, 3.0f64),
            (14.0, -19.0),
            (22.0, 5.0),
            (-30.0, -7.0),
            (-15.0, 0.0),
        ] {
            let expected = if x.abs() <= l {
                (cylinder.height(x, y), cylinder.gradient(x, y))
            } else {
                let dx = x - l * f64::signum(x);
                (sphere.height(dx, y), sphere.gradient(dx, y))
            };
            assert_eq!(
                (dome.height(x, y), dome.gradient(x, y)),
                expected,
                "({x}, {y})"
            );
            let fd = finite_difference_gradient(&dome, x, y).unwrap();
            let g = dome.gradient(x, y).unwrap();
            assert!(
                (fd.0 - g.0).abs() < 1e-5 && (fd.1 - g.1).abs() < 1e-5,
                "({x}, {y})"
            );
        }
        assert_eq!(dome.height(36.0, 0.0), None);
    }
}
