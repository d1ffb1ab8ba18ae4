//! `thermostamp fit fabric-tension` run as a user runs it: strip curves made from the shipped
//! card's yarn law give its `A_k` back, the fitted card reproduces the data in the FE strip test,
//! and bad input gives a one-line error with exit code 2 naming the file.
//!
//! The data of `tests/data/fit-tension/` and `examples/fit-fabric-tension/` are made by this
//! file: `cargo test --release --test cli_fit_fabric_tension -- --ignored regenerate` writes
//! them again, and `committed_data_are_what_the_generator_makes` checks that they still are.

mod common;

use common::{assert_bad_input, repo_path, run_ok, scratch_dir, t300_card, thermostamp};
use std::path::{Path, PathBuf};
use thermostamp::experiment::sheet_test::SheetTest;
use thermostamp::experiment::uniaxial::UniaxialTension;
use thermostamp::fit::fabric_tension::{fit_yarn_tension, strip_force_per_width};
use thermostamp::fit::strip_data::read_strip_curve;
use thermostamp::fit::synthetic::{strip_curve, Lcg};
use thermostamp::io::write_csv;
use thermostamp::material::MaterialCard;

/// One data set: where, how many points, how much noise.
struct DataSet {
    dir: &'static str,
    points: usize,
    noise: f64,
    seed: u64,
}

/// Noiseless: the CLI round trip and the FE check.
const TEST_DATA: DataSet = DataSet {
    dir: "tests/data/fit-tension",
    points: 11,
    noise: 0.0,
    seed: 1,
};

/// The example: 2 % noise.
const EXAMPLE: DataSet = DataSet {
    dir: "examples/fit-fabric-tension",
    points: 31,
    noise: 0.02,
    seed: 2018,
};

/// 2 % strain, the end of the standard virtual strip test (3 mm on 150 mm).
const MAX_STRAIN: f64 = 0.02;
/// The weft curve is written as force (N) of a 25 mm wide strip.
const WIDTH: f64 = 25.0;
const CARD: &str = "materials/t300-5hs-pps.toml";

/// `t_B` of the shipped card (mm).
fn fabric_thickness(card: &MaterialCard) -> f64 {
    let layers = card.laminate.layers();
    layers
        .iter()
        .find(|l| l.law.name() == "fabric")
        .unwrap()
        .thickness
}

/// `(warp A_k, weft A_k)` of the shipped card.
fn card_coefficients() -> (Vec<f64>, Vec<f64>) {
    let card = t300_card();
    (
        card.fabric.warp.coefficients().to_vec(),
        card.fabric.weft.coefficients().to_vec(),
    )
}

/// The files of `set`: `warp.csv` (strain, force_per_width) and `weft.csv` (stretch, force in
/// N of a 25 mm strip).
fn generate(set: &DataSet) -> Vec<(&'static str, String)> {
    let card = t300_card();
    let t_b = fabric_thickness(&card);
    let (warp, weft) = card_coefficients();
    let mut rng = Lcg::new(set.seed);
    let header = format!(
        "# Made by tests/cli_fit_fabric_tension.rs from the {{}} law of {CARD} ({} % noise, \
         seed {}).\n",
        100.0 * set.noise,
        set.seed
    );
    let shape = (MAX_STRAIN, set.points);
    let w = strip_curve("warp.csv", t_b, &warp, shape, set.noise, &mut rng);
    let f = strip_curve("weft.csv", t_b, &weft, shape, set.noise, &mut rng);
    let mut warp_csv = header.replace("{}", "warp").into_bytes();
    let rows = w.stretch.iter().zip(&w.force_per_width);
    write_csv(
        &mut warp_csv,
        &["strain", "force_per_width"],
        rows.map(|(l, n)| [l - 1.0, *n]),
    )
    .unwrap();
    let mut weft_csv = header.replace("{}", "weft").into_bytes();
    let rows = f.stretch.iter().zip(&f.force_per_width);
    write_csv(
        &mut weft_csv,
        &["stretch", "force"],
        rows.map(|(l, n)| [*l, n * WIDTH]),
    )
    .unwrap();
    vec![
        ("warp.csv", String::from_utf8(warp_csv).unwrap()),
        ("weft.csv", String::from_utf8(weft_csv).unwrap()),
    ]
}

#[test]
#[ignore = "writes the data files; run by hand after changing the generator"]
fn regenerate() {
    for set in [TEST_DATA, EXAMPLE] {
        std::fs::create_dir_all(repo_path(set.dir)).unwrap();
        for (name, content) in generate(&set) {
            std::fs::write(repo_path(set.dir).join(name), content).unwrap();
        }
    }
}

#[test]
fn committed_data_are_what_the_generator_makes() {
    for set in [TEST_DATA, EXAMPLE] {
        for (name, content) in generate(&set) {
            let scratch =
                scratch_dir("fit-fabric-tension", &format!("generated-{}", set.seed)).join(name);
            std::fs::write(&scratch, content).unwrap();
            let made = read_strip_curve(&scratch, Some(WIDTH)).unwrap();
            let committed = read_strip_curve(&repo_path(set.dir).join(name), Some(WIDTH)).unwrap();
            assert_eq!(made.stretch.len(), committed.stretch.len());
            for (x, y) in made
                .stretch
                .iter()
                .zip(&committed.stretch)
                .chain(made.force_per_width.iter().zip(&committed.force_per_width))
            {
                assert!(
                    (x - y).abs() <= 1e-9 * x.abs().max(1e-12),
                    "{name}: {x} vs {y}"
                );
            }
        }
    }
}

/// Fits the test data (or the example) with the CLI into `dir/card.toml`; returns its path and
/// the printed table.
fn fit_with_cli(set: &DataSet, dir: &Path, extra: &[&str]) -> (PathBuf, String) {
    let output = dir.join("card.toml");
    let stdout = fit_card_with_cli(set, CARD, &output, extra);
    (output, stdout)
}

/// Fits the test data (or the example) with the CLI to `card`, written to `output`; returns
/// the printed table.
fn fit_card_with_cli(set: &DataSet, card: &str, output: &Path, extra: &[&str]) -> String {
    let warp = format!("{}/warp.csv", set.dir);
    let weft = format!("{}/weft.csv", set.dir);
    let width = WIDTH.to_string();
    let mut args = vec![
        "fit",
        "fabric-tension",
        "--warp",
        &warp,
        "--weft",
        &weft,
        "--width",
        &width,
        "--card",
        card,
        "--output",
        output.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    run_ok(&args)
}

#[test]
fn noiseless_data_are_fitted_back_within_one_percent_and_the_card_keeps_the_rest() {
    let dir = scratch_dir("fit-fabric-tension", "round-trip");
    let png = dir.join("fit.png");
    let (output, stdout) = fit_with_cli(&TEST_DATA, &dir, &["--plot", png.to_str().unwrap()]);
    assert!(
        stdout.contains("A_k (MPa)") && stdout.contains("RMS res"),
        "{stdout}"
    );
    // Header, then A2 and A3 of each direction.
    assert_eq!(stdout.lines().count(), 5, "{stdout}");
    let card = MaterialCard::load(&output).unwrap();
    let (warp, weft) = card_coefficients();
    for (fitted, truth) in [
        (card.fabric.warp.coefficients(), &warp),
        (card.fabric.weft.coefficients(), &weft),
    ] {
        assert_eq!(fitted.len(), truth.len());
        for (a, b) in fitted.iter().zip(truth) {
            assert!((a / b - 1.0).abs() < 0.01, "{fitted:?} vs {truth:?}");
        }
    }
    // Only the two keys (and a comment line above each) changed.
    let shipped = std::fs::read_to_string(repo_path(CARD)).unwrap();
    let written = std::fs::read_to_string(&output).unwrap();
    let without = |text: &str| {
        text.lines()
            .filter(|l| !l.contains("_tension") && !l.starts_with("# Fitted by"))
            .collect::<Vec<_>>()
            .join("\n")
    };
    assert_eq!(without(&written), without(&shipped));
    assert_eq!(written.lines().count(), shipped.lines().count() + 2);
    assert!(std::fs::read(&png).unwrap().starts_with(b"\x89PNG"));
    // Fitting the written card again replaces the provenance comments instead of stacking them.
    let refit = dir.join("refit.toml");
    fit_card_with_cli(&TEST_DATA, output.to_str().unwrap(), &refit, &[]);
    assert_eq!(std::fs::read_to_string(&refit).unwrap(), written);
}

#[test]
fn example_with_two_percent_noise_is_within_two_standard_errors() {
    let t_b = fabric_thickness(&t300_card());
    let (warp, weft) = card_coefficients();
    for (file, truth) in [("warp.csv", warp), ("weft.csv", weft)] {
        let curve = read_strip_curve(&repo_path(EXAMPLE.dir).join(file), Some(WIDTH)).unwrap();
        let fit = fit_yarn_tension(&curve, t_b, truth.len()).unwrap();
        for ((a, se), b) in fit
            .coefficients
            .iter()
            .zip(&fit.standard_errors)
            .zip(&truth)
        {
            assert!((a - b).abs() < 2.0 * se, "{file}: {fit:?}");
        }
    }
}

/// The fitted card in the FE strip test of `experiment::uniaxial` (the standard 25 x 150 mm
/// strip at 300 °C pulled 3 mm, 2 % strain): warp and weft force per width at the end within
/// 1 % of the data's last point.
#[test]
fn fitted_card_reproduces_the_data_in_the_virtual_strip_test() {
    let dir = scratch_dir("fit-fabric-tension", "virtual");
    let (output, _) = fit_with_cli(&TEST_DATA, &dir, &[]);
    let card = MaterialCard::load(&output).unwrap();
    for (ply_angle, file) in [(0.0, "warp.csv"), (90.0, "weft.csv")] {
        let data = read_strip_curve(&repo_path(TEST_DATA.dir).join(file), Some(WIDTH)).unwrap();
        let (last_stretch, last_force) = (
            *data.stretch.last().unwrap(),
            *data.force_per_width.last().unwrap(),
        );
        let mut test = UniaxialTension::standard(300.0);
        test.ply_angle = ply_angle;
        assert!((test.process.end_displacement / test.length - (last_stretch - 1.0)).abs() < 1e-12);
        let result = test.run(&card.laminate, card.density, None, None).unwrap();
        assert!(
            result.run.outcome.is_ok(),
            "{:?}",
            result.run.outcome.as_ref().err()
        );
        let fe = result.rows.last().unwrap().stress_resultant;
        assert!(
            (fe / last_force - 1.0).abs() < 0.01,
            "{file}: FE {fe} N/mm, data {last_force} N/mm"
        );
    }
    // And the model itself at that point, for the record.
    let t_b = fabric_thickness(&card);
    let n = strip_force_per_width(t_b, card.fabric.warp.coefficients(), 1.0 + MAX_STRAIN);
    assert!(n > 0.0);
}

#[test]
fn bad_input_is_one_line_naming_the_file() {
    let dir = scratch_dir("fit-fabric-tension", "bad");
    let output = dir.join("out.toml");
    let out = output.to_str().unwrap();
    let case = |name: &str, csv: &str| {
        let path = dir.join(name);
        std::fs::write(&path, csv).unwrap();
        path.to_str().unwrap().to_string()
    };
    let empty = case("empty.csv", "");
    let back = case("back.csv", "strain,force_per_width\n0,0\n0.02,5\n0.01,6\n");
    let negative = case("negative.csv", "strain,force_per_width\n0,0\n0.01,-5\n");
    let compression = case("compression.csv", "strain,force_per_width\n-0.01,0\n0,0\n");
    let few = case(
        "few.csv",
        "strain,force_per_width\n0,0\n0.01,100\n0.02,300\n",
    );
    for (file, extra, expected) in [
        (&empty, "", vec!["empty.csv: the file is empty"]),
        (
            &back,
            "",
            vec!["back.csv: line 4: strain = 0.01 does not increase"],
        ),
        (
            &negative,
            "",
            vec!["negative.csv: line 3: force_per_width = -5 is negative"],
        ),
        (
            &compression,
            "",
            vec!["compression.csv", "compression-only"],
        ),
        (
            &few,
            "3",
            vec!["few.csv", "2 points with strain > 0 for 3 coefficients"],
        ),
    ] {
        let mut args = vec![
            "fit",
            "fabric-tension",
            "--weft",
            file,
            "--card",
            CARD,
            "--output",
            out,
        ];
        if !extra.is_empty() {
            args.extend(["--terms", extra]);
        }
        assert_bad_input(&args, &expected);
    }
    assert_bad_input(
        &[
            "fit",
            "fabric-tension",
            "--warp",
            "tests/data/fit-tension/weft.csv",
            "--card",
            CARD,
            "--output",
            out,
        ],
        &["weft.csv", "--width"],
    );
    assert!(!output.exists(), "nothing is written on bad input");
    let none = thermostamp(&["fit", "fabric-tension", "--card", CARD, "--output", out]);
    assert_eq!(none.status.code(), Some(2));
}
