//! `thermostamp fit matrix` run as a user runs it: the shipped data give back the parameters
//! they were made from, and bad input gives a one-line error with exit code 2 naming the file.
//!
//! The data of `tests/data/fit-matrix/` and `examples/fit-matrix/` are made by this file:
//! `cargo test --release --test cli_fit_matrix -- --ignored regenerate` writes them again, and
//! `committed_data_are_what_the_generator_makes` checks that they still are.

mod common;

use common::{assert_bad_input, repo_path, run_ok, scratch_dir, t300_card, thermostamp};
use std::path::{Path, PathBuf};
use thermostamp::fit::synthetic::{tension_curve, Lcg};
use thermostamp::fit::tension_data::read_manifest;
use thermostamp::io::write_csv;

/// One data set: where, which temperatures and rates, how many points, how much noise.
struct DataSet {
    dir: &'static str,
    temperatures: &'static [f64],
    points: usize,
    noise: f64,
    seed: u64,
}

/// Noiseless, two temperatures: the CLI round trip.
const TEST_DATA: DataSet = DataSet {
    dir: "tests/data/fit-matrix",
    temperatures: &[280.0, 320.0],
    points: 11,
    noise: 0.0,
    seed: 1,
};

/// The example: three temperatures, 2 % noise.
const EXAMPLE: DataSet = DataSet {
    dir: "examples/fit-matrix",
    temperatures: &[280.0, 300.0, 320.0],
    points: 31,
    noise: 0.02,
    seed: 2018,
};

/// Slow curves at 1/s given as a strain rate; fast ones at 600 mm/s on a 20 mm gauge (30/s),
/// given as crosshead speed and gauge length. Stretched to 60 % strain.
const SLOW_RATE: f64 = 1.0;
const FAST_SPEED: f64 = 600.0;
const GAUGE_LENGTH: f64 = 20.0;
const MAX_STRAIN: f64 = 0.6;

/// `(C10, eta1)` of the shipped T300/PPS card at `temperature`.
fn card_matrix(temperature: f64) -> (f64, f64) {
    let p = t300_card()
        .matrix
        .unwrap()
        .parameters_at(temperature)
        .unwrap();
    (p.c10, p.eta1)
}

/// The files of `set`: `(name, content)`, the manifest last.
fn generate(set: &DataSet) -> Vec<(String, String)> {
    let mut rng = Lcg::new(set.seed);
    let mut files = Vec::new();
    let mut manifest = format!(
        "# Made by tests/cli_fit_matrix.rs from the matrix of materials/t300-5hs-pps.toml \
         ({} % noise, seed {}).\n",
        100.0 * set.noise,
        set.seed
    );
    for &t in set.temperatures {
        for (kind, rate) in [("slow", SLOW_RATE), ("fast", FAST_SPEED / GAUGE_LENGTH)] {
            let name = format!("pps-{t}C-{kind}.csv");
            let curve = tension_curve(
                &name,
                t,
                rate,
                card_matrix(t),
                (MAX_STRAIN, set.points),
                set.noise,
                &mut rng,
            );
            // The fast curves are written as nominal stress against stretch, the slow ones as
            // true stress against strain: both forms are read.
            let mut csv = Vec::new();
            if kind == "slow" {
                let rows = curve.stretch.iter().zip(&curve.stress);
                write_csv(
                    &mut csv,
                    &["strain", "stress"],
                    rows.map(|(l, s)| [l - 1.0, *s]),
                )
                .unwrap();
                manifest.push_str(&format!(
                    "\n[[curve]]\nfile = \"{name}\"\ntemperature = {t:?}\nstrain_rate = {rate:?}\n"
                ));
            } else {
                let rows = curve.stretch.iter().zip(&curve.stress);
                write_csv(
                    &mut csv,
                    &["stretch", "nominal_stress"],
                    rows.map(|(l, s)| [*l, s / l]),
                )
                .unwrap();
                manifest.push_str(&format!(
                    "\n[[curve]]\nfile = \"{name}\"\ntemperature = {t:?}\n\
                     crosshead_speed = {FAST_SPEED:?}\ngauge_length = {GAUGE_LENGTH:?}\n"
                ));
            }
            files.push((name, String::from_utf8(csv).unwrap()));
        }
    }
    files.push(("manifest.toml".into(), manifest));
    files
}

#[test]
#[ignore = "writes the data files; run by hand after changing the generator"]
fn regenerate() {
    for set in [TEST_DATA, EXAMPLE] {
        for (name, content) in generate(&set) {
            std::fs::write(repo_path(set.dir).join(name), content).unwrap();
        }
    }
}

#[test]
fn committed_data_are_what_the_generator_makes() {
    for set in [TEST_DATA, EXAMPLE] {
        let scratch = scratch_dir("fit-matrix", &format!("generated-{}", set.seed));
        for (name, content) in generate(&set) {
            std::fs::write(scratch.join(name), content).unwrap();
        }
        let made = read_manifest(&scratch.join("manifest.toml")).unwrap();
        let committed = read_manifest(&repo_path(set.dir).join("manifest.toml")).unwrap();
        assert_eq!(made.len(), committed.len());
        for (a, b) in made.iter().zip(&committed) {
            assert_eq!(
                (a.temperature, a.strain_rate),
                (b.temperature, b.strain_rate)
            );
            for (x, y) in a
                .stress
                .iter()
                .zip(&b.stress)
                .chain(a.stretch.iter().zip(&b.stretch))
            {
                assert!(
                    (x - y).abs() <= 1e-9 * x.abs().max(1e-12),
                    "{}: {x} vs {y}",
                    b.origin
                );
            }
        }
    }
}

/// The `[matrix]` tables of a written card or section.
fn matrix_tables(path: &Path) -> toml::Table {
    let text = std::fs::read_to_string(path).unwrap();
    let doc: toml::Table = toml::from_str(&text).unwrap();
    doc["matrix"].as_table().unwrap().clone()
}

fn floats(table: &toml::Table, key: &str) -> Vec<f64> {
    table[key]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_float().unwrap())
        .collect()
}

#[test]
fn noiseless_data_are_fitted_back_within_one_percent() {
    let dir = scratch_dir("fit-matrix", "round-trip");
    let (card, png) = (dir.join("matrix.toml"), dir.join("fit.png"));
    let stdout = run_ok(&[
        "fit",
        "matrix",
        "--manifest",
        "tests/data/fit-matrix/manifest.toml",
        "--output",
        card.to_str().unwrap(),
        "--bulk-modulus",
        "1500",
        "--plot",
        png.to_str().unwrap(),
    ]);
    assert!(
        stdout.contains("C10 (MPa)") && stdout.contains("eta1 (MPa·s)"),
        "{stdout}"
    );
    assert_eq!(stdout.lines().count(), 3, "{stdout}");
    let m = matrix_tables(&card);
    assert_eq!(floats(&m, "temperature"), [280.0, 320.0]);
    for (i, t) in [280.0, 320.0].into_iter().enumerate() {
        let (c10, eta1) = card_matrix(t);
        assert!((floats(&m, "c10")[i] / c10 - 1.0).abs() < 0.01, "{m:?}");
        assert!((floats(&m, "eta1")[i] / eta1 - 1.0).abs() < 0.01, "{m:?}");
        assert!((floats(&m, "d1")[i] * 750.0 - 1.0).abs() < 1e-5, "{m:?}");
    }
    let png_bytes = std::fs::read(&png).unwrap();
    assert!(png_bytes.starts_with(b"\x89PNG"), "not a PNG");
}

#[test]
fn updating_a_card_keeps_the_rest_and_loads() {
    let dir = scratch_dir("fit-matrix", "update");
    let output = dir.join("card.toml");
    run_ok(&[
        "fit",
        "matrix",
        "--manifest",
        "examples/fit-matrix/manifest.toml",
        "--card",
        "materials/t300-5hs-pps.toml",
        "--output",
        output.to_str().unwrap(),
        "--poisson",
        "0.45",
    ]);
    let shipped = std::fs::read_to_string(repo_path("materials/t300-5hs-pps.toml")).unwrap();
    let written = std::fs::read_to_string(&output).unwrap();
    let tail = |text: &str| text[text.find("[fabric]").unwrap()..].to_string();
    assert_eq!(tail(&written), tail(&shipped));
    let head = |text: &str| text[..text.find("[matrix]").unwrap()].to_string();
    assert_eq!(head(&written), head(&shipped));
    let card = thermostamp::material::MaterialCard::load(&output).unwrap();
    let p = card.matrix.unwrap().parameters_at(300.0).unwrap();
    // 2 % noise: a few percent from the card's values.
    let (c10, eta1) = card_matrix(300.0);
    assert!((p.c10 / c10 - 1.0).abs() < 0.02, "{p:?}");
    assert!((p.eta1 / eta1 - 1.0).abs() < 0.15, "{p:?}");
    // nu = 0.45: K = 2 G 1.45 / 0.3 with G = 2 C10.
    assert!(
        (p.d1 - 2.0 / (4.0 * p.c10 * 1.45 / 0.3)).abs() < 1e-5 * p.d1,
        "{p:?}"
    );
}

/// A manifest in a scratch folder with the test data's slow 280 °C curve replaced by `csv`.
fn manifest_with(case: &str, csv: &str, extra_key: &str) -> PathBuf {
    let dir = scratch_dir("fit-matrix", case);
    let source = repo_path(TEST_DATA.dir);
    for entry in std::fs::read_dir(&source).unwrap() {
        let path = entry.unwrap().path();
        std::fs::copy(&path, dir.join(path.file_name().unwrap())).unwrap();
    }
    std::fs::write(dir.join("pps-280C-slow.csv"), csv).unwrap();
    let manifest = dir.join("manifest.toml");
    let text = std::fs::read_to_string(&manifest).unwrap();
    let text = text.replacen(
        "strain_rate = 1.0\n",
        &format!("strain_rate = 1.0\n{extra_key}"),
        1,
    );
    std::fs::write(&manifest, text).unwrap();
    manifest
}

fn fit_args(manifest: &Path, output: &Path) -> Vec<String> {
    [
        "fit",
        "matrix",
        "--manifest",
        manifest.to_str().unwrap(),
        "--output",
        output.to_str().unwrap(),
        "--bulk-modulus",
        "1500",
    ]
    .map(String::from)
    .to_vec()
}

#[test]
fn bad_data_give_one_line_naming_the_file() {
    let good = std::fs::read_to_string(repo_path(TEST_DATA.dir).join("pps-280C-slow.csv")).unwrap();
    let lines: Vec<&str> = good.lines().collect();
    let swapped = [&[lines[0], lines[1], lines[3], lines[2]][..], &lines[4..]]
        .concat()
        .join("\n");
    let negative = good.replacen(
        lines[3],
        &format!("{},-0.5", lines[3].split(',').next().unwrap()),
        1,
    );
    let cases: [(&str, String, &str, &[&str]); 6] = [
        (
            "empty",
            String::new(),
            "",
            &["pps-280C-slow.csv", "the file is empty"],
        ),
        (
            "text",
            good.replacen(lines[2], "0.06,abc", 1),
            "",
            &["pps-280C-slow.csv: line 3", "'abc'"],
        ),
        (
            "non-monotonic",
            swapped,
            "",
            &["pps-280C-slow.csv: line 4", "does not increase"],
        ),
        (
            "negative",
            negative,
            "",
            &["pps-280C-slow.csv: line 4", "negative"],
        ),
        (
            "unknown-key",
            good.clone(),
            "speed = 3.0\n",
            &["manifest.toml", "unknown field `speed`"],
        ),
        ("missing-file", good.clone(), "", &[]),
    ];
    for (case, csv, extra, expected) in cases {
        let manifest = manifest_with(case, &csv, extra);
        if case == "missing-file" {
            std::fs::remove_file(manifest.with_file_name("pps-320C-fast.csv")).unwrap();
        }
        let output = manifest.with_file_name("out.toml");
        let args = fit_args(&manifest, &output);
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let expected: Vec<&str> = if case == "missing-file" {
            vec!["pps-320C-fast.csv", "cannot read the curve"]
        } else {
            expected.to_vec()
        };
        assert_bad_input(&args, &expected);
        assert!(!output.exists(), "{case}: nothing is written on bad input");
    }
}

#[test]
fn too_few_points_and_missing_options_are_bad_input() {
    // One point per curve: two points at each temperature for two parameters.
    let manifest = manifest_with("too-few", "strain,stress\n0.1,0.1\n", "");
    for name in [
        "pps-280C-fast.csv",
        "pps-320C-slow.csv",
        "pps-320C-fast.csv",
    ] {
        let path = manifest.with_file_name(name);
        let text = std::fs::read_to_string(&path).unwrap();
        let first_two: Vec<&str> = text.lines().take(2).collect();
        std::fs::write(&path, first_two.join("\n")).unwrap();
    }
    let output = manifest.with_file_name("out.toml");
    let args = fit_args(&manifest, &output);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    assert_bad_input(
        &args,
        &[
            "280 °C",
            "pps-280C-slow.csv",
            "2 data points for 2 parameters",
        ],
    );

    let base = [
        "fit",
        "matrix",
        "--manifest",
        "tests/data/fit-matrix/manifest.toml",
        "--output",
    ];
    let out = scratch_dir("fit-matrix", "options").join("out.toml");
    let out = out.to_str().unwrap();
    assert_bad_input(
        &[&base[..], &[out]].concat(),
        &["--bulk-modulus", "--poisson"],
    );
    // Usage errors are clap's, with its usage lines.
    let both = thermostamp(
        &[
            &base[..],
            &[out, "--bulk-modulus", "1500", "--poisson", "0.4"],
        ]
        .concat(),
    );
    assert_eq!(both.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&both.stderr).contains("cannot be used with"));
    assert_bad_input(
        &[&base[..], &[out, "--poisson", "0.5"]].concat(),
        &["--poisson 0.5"],
    );
}
