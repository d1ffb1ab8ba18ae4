//! Checks of the A:B:A laminate (docs/model.md §4): plane stress in every layer, thickness,
//! membrane resultant as the derivative of the stored energy, objectivity, rate effect.

mod common;

use common::*;
use nalgebra::{Matrix2, Matrix3, Matrix3x2, Vector2};
use proptest::prelude::*;
use std::sync::Arc;
use thermostamp::experiment::material_point::{drive_laminate, MembraneSample};
use thermostamp::material::fabric::SLACK_BAND;
use thermostamp::material::laminate::BackwardEulerStep;
use thermostamp::material::{
    FibreDirections, Laminate, Layer, MaterialCard, MaterialError, MaterialLaw, MembraneKinematics,
};

const T: f64 = 300.0;

fn kinematics(f: &Matrix2<f64>, f_dot: &Matrix2<f64>, angle: f64) -> MembraneKinematics {
    MembraneKinematics::from_deformation(
        &in_plane(f),
        &in_plane(f_dot),
        T,
        FibreDirections::in_plane(angle),
    )
}

fn in_plane_gradient() -> impl Strategy<Value = Matrix2<f64>> {
    prop::array::uniform4(-0.3..0.3f64)
        .prop_map(|h| Matrix2::identity() + Matrix2::from_row_slice(&h))
        .prop_filter("det F >= 0.5", |f| f.determinant() >= 0.5)
}

/// Largest |S33| over the plane-stress layers, relative to the largest in-plane stress.
fn worst_plane_stress_residual(
    laminate: &Laminate,
    kin: &MembraneKinematics,
    state: &thermostamp::material::LaminateState,
) -> f64 {
    (0..laminate.layers().len())
        .filter(|&k| laminate.layers()[k].law.name() == "matrix")
        .map(|k| {
            let s = laminate.layer_stress(k, kin, state).unwrap();
            let scale = s.fixed_view::<2, 2>(0, 0).amax().max(1e-12);
            s[(2, 2)].abs() / scale
        })
        .fold(0.0, f64::max)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// Plane stress holds in every matrix layer (|S33| < 1e-8 of the in-plane stress), with and
    /// without the viscous thickness rate.
    #[test]
    fn matrix_layers_are_in_plane_stress(
        f in in_plane_gradient(),
        f_dot in prop::array::uniform4(-1.0..1.0f64),
        angle in 0.0..3.2f64,
        dt in prop::sample::select(vec![0.0, 1e-4, 1e-2]),
    ) {
        let laminate = t300_card().laminate;
        let kin = kinematics(&f, &Matrix2::from_row_slice(&f_dot), angle);
        let mut state = laminate.initial_state();
        laminate.membrane_response(&kin, dt, &mut state).unwrap();
        let residual = worst_plane_stress_residual(&laminate, &kin, &state);
        prop_assert!(residual < 1e-8, "|S33| / in-plane = {residual:e}");
    }

    /// docs/model.md §4: with plane stress the membrane resultant is the derivative of the stored
    /// energy per unit area, N = 2 d(sum t_k W_k)/dC2 (elastic: at rest, no step duration).
    #[test]
    fn membrane_resultant_is_twice_the_energy_gradient(f in in_plane_gradient(), angle in 0.0..3.2f64) {
        let laminate = t300_card().laminate;
        let kin = kinematics(&f, &Matrix2::zeros(), angle);
        let energy = |c: &Matrix3<f64>| {
            let k = MembraneKinematics { c: c.fixed_view::<2, 2>(0, 0).into(), ..kin };
            let mut state = laminate.initial_state();
            laminate.membrane_response(&k, 0.0, &mut state).unwrap();
            laminate.stored_energy(&k, &state).unwrap()
        };
        let mut c3 = Matrix3::identity();
        c3.fixed_view_mut::<2, 2>(0, 0).copy_from(&kin.c);
        let n_fd = twice_gradient_by_differences(energy, &c3, 1e-7);
        let mut state = laminate.initial_state();
        let n = laminate.membrane_response(&kin, 0.0, &mut state).unwrap().n;
        let mut n3 = Matrix3::zeros();
        n3.fixed_view_mut::<2, 2>(0, 0).copy_from(&n);
        prop_assert!(relative_difference(&n3, &n_fd, n.amax().max(1e-3)) < 1e-5, "{n} vs {n_fd}");
    }

    /// docs/model.md §7.2 for the laminate: a rigid (and spinning) rotation of the sheet in 3D
    /// changes neither N nor the thickness.
    #[test]
    fn laminate_is_objective(
        f in in_plane_gradient(),
        f_dot in prop::array::uniform4(-1.0..1.0f64),
        r in prop::array::uniform3(-3.0..3.0f64),
        spin in prop::array::uniform3(-5.0..5.0f64),
    ) {
        let laminate = t300_card().laminate;
        let fibres = FibreDirections::in_plane(0.4);
        let f3 = in_plane(&f);
        let f3_dot = in_plane(&Matrix2::from_row_slice(&f_dot));
        let q = rotation(r);
        let omega = Matrix3::new(0.0, -spin[2], spin[1], spin[2], 0.0, -spin[0], -spin[1], spin[0], 0.0);
        let respond = |f: Matrix3x2<f64>, f_dot: Matrix3x2<f64>| {
            let kin = MembraneKinematics::from_deformation(&f, &f_dot, T, fibres);
            let mut state = laminate.initial_state();
            laminate.membrane_response(&kin, 1e-3, &mut state).unwrap()
        };
        let plain = respond(f3, f3_dot);
        let rotated = respond(q * f3, omega * q * f3 + q * f3_dot);
        prop_assert!((plain.n - rotated.n).amax() <= 1e-9 * plain.n.amax().max(1e-6));
        prop_assert!((plain.thickness - rotated.thickness).abs() < 1e-12);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(100))]

    /// docs/solver.md, "Laminate tangent": the implicit solver's `D = dN/dE` from the layers'
    /// stress derivatives, with plane stress condensed into the matrix layers and the fabric's
    /// volume kept, equals central differences of the laminate's response over a
    /// backward-Euler step, for the matrix layers alone, the fabric alone and the A:B:A stack,
    /// on the shipped card and on a very viscous melt (`eta1 = 5 MPa·s`).
    #[test]
    fn step_tangent_is_the_derivative_of_the_step_response(
        f_start in in_plane_gradient(),
        f in in_plane_gradient(),
        angle in 0.0..3.2f64,
        dt in prop::sample::select(vec![1e-3, 0.05, 1.0]),
    ) {
        // Central differences (step 1e-5 in E) are no reference where a yarn's strain lies
        // within their reach of a kink of its tension's curvature: the rest length and the end
        // of the slack band (docs/model.md §3).
        let c = f.transpose() * f;
        let (s, co) = angle.sin_cos();
        let yarn_strains = [Vector2::new(co, s), Vector2::new(-s, co)].map(|a| a.dot(&(c * a)).sqrt() - 1.0);
        prop_assume!(yarn_strains.iter().all(|e| e.abs() > 4e-5 && (e - SLACK_BAND).abs() > 4e-5));
        for card in [t300_card(), MaterialCard::load(&repo_path("tests/data/viscous-prepreg.toml")).unwrap()] {
            let matrix: Arc<dyn MaterialLaw> = card.matrix.clone().unwrap();
            let fabric: Arc<dyn MaterialLaw> = card.fabric.clone();
            let stacks = [
                ("matrix", Laminate::new(vec![Layer { law: matrix.clone(), thickness: 0.05 }; 2]).unwrap()),
                ("fabric", Laminate::new(vec![Layer { law: fabric, thickness: 0.2 }]).unwrap()),
                ("A:B:A", card.laminate.clone()),
            ];
            for (name, laminate) in stacks {
                let fibres = FibreDirections::in_plane(angle);
                let c_of = |f: &Matrix2<f64>| f.transpose() * f;
                // the start of the step: the state reached from rest over one step
                let first = BackwardEulerStep { c: c_of(&f_start), c_start: Matrix2::identity(), dt, temperature: T.into(), fibres };
                let (_, start, _) = laminate.step_tangent(&first, &laminate.initial_state()).unwrap();
                let step = BackwardEulerStep { c: c_of(&f), c_start: c_of(&f_start), ..first };
                let (_, _, exact) = laminate.step_tangent(&step, &start).unwrap();
                let differenced = laminate.differenced_step_tangent(&step, &start).unwrap();
                let scale = exact.amax().max(1e-9);
                prop_assert!(
                    (exact - differenced).amax() < 1e-5 * scale,
                    "{name}, dt {dt}: {exact} vs {differenced}"
                );
            }
        }
    }
}

#[test]
fn no_membrane_force_at_rest_and_reference_thickness() {
    let laminate = t300_card().laminate;
    let mut state = laminate.initial_state();
    let r = laminate
        .membrane_response(
            &kinematics(&Matrix2::identity(), &Matrix2::zeros(), 0.3),
            1e-3,
            &mut state,
        )
        .unwrap();
    assert!(r.n.amax() < 1e-14);
    assert!((r.thickness - 0.31).abs() < 1e-14);
}

/// Equibiaxial stretch: tension in both yarns, no shear, and a thickness that shrinks
/// monotonically, each layer keeping (nearly) its volume.
#[test]
fn thickness_shrinks_under_equibiaxial_stretch() {
    let laminate = t300_card().laminate;
    let mut state = laminate.initial_state();
    let mut previous_thickness = laminate.reference_thickness();
    for i in 1..=20 {
        let l = 1.0 + 0.0025 * f64::from(i);
        let kin = kinematics(&Matrix2::from_diagonal_element(l), &Matrix2::zeros(), 0.0);
        let r = laminate.membrane_response(&kin, 0.0, &mut state).unwrap();
        assert!(
            r.thickness < previous_thickness,
            "stretch {l}: {} !< {previous_thickness}",
            r.thickness
        );
        previous_thickness = r.thickness;
        assert!(r.n[(0, 0)] > 0.0 && (r.n[(0, 0)] - r.n[(1, 1)]).abs() < 1e-9 * r.n[(0, 0)]);
        assert!(r.n[(0, 1)].abs() < 1e-12 * r.n[(0, 0)]);
        // incompressible fabric, nearly incompressible matrix (K = 2/D1 >> C10)
        let expected = laminate.reference_thickness() / (l * l);
        assert!(
            (r.thickness - expected).abs() < 1e-4 * expected,
            "{} vs {expected}",
            r.thickness
        );
        for k in [0, 2] {
            assert!(
                state.thickness_stretch[k] < 1.0
                    && state.thickness_stretch[k] > 1.0 / (l * l) - 1e-4
            );
        }
    }
}

/// The same simple shear reached faster gives a larger resultant, by exactly the viscous
/// stress of the two matrix layers: dN12 = 2 t_A S_v12, S_v12 = 2 eta1 (I1 - 3) Cdot12 with
/// I1 - 3 = g^2 (det C2 = 1, so lambda3 = 1) and Cdot12 = gdot (Eq. (9) of Gong et al. 2018).
#[test]
fn faster_shearing_adds_the_matrix_viscous_stress() {
    let card = t300_card();
    let laminate = &card.laminate;
    let g_end = 0.6;
    let run = |duration: f64| {
        let history: Vec<MembraneSample> = (0..=50)
            .map(|i| {
                let x = f64::from(i) / 50.0;
                MembraneSample {
                    t: duration * x,
                    f: Matrix2::new(1.0, g_end * x, 0.0, 1.0),
                    temperature: T,
                }
            })
            .collect();
        drive_laminate(laminate, FibreDirections::default(), &history).unwrap()[50]
    };
    let (slow, fast) = (run(1e4), run(0.01));
    let eta1 = card
        .matrix
        .as_deref()
        .unwrap()
        .parameters_at(T)
        .unwrap()
        .eta1;
    let t_a = laminate.layers()[0].thickness;
    let expected = 2.0 * t_a * 2.0 * eta1 * g_end * g_end * (g_end / 0.01);
    let got = fast.n[(0, 1)] - slow.n[(0, 1)];
    assert!(
        (got - expected).abs() < 1e-3 * expected,
        "viscous increment {got} vs {expected}"
    );
    assert!((fast.thickness - slow.thickness).abs() < 1e-6);
}

#[test]
fn inverted_sheet_and_hot_sheet_are_errors() {
    let laminate = t300_card().laminate;
    let mut state = laminate.initial_state();
    let flipped = kinematics(&Matrix2::new(-1.0, 0.0, 0.0, 1.0), &Matrix2::zeros(), 0.0);
    // det C2 > 0 for a mirrored sheet; a collapsed one has det C2 = 0
    let collapsed = MembraneKinematics {
        c: Matrix2::new(1.0, 1.0, 1.0, 1.0),
        ..flipped
    };
    let e = laminate
        .membrane_response(&collapsed, 0.0, &mut state)
        .unwrap_err();
    assert!(matches!(e, MaterialError::NonPositiveVolume { .. }), "{e}");
    let hot = MembraneKinematics {
        temperature: 400.0.into(),
        ..kinematics(&Matrix2::identity(), &Matrix2::zeros(), 0.0)
    };
    let e = laminate
        .membrane_response(&hot, 0.0, &mut state)
        .unwrap_err();
    assert!(
        matches!(e, MaterialError::TemperatureOutOfRange { .. }),
        "{e}"
    );
}

/// The two skins share one law and are solved once; solving each on its own law object must
/// give the same answer, also when their states differ (as a restart could make them).
#[test]
fn shared_skins_solve_like_separate_layers() {
    let card = t300_card();
    let separate_matrix: Arc<dyn MaterialLaw> = Arc::new(card.matrix.as_deref().unwrap().clone());
    let shared = Laminate::matrix_fabric_matrix(
        card.matrix.clone().unwrap(),
        0.04,
        card.fabric.clone(),
        0.23,
    )
    .unwrap();
    let separate = Laminate::new(vec![
        shared.layers()[0].clone(),
        shared.layers()[1].clone(),
        thermostamp::material::Layer {
            law: separate_matrix,
            thickness: 0.04,
        },
    ])
    .unwrap();
    let kin = kinematics(
        &Matrix2::new(1.05, 0.3, -0.1, 0.97),
        &Matrix2::new(0.2, 1.0, 0.5, -0.1),
        0.2,
    );
    for skin_start in [1.0, 0.98] {
        let mut a = shared.initial_state();
        let mut b = separate.initial_state();
        a.thickness_stretch[2] = skin_start;
        b.thickness_stretch[2] = skin_start;
        let ra = shared.membrane_response(&kin, 1e-3, &mut a).unwrap();
        let rb = separate.membrane_response(&kin, 1e-3, &mut b).unwrap();
        assert_eq!(a, b);
        assert!(
            (ra.n - rb.n).amax() <= 1e-14 * ra.n.amax(),
            "{} vs {}",
            ra.n,
            rb.n
        );
        assert!((ra.thickness - rb.thickness).abs() <= 1e-14);
        assert_eq!(
            a.thickness_stretch[0] == a.thickness_stretch[2],
            skin_start == 1.0
        );
    }
}

/// Small simple shear in the yarn frame: the neo-Hookean skins resist with `mu = 2 C10`, the
/// fabric with `2 W_s'(0)` (`I10 = sin^2 gamma`, so `W_s ~ W_s'(0) gamma^2`); the laminate's
/// initial shear modulus is their thickness-weighted mean.
#[test]
fn initial_shear_modulus_is_the_thickness_mean_of_the_layers() {
    let card = t300_card();
    let skins = card.matrix.as_ref().unwrap().parameters_at(T).unwrap();
    let layers = card.laminate.layers();
    let (t_a, t_b) = (layers[0].thickness, layers[1].thickness);
    let expected = (2.0 * t_a * 2.0 * skins.c10 + t_b * 2.0 * card.fabric.shear.derivative(0.0))
        / (2.0 * t_a + t_b);
    let g = card.laminate.shear_modulus(T).unwrap();
    assert!(
        (g / expected - 1.0).abs() < 1e-2,
        "{g} MPa, expected {expected} MPa"
    );
}

/// The yarn tensions written with the results (docs/model.md §4) are the yarns' nominal
/// forces: stretched along warp and weft (a square net, no shear), the laminate's warp tension
/// is `lambda_a N_aa` of its fabric layer alone, the weft's `lambda_b N_bb`, and the molten
/// skins add nothing to them; a yarn left at its length carries none.
#[test]
fn yarn_tensions_are_the_fabric_layers_nominal_forces_along_the_yarns() {
    let card = t300_card();
    let fabric_layer = card.laminate.layers()[1].clone();
    let fabric_only = Laminate::new(vec![fabric_layer]).unwrap();
    let angle: f64 = 0.4;
    let (a, b) = (
        Vector2::new(angle.cos(), angle.sin()),
        Vector2::new(-angle.sin(), angle.cos()),
    );
    for (la, lb) in [(1.01, 1.0), (1.03, 1.02), (1.0, 1.005)] {
        let f =
            Matrix2::identity() + a * a.transpose() * (la - 1.0) + b * b.transpose() * (lb - 1.0);
        let kin = kinematics(&f, &Matrix2::zeros(), angle);
        let mut state = fabric_only.initial_state();
        let n = fabric_only
            .membrane_response(&kin, 0.0, &mut state)
            .unwrap()
            .n;
        let nominal = [la * a.dot(&(n * a)), lb * b.dot(&(n * b))];
        let mut sheet = card.laminate.initial_state();
        card.laminate
            .membrane_response(&kin, 0.0, &mut sheet)
            .unwrap();
        let tensions = card.laminate.yarn_tensions(&kin, &sheet).unwrap();
        for k in 0..2 {
            assert!(
                (tensions[k] - nominal[k]).abs() <= 1e-9 * nominal[0].abs().max(nominal[1].abs()),
                "stretches {la}, {lb}: yarn {k}: {} against {}",
                tensions[k],
                nominal[k]
            );
        }
        if lb == 1.0 {
            assert!(tensions[1].abs() < 1e-12, "{}", tensions[1]);
        }
        assert!(tensions[0] > 0.0 || la == 1.0);
    }
}
