//! `thermostamp test uniaxial` and `thermostamp test picture-frame` run as a user runs them:
//! history, ParaView frames and plots written, summary printed, bad options refused with exit
//! code 2 and one line naming the option.

mod common;

use common::csv_header_and_last_row;
use common::thermostamp;
use std::path::{Path, PathBuf};

/// A fresh output folder under the target's temporary directory.
fn out_dir(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// Runs `thermostamp test <args> --output <dir>` on the stiff-yarn test fabric with three
/// frames, twelve history rows and one thread; checks the exit code and the summary.
fn run_quick(dir: &Path, args: &[&str]) {
    let quick = [
        "--card",
        "tests/data/stiff-yarn-fabric.toml",
        "--time-scaling",
        "1",
        "--frames",
        "3",
        "--history-points",
        "12",
        "--threads",
        "1",
        "--output",
        dir.to_str().unwrap(),
    ];
    let out = thermostamp(&[&["test"], args, &quick].concat());
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    for line in ["steps", "energy balance error", "element-steps per second"] {
        assert!(stdout.contains(line), "summary lacks '{line}':\n{stdout}");
    }
}

/// The PNGs are PNGs, the `.pvd` lists at least three frames and the first `.vtu` exists.
fn assert_plots_and_frames(dir: &Path, name: &str, plots: &[&str]) {
    for plot in plots {
        let bytes = std::fs::read(dir.join(format!("{name}-{plot}.png"))).unwrap();
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "{name}-{plot}.png");
    }
    let pvd = std::fs::read_to_string(dir.join(format!("{name}.pvd"))).unwrap();
    let frames = pvd.matches("<DataSet").count();
    assert!(frames >= 3, "{frames} frames");
    assert!(dir.join(format!("{name}_0000.vtu")).exists());
}

/// A weft strip (`--ply-angle -90`: negative values are accepted) pulled 1.5 mm: 1 % strain,
/// where the test fabric's yarns carry `W t_B A2 0.01 = 25 x 0.3 x 2000 x 0.01 = 150 N`.
#[test]
fn uniaxial_writes_history_frames_and_plot() {
    let dir = out_dir("uniaxial-cli");
    run_quick(
        &dir,
        &[
            "uniaxial",
            "--ply-angle",
            "-90",
            "--end-displacement",
            "1.5",
            "--speed",
            "200",
        ],
    );
    let (header, last) = csv_header_and_last_row(&dir.join("uniaxial.csv"));
    assert_eq!(
        header[..6],
        [
            "time",
            "displacement",
            "force",
            "strain",
            "stress_resultant",
            "shear_angle_deg"
        ]
    );
    // process time first, the solver's last: the test's time scaling is their ratio
    assert_eq!(
        header[header.len() - 2..],
        ["energy_balance_error", "solver_time"]
    );
    assert!(
        last[0] >= last[last.len() - 1] && last[last.len() - 1] > 0.0,
        "{last:?}"
    );
    assert!((last[1] - 1.5).abs() < 1e-9, "{last:?}");
    assert!((last[3] - 0.01).abs() < 1e-9, "{last:?}");
    assert!((last[2] - 150.0).abs() < 3.0, "force {} N", last[2]);
    assert!((last[4] - last[2] / 25.0).abs() < 1e-6, "{last:?}");
    assert_plots_and_frames(&dir, "uniaxial", &["force"]);
}

/// A 150 mm frame on 75 mm cells pulled 20 mm: the frame is at 11.39° and the interior with it.
#[test]
fn picture_frame_writes_history_frames_and_plots() {
    let dir = out_dir("picture-frame-cli");
    run_quick(
        &dir,
        &[
            "picture-frame",
            "--element-size",
            "75",
            "--end-displacement",
            "20",
            "--speed",
            "200",
            "--target-step",
            "5e-5",
        ],
    );
    let (header, last) = csv_header_and_last_row(&dir.join("picture-frame.csv"));
    assert_eq!(
        header[..6],
        [
            "time",
            "displacement",
            "force",
            "shear_angle_deg",
            "shear_angle_frame_deg",
            "normalised_shear_force"
        ]
    );
    assert!((last[1] - 20.0).abs() < 1e-9, "{last:?}");
    assert!(last[2] > 0.0, "pulling needs a positive force: {last:?}");
    assert!((last[3] - last[4]).abs() < 0.2, "{last:?}");
    assert!((last[4] - 11.39).abs() < 0.01, "{last:?}");
    assert_plots_and_frames(&dir, "picture-frame", &["force", "shear-angle"]);
}

#[test]
fn bad_options_are_exit_code_2_with_one_line_naming_them() {
    let stiff = "tests/data/stiff-yarn-fabric.toml";
    let cases: [(&[&str], &str); 7] = [
        (&["uniaxial", "--card", stiff, "--width", "-25"], "--width"),
        (&["uniaxial", "--card", stiff, "--length", "0"], "--length"),
        (
            &["uniaxial", "--card", stiff, "--element-size", "20"],
            "two elements along the width",
        ),
        (&["uniaxial", "--card", stiff, "--speed", "-1"], "speed"),
        (
            &["picture-frame", "--card", stiff, "--side", "-150"],
            "--side",
        ),
        (
            &[
                "picture-frame",
                "--card",
                stiff,
                "--end-displacement",
                "100",
            ],
            "90° of shear",
        ),
        (
            &["picture-frame", "--card", "materials/t300-5hs-pps.toml"],
            "--temperature is required",
        ),
    ];
    for (args, expected) in cases {
        let out = thermostamp(&[&["test"], args].concat());
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(expected), "{args:?}: {stderr}");
        assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    }
}

/// A crosshead faster than 1 % of the sheet's shear wave speed gets a warning before the run
/// (the stiff-yarn fabric: `G = 2 c1 = 0.2 MPa`, `rho = 1e-9`, `c = 14142 mm/s`); a slow one
/// none. The run goes on either way (over 2 mm: 0.5 mm at 500 mm/s is covered in 365 steps,
/// which is refused as too few).
#[test]
fn fast_crosshead_is_warned_about() {
    for (speed, warned) in [("50", false), ("500", true)] {
        let dir = out_dir(&format!("warn-{speed}"));
        let out = thermostamp(&[
            "test",
            "uniaxial",
            "--card",
            "tests/data/stiff-yarn-fabric.toml",
            "--time-scaling",
            "1",
            "--speed",
            speed,
            "--end-displacement",
            "2",
            "--frames",
            "0",
            "--output",
            dir.to_str().unwrap(),
        ]);
        assert!(out.status.success());
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(
            stderr.contains("% of the specimen's shear wave speed"),
            warned,
            "{speed} mm/s: {stderr}"
        );
    }
}
