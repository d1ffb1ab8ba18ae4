//! The estimate before the run and the set-up refusals that follow from it: each run that
//! cannot mean anything is refused at once with exit code 2 and a line naming the scenario key
//! (or the command-line option) to change, before the mesh is built.

mod common;

use common::{repo_path, thermostamp};
use std::path::PathBuf;
use std::time::Instant;

fn out_dir(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// `thermostamp run tests/data/hemisphere-explicit.toml --set ...`: exit code and standard error.
fn hemisphere_with(name: &str, overrides: &[&str]) -> (Option<i32>, String) {
    let dir = out_dir(name);
    let mut args = vec!["run", "tests/data/hemisphere-explicit.toml"];
    for o in overrides {
        args.extend(["--set", o]);
    }
    args.extend(["--output", dir.to_str().unwrap()]);
    let out = thermostamp(&args);
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Exit code 2 and a last line on standard error (after any notes) that is the error and
/// names every piece of `names`.
fn assert_refused(code: Option<i32>, stderr: &str, names: &[&str]) {
    assert_eq!(code, Some(2), "{stderr}");
    let last = stderr.trim().lines().last().unwrap_or_default();
    assert!(last.starts_with("error: "), "{stderr}");
    for name in names {
        assert!(last.contains(name), "'{name}' not named: {stderr}");
    }
}

/// 1e4 mm/s, the fastest punch speed allowed (x10 time scaling), moves the punch 0.45 mm per
/// step of the example's 4.5e-6 s: through the 0.31 mm ply in the first step.
#[test]
fn a_punch_that_would_pass_through_the_blank_is_refused() {
    let (code, stderr) = hemisphere_with("refuse-fast", &["process.punch_speed=10000"]);
    assert_refused(
        code,
        &stderr,
        &["process.punch_speed", "per step", "pass through"],
    );
}

/// 2000 mm/s: 0.09 mm per step, under the tunnelling limit, but the 30 mm stroke in 342
/// steps.
#[test]
fn a_stroke_in_too_few_steps_is_refused() {
    let (code, stderr) = hemisphere_with("refuse-few", &["process.punch_speed=2000"]);
    assert_refused(code, &stderr, &["process.punch_speed", "342 steps"]);
}

/// 1e-4 mm/s, the slowest punch speed allowed: 6.8e9 steps.
#[test]
fn an_absurd_step_count_is_refused() {
    let (code, stderr) = hemisphere_with("refuse-many", &["process.punch_speed=1e-4"]);
    assert_refused(code, &stderr, &["process.punch_speed", "6.833e9 steps"]);
}

/// 0.01 mm cells on the 160 mm blank: 5e8 triangles, a terabyte; refused from the keys
/// before the mesh is made, in well under a second (it aborted on a failed allocation).
#[test]
fn a_mesh_that_cannot_fit_the_memory_is_refused_at_once() {
    let start = Instant::now();
    let (code, stderr) = hemisphere_with("refuse-fine", &["blank.element_size=0.01"]);
    let seconds = start.elapsed().as_secs_f64();
    assert_refused(code, &stderr, &["blank.element_size", "of memory"]);
    assert!(seconds < 1.0, "took {seconds} s");
}

/// A card 1e296 times too stiff (the run used to report a punch force of 1e304 N): its yarn
/// modulus is beyond any fibre's, refused when the card is read, naming the card and the key.
#[test]
fn an_absurdly_stiff_card_is_refused() {
    let card = std::fs::read_to_string(repo_path("materials/t300-5hs-pps.toml")).unwrap();
    let absurd = card
        .replace("warp_tension = [4.0e4,", "warp_tension = [4.0e300,")
        .replace("weft_tension = [4.0e4,", "weft_tension = [4.0e300,");
    assert_ne!(card, absurd);
    let dir = out_dir("refuse-card");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("absurd.toml");
    std::fs::write(&path, absurd).unwrap();
    let set = format!("blank.card={}", path.display());
    let (code, stderr) = hemisphere_with("refuse-card-run", &[&set]);
    assert_refused(
        code,
        &stderr,
        &[
            "absurd.toml",
            "warp_tension[0] (A2) = 4e300 MPa",
            "out of range",
        ],
    );
}

/// A virtual test on 0.001 mm cells is refused before its mesh, naming the option.
#[test]
fn a_virtual_test_mesh_that_cannot_fit_is_refused() {
    let dir = out_dir("refuse-test-mesh");
    let start = Instant::now();
    let out = thermostamp(&[
        "test",
        "bias-extension",
        "--card",
        "tests/data/stiff-yarn-fabric.toml",
        "--element-size",
        "0.001",
        "--output",
        dir.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_refused(out.status.code(), &stderr, &["--element-size", "of memory"]);
    assert!(start.elapsed().as_secs_f64() < 1.0);
}

/// A virtual test whose travel is covered in a handful of steps names the speed options.
#[test]
fn a_virtual_test_in_too_few_steps_is_refused() {
    let dir = out_dir("refuse-test-fast");
    let out = thermostamp(&[
        "test",
        "uniaxial",
        "--card",
        "tests/data/stiff-yarn-fabric.toml",
        "--speed",
        "1e4",
        "--time-scaling",
        "100",
        "--output",
        dir.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_refused(out.status.code(), &stderr, &["--speed", "steps"]);
}
