//! The shortcuts of the material evaluation give the very numbers of the plain evaluation:
//! parameters pinned at the run's temperature, `S33` alone for the plane-stress slope probe,
//! and both stable-step moduli from one call.

mod common;

use common::*;
use nalgebra::{Matrix2, Matrix3};
use proptest::prelude::*;
use thermostamp::material::{
    FibreDirections, Laminate, MaterialLaw, MembraneKinematics, PointKinematics,
};

const T: f64 = 300.0;

fn laws() -> Vec<std::sync::Arc<dyn MaterialLaw>> {
    let card = t300_card();
    card.laminate
        .layers()
        .iter()
        .map(|l| l.law.clone())
        .collect()
}

/// The same membrane history on two laminates, compared bit for bit.
fn assert_same_history(a: &Laminate, b: &Laminate, temperature: f64) {
    let (mut sa, mut sb) = (a.initial_state(), b.initial_state());
    for i in 0..200 {
        let g = 0.2 + 1e-3 * i as f64;
        let kin = MembraneKinematics {
            c: Matrix2::new(1.0 + 0.5 * g * g, g, g, 1.0 + g * g),
            c_dot: Matrix2::new(0.05, 0.3, 0.3, 0.2 * g),
            temperature,
            fibres: FibreDirections::in_plane(0.3),
        };
        let ra = a.membrane_response(&kin, 1e-3, &mut sa).unwrap();
        let rb = b.membrane_response(&kin, 1e-3, &mut sb).unwrap();
        assert_eq!(ra, rb, "step {i}");
        assert_eq!(sa, sb, "step {i}");
        assert_eq!(a.step_moduli(&kin, &sa), b.step_moduli(&kin, &sb));
        assert_eq!(a.stored_energy(&kin, &sa), b.stored_energy(&kin, &sb));
    }
}

#[test]
fn pinned_laminate_reproduces_the_tables_bit_for_bit() {
    let laminate = t300_card().laminate;
    let pinned = laminate.at_temperature(T);
    assert_same_history(&laminate, &pinned, T);
    // another temperature is still interpolated
    assert_same_history(&laminate, &pinned, T + 7.3);
    // and time scaling keeps the pinned parameters consistent with the scaled tables
    assert_same_history(&laminate.time_scaled(25.0), &pinned.time_scaled(25.0), T);
}

#[test]
fn pinned_laminate_reports_temperatures_outside_the_tables() {
    let laminate = t300_card().laminate;
    let (hot, pinned_hot) = (1e4, laminate.at_temperature(1e4));
    let kin = MembraneKinematics {
        c: Matrix2::identity(),
        c_dot: Matrix2::zeros(),
        temperature: hot,
        fibres: FibreDirections::default(),
    };
    let plain = laminate.membrane_response(&kin, 0.0, &mut laminate.initial_state());
    let pinned = pinned_hot.membrane_response(&kin, 0.0, &mut laminate.initial_state());
    assert!(plain.is_err());
    assert_eq!(plain, pinned);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn through_thickness_stress_is_the_33_component(f in deformation_gradient(), f_dot in deformation_rate()) {
        let p = PointKinematics::from_deformation(&f, &f_dot, T, FibreDirections::in_plane(0.4));
        for law in laws() {
            let s: Matrix3<f64> = law.second_piola_kirchhoff(&p).unwrap();
            prop_assert_eq!(law.through_thickness_stress(&p).unwrap(), s[(2, 2)], "{}", law.name());
        }
    }

    #[test]
    fn step_moduli_are_the_two_moduli(f in deformation_gradient(), f_dot in deformation_rate()) {
        let p = PointKinematics::from_deformation(&f, &f_dot, T, FibreDirections::in_plane(0.4));
        for law in laws() {
            let both = law.step_moduli(&p).unwrap();
            prop_assert_eq!(both.wave, law.wave_modulus(&p).unwrap());
            prop_assert_eq!(both.viscous, law.viscous_modulus(&p).unwrap());
        }
    }
}
