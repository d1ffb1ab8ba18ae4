//! Linear viscosity on the yarn strain rates: the membrane counterpart of the linear bulk
//! viscosity of explicit codes.
//!
//! Why: a yarn is ~1000 times stiffer in tension than in compression (docs/model.md §3), so a yarn
//! that chatters about its rest length switches stiffness within a step. Central differences
//! are not energy-conserving across such a kink: on fine meshes of a bias-extension specimen
//! (7.5 mm cells) the yarn modes slowly gain energy until the run is ruined, while a linear
//! yarn law stays exact. A viscosity of a few per cent of critical on the yarn strain rates
//! removes this ringing. Quasi-static yarn strain rates are tiny (the yarns barely stretch
//! while the fabric shears), so the measured forces are not biased; the power it takes is
//! booked in [`super::Energies::numerical_damping`].
//!
//! With `xi` the fraction of critical damping of the element's highest yarn mode
//! (`omega ~ 2 / dt_e`, `dt_e` the element's stable step), the coefficient is
//! `c = 2 xi / omega = xi dt_e`, and the damping resultant per unit reference width is
//! `N_d = xi dt_e E_e t0 (edot_a a0 (x) a0 + edot_b b0 (x) b0)`, `edot_a = a0 . Edot . a0`,
//! `Edot = Cdot / 2`. The critical step of a damped oscillator is
//! `(2 / omega)(sqrt(1 + xi^2) - xi)`: the stable step is reduced by that factor.

use crate::material::MembraneKinematics;
use nalgebra::{Matrix2, Vector2};

/// The damping resultant `N_d` (N/mm) of one element, and the power it takes per unit
/// reference area, `N_d : Edot` (>= 0).
pub fn yarn_damping_resultant(
    kin: &MembraneKinematics,
    xi: f64,
    element_step: f64,
    modulus: f64,
    thickness: f64,
) -> (Matrix2<f64>, f64) {
    let c = xi * element_step * modulus * thickness;
    let e_dot = 0.5 * kin.c_dot;
    let mut n = Matrix2::zeros();
    let mut power = 0.0;
    for fibre in [&kin.fibres.warp, &kin.fibres.weft] {
        let a = Vector2::new(fibre.x, fibre.y);
        let rate = a.dot(&(e_dot * a));
        n += a * a.transpose() * (c * rate);
        power += c * rate * rate;
    }
    (n, power)
}

/// Factor on the undamped critical step, `sqrt(1 + xi^2) - xi`.
pub fn step_reduction(xi: f64) -> f64 {
    (1.0 + xi * xi).sqrt() - xi
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::FibreDirections;

    fn kinematics(c_dot: Matrix2<f64>) -> MembraneKinematics {
        MembraneKinematics {
            c: Matrix2::identity(),
            c_dot,
            temperature: 20.0.into(),
            fibres: FibreDirections::in_plane(0.3),
        }
    }

    #[test]
    fn pure_shear_in_the_yarn_frame_is_not_damped() {
        // Edot = s (a0 (x) b0 + b0 (x) a0): no stretching along either yarn
        let f = FibreDirections::in_plane(0.3);
        let (a, b) = (
            Vector2::new(f.warp.x, f.warp.y),
            Vector2::new(f.weft.x, f.weft.y),
        );
        let e_dot = (a * b.transpose() + b * a.transpose()) * 0.7;
        let (n, power) = yarn_damping_resultant(&kinematics(2.0 * e_dot), 0.06, 1e-6, 4e3, 0.3);
        assert!(n.amax() < 1e-15 && power.abs() < 1e-15);
    }

    #[test]
    fn yarn_stretching_is_resisted_and_the_power_is_the_resultant_times_the_rate() {
        let f = FibreDirections::in_plane(0.3);
        let a = Vector2::new(f.warp.x, f.warp.y);
        let e_dot = a * a.transpose() * 2.5;
        let (xi, dt, e, t) = (0.06, 1e-6, 4e3, 0.3);
        let (n, power) = yarn_damping_resultant(&kinematics(2.0 * e_dot), xi, dt, e, t);
        let expected = a * a.transpose() * (xi * dt * e * t * 2.5);
        assert!((n - expected).amax() < 1e-15);
        assert!((power - n.dot(&e_dot)).abs() < 1e-15 && power > 0.0);
    }

    #[test]
    fn damped_critical_step_shrinks_with_damping() {
        assert_eq!(step_reduction(0.0), 1.0);
        assert!((step_reduction(0.06) - 0.9417).abs() < 1e-4);
    }
}
