//! `thermostamp run` as a user runs it: the bundled hemisphere and double-dome examples in a
//! reduced form (the CI check that keeps them from rotting), and bad scenarios refused with
//! exit code 2 and one line naming the key or the file.

mod common;

use common::thermostamp;
use std::path::PathBuf;

fn out_dir(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// The example on 10 mm cells, 8 mm of stroke, two frames: it reaches the stroke, writes its
/// files, and the punch force grows with the stroke.
#[test]
fn hemisphere_example_runs_in_reduced_form() {
    let dir = out_dir("forming-hemisphere");
    let out = thermostamp(&[
        "run",
        "examples/hemisphere.toml",
        "--set",
        "blank.element_size=10",
        "--set",
        "process.stroke=8",
        "--set",
        "output.frames=2",
        "--set",
        "output.history_points=8",
        "--output",
        dir.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let stdout = String::from_utf8_lossy(&out.stdout);
    for line in [
        "stroke reached              8.00 mm",
        "peak punch force",
        "bending on",
    ] {
        assert!(stdout.contains(line), "summary lacks '{line}':\n{stdout}");
    }
    for file in [
        "forming.csv",
        "forming-punch-force.png",
        "forming.pvd",
        "forming_0002.vtu",
        "formed-blank.inp",
        "formed-blank.vtu",
    ] {
        assert!(dir.join(file).exists(), "{file} missing");
    }
    let frame = std::fs::read_to_string(dir.join("forming_0002.vtu")).unwrap();
    for field in [
        "shear_angle_deg",
        "contact_pressure",
        "contact_status",
        "gap_punch",
        "gap_die",
    ] {
        assert!(
            frame.contains(&format!("Name=\"{field}\"")),
            "frame lacks {field}"
        );
    }
    let csv = std::fs::read_to_string(dir.join("forming.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(&header[..3], &["time", "stroke", "punch_force"]);
    let force: Vec<f64> = lines
        .map(|l| l.split(',').nth(2).unwrap().parse().unwrap())
        .collect();
    assert!(force.last().unwrap() > &force[force.len() / 2]);
}

/// The double-dome example on 10 mm cells, 6 mm of stroke, a larger mass-scaling step: it
/// reaches the stroke with the holder at its force, and its drape preview runs.
#[test]
fn double_dome_example_runs_in_reduced_form() {
    let dir = out_dir("forming-double-dome");
    let out = thermostamp(&[
        "run",
        "examples/double-dome.toml",
        "--set",
        "blank.element_size=10",
        "--set",
        "process.stroke=6",
        "--set",
        "output.frames=1",
        "--output",
        dir.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("stroke reached              6.00 mm"),
        "{stdout}"
    );
    for file in ["forming.csv", "forming-shear-map.png", "forming_0001.vtu"] {
        assert!(dir.join(file).exists(), "{file} missing");
    }
    let csv = std::fs::read_to_string(dir.join("forming.csv")).unwrap();
    let last: Vec<f64> = csv
        .lines()
        .last()
        .unwrap()
        .split(',')
        .map(|v| v.parse().unwrap())
        .collect();
    assert!((last[3] - 300.0).abs() < 3.0, "holder force {}", last[3]);
    let drape_dir = out_dir("drape-double-dome");
    let out = thermostamp(&[
        "drape",
        "examples/double-dome.toml",
        "--output",
        drape_dir.to_str().unwrap(),
    ]);
    assert!(out.status.success());
    assert!(drape_dir.join("drape.vtu").exists());
}

/// Bad scenarios: exit code 2 and the key, line or file named.
#[test]
fn bad_scenarios_are_refused_with_the_key_named() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("bad-scenarios");
    std::fs::create_dir_all(&dir).unwrap();
    let example = std::fs::read_to_string(common::repo_path("examples/hemisphere.toml")).unwrap();
    let example = example.replace(
        "../materials/",
        &format!("{}/materials/", env!("CARGO_MANIFEST_DIR")),
    );
    let cases = [
        (
            "unknown-key",
            example.replace("stroke = 30.0", "stroke = 30.0\nstrok = 3"),
            "strok",
        ),
        (
            "missing-card",
            example.replace("t300-5hs-pps.toml", "nothing.toml"),
            "nothing.toml",
        ),
        (
            "deep-stroke",
            example.replace("stroke = 30.0", "stroke = 95.0"),
            "process.stroke",
        ),
        (
            "punch-too-big",
            example.replace("punch_radius = 40.0", "punch_radius = 45.0"),
            "die_opening_radius",
        ),
        (
            "hemisphere-with-ridge",
            example.replace(
                "shape = \"hemisphere\"",
                "shape = \"hemisphere\"\nhalf_length = 5.0",
            ),
            "tools.half_length",
        ),
        (
            "double-dome-without-ridge",
            example.replace("shape = \"hemisphere\"", "shape = \"double-dome\""),
            "tools.half_length",
        ),
        (
            "unknown-shape",
            example.replace("shape = \"hemisphere\"", "shape = \"cup\""),
            "tools.shape",
        ),
        (
            "force-and-gap",
            example.replace(
                "blank_holder_force = 200.0",
                "blank_holder_force = 200.0\nblank_holder_gap = 0.1",
            ),
            "blank_holder_gap",
        ),
        (
            "negative-force",
            example.replace("blank_holder_force = 200.0", "blank_holder_force = -5.0"),
            "blank_holder_force",
        ),
    ];
    for (name, text, expected) in cases {
        let path = dir.join(format!("{name}.toml"));
        std::fs::write(&path, text).unwrap();
        let out = thermostamp(&["run", path.to_str().unwrap()]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{name}: {stderr}");
        assert!(stderr.contains(expected), "{name}: {stderr}");
        assert_eq!(stderr.trim().lines().count(), 1, "{name}: {stderr}");
    }
    let out = thermostamp(&[
        "run",
        "examples/hemisphere.toml",
        "--set",
        "process.temprature=300",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("temprature"), "{stderr}");
    let out = thermostamp(&["run", "no/such/scenario.toml"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no/such/scenario.toml"));
}

/// `thermostamp drape` on the example: files written, and a deeper stroke drapes the fabric over
/// more of the dome, so its largest shear angle is larger.
#[test]
fn drape_preview_of_the_example() {
    let largest = |stroke: &str| {
        let dir = out_dir(&format!("drape-{stroke}"));
        let out = thermostamp(&[
            "drape",
            "examples/hemisphere.toml",
            "--set",
            &format!("process.stroke={stroke}"),
            "--output",
            dir.to_str().unwrap(),
        ]);
        let stdout = String::from_utf8_lossy(&out.stdout).to_string();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(dir.join("drape.csv").exists() && dir.join("drape.vtu").exists());
        let angle: f64 = stdout
            .split("largest shear angle ")
            .nth(1)
            .and_then(|s| s.split('°').next())
            .and_then(|s| s.parse().ok())
            .unwrap_or_else(|| panic!("no angle in: {stdout}"));
        angle
    };
    let (shallow, deep) = (largest("5"), largest("30"));
    assert!(shallow < deep, "5 mm: {shallow}°, 30 mm: {deep}°");
}

/// The net's generators from the command line: turned by 45°, the largest shear moves from the
/// diagonals onto the x axis (it lies at ±45° to the yarns); a start off the punch is an error.
#[test]
fn drape_generators_can_be_chosen() {
    let dir = out_dir("drape-generators");
    let centre = |extra: &[&str]| {
        let mut args = vec![
            "drape",
            "examples/hemisphere.toml",
            "--output",
            dir.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        let out = thermostamp(&args);
        let stdout = String::from_utf8_lossy(&out.stdout).to_string();
        assert!(out.status.success(), "{stdout}");
        let at = stdout
            .split(") mm")
            .next()
            .unwrap()
            .rsplit('(')
            .next()
            .unwrap();
        let xyz: Vec<f64> = at.split(',').map(|v| v.trim().parse().unwrap()).collect();
        (xyz[0], xyz[1])
    };
    let (x, y) = centre(&[]);
    assert!((x.abs() - y.abs()).abs() < 1.0, "default: ({x}, {y})");
    let (x, y) = centre(&["--warp-angle", "45"]);
    assert!(y.abs() < 1.0 && x.abs() > 20.0, "turned: ({x}, {y})");
    let out = thermostamp(&["drape", "examples/hemisphere.toml", "--start", "100,0"]);
    assert_ne!(out.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&out.stderr).contains("start"));
}
