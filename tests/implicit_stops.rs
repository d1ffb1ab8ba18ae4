//! How the implicit solver meets a part it cannot form, and which solver a scenario gets:
//! a run made to fail on purpose (a pyramid punch crushing the blank against a closed die)
//! keeps its last converged state and says what to try; a scenario that does not choose its
//! solver runs implicitly; an explicit run estimated at over ten minutes names the implicit
//! solver.

mod common;

use common::{assert_bad_input, repo_path, scratch_dir, thermostamp, write_stl};
use std::path::{Path, PathBuf};
use thermostamp::forming::preflight::{estimate_from_keys, implicit_advice, BlankSize};
use thermostamp::forming::Scenario;
use thermostamp::material::MaterialCard;
use thermostamp::solver::SolverKind;

/// The apex of the punch (mm, below the blank's mid-plane at z = 0) and the die's flat face
/// above it: the punch's tip meets the die after [`CLOSING`] mm of stroke less the ply.
const APEX: f64 = -1.0;
const DIE_FACE: f64 = 2.0;
const CLOSING: f64 = DIE_FACE - APEX;

/// In `dir`: a pyramid punch (apex at [`APEX`], base 200 mm square at z = -20) and a closed
/// die (a flat plate at [`DIE_FACE`], facing the blank), and a scenario of an 80 mm square
/// T300/PPS blank in 8 mm cells between them, with no `process.solver`.
fn crushing_scenario(dir: &Path, stroke: f64) -> PathBuf {
    let square = |z: f64| {
        [
            [-100.0, -100.0, z],
            [100.0, -100.0, z],
            [100.0, 100.0, z],
            [-100.0, 100.0, z],
        ]
    };
    let base = square(-20.0);
    let pyramid: Vec<[[f64; 3]; 3]> = (0..4)
        .map(|k| [base[k], base[(k + 1) % 4], [0.0, 0.0, APEX]])
        .collect();
    write_stl(&dir.join("punch.stl"), &pyramid);
    let p = square(DIE_FACE);
    write_stl(
        &dir.join("die.stl"),
        &[[p[0], p[2], p[1]], [p[0], p[3], p[2]]],
    );
    let card = repo_path("materials/t300-5hs-pps.toml");
    let text = format!(
        "[blank]\ncard = {card:?}\nwidth = 80.0\nlength = 80.0\nelement_size = 8.0\n\n\
         [tools]\nshape = \"files\"\npunch = {{ file = \"punch.stl\" }}\n\
         die = {{ file = \"die.stl\" }}\n\n\
         [process]\ntemperature = 300.0\nstroke = {stroke}\npunch_speed = 10.0\n\n\
         [process.friction]\npunch = 0.2\ndie = 0.2\nholder = 0.2\n"
    );
    let path = dir.join("crush.toml");
    std::fs::write(&path, text).unwrap();
    path
}

/// `thermostamp run scenario --output out`: exit code, standard output and standard error.
fn run_into(scenario: &Path, out: &Path) -> (Option<i32>, String, String) {
    let run = thermostamp(&[
        "run",
        scenario.to_str().unwrap(),
        "--output",
        out.to_str().unwrap(),
    ]);
    let text = |bytes: &[u8]| String::from_utf8_lossy(bytes).into_owned();
    (run.status.code(), text(&run.stdout), text(&run.stderr))
}

/// The column `name` of a CSV's last row.
fn last_value(csv: &Path, name: &str) -> String {
    let text = std::fs::read_to_string(csv).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let column = header.iter().position(|h| *h == name).unwrap();
    let last = lines.last().unwrap();
    // the status is quoted and may hold commas: count from the end for the numbers
    let cells: Vec<&str> = last.rsplitn(header.len(), ',').collect();
    cells[header.len() - 1 - column].to_string()
}

/// The punch crushes the blank against the closed die: the increment where the ply is
/// squeezed through cannot converge. The run exits 1 with advice naming the keys to try, and
/// writes the part as formed at the last converged increment: its history ends there and the
/// result row, shear map, formed blank and frames are written from that state.
#[test]
fn a_blank_crushed_against_a_closed_die_keeps_its_last_converged_state() {
    let dir = scratch_dir("implicit-stops", "crushed");
    let scenario = crushing_scenario(&dir, 8.0);
    let out = dir.join("out");
    let (code, stdout, stderr) = run_into(&scenario, &out);
    assert_eq!(code, Some(1), "{stdout}\n{stderr}");
    assert!(stderr.contains("did not converge"), "{stderr}");
    for key in [
        "what to try",
        "process.max_increment",
        "blank.element_size",
        "tools.punch (",
        "tools.die (",
        "process.solver = \"explicit\"",
        "last converged increment, is written",
    ] {
        assert!(stderr.contains(key), "'{key}' not in {stderr}");
    }
    for file in [
        "forming.csv",
        "forming-result.csv",
        "forming-punch-force.png",
        "forming-shear-map.png",
        "formed-blank.inp",
        "formed-blank.vtu",
        "forming.pvd",
    ] {
        assert!(out.join(file).is_file(), "{file} not written: {stdout}");
    }
    let result = out.join("forming-result.csv");
    assert!(
        last_value(&result, "status").starts_with("\"stopped: increment"),
        "{}",
        std::fs::read_to_string(&result).unwrap()
    );
    // the stroke where it stopped: near where the punch's tip meets the die through the ply
    let reached: f64 = last_value(&result, "stroke_reached").parse().unwrap();
    let history: f64 = last_value(&out.join("forming.csv"), "stroke")
        .parse()
        .unwrap();
    assert!(
        (reached - history).abs() < 1e-8 * reached,
        "the result row ({reached}) is the history's last row ({history})"
    );
    assert!(
        reached > CLOSING - 1.0 && reached < CLOSING + 1.0,
        "stopped at {reached} mm, the tip meets the die at {CLOSING} mm less the ply"
    );
    assert!(
        stdout.contains("status                      stopped: increment"),
        "{stdout}"
    );
}

/// Without `process.solver` a scenario runs implicitly (no time or mass scaling asked): the
/// estimate and the summary say so. With an explicit-only key and no solver, the key is
/// refused, naming `process.solver`.
#[test]
fn a_scenario_without_a_solver_runs_implicitly() {
    let dir = scratch_dir("implicit-stops", "default");
    let scenario = crushing_scenario(&dir, 1.0);
    let out = dir.join("out");
    let (code, stdout, stderr) = run_into(&scenario, &out);
    assert_eq!(code, Some(0), "{stdout}\n{stderr}");
    assert!(
        stderr.contains("estimate: implicit quasi-static run"),
        "{stderr}"
    );
    assert!(
        stdout.contains("solver                      implicit:"),
        "{stdout}"
    );
    for key in ["process.time_scaling=10", "process.target_time_step=1e-5"] {
        let name = key.split('=').next().unwrap();
        assert_bad_input(
            &["run", scenario.to_str().unwrap(), "--set", key],
            &[name, "process.solver = \"explicit\""],
        );
    }
}

/// The explicit hemisphere's estimate is about a minute on its 10 mm cells: no advice. On 2 mm
/// cells (25 times the cells, each step 5 times shorter) it is hours: the note names the
/// implicit solver, its estimate, and how to choose it.
#[test]
fn an_explicit_run_estimated_over_ten_minutes_names_the_implicit_solver() {
    let load = |overrides: &[&str]| {
        let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
        Scenario::load(
            &repo_path("tests/data/hemisphere-explicit.toml"),
            &overrides,
        )
        .unwrap()
    };
    let advice = |s: &Scenario| {
        let card = MaterialCard::load(&repo_path("materials/t300-5hs-pps.toml")).unwrap();
        let estimate = estimate_from_keys(s, &card, BlankSize::of_rectangle(s).unwrap()).unwrap();
        (estimate.wall_seconds, implicit_advice(s, &estimate))
    };
    let (seconds, note) = advice(&load(&[]));
    assert!(seconds < 600.0 && note.is_none(), "{seconds} s: {note:?}");
    let (seconds, note) = advice(&load(&["blank.element_size=2"]));
    let note = note.unwrap_or_else(|| panic!("no advice at {seconds} s"));
    assert!(seconds > 600.0, "{seconds}");
    for key in [
        "implicit solver",
        "process.solver = \"implicit\"",
        "process.time_scaling",
    ] {
        assert!(note.contains(key), "'{key}' not in {note}");
    }
    let mut implicit = load(&["blank.element_size=2"]);
    implicit.process.solver = SolverKind::Implicit;
    assert!(
        advice(&implicit).1.is_none(),
        "an implicit run gets no advice"
    );
}
