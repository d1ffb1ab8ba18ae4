//! Closed-form kinematics and force normalisation of the standard shear tests (docs/model.md §5).

use crate::limits::shown_apart;
use std::f64::consts::FRAC_PI_2;

/// The bias-extension kinematics needs a free length `length` of at least twice the width
/// `width` (mm); the refusal shows the ratio with the digits that put it below 2.
pub fn check_bias_aspect(width: f64, length: f64) -> Result<(), String> {
    if length < 2.0 * width {
        return Err(format!(
            "length/width = {}: the bias-extension kinematics (docs/model.md §5) needs a free \
             length of at least twice the width",
            shown_apart(length / width, 2.0)
        ));
    }
    Ok(())
}

/// Bias extension of a specimen `width` x `length` (free length, `length/width >= 2`):
/// pin-jointed shear angle of the central zone at crosshead displacement `d` (radians),
/// `gamma = 90° - 2 arccos((D + d) / (sqrt(2) D))`, `D = length - width`.
pub fn bias_extension_shear_angle(width: f64, length: f64, d: f64) -> f64 {
    let big_d = length - width;
    let c = ((big_d + d) / (std::f64::consts::SQRT_2 * big_d)).clamp(-1.0, 1.0);
    FRAC_PI_2 - 2.0 * c.acos()
}

/// Crosshead displacement at which the pin-jointed central zone reaches `gamma` (inverse of
/// [`bias_extension_shear_angle`]).
pub fn bias_extension_displacement(width: f64, length: f64, gamma: f64) -> f64 {
    let big_d = length - width;
    std::f64::consts::SQRT_2 * big_d * ((FRAC_PI_2 - gamma) / 2.0).cos() - big_d
}

/// Bias-extension force produced by a normalised shear force `f_sh(gamma)` (N/mm) at shear
/// angle `gamma` of the central zone, from the energy balance of Cao et al. 2008 (the forward
/// form of [`bias_extension_normalised_shear_force`]).
pub fn bias_extension_force(width: f64, length: f64, gamma: f64, f_sh: impl Fn(f64) -> f64) -> f64 {
    let (w, h) = (width, length);
    let half = 0.5 * gamma;
    ((2.0 * h - 3.0 * w) * gamma.cos() * f_sh(gamma) + w * f_sh(half) * half.cos())
        / ((h / w - 1.0) * (half.cos() - half.sin()))
}

/// Normalised shear force from a measured bias-extension curve (docs/model.md §5, Cao et al. 2008):
/// `F_sh(g) = [(H/W - 1) F (cos(g/2) - sin(g/2)) - W F_sh(g/2) cos(g/2)] / [(2H - 3W) cos g]`,
/// solved from small angles up. `F_sh(g/2)` is interpolated in the values already found;
/// below the first of them `F_sh` is taken proportional to `g`, so `F_sh(g/2) = F_sh(g)/2`.
/// Returns `(gamma, F_sh)` per point with positive displacement, in the input order, which
/// must be increasing in displacement.
pub fn bias_extension_normalised_shear_force(
    width: f64,
    length: f64,
    displacement: &[f64],
    force: &[f64],
) -> Vec<(f64, f64)> {
    let (w, h) = (width, length);
    let mut found: Vec<(f64, f64)> = Vec::with_capacity(displacement.len());
    for (&d, &f) in displacement.iter().zip(force) {
        if d <= 0.0 {
            continue;
        }
        let gamma = bias_extension_shear_angle(w, h, d);
        let half = 0.5 * gamma;
        let driving = (h / w - 1.0) * f * (half.cos() - half.sin());
        let denominator = (2.0 * h - 3.0 * w) * gamma.cos();
        let f_sh = match interpolate(&found, half) {
            Some(f_half) => (driving - w * f_half * half.cos()) / denominator,
            None => driving / (denominator + 0.5 * w * half.cos()),
        };
        found.push((gamma, f_sh));
    }
    found
}

/// The limit of [`bias_extension_normalised_shear_force`] at zero displacement, where the
/// central zone is not sheared: with `F_sh` proportional to `g` near 0,
/// `F_sh(0) = (H/W - 1) F / (2H - 3W + W/2)`. Zero for a specimen at rest (`F = 0`).
pub fn bias_extension_normalised_shear_force_at_zero_shear(
    width: f64,
    length: f64,
    force: f64,
) -> f64 {
    let (w, h) = (width, length);
    (h / w - 1.0) * force / (2.0 * h - 3.0 * w + 0.5 * w)
}

/// Linear interpolation in increasing `(x, y)` points; `None` outside them.
fn interpolate(points: &[(f64, f64)], x: f64) -> Option<f64> {
    let i = points.partition_point(|p| p.0 < x);
    if i == 0 || i == points.len() {
        return (i > 0 && (points[i - 1].0 - x).abs() < 1e-15).then(|| points[i - 1].1);
    }
    let ((x0, y0), (x1, y1)) = (points[i - 1], points[i]);
    Some(y0 + (y1 - y0) * (x - x0) / (x1 - x0))
}

/// Picture frame of side `side` pulled by `d` along its diagonal: half the angle between the
/// arms, `theta = arccos((sqrt(2) L + d) / (2 L))`, and the shear angle `90° - 2 theta`.
pub fn picture_frame_angles(side: f64, d: f64) -> (f64, f64) {
    let theta = ((std::f64::consts::SQRT_2 * side + d) / (2.0 * side))
        .clamp(-1.0, 1.0)
        .acos();
    (theta, FRAC_PI_2 - 2.0 * theta)
}

/// Normalised shear force of a picture-frame test: `F_s = F / (2 cos theta)`, then
/// `F_norm = F_s L_frame / L_fabric^2` (N/mm).
pub fn picture_frame_normalised_force(
    frame_side: f64,
    fabric_side: f64,
    d: f64,
    force: f64,
) -> f64 {
    let (theta, _) = picture_frame_angles(frame_side, d);
    force / (2.0 * theta.cos()) * frame_side / (fabric_side * fabric_side)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bias_extension_shear_force_at_zero_is_the_limit_of_small_displacements() {
        let (w, h, force) = (150.0, 450.0, 2.5);
        let at_zero = bias_extension_normalised_shear_force_at_zero_shear(w, h, force);
        // (450/150 - 1) 2.5 / (900 - 450 + 75)
        assert!((at_zero - 5.0 / 525.0).abs() < 1e-15, "{at_zero}");
        for d in [1e-3, 1e-5, 1e-7] {
            let f_sh = bias_extension_normalised_shear_force(w, h, &[d], &[force])[0].1;
            assert!(
                (f_sh - at_zero).abs() < 2.0 * d * at_zero,
                "d = {d}: {f_sh} against {at_zero}"
            );
        }
        assert_eq!(
            bias_extension_normalised_shear_force_at_zero_shear(w, h, 0.0),
            0.0
        );
    }

    #[test]
    fn bias_extension_angle_starts_at_zero_and_inverts() {
        assert!(bias_extension_shear_angle(150.0, 450.0, 0.0).abs() < 1e-15);
        for deg in [5.0, 20.0, 40.0, 60.0] {
            let g = f64::to_radians(deg);
            let d = bias_extension_displacement(150.0, 450.0, g);
            assert!((bias_extension_shear_angle(150.0, 450.0, d) - g).abs() < 1e-12);
        }
        // D = 300 mm: 40° of shear needs d = sqrt(2) 300 cos(25°) - 300
        let d40 = bias_extension_displacement(150.0, 450.0, 40f64.to_radians());
        assert!((d40 - (2f64.sqrt() * 300.0 * 25f64.to_radians().cos() - 300.0)).abs() < 1e-9);
    }

    /// A curve generated from a known F_sh is normalised back to it.
    #[test]
    fn normalised_shear_force_round_trip() {
        let f_sh = |g: f64| 0.05 * g + 0.4 * g.powi(3);
        let d: Vec<f64> = (1..=300).map(|i| 0.25 * f64::from(i)).collect();
        let force: Vec<f64> = d
            .iter()
            .map(|&d| {
                bias_extension_force(
                    150.0,
                    450.0,
                    bias_extension_shear_angle(150.0, 450.0, d),
                    f_sh,
                )
            })
            .collect();
        let recovered = bias_extension_normalised_shear_force(150.0, 450.0, &d, &force);
        assert_eq!(recovered.len(), d.len());
        for &(g, value) in recovered.iter().skip(10) {
            assert!(
                (value - f_sh(g)).abs() < 2e-3 * f_sh(g),
                "{}°: {value} vs {}",
                g.to_degrees(),
                f_sh(g)
            );
        }
    }

    #[test]
    fn picture_frame_kinematics() {
        let (theta, gamma) = picture_frame_angles(200.0, 0.0);
        assert!((theta - std::f64::consts::FRAC_PI_4).abs() < 1e-12 && gamma.abs() < 1e-12);
        // arms closing to 60° between them: gamma = 30°
        let d = 2.0 * 200.0 * 30f64.to_radians().cos() - 2f64.sqrt() * 200.0;
        let (_, gamma) = picture_frame_angles(200.0, d);
        assert!((gamma - 30f64.to_radians()).abs() < 1e-12);
        let f = picture_frame_normalised_force(200.0, 200.0, d, 10.0);
        assert!((f - 10.0 / (2.0 * 30f64.to_radians().cos()) / 200.0).abs() < 1e-12);
    }
}
