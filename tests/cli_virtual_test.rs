//! `thermostamp test bias-extension` run as a user runs it.

mod common;

use common::{thermostamp, QUICK_BIAS_EXTENSION};
use std::path::PathBuf;

#[test]
fn bias_extension_writes_history_frames_and_plots() {
    let out_dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("bias-cli");
    let _ = std::fs::remove_dir_all(&out_dir);
    let out = thermostamp(
        &[
            &QUICK_BIAS_EXTENSION[..],
            &["--threads", "1", "--output", out_dir.to_str().unwrap()],
        ]
        .concat(),
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for line in [
        "steps",
        "energy balance error",
        "element-steps per second",
        "wrote",
    ] {
        assert!(stdout.contains(line), "summary lacks '{line}':\n{stdout}");
    }
    let csv = std::fs::read_to_string(out_dir.join("bias-extension.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(
        header[..4],
        ["time", "displacement", "force", "shear_angle_deg"]
    );
    let last: Vec<f64> = lines
        .last()
        .unwrap()
        .split(',')
        .map(|v| v.parse().unwrap())
        .collect();
    assert!(
        (last[1] - 20.0).abs() < 1e-9,
        "ends at the requested displacement: {last:?}"
    );
    assert!(last[2] > 0.0, "pulling needs a positive force: {last:?}");
    for png in ["bias-extension-force.png", "bias-extension-shear-angle.png"] {
        let bytes = std::fs::read(out_dir.join(png)).unwrap();
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "{png}");
    }
    let pvd = std::fs::read_to_string(out_dir.join("bias-extension.pvd")).unwrap();
    let frames = pvd.matches("<DataSet").count();
    assert!(frames >= 3, "{frames} frames");
    assert!(out_dir.join("bias-extension_0000.vtu").exists());
}

#[test]
fn bias_extension_bad_input_is_exit_code_2() {
    let cases: [(&[&str], &str); 3] = [
        (
            &[
                "--card",
                "tests/data/stiff-yarn-fabric.toml",
                "--length",
                "200",
            ],
            "twice the width",
        ),
        (
            &["--card", "materials/t300-5hs-pps.toml"],
            "--temperature is required",
        ),
        (
            &[
                "--card",
                "tests/data/stiff-yarn-fabric.toml",
                "--end-displacement",
                "200",
            ],
            "pin-jointed limit",
        ),
    ];
    for (args, expected) in cases {
        let out = thermostamp(&[&["test", "bias-extension"], args].concat());
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(expected), "{args:?}: {stderr}");
        assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    }
}
