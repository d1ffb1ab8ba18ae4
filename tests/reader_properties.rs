//! Property tests of the scenario and material-card readers: arbitrary TOML, arbitrary values
//! in every key of the shipped files, arbitrary bytes and `--set` overrides never panic or
//! hang; a refusal is one line naming the file, and through the command line it exits 2.

mod common;

use common::{repo_path, scratch_dir, thermostamp};
use proptest::prelude::*;
use std::path::PathBuf;
use std::time::{Duration, Instant};
use thermostamp::forming::Scenario;
use thermostamp::material::MaterialCard;

/// Longest a reader may take on any input.
const READ_TIME: Duration = Duration::from_secs(2);

/// A TOML value of any kind, with the numbers a careless or hostile user gives.
fn toml_value() -> impl Strategy<Value = String> {
    let special = prop::sample::select(vec![
        "nan",
        "inf",
        "-inf",
        "0",
        "0.0",
        "-0.0",
        "1e308",
        "-1e308",
        "1e-308",
        "5e-324",
        "1e300",
        "-1",
        "9223372036854775807",
        "-9223372036854775808",
        "true",
        "\"\"",
        "[]",
        "{}",
        "[[1.0]]",
        "\"../../etc/passwd\"",
        "1979-05-27T07:32:00Z",
    ])
    .prop_map(str::to_string);
    prop_oneof![
        special,
        any::<f64>().prop_map(|x| format!("{x:e}")),
        any::<i64>().prop_map(|i| i.to_string()),
        "[a-z ]{0,12}".prop_map(|s| format!("\"{s}\"")),
        prop::collection::vec(-1e3..1e3f64, 0..5).prop_map(|v| format!(
            "[{}]",
            v.iter()
                .map(|x| format!("{x:e}"))
                .collect::<Vec<_>>()
                .join(", ")
        )),
        (-1e3..1e3f64).prop_map(|x| format!("{{ value = {x:e} }}")),
    ]
}

/// `text` with the value of its `line`-th assignment (counted modulo their number) replaced
/// by `value`.
fn with_value(text: &str, line: usize, value: &str) -> String {
    let assignments: Vec<usize> = text
        .lines()
        .enumerate()
        .filter(|(_, l)| {
            let l = l.trim_start();
            !l.starts_with('#') && !l.starts_with('[') && l.contains('=')
        })
        .map(|(i, _)| i)
        .collect();
    let target = assignments[line % assignments.len()];
    text.lines()
        .enumerate()
        .map(|(i, l)| match l.split_once('=') {
            Some((key, _)) if i == target => format!("{key}= {value}\n"),
            _ => format!("{l}\n"),
        })
        .collect()
}

/// `text` without its `line`-th line (modulo their number), or with it twice.
fn with_line_edited(text: &str, line: usize, twice: bool) -> String {
    let lines: Vec<&str> = text.lines().collect();
    let target = line % lines.len();
    lines
        .iter()
        .enumerate()
        .flat_map(|(i, l)| match (i == target, twice) {
            (false, _) => vec![*l],
            (true, false) => vec![],
            (true, true) => vec![*l, *l],
        })
        .map(|l| format!("{l}\n"))
        .collect()
}

fn example_scenario() -> String {
    std::fs::read_to_string(repo_path("examples/hemisphere.toml"))
        .unwrap()
        .replace(
            "../materials/",
            &format!("{}/", repo_path("materials").display()),
        )
}

fn shipped_card() -> String {
    std::fs::read_to_string(repo_path("materials/t300-5hs-pps.toml")).unwrap()
}

/// Writes `text` as a scenario file and loads it with `overrides`: no panic, in time, and a
/// refusal is one line that names the file.
fn load_scenario(text: &str, overrides: &[String]) -> Result<(), TestCaseError> {
    let path = scratch_file("scenario.toml", text.as_bytes());
    let start = Instant::now();
    let result = Scenario::load(&path, overrides);
    prop_assert!(start.elapsed() < READ_TIME, "took {:?}", start.elapsed());
    if let Err(e) = result {
        let message = e.to_string();
        prop_assert!(
            message.starts_with(&path.display().to_string()),
            "{message}"
        );
        prop_assert!(!message.contains('\n'), "{message}");
    }
    Ok(())
}

fn load_card(text: &str) -> Result<(), TestCaseError> {
    let start = Instant::now();
    let result = MaterialCard::from_toml(text, "card.toml");
    prop_assert!(start.elapsed() < READ_TIME, "took {:?}", start.elapsed());
    if let Err(e) = result {
        let message = e.to_string();
        prop_assert!(message.starts_with("card.toml: "), "{message}");
        prop_assert!(!message.contains('\n'), "{message}");
    }
    Ok(())
}

/// A file in this test process's scratch folder (one per thread, as proptest runs cases of
/// different tests in parallel).
fn scratch_file(name: &str, bytes: &[u8]) -> PathBuf {
    let thread = format!("{:?}", std::thread::current().id()).replace(['(', ')'], "");
    let dir = scratch_dir("reader-properties", &thread);
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn scenario_with_any_value_in_any_key(line in 0usize..200, value in toml_value()) {
        load_scenario(&with_value(&example_scenario(), line, &value), &[])?;
    }

    #[test]
    fn scenario_with_a_line_dropped_or_doubled(line in 0usize..200, twice in any::<bool>()) {
        load_scenario(&with_line_edited(&example_scenario(), line, twice), &[])?;
    }

    #[test]
    fn scenario_of_arbitrary_bytes(bytes in prop::collection::vec(any::<u8>(), 0..600)) {
        load_scenario(&String::from_utf8_lossy(&bytes), &[])?;
    }

    #[test]
    fn scenario_with_any_override(
        key in prop::sample::select(vec![
            "blank.width", "blank.element_size", "blank.ply_angle", "blank.pattern",
            "blank.card", "tools.shape", "tools.punch_radius", "tools.resolution",
            "process.temperature", "process.stroke", "process.punch_speed",
            "process.blank_holder_force", "process.time_scaling", "process.target_time_step",
            "process.friction.die", "output.frames", "output.history_points",
            "output.locking_angle", "process", "blank.width.x", "nothing.at_all",
        ]),
        value in toml_value(),
    ) {
        load_scenario(&example_scenario(), &[format!("{key}={value}")])?;
    }

    #[test]
    fn card_with_any_value_in_any_key(line in 0usize..200, value in toml_value()) {
        load_card(&with_value(&shipped_card(), line, &value))?;
    }

    #[test]
    fn card_with_a_line_dropped_or_doubled(line in 0usize..200, twice in any::<bool>()) {
        load_card(&with_line_edited(&shipped_card(), line, twice))?;
    }

    #[test]
    fn card_of_arbitrary_bytes(bytes in prop::collection::vec(any::<u8>(), 0..600)) {
        load_card(&String::from_utf8_lossy(&bytes))?;
    }
}

proptest! {
    // each case starts the binary
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// Through the command line a card is used or refused with exit 2 and one line naming it.
    #[test]
    fn material_point_on_any_card_exits_0_or_2(line in 0usize..200, value in toml_value()) {
        let card = scratch_file("card.toml", with_value(&shipped_card(), line, &value).as_bytes());
        let history = repo_path("examples/material-point/laminate-shear-300C.csv");
        let out = thermostamp(&[
            "material-point",
            "--card",
            card.to_str().unwrap(),
            "--layer",
            "laminate",
            "--history",
            history.to_str().unwrap(),
        ]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        match out.status.code() {
            Some(0) => {}
            Some(2) => {
                prop_assert_eq!(stderr.trim_end().lines().count(), 1, "{}", stderr);
                prop_assert!(
                    stderr.contains(card.to_str().unwrap()) || stderr.contains("history"),
                    "{}", stderr
                );
            }
            code => prop_assert!(false, "exit code {:?}: {}", code, stderr),
        }
    }
}
