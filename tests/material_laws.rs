//! Checks of the layer laws against physics (docs/model.md §7): stress as the derivative of the
//! energy, objectivity, rest state, symmetry, and closed-form responses.

mod common;

use common::*;
use nalgebra::{Matrix3, Vector3};
use proptest::prelude::*;
use std::f64::consts::FRAC_PI_2;
use thermostamp::experiment::material_point::{drive_layer, matrix_uniaxial_stress, PointSample};
use thermostamp::material::fabric::{
    shear_angle, ShearInteraction, ShearTerm, YarnTension, SLACK_BAND,
};
use thermostamp::material::{
    cauchy_stress, FibreDirections, MaterialError, MaterialLaw, PointKinematics, TemperatureTable,
    ViscoHyperelasticMatrix, WovenFabric,
};

const T: f64 = 300.0;

fn matrix_with(c10: f64, d1: f64, eta1: f64) -> ViscoHyperelasticMatrix {
    let table =
        |name: &str, v: f64| TemperatureTable::new(name, vec![280.0, 320.0], vec![v, v]).unwrap();
    ViscoHyperelasticMatrix::new(table("c10", c10), table("d1", d1), table("eta1", eta1))
}

/// An unbalanced fabric so that warp and weft can be told apart.
fn unbalanced_fabric() -> WovenFabric {
    WovenFabric::new(
        YarnTension::new(vec![4.0e4, 2.0e6], 1e-3),
        YarnTension::new(vec![1.0e4, 5.0e5, 3.0e7], 1e-3),
        ShearInteraction::new(vec![0.25, 0.1, 2.0]),
    )
}

/// The unbalanced fabric with every kind of shear term (docs/model.md §3): friction-like (onset
/// 2°), polynomial and locking beyond 40°.
fn fabric_with_every_shear_term() -> WovenFabric {
    let fabric = unbalanced_fabric();
    WovenFabric::new(
        fabric.warp,
        fabric.weft,
        ShearInteraction::from_terms(vec![
            (
                ShearTerm::Friction {
                    onset: 2f64.to_radians(),
                },
                0.3,
            ),
            (ShearTerm::Power(1), 0.25),
            (ShearTerm::Power(3), 2.0),
            (
                ShearTerm::Locking {
                    angle: 40f64.to_radians(),
                },
                20.0,
            ),
        ]),
    )
}

fn point(f: &Matrix3<f64>, f_dot: &Matrix3<f64>, fibres: FibreDirections) -> PointKinematics {
    PointKinematics::from_deformation(f, f_dot, T, fibres)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// docs/model.md §7.1, matrix: S_e = 2 dW_e/dC and S_v = 2 dpsi_v/dCdot (Eqs. (5)–(9) of Gong
    /// et al. 2018).
    #[test]
    fn matrix_stress_is_twice_the_energy_gradient(f in deformation_gradient(), f_dot in deformation_rate()) {
        let card = t300_card();
        let law = card.matrix.as_deref().unwrap();
        let p = point(&f, &f_dot, FibreDirections::default());
        let at_rest_rate = PointKinematics { c_dot: Matrix3::zeros(), ..p };
        let s_e = law.second_piola_kirchhoff(&at_rest_rate).unwrap();
        let s_total = law.second_piola_kirchhoff(&p).unwrap();
        let w = |c: &Matrix3<f64>| law.strain_energy(&PointKinematics { c: *c, ..p }).unwrap();
        let psi = |c_dot: &Matrix3<f64>| law.viscous_potential(&PointKinematics { c_dot: *c_dot, ..p }).unwrap();
        let s_e_fd = twice_gradient_by_differences(w, &p.c, 1e-6);
        let s_v_fd = twice_gradient_by_differences(psi, &p.c_dot, 1e-4);
        let scale = s_e.amax().max(0.1);
        prop_assert!(relative_difference(&s_e, &s_e_fd, scale) < 1e-6, "S_e {s_e} vs {s_e_fd}");
        // S_v is taken as S_total - S_e, so it carries the rounding of S_e (a few ulp of it):
        // 1e-6 of S_v is asked for, above that floor.
        let s_v = s_total - s_e;
        let rounding = 64.0 * f64::EPSILON * s_e.amax();
        let tolerance = 1e-6 * s_v.amax() + rounding;
        prop_assert!((s_v - s_v_fd).amax() < tolerance.max(1e-15), "S_v {s_v} vs {s_v_fd}, S_e {s_e}");
    }

    /// docs/model.md §7.1, fabric, including large shear (|gamma| up to 60°) and compressed yarns.
    #[test]
    fn fabric_stress_is_twice_the_energy_gradient(
        gamma in -60.0..60.0f64,
        la in 0.85..1.03f64,
        lb in 0.85..1.03f64,
        angle in 0.0..180.0f64,
        r in prop::array::uniform3(-3.0..3.0f64),
    ) {
        let fibres = FibreDirections::in_plane(angle.to_radians());
        // shear the material frame, then rotate it in the plane to the fibre angle
        let to_fibres = rotation([0.0, 0.0, angle.to_radians()]);
        let f = rotation(r) * to_fibres * trellis(gamma.to_radians(), la, lb, 1.1) * to_fibres.transpose();
        let p = point(&f, &Matrix3::zeros(), fibres);
        for law in [unbalanced_fabric(), fabric_with_every_shear_term()] {
            let s = law.second_piola_kirchhoff(&p).unwrap();
            let w = |c: &Matrix3<f64>| law.strain_energy(&PointKinematics { c: *c, ..p }).unwrap();
            let s_fd = twice_gradient_by_differences(w, &p.c, 1e-7);
            prop_assert!(relative_difference(&s, &s_fd, s.amax().max(1.0)) < 1e-6, "{s} vs {s_fd}");
        }
        let measured = shear_angle(&p.c, &fibres).to_degrees();
        prop_assert!((measured - gamma).abs() < 1e-9, "shear angle {measured} vs {gamma}");
    }

    /// docs/model.md §7.2: F -> R F leaves S unchanged, also under a spinning R (Cdot is
    /// objective).
    #[test]
    fn both_layers_are_objective(
        f in deformation_gradient(),
        f_dot in deformation_rate(),
        r in prop::array::uniform3(-3.0..3.0f64),
        spin in prop::array::uniform3(-5.0..5.0f64),
    ) {
        let card = t300_card();
        let fibres = FibreDirections::in_plane(0.3);
        let q = rotation(r);
        let omega = Matrix3::new(0.0, -spin[2], spin[1], spin[2], 0.0, -spin[0], -spin[1], spin[0], 0.0);
        let q_dot = omega * q; // d/dt of a rotation spinning at omega
        let laws: [&dyn MaterialLaw; 2] = [card.matrix.as_deref().unwrap(), card.fabric.as_ref()];
        for law in laws {
            let s = law.second_piola_kirchhoff(&point(&f, &f_dot, fibres)).unwrap();
            let rotated = point(&(q * f), &(q_dot * f + q * f_dot), fibres);
            let s_rotated = law.second_piola_kirchhoff(&rotated).unwrap();
            prop_assert!(relative_difference(&s, &s_rotated, s.amax().max(1e-3)) < 1e-9, "{}", law.name());
            // S symmetric, and the Cauchy stress rotates with the body
            prop_assert!(relative_difference(&s, &s.transpose(), s.amax().max(1e-3)) < 1e-12);
            let sigma = cauchy_stress(&f, &s);
            let sigma_rotated = cauchy_stress(&(q * f), &s_rotated);
            prop_assert!(relative_difference(&(q * sigma * q.transpose()), &sigma_rotated, sigma.amax().max(1e-3)) < 1e-9);
        }
    }

    /// Rotating the fibre angle by 90° swaps warp and weft.
    #[test]
    fn quarter_turn_of_the_fibres_swaps_warp_and_weft(f in deformation_gradient()) {
        let fabric = unbalanced_fabric();
        let swapped = WovenFabric::new(fabric.weft.clone(), fabric.warp.clone(), fabric.shear.clone());
        let s_turned = fabric.second_piola_kirchhoff(&point(&f, &Matrix3::zeros(), FibreDirections::in_plane(FRAC_PI_2))).unwrap();
        let s_swapped = swapped.second_piola_kirchhoff(&point(&f, &Matrix3::zeros(), FibreDirections::in_plane(0.0))).unwrap();
        prop_assert!(relative_difference(&s_turned, &s_swapped, s_turned.amax().max(1.0)) < 1e-12);
    }
}

/// `dS` along `(dC, dCdot)` by central differences of the stress of `law` (step `h` of both).
fn stress_change_by_differences(
    law: &dyn MaterialLaw,
    p: &PointKinematics,
    (dc, dc_dot): (&Matrix3<f64>, &Matrix3<f64>),
    h: f64,
) -> Matrix3<f64> {
    let at = |sign: f64| {
        let moved = PointKinematics {
            c: p.c + dc * (sign * h),
            c_dot: p.c_dot + dc_dot * (sign * h),
            ..*p
        };
        law.second_piola_kirchhoff(&moved).unwrap()
    };
    (at(1.0) - at(-1.0)) / (2.0 * h)
}

/// A symmetric direction from six numbers.
fn symmetric(v: [f64; 6]) -> Matrix3<f64> {
    Matrix3::new(v[0], v[3], v[4], v[3], v[1], v[5], v[4], v[5], v[2])
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// docs/model.md §2 and §3, "Tangent": each law's stress derivatives (the implicit
    /// solver's consistent tangent) equal central differences of its stress along random
    /// changes of `C` and `Cdot`; the matrix with its viscous stress, the fabric with yarns
    /// slack, in their slack band and taut.
    #[test]
    fn stress_derivatives_are_the_derivatives_of_the_stress(
        f in deformation_gradient(),
        f_dot in deformation_rate(),
        gamma in -60.0..60.0f64,
        la in 0.98..1.01f64,
        lb in 0.98..1.01f64,
        dc in prop::array::uniform6(-1.0..1.0f64),
        dc_dot in prop::array::uniform6(-1.0..1.0f64),
    ) {
        // Central differences are no reference where a yarn's stretch lies within their reach
        // (about 1e-6) of a kink of its tension's curvature: the rest length and the end of
        // the slack band (docs/model.md §3).
        let away_from_kinks = |l: f64| (l - 1.0).abs() > 1e-5 && (l - 1.0 - SLACK_BAND).abs() > 1e-5;
        prop_assume!(away_from_kinks(la) && away_from_kinks(lb));
        let card = t300_card();
        let matrix = card.matrix.as_deref().unwrap();
        let fabric = unbalanced_fabric();
        let every_term = fabric_with_every_shear_term();
        let fibres = FibreDirections::in_plane(0.4);
        let to_fibres = rotation([0.0, 0.0, 0.4]);
        let sheared = to_fibres * trellis(gamma.to_radians(), la, lb, 1.0) * to_fibres.transpose();
        let cases: [(&dyn MaterialLaw, PointKinematics, f64); 3] = [
            (matrix, point(&f, &f_dot, fibres), 1e-6),
            // at 1e-7 the rounding of the stress over the step reached 1e-5 of the derivative
            (&fabric, point(&sheared, &Matrix3::zeros(), fibres), 1e-6),
            (&every_term, point(&sheared, &Matrix3::zeros(), fibres), 1e-6),
        ];
        let direction = (symmetric(dc), symmetric(dc_dot));
        for (law, p, h) in cases {
            let mut exact = [Matrix3::zeros()];
            prop_assert!(law.stress_derivatives(&p, &[direction], &mut exact).unwrap());
            let by_differences = stress_change_by_differences(law, &p, (&direction.0, &direction.1), h);
            let scale = by_differences.amax().max(exact[0].amax()).max(1e-3);
            prop_assert!(
                relative_difference(&exact[0], &by_differences, scale) < 1e-5,
                "{}: {} vs {}", law.name(), exact[0], by_differences
            );
        }
    }
}

/// docs/model.md §7.3: no stress in the undeformed state at rest, at every table temperature.
#[test]
fn no_stress_at_rest() {
    let card = t300_card();
    for temperature in [280.0, 295.0, 320.0] {
        let rest = PointKinematics::at_rest(temperature, FibreDirections::in_plane(0.7));
        for law in [
            card.matrix.as_deref().unwrap() as &dyn MaterialLaw,
            card.fabric.as_ref(),
        ] {
            let s = law.second_piola_kirchhoff(&rest).unwrap();
            assert!(s.amax() < 1e-14, "{}: {s}", law.name());
            assert_eq!(law.strain_energy(&rest).unwrap(), 0.0);
        }
    }
}

/// The closed form of docs/model.md §5 for incompressible uniaxial tension:
/// sigma11 = 2 C10 (l^2 - 1/l) + 2 eta1 (l^2 + 2/l - 3)(2 l^3 + l^-3) ldot.
fn uniaxial_closed_form(c10: f64, eta1: f64, l: f64, l_dot: f64) -> f64 {
    2.0 * c10 * (l * l - 1.0 / l)
        + 2.0 * eta1 * (l * l + 2.0 / l - 3.0) * (2.0 * l.powi(3) + l.powi(-3)) * l_dot
}

/// docs/model.md §7.4, exact kinematics: for an isochoric stretch the pressure-free difference
/// sigma11 - sigma22 is the closed form, whatever D1.
#[test]
fn matrix_isochoric_stretch_matches_the_closed_form() {
    let (c10, eta1) = (0.1, 0.05);
    let law = matrix_with(c10, 1e-3, eta1);
    for (l, l_dot) in [
        (1.0_f64, 0.5),
        (1.2, 0.0),
        (1.5, 0.1),
        (2.0, 1.0),
        (0.8, -0.3),
    ] {
        let f = Matrix3::from_diagonal(&Vector3::new(l, l.powf(-0.5), l.powf(-0.5)));
        let f_dot = Matrix3::from_diagonal(&Vector3::new(
            l_dot,
            -0.5 * l.powf(-1.5) * l_dot,
            -0.5 * l.powf(-1.5) * l_dot,
        ));
        let s = law
            .second_piola_kirchhoff(&point(&f, &f_dot, FibreDirections::default()))
            .unwrap();
        let sigma = cauchy_stress(&f, &s);
        let expected = uniaxial_closed_form(c10, eta1, l, l_dot);
        let got = sigma[(0, 0)] - sigma[(1, 1)];
        assert!(
            (got - expected).abs() <= 1e-10 * expected.abs().max(c10),
            "l = {l}: {got} vs {expected}"
        );
    }
}

/// docs/model.md §7.4, uniaxial stress: lateral stretches solved for S22 = S33 = 0 with a small D1
/// converge to the incompressible closed form, elastic and viscous.
#[test]
fn matrix_uniaxial_stress_with_small_d1_matches_the_closed_form() {
    let (c10, eta1, l_dot) = (0.1, 0.05, 0.5);
    for d1 in [1e-4, 1e-6] {
        let law = matrix_with(c10, d1, eta1);
        let times: Vec<f64> = (0..=2000).map(|i| i as f64 * 1e-3).collect();
        let stretches: Vec<f64> = times.iter().map(|t| 1.0 + l_dot * t).collect();
        let response = matrix_uniaxial_stress(&law, &times, &stretches, T).unwrap();
        let mut worst: f64 = 0.0;
        for ((&l, &(lateral, sigma11)), _) in stretches.iter().zip(&response).zip(&times).skip(10) {
            let expected = uniaxial_closed_form(c10, eta1, l, l_dot);
            worst = worst.max((sigma11 - expected).abs() / expected);
            assert!(
                (lateral - l.powf(-0.5)).abs() < 100.0 * d1 * c10,
                "lateral stretch {lateral} at l = {l}"
            );
        }
        // error of order D1 C10 from compressibility plus O(dt) from the lateral rate
        assert!(worst < 2e-3, "D1 = {d1}: worst relative error {worst}");
    }
}

/// The viscous stress raises the uniaxial stress with the rate and vanishes at rest.
#[test]
fn matrix_uniaxial_stress_grows_with_rate_and_falls_with_temperature() {
    let card = t300_card();
    let at = |temperature: f64, rate: f64| {
        let times = [0.0, 0.5 / rate, 1.0 / rate];
        let stretches = [1.0, 1.25, 1.5];
        matrix_uniaxial_stress(
            card.matrix.as_deref().unwrap(),
            &times,
            &stretches,
            temperature,
        )
        .unwrap()[2]
            .1
    };
    assert!(at(300.0, 10.0) > at(300.0, 0.1));
    assert!(at(280.0, 1.0) > at(300.0, 1.0) && at(300.0, 1.0) > at(320.0, 1.0));
}

/// The driver's finite-difference rates reproduce the exact viscous stress of a history whose
/// F is linear in time (C quadratic: three-point differences are exact).
#[test]
fn driver_rates_are_exact_for_linear_histories() {
    let law = matrix_with(0.1, 1e-3, 0.05);
    let f_dot = Matrix3::new(0.3, 0.1, 0.0, -0.2, 0.1, 0.05, 0.0, 0.02, -0.1);
    let history: Vec<PointSample> = [0.0, 0.3, 0.5, 1.1, 1.2]
        .iter()
        .map(|&t| PointSample {
            t,
            f: Matrix3::identity() + f_dot * t,
            temperature: T,
        })
        .collect();
    let out = drive_layer(&law, FibreDirections::default(), &history).unwrap();
    for (sample, response) in history.iter().zip(&out) {
        let exact = law
            .second_piola_kirchhoff(&point(&sample.f, &f_dot, FibreDirections::default()))
            .unwrap();
        assert!(
            relative_difference(&response.s, &exact, exact.amax().max(1e-9)) < 1e-10,
            "t = {}",
            sample.t
        );
    }
}

/// docs/model.md §7.5: pure shear of the fabric layer, F_sh = 2 t_B sin(gamma) W_s'(sin^2 gamma),
/// from the stress and from the energy along the shear path, up to 60°.
#[test]
fn fabric_pure_shear_matches_the_normalised_shear_force() {
    let card = t300_card();
    let t_b = card.laminate.layers()[1].thickness;
    let fabric = card.fabric.as_ref();
    let fibres = FibreDirections::default();
    let energy = |g: f64| {
        fabric
            .strain_energy(&point(
                &trellis(g, 1.0, 1.0, 1.0),
                &Matrix3::zeros(),
                fibres,
            ))
            .unwrap()
    };
    for deg in (1..=60).step_by(3) {
        let g = f64::from(deg).to_radians();
        let expected = fabric.shear.normalised_shear_force(t_b, g);
        let by_formula = 2.0 * t_b * g.sin() * (0.25 + 3.0 * 2.0 * g.sin().powi(4)); // card: c = [0.25, 0, 2]
        assert!((expected - by_formula).abs() < 1e-12 * by_formula);
        let s = fabric
            .second_piola_kirchhoff(&point(
                &trellis(g, 1.0, 1.0, 1.0),
                &Matrix3::zeros(),
                fibres,
            ))
            .unwrap();
        // shear power per unit area: F_sh cos(gamma) = t_B dW/dgamma, and S12 = dW/dC12 pairs with dC12 = cos(g) dg
        let from_stress = t_b * s[(0, 1)];
        let h = 1e-6;
        let from_energy = t_b * (energy(g + h) - energy(g - h)) / (2.0 * h) / g.cos();
        assert!(
            (from_stress - expected).abs() < 1e-10 * expected,
            "{deg}°: {from_stress} vs {expected}"
        );
        assert!(
            (from_energy - expected).abs() < 1e-6 * expected,
            "{deg}°: {from_energy} vs {expected}"
        );
        // inextensible yarns: no warp or weft strain energy
        assert!((energy(g) - fabric.shear.energy(g.sin().powi(2))).abs() < 1e-15);
    }
}

/// docs/model.md §7.6: tension along the warp only activates the warp term, at any fibre angle.
#[test]
fn fabric_tension_along_the_warp_activates_only_the_warp() {
    let fabric = unbalanced_fabric();
    let no_weft = WovenFabric::new(
        fabric.warp.clone(),
        YarnTension::new(vec![1.0], 0.0),
        fabric.shear.clone(),
    );
    for angle_deg in [0.0, 30.0, 90.0, 137.0] {
        let fibres = FibreDirections::in_plane(f64::to_radians(angle_deg));
        let a0 = fibres.warp;
        for strain in [0.002, 0.01, -0.01] {
            let l = 1.0 + strain;
            // stretch l along the warp, nothing across it
            let f = Matrix3::identity() + a0 * a0.transpose() * strain;
            let s = fabric
                .second_piola_kirchhoff(&point(&f, &Matrix3::zeros(), fibres))
                .unwrap();
            let expected = a0 * a0.transpose() * (fabric.warp.tension(l) / l);
            assert!(
                relative_difference(&s, &expected, expected.amax()) < 1e-12,
                "{angle_deg}°, {strain}"
            );
            let s_no_weft = no_weft
                .second_piola_kirchhoff(&point(&f, &Matrix3::zeros(), fibres))
                .unwrap();
            assert_eq!(s, s_no_weft);
        }
    }
    // compression is carried with f A2 only
    let tension = YarnTension::new(vec![4.0e4, 2.0e6], 1e-3);
    assert!((tension.tension(0.99) + 1e-3 * 4.0e4 * 0.01).abs() < 1e-12);
    // past the slack band (docs/model.md §3) the taut branch is shifted by (1 - f) A2 band / 2
    let shift = 0.5 * (4.0e4 - 40.0) * thermostamp::material::fabric::SLACK_BAND;
    assert!((tension.tension(1.01) - (4.0e4 * 0.01 + 2.0e6 * 1e-4 - shift)).abs() < 1e-9);
}

#[test]
fn temperature_outside_the_table_is_an_error() {
    let card = t300_card();
    let hot = PointKinematics::at_rest(350.0, FibreDirections::default());
    let e = card
        .matrix
        .as_deref()
        .unwrap()
        .second_piola_kirchhoff(&hot)
        .unwrap_err();
    assert!(
        matches!(e, MaterialError::TemperatureOutOfRange { .. }),
        "{e}"
    );
    assert!(e.to_string().contains("150 to 320"), "{e}");
}

#[test]
fn inverted_or_nan_deformations_are_errors_not_nans() {
    let card = t300_card();
    let inverted = Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, -1.0));
    let c = PointKinematics {
        c: inverted,
        ..PointKinematics::at_rest(T, FibreDirections::default())
    };
    assert!(matches!(
        card.matrix.as_deref().unwrap().second_piola_kirchhoff(&c),
        Err(MaterialError::NonPositiveVolume { .. })
    ));
    let nan = PointKinematics {
        c: Matrix3::from_element(f64::NAN),
        ..c
    };
    for law in [
        card.matrix.as_deref().unwrap() as &dyn MaterialLaw,
        card.fabric.as_ref(),
    ] {
        assert!(matches!(
            law.second_piola_kirchhoff(&nan),
            Err(MaterialError::NonFinite { .. })
        ));
    }
}
