//! Cost of one material-point evaluation, the innermost call of every element of the explicit
//! solver: `cargo bench --bench material_point`.
//!
//! A plain timing loop (no benchmarking framework, to keep the dependency tree lean): each case
//! runs for about a second after a warm-up and reports nanoseconds per evaluation.

use nalgebra::{Matrix2, Matrix3};
use std::hint::black_box;
use std::path::Path;
use std::time::{Duration, Instant};
use thermostamp::material::{
    FibreDirections, Laminate, MaterialCard, MaterialLaw, MembraneKinematics, PointKinematics,
};

const T: f64 = 300.0;

/// Runs `f` repeatedly for about `budget` and returns nanoseconds per call.
fn time_per_call(budget: Duration, mut f: impl FnMut(u64)) -> f64 {
    for i in 0..1000 {
        f(i);
    }
    let start = Instant::now();
    let mut calls = 0u64;
    while start.elapsed() < budget {
        for _ in 0..1000 {
            f(calls);
            calls += 1;
        }
    }
    start.elapsed().as_nanos() as f64 / calls as f64
}

fn main() {
    let card = MaterialCard::load(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("materials/t300-5hs-pps.toml"),
    )
    .expect("shipped card");
    let budget = Duration::from_secs(1);
    let fibres = FibreDirections::in_plane(0.3);
    let f = Matrix3::new(1.02, 0.15, 0.0, 0.05, 0.99, 0.0, 0.0, 0.0, 0.95);
    let f_dot = Matrix3::new(0.1, 0.3, 0.0, 0.2, -0.1, 0.0, 0.0, 0.0, -0.05);
    let point = PointKinematics::from_deformation(&f, &f_dot, T, fibres);

    let matrix_ns = time_per_call(budget, |_| {
        black_box(
            card.matrix
                .as_deref()
                .unwrap()
                .second_piola_kirchhoff(black_box(&point))
                .unwrap(),
        );
    });
    let fabric_ns = time_per_call(budget, |_| {
        black_box(
            card.fabric
                .second_piola_kirchhoff(black_box(&point))
                .unwrap(),
        );
    });

    // An explicit step changes the deformation very little: warm-started plane stress; the
    // solver's laminate has its parameters interpolated once at the run's temperature.
    let laminate_ns = laminate_time(&card.laminate, fibres, budget);
    let isothermal_ns = laminate_time(&card.laminate.at_temperature(T), fibres, budget);

    println!("material-point evaluation, ns per call (1 thread):");
    println!("  matrix layer S (Eqs. 8-9)            {matrix_ns:8.1}");
    println!("  fabric layer S (docs/model.md §3)         {fabric_ns:8.1}");
    println!("  A:B:A laminate N, plane stress       {laminate_ns:8.1}");
    println!("  the same, laws pinned at T           {isothermal_ns:8.1}");
}

/// Nanoseconds per membrane response of `laminate` on a slowly shearing point.
fn laminate_time(laminate: &Laminate, fibres: FibreDirections, budget: Duration) -> f64 {
    let mut state = laminate.initial_state();
    let dt = 1e-6;
    time_per_call(budget, |i| {
        let g = 0.3 + 1e-7 * (i % 1000) as f64;
        let kin = MembraneKinematics {
            c: Matrix2::new(1.0, g, g, 1.0 + g * g),
            c_dot: Matrix2::new(0.0, 0.1, 0.1, 0.2 * g),
            temperature: T.into(),
            fibres,
        };
        black_box(
            laminate
                .membrane_response(black_box(&kin), dt, &mut state)
                .unwrap(),
        );
    })
}
