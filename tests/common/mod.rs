//! Helpers shared by the integration tests.
#![allow(dead_code)]

pub mod adversarial;
pub mod calculix;

use nalgebra::{Matrix3, Rotation3, Vector3};
use proptest::prelude::*;
use std::path::PathBuf;
use std::process::{Command, Output};
use thermostamp::material::MaterialCard;

pub fn repo_path(relative: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(relative)
}

/// The shipped T300/PPS card.
pub fn t300_card() -> MaterialCard {
    MaterialCard::load(&repo_path("materials/t300-5hs-pps.toml")).expect("shipped card loads")
}

/// `2 dW/dX` by central differences with symmetric perturbations of the symmetric `x`:
/// for `i != j` both `X_ij` and `X_ji` move by `h`, so `dW = h (dW/dX_ij + dW/dX_ji) = h S_ij`.
pub fn twice_gradient_by_differences(
    energy: impl Fn(&Matrix3<f64>) -> f64,
    x: &Matrix3<f64>,
    h: f64,
) -> Matrix3<f64> {
    let mut s = Matrix3::zeros();
    for i in 0..3 {
        for j in i..3 {
            let mut e = Matrix3::zeros();
            e[(i, j)] += 1.0;
            e[(j, i)] += 1.0;
            // diagonal: the entry moves by 2h; off-diagonal: two entries move by h each
            let dw = (energy(&(x + e * h)) - energy(&(x - e * h))) / (2.0 * h);
            s[(i, j)] = dw;
            s[(j, i)] = dw;
        }
    }
    s
}

/// Largest entry of `a - b` relative to `scale`.
pub fn relative_difference(a: &Matrix3<f64>, b: &Matrix3<f64>, scale: f64) -> f64 {
    (a - b).amax() / scale
}

pub fn rotation(axis_angle: [f64; 3]) -> Matrix3<f64> {
    Rotation3::new(Vector3::from(axis_angle)).into_inner()
}

/// Deformation gradients `R (I + H)` with `|H_ij| <= 0.35` and `det F >= 0.3`.
pub fn deformation_gradient() -> impl Strategy<Value = Matrix3<f64>> {
    (
        prop::array::uniform9(-0.35..0.35f64),
        prop::array::uniform3(-3.0..3.0f64),
    )
        .prop_map(|(h, r)| rotation(r) * (Matrix3::identity() + Matrix3::from_row_slice(&h)))
        .prop_filter("det F >= 0.3", |f| f.determinant() >= 0.3)
}

/// Rates of deformation with entries up to 2 /s.
pub fn deformation_rate() -> impl Strategy<Value = Matrix3<f64>> {
    prop::array::uniform9(-2.0..2.0f64).prop_map(|h| Matrix3::from_row_slice(&h))
}

/// In-plane trellis shear `gamma` (radians) with yarn stretches `la`, `lb`: the warp `x` becomes
/// `la (cos(g/2), sin(g/2))`, the weft `y` becomes `lb (sin(g/2), cos(g/2))`.
pub fn trellis(gamma: f64, la: f64, lb: f64, thickness_stretch: f64) -> Matrix3<f64> {
    let (s, c) = (0.5 * gamma).sin_cos();
    Matrix3::new(
        la * c,
        lb * s,
        0.0,
        la * s,
        lb * c,
        0.0,
        0.0,
        0.0,
        thickness_stretch,
    )
}

/// Embeds an in-plane deformation gradient in 3D (the x–y plane stays at z = 0).
pub fn in_plane(f: &nalgebra::Matrix2<f64>) -> nalgebra::Matrix3x2<f64> {
    nalgebra::Matrix3x2::new(f[(0, 0)], f[(0, 1)], f[(1, 0)], f[(1, 1)], 0.0, 0.0)
}

/// The `thermostamp` binary run from the repository root, as a user runs it.
pub fn thermostamp(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_thermostamp"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("the binary runs")
}

/// A quick bias-extension test of the stiff-yarn fabric: 37.5 mm cells, 20 mm of travel at
/// 200 mm/s without time or mass scaling, three frames and twelve history rows (a second).
pub const QUICK_BIAS_EXTENSION: [&str; 18] = [
    "test",
    "bias-extension",
    "--card",
    "tests/data/stiff-yarn-fabric.toml",
    "--element-size",
    "37.5",
    "--end-displacement",
    "20",
    "--speed",
    "200",
    "--time-scaling",
    "1",
    "--target-step",
    "0",
    "--frames",
    "3",
    "--history-points",
    "12",
];

/// Whether an outside reader a test runs the output through (CalculiX, VTK) is there: `found`
/// as probed by the test; a missing one fails the test under CI (which installs it) and skips
/// it, saying so, elsewhere.
pub fn reader_available(found: bool, test: &str, missing: &str) -> bool {
    if !found {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI is set but {missing} is not available"
        );
        println!("{test}: skipped, {missing} is not installed");
    }
    found
}

/// Exit code 2 and a single line on stderr that contains every piece of `expected`.
pub fn assert_bad_input(args: &[&str], expected: &[&str]) {
    let out = thermostamp(args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
    assert_eq!(
        stderr.trim_end().lines().count(),
        1,
        "{args:?}: not one line: {stderr}"
    );
    for piece in expected {
        assert!(
            stderr.contains(piece),
            "{args:?}: '{piece}' not in: {stderr}"
        );
    }
}

/// The scratch folder `group/name` under the tests' temporary directory, created if absent.
pub fn scratch_dir(group: &str, name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join(group)
        .join(name);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Runs the binary, asserts success and returns its standard output.
pub fn run_ok(args: &[&str]) -> String {
    let out = thermostamp(args);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// Per element of `model`: its centroid and shear angle (degrees) at the positions `x`.
pub fn element_shear(
    model: &thermostamp::solver::Model,
    x: &[Vector3<f64>],
) -> Vec<(Vector3<f64>, f64)> {
    model
        .elements
        .iter()
        .map(|e| (e.centroid(x), e.shear_angle(x).to_degrees()))
        .collect()
}

/// Largest difference of shear angle between each element of `other` and its twin in
/// `reference`, the element whose centroid is nearest (which must lie within `reach` mm).
pub fn largest_twin_difference(
    reference: &[(Vector3<f64>, f64)],
    other: &[(Vector3<f64>, f64)],
    reach: f64,
) -> f64 {
    other
        .iter()
        .map(|(c, gamma)| {
            let twin = reference
                .iter()
                .min_by(|a, b| (a.0 - c).norm().total_cmp(&(b.0 - c).norm()))
                .expect("a reference element");
            assert!(
                (twin.0 - c).norm() < reach,
                "no twin for the element at {c}"
            );
            (twin.1 - gamma).abs()
        })
        .fold(0.0, f64::max)
}

/// Largest relative difference of the normalised shear force `F_sh(gamma)` of `law` from that
/// of `truth` (fabric layer of `thickness` mm) over `degrees`.
pub fn shear_law_error(
    law: &thermostamp::material::fabric::ShearInteraction,
    truth: &thermostamp::material::fabric::ShearInteraction,
    thickness: f64,
    degrees: impl Iterator<Item = u32>,
) -> f64 {
    degrees
        .map(|deg| f64::from(deg).to_radians())
        .map(|g| {
            let t = truth.normalised_shear_force(thickness, g);
            (law.normalised_shear_force(thickness, g) - t).abs() / t
        })
        .fold(0.0, f64::max)
}

/// A `60 x 60` mm square plate at height `z`, its normal along `side` (+1 up, -1 down).
pub fn square_plate(z: f64, side: f64) -> thermostamp::contact::TriangleSurface {
    let corner = |x: f64, y: f64| Vector3::new(x, y, z);
    let vertices = vec![
        corner(-30.0, -30.0),
        corner(30.0, -30.0),
        corner(30.0, 30.0),
        corner(-30.0, 30.0),
    ];
    let triangles = if side > 0.0 {
        vec![[0, 1, 2], [0, 2, 3]]
    } else {
        vec![[0, 2, 1], [0, 3, 2]]
    };
    thermostamp::contact::TriangleSurface {
        vertices,
        triangles,
    }
}

/// Amplitudes (mm) of the Fourier harmonics `1..=24` of the flange's height around the part
/// (entry `n - 1` for `n` waves): the heights at `x` of the nodes whose reference radius is
/// 58–72 mm, against their angle around the punch's axis.
pub fn flange_harmonics(model: &thermostamp::solver::Model, x: &[Vector3<f64>]) -> Vec<f64> {
    let ring: Vec<(f64, f64)> = model
        .mesh
        .nodes
        .iter()
        .zip(x)
        .filter(|(x0, _)| (58.0..=72.0).contains(&x0.x.hypot(x0.y)))
        .map(|(x0, x)| (x0.y.atan2(x0.x), x.z))
        .collect();
    let mean = ring.iter().map(|r| r.1).sum::<f64>() / ring.len() as f64;
    (1..=24)
        .map(|n| {
            let (c, s) = ring.iter().fold((0.0, 0.0), |(c, s), &(theta, z)| {
                let a = n as f64 * theta;
                (c + (z - mean) * a.cos(), s + (z - mean) * a.sin())
            });
            2.0 * c.hypot(s) / ring.len() as f64
        })
        .collect()
}

/// The number of waves of the largest of [`flange_harmonics`].
pub fn dominant_waves(harmonics: &[f64]) -> usize {
    1 + (0..harmonics.len())
        .max_by(|&a, &b| harmonics[a].total_cmp(&harmonics[b]))
        .unwrap()
}

/// A sheet of `card` on `mesh` (no bending; reference warp along x at 20 °C) held by
/// `constraints`, among `tools` whose contact springs sit half a ply from its mid-plane
/// (penalty scale 0.1, reach one ply).
pub fn sheet_among_tools(
    card: &MaterialCard,
    mesh: thermostamp::mesh::Mesh,
    constraints: Vec<thermostamp::solver::Constraint>,
    tools: Vec<thermostamp::contact::RigidTool>,
) -> thermostamp::solver::Model {
    let t = card.laminate.reference_thickness();
    let contact = thermostamp::contact::ContactSettings {
        offset: t / 2.0,
        penalty_scale: 0.1,
        max_penetration: t,
    };
    thermostamp::solver::Model::new(
        mesh,
        card.laminate.clone(),
        card.density,
        20.0,
        Vector3::x(),
        constraints,
    )
    .unwrap()
    .with_tools(tools, contact)
}

/// A free 20 x 20 mm sheet of `card` (4 x 4 cells, nothing held) among `tools`, as
/// [`sheet_among_tools`].
pub fn free_sheet(
    card: &MaterialCard,
    tools: Vec<thermostamp::contact::RigidTool>,
) -> thermostamp::solver::Model {
    use thermostamp::mesh::{rectangle, DiagonalPattern};
    let mesh = rectangle(20.0, 20.0, 4, 4, DiagonalPattern::Right);
    sheet_among_tools(card, mesh, vec![], tools)
}

/// The forming scenario `file` (relative to the repository) with the `--set` overrides
/// `overrides`, run to its end: the model and the run's outcome and records.
pub fn form(
    file: &str,
    overrides: &[String],
) -> (
    thermostamp::forming::FormingModel,
    thermostamp::forming::run::FormingRun,
) {
    let scenario = thermostamp::forming::Scenario::load(&repo_path(file), overrides).unwrap();
    let forming = thermostamp::forming::FormingModel::new(&scenario).unwrap();
    let result = on_the_pool(|| thermostamp::forming::run::run(&forming, None, None));
    (forming, result)
}

/// `thermostamp test bias-extension` as a user runs it on the implicit solver: a `width x
/// length` specimen at `temperature`, the test's default mesh (ten cells across the width)
/// divided by `refinement`, the physical 20 mm/min, pulled to the pin-jointed `end_deg`, with
/// `records` rows.
pub fn implicit_bias_test(
    (width, length): (f64, f64),
    temperature: f64,
    refinement: f64,
    end_deg: f64,
    records: usize,
) -> thermostamp::experiment::bias_extension::BiasExtension {
    let mut test = thermostamp::experiment::bias_extension::BiasExtension::benchmark(temperature);
    test.width = width;
    test.length = length;
    test.process.element_size = test.default_element_size() / refinement;
    test.process.solver = thermostamp::solver::SolverKind::Implicit;
    test.process.time_scaling = 1.0;
    test.process.target_time_step = None;
    test.process.end_displacement =
        thermostamp::experiment::kinematics::bias_extension_displacement(
            width,
            length,
            end_deg.to_radians(),
        );
    test.process.history_points = records;
    test
}

/// An ASCII STL of `facets` (corners counter-clockwise seen from the side they face).
pub fn write_stl(path: &std::path::Path, facets: &[[[f64; 3]; 3]]) {
    let mut text = String::from("solid tool\n");
    for f in facets {
        text.push_str("  facet normal 0 0 0\n    outer loop\n");
        for p in f {
            text.push_str(&format!("      vertex {} {} {}\n", p[0], p[1], p[2]));
        }
        text.push_str("    endloop\n  endfacet\n");
    }
    text.push_str("endsolid tool\n");
    std::fs::write(path, text).unwrap();
}

/// `f` of each of `items`, all at once on the threads of rayon's pool; the results in the
/// order of `items` (a panic in one is re-raised here). The solvers split their loops into
/// fixed chunks of 256 elements, so a run on a few hundred cells keeps about one core busy: a
/// test's independent runs side by side use the machine's other cores. Each runs on a thread
/// of the pool, where a loop of one chunk runs at once on that thread instead of being handed
/// to the pool and waited for step after step as from the test's own thread. Their results
/// are the same bits as run one after the other (no solver's sums depend on the threads).
pub fn side_by_side<I: Send, T: Send>(items: Vec<I>, f: impl Fn(I) -> T + Sync + Send) -> Vec<T> {
    use rayon::prelude::*;
    items.into_par_iter().map(f).collect()
}

/// `f()` on a thread of rayon's pool, as [`side_by_side`] runs each job: a solver's loops over
/// one chunk then run at once on that thread, not handed to the pool and waited for at every
/// step. The same bits as from the test's own thread.
pub fn on_the_pool<T: Send>(f: impl FnOnce() -> T + Send) -> T {
    rayon::scope(|_| f())
}

/// `a()` and `b()` side by side, as [`side_by_side`].
pub fn both<A: Send, B: Send>(
    a: impl FnOnce() -> A + Send,
    b: impl FnOnce() -> B + Send,
) -> (A, B) {
    rayon::join(a, b)
}

/// Header and last row of a CSV history.
pub fn csv_header_and_last_row(path: &std::path::Path) -> (Vec<String>, Vec<f64>) {
    let csv = std::fs::read_to_string(path).unwrap();
    let mut lines = csv.lines();
    let header = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_string)
        .collect();
    let last = lines
        .last()
        .unwrap()
        .split(',')
        .map(|v| v.parse().unwrap())
        .collect();
    (header, last)
}

/// Runs `python3 SCRIPT ARGS` in `dir`, the script named from the repository's root; its
/// standard output, once it succeeded (else the test fails with its standard error).
pub fn run_python<S: AsRef<std::ffi::OsStr>>(
    script: &str,
    args: &[S],
    dir: &std::path::Path,
) -> String {
    let out = Command::new("python3")
        .arg(repo_path(script))
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "{script} failed: {}\n{stdout}",
        String::from_utf8_lossy(&out.stderr)
    );
    stdout
}
