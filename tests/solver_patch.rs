//! Patch tests of the membrane element and explicit solver: a homogeneous deformation gives
//! the material-point stress in every element and no net force on interior nodes; a rigid
//! rotation gives no stress.

mod common;

use common::*;
use nalgebra::{Matrix2, Matrix3, Rotation3, Vector3};
use std::sync::Arc;
use thermostamp::material::{FibreDirections, Laminate, MembraneKinematics};
use thermostamp::mesh::{rectangle, Cell, DiagonalPattern, Mesh};
use thermostamp::solver::{self, Constraint, Model, Motion, Observer, SolverSettings, State};

/// The T300 ply without matrix viscosity: its response depends on the final F only.
fn elastic_t300() -> Laminate {
    t300_card().laminate.time_scaled(f64::INFINITY)
}

struct Last(Option<State>);

impl Observer for Last {
    fn record(&mut self, _: &Model, state: &State) -> anyhow::Result<()> {
        self.0 = Some(state.clone());
        Ok(())
    }
}

/// The meshes of the patch tests: crossed triangles, square quadrilaterals, and
/// quadrilaterals with their interior nodes moved by up to a fifth of a cell (no two edges
/// parallel).
#[derive(Clone, Copy, Debug)]
enum PatchMesh {
    Crossed,
    Quad,
    DistortedQuad,
}

const PATCH_MESHES: [PatchMesh; 3] = [
    PatchMesh::Crossed,
    PatchMesh::Quad,
    PatchMesh::DistortedQuad,
];

fn patch_mesh(kind: PatchMesh) -> Mesh {
    let pattern = match kind {
        PatchMesh::Crossed => DiagonalPattern::Crossed,
        PatchMesh::Quad | PatchMesh::DistortedQuad => DiagonalPattern::Quad,
    };
    let mut mesh = rectangle(10.0, 10.0, 4, 4, pattern);
    if let PatchMesh::DistortedQuad = kind {
        for (i, p) in mesh.nodes.iter_mut().enumerate() {
            if p.x.abs() < 4.9 && p.y.abs() < 4.9 {
                let s = i as f64;
                *p += Vector3::new(0.5 * (1.7 * s).sin(), 0.5 * (2.3 * s).cos(), 0.0);
            }
        }
    }
    mesh
}

/// Every node follows `x = X + t G X` (a 3x3 `G`) with `G X` as constant velocity.
fn homogeneous_run(kind: PatchMesh, g: Matrix3<f64>, end_time: f64, angle: f64) -> (Model, State) {
    let mesh = patch_mesh(kind);
    let all = mesh.node_set("all").unwrap().to_vec();
    let motion = Motion::Velocity(Arc::new(move |_t, x0: &Vector3<f64>| g * x0));
    let warp = Vector3::new(angle.cos(), angle.sin(), 0.0);
    let model = Model::new(
        mesh,
        elastic_t300(),
        1.56e-9,
        300.0,
        warp,
        vec![Constraint {
            name: "all".into(),
            nodes: all,
            motion,
        }],
    )
    .unwrap();
    let settings = SolverSettings {
        end_time,
        time_step_safety: 0.9,
        target_time_step: None,
        output_interval: end_time,
        damping: 0.0,
        yarn_damping: 0.0,
    };
    let mut last = Last(None);
    solver::run(&model, &settings, &mut last).unwrap();
    (model, last.0.unwrap())
}

/// The patch test: a uniform stretch and shear gives every element the material point's
/// response, leaves the interior nodes in equilibrium and loads the edges with the membrane
/// traction, on triangles and on square and distorted quadrilaterals (yarns at 23° to the
/// edges).
#[test]
fn homogeneous_deformation_reproduces_the_material_point() {
    for kind in PATCH_MESHES {
        homogeneous_patch(kind);
    }
}

fn homogeneous_patch(kind: PatchMesh) {
    let g = Matrix3::new(0.005, 0.15, 0.0, 0.02, -0.003, 0.0, 0.0, 0.0, 0.0);
    let end = 1e-4;
    let angle = 0.4;
    let (model, state) = homogeneous_run(kind, g / end, end, angle);
    let f2 = Matrix2::new(1.0 + g[(0, 0)], g[(0, 1)], g[(1, 0)], 1.0 + g[(1, 1)]);
    let kin = MembraneKinematics {
        c: f2.transpose() * f2,
        c_dot: Matrix2::zeros(),
        temperature: 300.0.into(),
        fibres: FibreDirections::in_plane(angle),
    };
    let laminate = elastic_t300();
    let mut point_state = laminate.initial_state();
    let expected = laminate
        .membrane_response(&kin, 0.0, &mut point_state)
        .unwrap();
    // the material point was evaluated in the global x-y basis; elements work in their own
    for (k, m) in state.membrane.iter().enumerate() {
        let n = model.elements[k]
            .to_global(&m.n)
            .fixed_view::<2, 2>(0, 0)
            .into_owned();
        assert!(
            (n - expected.n).amax() < 1e-8 * expected.n.amax(),
            "{kind:?}, element {k}: {n} vs {}",
            expected.n
        );
        assert!((m.thickness - expected.thickness).abs() < 1e-12);
    }
    // interior nodes: the uniform stress field is in equilibrium there
    let scale = state.reactions.iter().map(|r| r.norm()).fold(0.0, f64::max);
    let boundary: Vec<usize> = ["bottom", "top", "left", "right"]
        .iter()
        .flat_map(|s| model.mesh.node_set(s).unwrap().to_vec())
        .collect();
    for (node, r) in state.internal_forces.iter().enumerate() {
        if !boundary.contains(&node) {
            assert!(
                r.norm() < 1e-9 * scale,
                "{kind:?}, interior node {node}: {r}"
            );
        }
    }
    // and the boundary tractions are those of the membrane stress: total force on the right
    // edge equals F N e_x times the edge length (Piola traction on the reference edge)
    let right: Vector3<f64> = model
        .mesh
        .node_set("right")
        .unwrap()
        .iter()
        .map(|&n| state.internal_forces[n])
        .sum();
    let p = nalgebra::Matrix3x2::new(f2[(0, 0)], f2[(0, 1)], f2[(1, 0)], f2[(1, 1)], 0.0, 0.0)
        * expected.n;
    let traction = p * nalgebra::Vector2::new(1.0, 0.0) * 10.0;
    assert!(
        (right - traction).norm() < 1e-6 * traction.norm(),
        "{kind:?}: {right} vs {traction}"
    );
}

/// Largest spurious yarn strain, N / (t_B A2), after a quarter turn at `safety` x critical step.
fn spurious_strain_after_rotation(kind: PatchMesh, axis: Vector3<f64>, safety: f64) -> f64 {
    let omega = std::f64::consts::FRAC_PI_2 / 1e-4;
    let mesh = patch_mesh(kind);
    let all = mesh.node_set("all").unwrap().to_vec();
    let motion = Motion::Velocity(Arc::new(move |t, x0: &Vector3<f64>| {
        let x = Rotation3::new(axis * omega * t) * x0;
        axis.cross(&x) * omega
    }));
    let model = Model::new(
        mesh,
        elastic_t300(),
        1.56e-9,
        300.0,
        Vector3::x(),
        vec![Constraint {
            name: "all".into(),
            nodes: all,
            motion,
        }],
    )
    .unwrap();
    let settings = SolverSettings {
        end_time: 1e-4,
        time_step_safety: safety,
        target_time_step: None,
        output_interval: 1e-4,
        damping: 0.0,
        yarn_damping: 0.0,
    };
    let mut last = Last(None);
    solver::run(&model, &settings, &mut last).unwrap();
    let state = last.0.unwrap();
    let expected = Rotation3::new(axis * std::f64::consts::FRAC_PI_2) * model.mesh.nodes[0];
    assert!(
        (state.positions[0] - expected).norm() < 1e-3,
        "{} vs {expected}",
        state.positions[0]
    );
    state
        .membrane
        .iter()
        .map(|m| m.n.amax())
        .fold(0.0, f64::max)
        / (0.23 * 4.0e4)
}

/// A rigid rotation strains nothing, up to the O(dt^2) error of integrating the prescribed
/// path with midpoint velocities: tiny, and four times smaller at half the step; on every
/// patch mesh (the quadrilaterals' hourglass mode is blind to rotations too).
#[test]
fn rigid_rotation_gives_no_stress() {
    for kind in PATCH_MESHES {
        for axis in [Vector3::z(), Vector3::new(1.0, 1.0, 0.0).normalize()] {
            let coarse = spurious_strain_after_rotation(kind, axis, 0.9);
            let fine = spurious_strain_after_rotation(kind, axis, 0.45);
            assert!(
                coarse < 1e-5,
                "{kind:?}: spurious strain {coarse:e} about {axis}"
            );
            assert!(
                fine < 0.35 * coarse,
                "{kind:?}, second order: {coarse:e} -> {fine:e}"
            );
        }
    }
}

/// The step the solver takes, `0.9 x altitude x sqrt(rho / E_wave)`, stays below the exact
/// critical step `2 / omega_max` of a lone element with lumped mass (which bounds that of any
/// mesh), for stiff yarns along, across and at 45° to the edges.
#[test]
fn stable_step_is_below_the_critical_step_of_the_element() {
    use nalgebra::{DMatrix, Vector2};
    use thermostamp::element::MembraneElement;
    let card =
        thermostamp::material::MaterialCard::load(&repo_path("tests/data/stiff-yarn-fabric.toml"))
            .unwrap();
    let laminate = card.laminate;
    let t = laminate.reference_thickness();
    let v = Vector2::new;
    let shapes: [Vec<Vector2<f64>>; 7] = [
        vec![v(0.0, 0.0), v(2.0, 0.0), v(1.0, 1.0)], // crossed cell
        vec![v(0.0, 0.0), v(1.0, 0.0), v(0.0, 1.0)], // right
        vec![v(0.0, 0.0), v(1.0, 0.0), v(0.5, 0.866)], // equilateral
        vec![v(0.0, 0.0), v(3.0, 0.0), v(0.4, 0.7)], // skewed
        vec![v(0.0, 0.0), v(1.0, 0.0), v(1.0, 1.0), v(0.0, 1.0)], // square
        vec![v(0.0, 0.0), v(3.0, 0.0), v(3.0, 1.0), v(0.0, 1.0)], // long quadrilateral
        vec![v(0.0, 0.0), v(1.3, 0.2), v(1.0, 1.1), v(-0.2, 0.8)], // distorted quadrilateral
    ];
    for (shape, gamma_deg) in shapes
        .iter()
        .flat_map(|s| [0.0, 20.0, 40.0].map(move |g| (s.clone(), g)))
    {
        for angle_deg in [0.0, 30.0, 45.0, 90.0] {
            let angle = f64::to_radians(angle_deg);
            let x_ref: Vec<Vector3<f64>> =
                shape.iter().map(|p| Vector3::new(p.x, p.y, 0.0)).collect();
            // sheared like a bias-extension zone: yarns at +-45° turned towards each other
            let g = f64::to_radians(gamma_deg);
            let shear = rotation([0.0, 0.0, std::f64::consts::FRAC_PI_4])
                * trellis(g, 1.002, 1.002, 1.0)
                * rotation([0.0, 0.0, -std::f64::consts::FRAC_PI_4]);
            let x0: Vec<Vector3<f64>> = x_ref.iter().map(|x| shear * x).collect();
            let cell = match shape.len() {
                3 => Cell::Triangle([0, 1, 2]),
                _ => Cell::Quad([0, 1, 2, 3]),
            };
            let corners = shape.len();
            let e =
                MembraneElement::new(cell, &x_ref, &Vector3::new(angle.cos(), angle.sin(), 0.0))
                    .unwrap();
            let forces = |x: &[Vector3<f64>]| {
                let f = e.gradient(x);
                let kin = MembraneKinematics::from_deformation(
                    &f,
                    &nalgebra::Matrix3x2::zeros(),
                    20.0,
                    e.fibres,
                );
                let n = laminate
                    .membrane_response(&kin, 0.0, &mut laminate.initial_state())
                    .unwrap()
                    .n;
                let mut forces = e.internal_forces(&f, &n);
                let moduli = thermostamp::element::membrane::HourglassModuli {
                    shear: laminate.shear_modulus(20.0).unwrap() * t,
                    yarn: laminate
                        .wave_modulus(
                            &MembraneKinematics {
                                c: Matrix2::identity(),
                                c_dot: Matrix2::zeros(),
                                temperature: 20.0.into(),
                                fibres: FibreDirections::default(),
                            },
                            &laminate.initial_state(),
                        )
                        .unwrap()
                        * t,
                };
                e.hourglass_forces(x, &f, &moduli, &mut forces);
                forces
            };
            // in-plane stiffness by central differences at rest
            let h = 1e-7;
            let dofs = 2 * corners;
            let mut k = DMatrix::zeros(dofs, dofs);
            for j in 0..dofs {
                let (node, dir) = (j / 2, j % 2);
                let mut plus = x0.to_vec();
                let mut minus = x0.to_vec();
                plus[node][dir] += h;
                minus[node][dir] -= h;
                let (fp, fm) = (forces(&plus), forces(&minus));
                for i in 0..dofs {
                    k[(i, j)] = (fp[i / 2][i % 2] - fm[i / 2][i % 2]) / (2.0 * h);
                }
            }
            let mass = card.density * t * e.area / corners as f64;
            let k_sym = (&k + k.transpose()) * (0.5 / mass);
            let omega_max = k_sym.symmetric_eigenvalues().max().sqrt();
            let critical = 2.0 / omega_max;
            let kin = MembraneKinematics {
                c: Matrix2::identity(),
                c_dot: Matrix2::zeros(),
                temperature: 20.0.into(),
                fibres: e.fibres,
            };
            let modulus = laminate
                .wave_modulus(&kin, &laminate.initial_state())
                .unwrap();
            let taken = 0.9 * e.altitude * (card.density / modulus).sqrt();
            assert!(
                taken < critical,
                "{angle_deg}° on {shape:?}: step {taken:e} >= critical {critical:e}"
            );
        }
    }
}
