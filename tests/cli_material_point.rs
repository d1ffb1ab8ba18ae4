//! `thermostamp material-point` run as a user runs it: the shipped examples give the physics
//! they document, and bad input gives a one-line error with exit code 2.

mod common;

use common::{assert_bad_input, repo_path, thermostamp};
use std::path::PathBuf;

const CARD: &str = "materials/t300-5hs-pps.toml";

/// `material-point` on the shipped card with `layer` and `history`.
fn driver_args<'a>(layer: &'a str, history: &'a str) -> Vec<&'a str> {
    vec![
        "material-point",
        "--card",
        CARD,
        "--layer",
        layer,
        "--history",
        history,
    ]
}

/// Runs the driver and parses its CSV output into (header, rows).
fn drive(layer: &str, history: &str, extra: &[&str]) -> (Vec<String>, Vec<Vec<f64>>) {
    let mut args = driver_args(layer, history);
    args.extend_from_slice(extra);
    let out = thermostamp(&args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    (header, rows)
}

fn scratch(name: &str, content: &str) -> PathBuf {
    let path = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    std::fs::write(&path, content).unwrap();
    path
}

#[test]
fn laminate_shear_example_follows_the_fabric_shear_law() {
    let (header, rows) = drive(
        "laminate",
        "examples/material-point/laminate-shear-300C.csv",
        &[],
    );
    assert_eq!(header, ["t", "N11", "N22", "N12", "thickness"]);
    assert_eq!(rows.len(), 51);
    let card = common::t300_card();
    let t_b = card.laminate.layers()[1].thickness;
    for row in &rows[1..] {
        let gamma = (row[0] * 5.0).to_radians(); // the history shears at 5°/s
        let fabric_only = card.fabric.shear.normalised_shear_force(t_b, gamma);
        // the fabric carries the shear; the molten matrix skins add a little
        assert!(
            row[3] > fabric_only && row[3] < 1.2 * fabric_only,
            "{row:?} vs {fabric_only}"
        );
        // both yarn families equally loaded, and every layer keeps its volume: t = t0 / cos(gamma)
        assert!((row[1] - row[2]).abs() <= 1e-9 * row[1].abs());
        let thickness = 0.31 / gamma.cos();
        assert!((row[4] - thickness).abs() < 1e-4 * thickness, "{row:?}");
    }
}

#[test]
fn fabric_warp_tension_example_follows_the_tension_polynomial() {
    let (header, rows) = drive(
        "fabric",
        "examples/material-point/fabric-warp-tension.csv",
        &[],
    );
    assert_eq!(header[..4], ["t", "S11", "S22", "S33"]);
    assert_eq!(header.len(), 13);
    for row in &rows {
        let strain = row[0] / 100.0; // 1 % per second
        let stretch = 1.0 + strain;
        // card: A2, A3; past the slack band the taut branch is shifted by (1 - f) A2 band / 2
        // (docs/model.md §3, f = 1e-3)
        let band = thermostamp::material::fabric::SLACK_BAND;
        let shift = if strain >= band {
            0.5 * (4.0e4 - 40.0) * band
        } else {
            0.0
        };
        let tension = 4.0e4 * strain + 2.0e6 * strain * strain - shift;
        assert!(
            (row[1] - tension / stretch).abs() <= 1e-8 * tension.max(1.0),
            "{row:?}"
        );
        assert!(
            (row[7] - tension * stretch).abs() <= 1e-8 * tension.max(1.0),
            "sigma11 {row:?}"
        );
        assert!(
            row[2..7].iter().chain(&row[8..]).all(|v| v.abs() < 1e-9),
            "{row:?}"
        );
    }
}

#[test]
fn matrix_uniaxial_example_matches_the_closed_form() {
    let (_, rows) = drive(
        "matrix",
        "examples/material-point/matrix-uniaxial-300C.csv",
        &[],
    );
    let (c10, eta1, rate) = (0.10, 1.86e-4, 0.1); // card at 300 °C; history: l = 1 + 0.1 t
    for row in &rows {
        let l = 1.0 + rate * row[0];
        let expected = 2.0 * c10 * (l * l - 1.0 / l)
            + 2.0 * eta1 * (l * l + 2.0 / l - 3.0) * (2.0 * l.powi(3) + l.powi(-3)) * rate;
        let difference = row[7] - row[8]; // sigma11 - sigma22: free of the pressure
        assert!(
            (difference - expected).abs() <= 1e-6 * expected.max(1e-3),
            "{row:?}: {difference} vs {expected}"
        );
    }
}

#[test]
fn fibre_angle_option_turns_the_yarns() {
    let history = "examples/material-point/fabric-warp-tension.csv";
    let (_, along) = drive("fabric", history, &[]);
    let (_, bias) = drive("fabric", history, &["--angle", "45"]);
    let (_, bias_neg) = drive("fabric", history, &["--angle=-45"]);
    let last = along.len() - 1;
    // at 45° each yarn sees only about half the strain: far less stress than along the warp
    assert!(bias[last][1] > 0.0 && bias[last][1] < 0.6 * along[last][1]);
    // mirror symmetry: -45° gives the same normal stresses
    assert!((bias[last][1] - bias_neg[last][1]).abs() < 1e-9 * bias[last][1]);
}

#[test]
fn output_option_writes_the_same_csv() {
    let path = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("laminate-out.csv");
    let history = "examples/material-point/laminate-shear-300C.csv";
    let args = driver_args("laminate", history);
    let to_stdout = thermostamp(&args);
    let to_file = thermostamp(&[&args[..], &["--output", path.to_str().unwrap()]].concat());
    assert!(to_file.status.success() && to_file.stdout.is_empty());
    assert_eq!(std::fs::read(&path).unwrap(), to_stdout.stdout);
}

#[test]
fn bad_histories_give_a_located_one_line_error() {
    let header = "t,F11,F12,F13,F21,F22,F23,F31,F32,F33,T\n";
    let ok_row = "0,1,0,0,0,1,0,0,0,1,300\n";
    let cases: [(&str, String, &[&str]); 5] = [
        (
            "missing-column.csv",
            "t,F11,F12,F13,F21,F22,F23,F31,F32,T\n0,1,0,0,0,1,0,0,0,300\n".into(),
            &["missing-column.csv", "missing column 'F33'"],
        ),
        (
            "non-numeric.csv",
            format!("{header}{ok_row}1,1.1,0,0,0,one,0,0,0,1,300\n"),
            &["non-numeric.csv: line 3", "'one'"],
        ),
        (
            "inverted.csv",
            format!("{header}{ok_row}1,1,0,0,0,1,0,0,0,-0.5,300\n"),
            &["inverted.csv: line 3", "det F"],
        ),
        (
            "too-hot.csv",
            format!("{header}{ok_row}# heating\n1,1,0,0,0,1,0,0,0,1,345\n"),
            &["too-hot.csv: line 4", "345", "150 to 320"],
        ),
        (
            "time-back.csv",
            format!("{header}{ok_row}0,1,0,0,0,1,0,0,0,1,300\n"),
            &["time-back.csv: line 3", "does not increase"],
        ),
    ];
    for (name, content, expected) in cases {
        let path = scratch(name, &content);
        assert_bad_input(&driver_args("matrix", path.to_str().unwrap()), expected);
    }
    let laminate_row = scratch(
        "laminate-inverted.csv",
        "t,F11,F12,F21,F22,T\n0,1,0,0,1,300\n1,1,2,1,1,300\n",
    );
    assert_bad_input(
        &driver_args("laminate", laminate_row.to_str().unwrap()),
        &["line 3", "det F"],
    );
}

#[test]
fn bad_cards_and_arguments_give_exit_code_2() {
    let history = "examples/material-point/laminate-shear-300C.csv";
    let card_text = std::fs::read_to_string(repo_path(CARD)).unwrap();
    let unknown_key = scratch(
        "unknown-key.toml",
        &card_text.replace("[fabric]\n", "[fabric]\nlocking = 50\n"),
    );
    let negative = scratch(
        "negative.toml",
        &card_text.replace("fabric_thickness = 0.23", "fabric_thickness = -0.23"),
    );
    let with_card = |card: &str, expected: &[&str]| {
        let args = [
            "material-point",
            "--card",
            card,
            "--layer",
            "laminate",
            "--history",
            history,
        ];
        assert_bad_input(&args, expected);
    };
    with_card(
        unknown_key.to_str().unwrap(),
        &["unknown-key.toml: line", "locking"],
    );
    with_card(negative.to_str().unwrap(), &["fabric_thickness"]);
    with_card("no/such/card.toml", &["no/such/card.toml"]);
    assert_bad_input(&driver_args("laminate", "no/such.csv"), &["no/such.csv"]);
    // clap's own usage errors: exit code 2 with a usage hint after the message
    for (args, culprit) in [
        (driver_args("resin", history), "resin"),
        (
            [driver_args("laminate", history), vec!["--angle", "abc"]].concat(),
            "abc",
        ),
        (vec![], "Usage"),
    ] {
        let out = thermostamp(&args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        assert!(
            String::from_utf8_lossy(&out.stderr).contains(culprit),
            "{args:?}"
        );
    }
    assert_eq!(
        thermostamp(&["material-point", "--help"]).status.code(),
        Some(0)
    );
}
