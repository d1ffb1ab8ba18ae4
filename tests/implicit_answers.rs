//! Implicit runs whose answer depends on nothing but the physics: not on how fast a
//! rate-independent fabric is formed (friction is Coulomb's with an elastic stick that
//! remembers, not a regularisation by the slip rate), not on how often the run writes (the
//! increments, the checks and the punch force are the solver's own, docs/solver.md), and large
//! runs that answer at once, from the scenario's keys, and stop at Ctrl-C during their set-up.

mod common;

use common::{scratch_dir, thermostamp};
use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// The dry test fabric (no matrix: nothing in it depends on a rate) over the hemisphere on
/// 10 mm cells, 20 mm deep, with Coulomb friction 0.2 on every tool, at `speed` mm/s.
fn dry_fabric_peak_force(speed: f64) -> f64 {
    let overrides = [
        "blank.card=../tests/data/forming-fabric.toml".to_string(),
        "blank.element_size=10".into(),
        "process.stroke=20".into(),
        format!("process.punch_speed={speed}"),
    ];
    let (_, run) = common::form("examples/hemisphere.toml", &overrides);
    run.outcome.expect("the run reaches the end of its stroke");
    assert_eq!(run.checks.warnings().count(), 0, "{:?}", run.checks);
    run.records
        .iter()
        .map(|r| r.punch_force)
        .fold(0.0, f64::max)
}

/// A rate-independent dry fabric with friction 0.2 at 0.01, 1 and 10 mm/s: the same peak punch
/// force within 2 % (the bound; measured: the same to the digits printed, 22.69 N).
/// With a regularisation by a sliding speed of 0.1 mm/s it was 22.3 N at 10 mm/s and 2.5 N, the
/// frictionless force, at 0.01 mm/s.
#[test]
fn a_dry_fabric_gives_the_same_force_at_any_punch_speed() {
    let forces: Vec<f64> = [0.01, 1.0, 10.0]
        .into_iter()
        .map(dry_fabric_peak_force)
        .collect();
    let frictionless = {
        let overrides = [
            "blank.card=../tests/data/forming-fabric.toml".to_string(),
            "blank.element_size=10".into(),
            "process.stroke=20".into(),
            "process.friction.punch=0".into(),
            "process.friction.die=0".into(),
            "process.friction.holder=0".into(),
        ];
        let (_, run) = common::form("examples/hemisphere.toml", &overrides);
        run.records
            .iter()
            .map(|r| r.punch_force)
            .fold(0.0, f64::max)
    };
    let (low, high) = forces
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(l, h), &f| (l.min(f), h.max(f)));
    assert!(high / low - 1.0 < 0.02, "peak forces {forces:?}");
    // friction does show: the holder's 200 N at mu = 0.2 pull on the flange
    assert!(
        low > 2.0 * frictionless,
        "{forces:?} against {frictionless} N"
    );
}

/// The summary's peak punch force, the checks' lines and the frames of a CLI run of the shipped
/// example with `rows` history rows.
fn example_with_rows(rows: usize) -> (f64, String, usize) {
    let dir = scratch_dir("implicit-answers", &format!("rows-{rows}"));
    let out = thermostamp(&[
        "run",
        "examples/hemisphere.toml",
        "--set",
        &format!("output.history_points={rows}"),
        "--output",
        dir.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout).to_string();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{rows} rows: {stderr}");
    assert!(!stderr.contains("warning"), "{rows} rows: {stderr}");
    let peak = stdout
        .lines()
        .find(|l| l.starts_with("peak punch force"))
        .and_then(|l| l.split_whitespace().nth(3))
        .and_then(|v| v.parse::<f64>().ok())
        .unwrap_or_else(|| panic!("no peak force in {stdout}"));
    let frames = std::fs::read_dir(&dir)
        .unwrap()
        .filter(|e| {
            let name = e.as_ref().unwrap().file_name();
            let name = name.to_string_lossy();
            // the sheet's frames; each has its tools beside it, `forming_NNNN_tools.vtu`
            name.starts_with("forming_") && name.ends_with(".vtu") && !name.contains("tools")
        })
        .count();
    let checks = stdout
        .lines()
        .skip_while(|l| !l.starts_with("checks"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .map(|l| format!("{l}\n"))
        .collect();
    (peak, checks, frames)
}

/// The shipped hemisphere with 10, 60 and 1,000 history rows: every run finishes with every
/// check OK, the same peak punch force within 0.5 % (measured: identical) and the same frames.
/// The rows once set the increments: 10 rows stopped the run at 3 mm (a tool through the
/// blank), 1,000 took 1,003 increments, and the interval-averaged force read 62 N against 72 N.
#[test]
fn the_answer_does_not_depend_on_how_often_the_run_writes() {
    let runs: Vec<(f64, String, usize)> =
        [10, 60, 1000].into_iter().map(example_with_rows).collect();
    for (peak, checks, frames) in &runs {
        assert_eq!(checks.lines().count(), 6, "{checks}");
        assert!(checks.lines().all(|l| l.contains(" OK: ")), "{checks}");
        assert!(
            (peak / runs[1].0 - 1.0).abs() < 0.005,
            "{peak} against {}",
            runs[1].0
        );
        // the example's 10 frames and the start
        assert_eq!(*frames, 11);
    }
}

/// The first line a command writes on standard error, or what it wrote within `limit`; the
/// process is killed either way.
fn first_line_within(args: &[&str], limit: Duration) -> (Option<String>, Duration) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_thermostamp"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the binary starts");
    let stderr = child.stderr.take().unwrap();
    let (send, receive) = mpsc::channel();
    std::thread::spawn(move || {
        let mut line = String::new();
        let _ = BufReader::new(stderr).read_line(&mut line);
        let _ = send.send(line);
    });
    let start = Instant::now();
    let line = receive.recv_timeout(limit).ok();
    let elapsed = start.elapsed();
    let _ = child.kill();
    let _ = child.wait();
    (line, elapsed)
}

/// 0.1 mm cells on the 160 mm example, 2.56 million cells: by either solver an estimate or a
/// refusal within 2 s, from the scenario's keys, before any mesh is made (it printed nothing
/// for minutes and held 3.5 GB). The implicit run's sparse factor alone would need about 190 GiB;
/// the explicit run's mass scaling would add 1e5 times the blank's mass.
#[test]
fn a_run_of_millions_of_cells_answers_at_once() {
    let out = scratch_dir("implicit-answers", "millions");
    for example in [
        "examples/hemisphere.toml",
        "tests/data/hemisphere-explicit.toml",
    ] {
        let (line, elapsed) = first_line_within(
            &[
                "run",
                example,
                "--set",
                "blank.element_size=0.1",
                "--output",
                out.to_str().unwrap(),
            ],
            Duration::from_secs(10),
        );
        let line = line.unwrap_or_else(|| panic!("{example}: nothing in 10 s"));
        assert!(
            line.starts_with("estimate") || line.starts_with("error"),
            "{example}: {line}"
        );
        assert!(
            line.contains("2560000 elements") || line.contains("error"),
            "{line}"
        );
        assert!(elapsed < Duration::from_secs(2), "{example}: {elapsed:?}");
    }
}

/// Ctrl-C while a large blank (102,400 cells) is being set up: the process ends within 2 s with
/// exit code 130, says so, and leaves no output folder (it went on setting up for a minute).
#[test]
fn ctrl_c_during_the_set_up_ends_the_run_at_once() {
    let out = scratch_dir("implicit-answers", "set-up").join("results");
    let _ = std::fs::remove_dir_all(&out);
    let mut child = Command::new(env!("CARGO_BIN_EXE_thermostamp"))
        .args([
            "run",
            "tests/data/hemisphere-explicit.toml",
            "--set",
            "blank.element_size=0.5",
            "--output",
            out.to_str().unwrap(),
        ])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the binary starts");
    let mut stderr = BufReader::new(child.stderr.take().unwrap());
    let mut first = String::new();
    stderr.read_line(&mut first).unwrap();
    assert!(
        first.contains("before set-up") && first.contains("102400 elements"),
        "{first}"
    );
    let interrupted = Instant::now();
    let status = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
    let code = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status.code();
        }
        if interrupted.elapsed() > Duration::from_secs(10) {
            let _ = child.kill();
            panic!("still setting up 10 s after Ctrl-C");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let waited = interrupted.elapsed();
    let mut rest = String::new();
    std::io::Read::read_to_string(&mut stderr, &mut rest).unwrap();
    assert_eq!(code, Some(130), "{rest}");
    assert!(rest.contains("interrupted during the set-up"), "{rest}");
    assert!(waited < Duration::from_secs(2), "{waited:?}");
    assert!(!Path::new(&out).exists(), "{out:?} was written");
}

/// The implicit solver's sparse memory from the node count alone (what the estimate from the
/// scenario's keys uses, before any mesh) against the exact count of the tangent's and
/// factor's entries on the built hemisphere, 441 to 5,184 nodes: within 10 % (measured 1 to 3 %).
#[test]
fn the_sparse_memory_from_the_node_count_matches_the_factor() {
    use thermostamp::solver::implicit::{sparse_memory, sparse_memory_of_size};
    for size in ["8", "4", "2.26"] {
        let scenario = thermostamp::forming::Scenario::load(
            &common::repo_path("examples/hemisphere.toml"),
            &[format!("blank.element_size={size}")],
        )
        .unwrap();
        let forming = thermostamp::forming::FormingModel::new(&scenario).unwrap();
        let model = &forming.model;
        let exact = sparse_memory(model).unwrap();
        let counted = sparse_memory_of_size(model.mesh.nodes.len() as f64);
        assert!(
            (counted / exact - 1.0).abs() < 0.1,
            "{size} mm: {counted} bytes against {exact}"
        );
    }
}

/// The implicit solver's own keys and the values that drove it to nonsense: each refused with
/// exit code 2 naming the key.
#[test]
fn implicit_keys_out_of_range_are_refused_naming_them() {
    use common::adversarial::{assert_all_pass, case, Fixtures};
    let f = Fixtures::new("implicit");
    let run = |name: &str, set: &str, names: &[&str]| {
        case(
            name,
            &[
                "run",
                "examples/hemisphere.toml",
                "--set",
                set,
                "--output",
                &f.output(name),
            ],
            2,
            names,
        )
    };
    let cases = [
        run(
            "zero increment",
            "process.max_increment=0",
            &["process.max_increment"],
        ),
        run(
            "negative increment",
            "process.max_increment=-1",
            &["process.max_increment"],
        ),
        run(
            "increment past the stroke",
            "process.max_increment=31",
            &["process.max_increment", "stroke"],
        ),
        run(
            "increment not a number",
            "process.max_increment=nan",
            &["process.max_increment"],
        ),
        run(
            "punch at 1e300 mm/s",
            "process.punch_speed=1e300",
            &["process.punch_speed"],
        ),
        case(
            "increment with the explicit solver",
            &[
                "run",
                "tests/data/hemisphere-explicit.toml",
                "--set",
                "process.max_increment=1",
                "--output",
                &f.output("explicit-increment"),
            ],
            2,
            &["process.max_increment", "implicit"],
        ),
    ];
    assert_all_pass(&cases, 1);
}
