//! Files and studies as a careless or adversarial user leaves them (issue 38): nothing of the
//! user's is written through (a symbolic link under the name of a result, at the lock file,
//! as the output folder, as a case folder), one study per folder (a second sweep, another
//! study's folder, the same case twice at once), and study files that mean one thing (a key
//! given twice, counts and case totals that cannot be run). Each case has its exit code and
//! the file, key or option its one-line message names; everything is written under this
//! test's scratch folder.

mod common;

use common::adversarial::{assert_all_pass, case, Case, Fixtures};
use common::thermostamp;
use std::io::BufRead;
use std::os::unix::fs::symlink;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// The scratch group of a test: its own, since the tests run side by side and each writes
/// its fixtures.
fn fixtures(test: &str) -> Fixtures {
    Fixtures::new(&format!("files-studies/{test}"))
}

/// An empty folder `name` under the fixtures' folder.
fn fresh(f: &Fixtures, name: &str) -> PathBuf {
    let dir = f.dir.join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn text(path: &Path) -> String {
    path.display().to_string()
}

/// A file of the user's, `mine.csv` in `dir`, with bytes no run writes.
fn users_file(dir: &Path) -> PathBuf {
    let mine = dir.join("mine.csv");
    std::fs::write(&mine, USERS_BYTES).unwrap();
    mine
}

const USERS_BYTES: &str = "the user's own data, 1,2,3\n";

/// The explicit hemisphere on 10 mm cells over half a millimetre of stroke, no frames (about a
/// second), as the base of the studies.
fn quick_base(f: &Fixtures) -> String {
    let text = f
        .scenario
        .replace("element_size = 8.0", "element_size = 10.0")
        .replace("stroke = 30.0", "stroke = 0.5")
        .replace("frames = 10", "frames = 0");
    f.file("quick-base.toml", text.as_bytes())
}

/// A study `name.toml` on the quick base with the `parameters` lines, into `folder`.
fn study(f: &Fixtures, name: &str, parameters: &str, folder: &Path) -> String {
    let text = format!(
        "base = \"{}\"\n[parameters]\n{parameters}\n[output]\nfolder = \"{}\"\n",
        quick_base(f),
        folder.display()
    );
    f.file(&format!("{name}.toml"), text.as_bytes())
}

/// `thermostamp run` of the example into `dir`.
fn run_into(f: &Fixtures, dir: &Path) -> Vec<String> {
    let scenario = f.file("example.toml", f.scenario.as_bytes());
    vec!["run".into(), scenario, "--output".into(), text(dir)]
}

fn owned(case_name: &str, args: Vec<String>, code: i32, names: &[&str]) -> Case {
    Case {
        name: case_name.into(),
        args,
        code,
        names: names.iter().map(|s| s.to_string()).collect(),
    }
}

/// Point 1: a symbolic link under a result's name, at the lock file, or on the way to the
/// output folder, for every command that writes results. Refused, naming it and where it
/// points.
fn link_cases(f: &Fixtures) -> Vec<Case> {
    let mut cases = Vec::new();
    for (label, name) in [
        ("history", "forming.csv"),
        ("result row", "forming-result.csv"),
        ("a frame", "forming_0003.vtu"),
        ("a temporary file", "forming.pvd.tmp"),
        ("the formed blank", "formed-blank.inp"),
        ("the lock file", ".thermostamp.lock"),
    ] {
        let dir = fresh(f, &format!("link-run-{name}"));
        let mine = users_file(&dir);
        symlink(&mine, dir.join(name)).unwrap();
        cases.push(owned(
            &format!("run: {label} is a link"),
            run_into(f, &dir),
            2,
            &[&text(&dir.join(name)), &text(&mine), "symbolic link"],
        ));
    }
    let dir = fresh(f, "link-output-dangling");
    let nowhere = dir.join("nowhere");
    symlink(&nowhere, dir.join("out")).unwrap();
    cases.push(owned(
        "run: --output a dangling link",
        run_into(f, &dir.join("out")),
        2,
        &[&text(&dir.join("out")), &text(&nowhere), "does not exist"],
    ));
    let dir = fresh(f, "link-output-loop");
    symlink(dir.join("b"), dir.join("a")).unwrap();
    symlink(dir.join("a"), dir.join("b")).unwrap();
    cases.push(owned(
        "run: --output a loop of links",
        run_into(f, &dir.join("a").join("results")),
        2,
        &[&text(&dir.join("a")), "loop of symbolic links"],
    ));
    let dir = fresh(f, "link-output-file");
    let mine = users_file(&dir);
    symlink(&mine, dir.join("out")).unwrap();
    cases.push(owned(
        "run: --output a link to a file",
        run_into(f, &dir.join("out")),
        2,
        &[&text(&dir.join("out")), &text(&mine), "not a folder"],
    ));
    let dir = fresh(f, "link-test");
    let mine = users_file(&dir);
    symlink(&mine, dir.join("bias-extension.csv")).unwrap();
    let mut args: Vec<String> = common::QUICK_BIAS_EXTENSION.map(String::from).to_vec();
    args.extend(["--output".into(), text(&dir)]);
    cases.push(owned(
        "test bias-extension: its history is a link",
        args,
        2,
        &[&text(&dir.join("bias-extension.csv")), &text(&mine)],
    ));
    for name in ["drape.csv", "drape.vtu.tmp"] {
        let dir = fresh(f, &format!("link-drape-{name}"));
        let mine = users_file(&dir);
        symlink(&mine, dir.join(name)).unwrap();
        let scenario = f.file("example.toml", f.scenario.as_bytes());
        cases.push(owned(
            &format!("drape: {name} is a link"),
            vec!["drape".into(), scenario, "--output".into(), text(&dir)],
            2,
            &[
                &text(&dir.join(name.trim_end_matches(".tmp"))),
                name,
                &text(&mine),
            ],
        ));
    }
    cases.extend(study_link_cases(f));
    cases
}

/// Point 1 in a study's folder: the summary, a chart, a case folder, the folder itself.
fn study_link_cases(f: &Fixtures) -> Vec<Case> {
    let mut cases = Vec::new();
    for (label, name, mode) in [
        ("summary", "summary.csv", "--summarise"),
        ("chart", "study-waviness.png", "--summarise"),
        ("summary's temporary file", "summary.csv.tmp", "--summarise"),
    ] {
        let dir = fresh(f, &format!("link-study-{name}"));
        let mine = users_file(&dir);
        std::fs::create_dir_all(dir.join("out")).unwrap();
        symlink(&mine, dir.join("out").join(name)).unwrap();
        let path = study(
            f,
            &format!("link-study-{name}"),
            "process.temperature = [300.0]",
            &dir.join("out"),
        );
        cases.push(owned(
            &format!("sweep {mode}: the {label} is a link"),
            vec!["sweep".into(), path, mode.into()],
            2,
            &[&text(&dir.join("out").join(name)), &text(&mine)],
        ));
    }
    let dir = fresh(f, "link-study-case");
    let theirs = dir.join("their-folder");
    std::fs::create_dir_all(&theirs).unwrap();
    std::fs::create_dir_all(dir.join("out")).unwrap();
    let path = study(
        f,
        "link-study-case",
        "process.temperature = [300.0]",
        &dir.join("out"),
    );
    let claimed = thermostamp(&["sweep", &path, "--summarise"]);
    assert_eq!(claimed.status.code(), Some(1), "the study's folder taken");
    symlink(&theirs, dir.join("out/case-001")).unwrap();
    cases.push(owned(
        "sweep: a case folder is a link",
        vec!["sweep".into(), path.clone()],
        2,
        &[&text(&dir.join("out/case-001")), &text(&theirs)],
    ));
    cases.push(owned(
        "sweep --case: its folder is a link",
        vec!["sweep".into(), path, "--case".into(), "1".into()],
        2,
        &[&text(&dir.join("out/case-001")), &text(&theirs)],
    ));
    let dir = fresh(f, "link-study-dangling");
    symlink(dir.join("nowhere"), dir.join("out")).unwrap();
    let path = study(
        f,
        "link-study-dangling",
        "process.temperature = [300.0]",
        &dir.join("out"),
    );
    cases.push(owned(
        "sweep: output.folder a dangling link",
        vec!["sweep".into(), path],
        2,
        &[&text(&dir.join("out")), "does not exist"],
    ));
    cases
}

/// Point 2: one study per folder, and a summary that says when cases are missing.
fn folder_cases(f: &Fixtures) -> Vec<Case> {
    let mut cases = Vec::new();
    let dir = fresh(f, "other-study");
    let out = dir.join("out");
    let first = study(f, "first", "process.temperature = [280.0, 320.0]", &out);
    let claimed = thermostamp(&["sweep", &first, "--summarise"]);
    assert_eq!(
        claimed.status.code(),
        Some(1),
        "the first study's folder taken"
    );
    let second = study(f, "second", "process.temperature = [300.0, 310.0]", &out);
    let other = [text(&out), first.clone(), "another study".into()];
    let other: Vec<&str> = other.iter().map(String::as_str).collect();
    for mode in [None, Some("--list"), Some("--summarise"), Some("--case")] {
        let mut args = vec!["sweep".to_string(), second.clone()];
        args.extend(mode.map(String::from));
        if mode == Some("--case") {
            args.push("1".into());
        }
        cases.push(owned(
            &format!("sweep {}: a folder of another study", mode.unwrap_or("")),
            args,
            2,
            &other,
        ));
    }
    // the same parameters on another base scenario are another study too
    let edited = f.file(
        "edited-base.toml",
        std::fs::read_to_string(quick_base(f))
            .unwrap()
            .replace("punch_speed = 10.0", "punch_speed = 12.0")
            .as_bytes(),
    );
    let text_of_first = std::fs::read_to_string(&first).unwrap();
    let on_edited = f.file(
        "first-on-edited-base.toml",
        text_of_first.replace(&quick_base(f), &edited).as_bytes(),
    );
    cases.push(owned(
        "sweep: the same parameters on another base",
        vec!["sweep".into(), on_edited],
        2,
        &[&text(&out), "base scenario differs"],
    ));
    let dir = fresh(f, "unrecorded");
    std::fs::create_dir_all(dir.join("out/case-001")).unwrap();
    let path = study(
        f,
        "unrecorded",
        "process.temperature = [300.0]",
        &dir.join("out"),
    );
    cases.push(owned(
        "sweep: case folders without a record",
        vec!["sweep".into(), path],
        2,
        &[&text(&dir.join("out")), "case-001", "study-identity.toml"],
    ));
    let dir = fresh(f, "garbled-record");
    std::fs::create_dir_all(dir.join("out")).unwrap();
    std::fs::write(dir.join("out/study-identity.toml"), "parameters = 3\n[[").unwrap();
    let path = study(
        f,
        "garbled",
        "process.temperature = [300.0]",
        &dir.join("out"),
    );
    cases.push(owned(
        "sweep: a record that cannot be read",
        vec!["sweep".into(), path],
        2,
        &["study-identity.toml", "cannot be read"],
    ));
    let dir = fresh(f, "summarise-missing");
    let path = study(
        f,
        "summarise-missing",
        "process.temperature = [280.0, 300.0, 320.0]\nprocess.blank_holder_force = [0.0, 200.0]",
        &dir.join("out"),
    );
    cases.push(owned(
        "sweep --summarise: no case run",
        vec!["sweep".into(), path, "--summarise".into()],
        1,
        &[
            "6 of 6 cases not run",
            "cases 1, 2, 3, 4, 5, 6",
            "summary.csv",
        ],
    ));
    cases
}

/// Point 3: study files that could mean two things, or cases that cannot be run.
fn study_file_cases(f: &Fixtures) -> Vec<Case> {
    let dir = fresh(f, "study-files");
    let out = dir.join("out");
    let file = |name: &str, parameters: &str| study(f, name, parameters, &out);
    let sweep = |path: String, extra: &[&str]| {
        let mut args = vec!["sweep".to_string(), path];
        args.extend(extra.iter().map(|s| s.to_string()));
        args
    };
    let range = |count: &str| {
        format!("process.temperature = {{ from = 280.0, to = 320.0, count = {count} }}")
    };
    let mut cases = vec![
        owned(
            "a key quoted and nested",
            sweep(
                file(
                    "twice",
                    "\"process.temperature\" = [280.0]\nprocess.temperature = [320.0]",
                ),
                &["--list"],
            ),
            2,
            &["process.temperature", "given twice"],
        ),
        owned(
            "a key quoted and in a nested table",
            sweep(
                file(
                    "twice-table",
                    "\"process.blank_holder_force\" = [0.0]\n[parameters.process]\nblank_holder_force = [200.0]",
                ),
                &[],
            ),
            2,
            &["process.blank_holder_force", "given twice"],
        ),
    ];
    for (label, count) in [
        ("a count of 1e12", "1e12"),
        ("the largest count", "9223372036854775807"),
        ("a count over the cap", "1000001"),
        ("a negative count", "-3"),
        ("a count in text", "\"four\""),
    ] {
        cases.push(owned(
            &format!("range: {label}"),
            sweep(file(&format!("count-{label}"), &range(count)), &["--list"]),
            2,
            &["parameters.process.temperature.count", "1000000"],
        ));
    }
    let huge: String = [
        "temperature",
        "blank_holder_force",
        "stroke",
        "punch_speed",
        "target_time_step",
    ]
    .map(|key| format!("process.{key} = {{ from = 1.0, to = 2.0, count = 100000 }}\n"))
    .concat();
    cases.push(owned(
        "1e25 cases",
        sweep(file("huge", &huge), &["--list"]),
        2,
        &["1e25 cases", "parameters.process.stroke: 100000", "1000000"],
    ));
    cases.push(owned(
        "a million and one cases",
        sweep(
            file(
                "million-and-one",
                "process.temperature = { from = 280.0, to = 320.0, count = 1001 }\n\
                 process.stroke = { from = 0.5, to = 1.0, count = 1000 }",
            ),
            &[],
        ),
        2,
        &["1001000 cases", "parameters.process.temperature: 1001"],
    ));
    cases.push(owned(
        "a range with a step",
        sweep(
            file(
                "step",
                "process.temperature = { from = 280.0, to = 320.0, count = 3, step = 20.0 }",
            ),
            &[],
        ),
        2,
        &["parameters.process.temperature.step"],
    ));
    cases.push(owned(
        "a range from text",
        sweep(
            file(
                "from-text",
                "process.temperature = { from = \"hot\", to = 320.0, count = 3 }",
            ),
            &[],
        ),
        2,
        &["parameters.process.temperature.from", "hot"],
    ));
    let million = file(
        "a-million",
        "process.temperature = { from = 280.0, to = 320.0, count = 1000 }\n\
         process.blank_holder_force = { from = 0.0, to = 300.0, count = 1000 }",
    );
    cases.push(owned(
        "--case past a million cases",
        sweep(million, &["--case", "1000001"]),
        2,
        &["--case 1000001", "1 to 1000000"],
    ));
    cases.push(case(
        "--case 0",
        &[
            "sweep",
            &file("case-zero", "process.temperature = [300.0]"),
            "--case",
            "0",
        ],
        2,
        &["--case 0"],
    ));
    cases
}

#[test]
fn every_bad_file_or_study_is_refused_naming_its_source() {
    let fixtures = fixtures("table");
    let mut cases = link_cases(&fixtures);
    cases.extend(folder_cases(&fixtures));
    cases.extend(study_file_cases(&fixtures));
    assert_all_pass(&cases, 30);
}

/// A link in a result's place keeps its target's bytes and stays a link, for a run, a study's
/// summary and a study's case folder; a folder given through a link to an existing folder is
/// used as that folder.
#[test]
fn a_linked_result_keeps_its_targets_bytes() {
    let f = fixtures("bytes");
    let dir = fresh(&f, "bytes-run");
    let mine = users_file(&dir);
    symlink(&mine, dir.join("forming.csv")).unwrap();
    let args = run_into(&f, &dir);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    assert_eq!(thermostamp(&args).status.code(), Some(2));
    assert_eq!(std::fs::read_to_string(&mine).unwrap(), USERS_BYTES);
    assert!(dir.join("forming.csv").is_symlink());

    let dir = fresh(&f, "bytes-study");
    let mine = users_file(&dir);
    let theirs = dir.join("their-folder");
    std::fs::create_dir_all(&theirs).unwrap();
    std::fs::write(theirs.join("notes.txt"), USERS_BYTES).unwrap();
    let path = study(
        &f,
        "bytes-study",
        "process.temperature = [300.0]",
        &dir.join("out"),
    );
    assert_eq!(
        thermostamp(&["sweep", &path, "--summarise"]).status.code(),
        Some(1)
    );
    std::fs::remove_file(dir.join("out/summary.csv")).unwrap();
    symlink(&mine, dir.join("out/summary.csv")).unwrap();
    symlink(&theirs, dir.join("out/case-001")).unwrap();
    assert_eq!(thermostamp(&["sweep", &path]).status.code(), Some(2));
    assert_eq!(
        thermostamp(&["sweep", &path, "--summarise"]).status.code(),
        Some(2)
    );
    assert_eq!(std::fs::read_to_string(&mine).unwrap(), USERS_BYTES);
    assert_eq!(
        std::fs::read_dir(&theirs).unwrap().count(),
        1,
        "their folder was written"
    );
    assert_eq!(
        std::fs::read_to_string(theirs.join("notes.txt")).unwrap(),
        USERS_BYTES
    );

    let dir = fresh(&f, "bytes-drape");
    std::fs::create_dir_all(dir.join("elsewhere")).unwrap();
    symlink(dir.join("elsewhere"), dir.join("out")).unwrap();
    let scenario = f.file("example.toml", f.scenario.as_bytes());
    common::run_ok(&["drape", &scenario, "--output", &text(&dir.join("out"))]);
    assert!(dir.join("elsewhere/drape.csv").is_file());
}

/// Kills a process group when dropped, so that a failed assertion leaves no run behind.
struct Group(Child);

impl Drop for Group {
    fn drop(&mut self) {
        let _ = Command::new("kill")
            .args(["-9", "--", &format!("-{}", self.0.id())])
            .status();
        let _ = self.0.wait();
    }
}

/// `thermostamp sweep path extra...` in its own process group.
fn spawn_sweep(path: &str, extra: &[&str]) -> Group {
    use std::os::unix::process::CommandExt;
    Group(
        Command::new(env!("CARGO_BIN_EXE_thermostamp"))
            .arg("sweep")
            .arg(path)
            .args(extra)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .process_group(0)
            .spawn()
            .unwrap(),
    )
}

/// Waits until `file` exists (a case has started).
fn wait_for(file: &Path) {
    let deadline = Instant::now() + Duration::from_secs(120);
    while !file.exists() {
        assert!(Instant::now() < deadline, "{file:?} never came");
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// A study whose first case runs for minutes (the full stroke on 6 mm cells) and whose second
/// takes a second.
fn slow_study(f: &Fixtures, name: &str, out: &Path) -> String {
    study(
        f,
        name,
        "blank.element_size = [6.0]\nprocess.stroke = [30.0, 0.5]",
        out,
    )
}

/// Exit code 2 and a message holding every piece of `names`.
fn assert_refused(args: &[&str], names: &[&str]) {
    let out = thermostamp(args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
    for name in names {
        assert!(stderr.contains(name), "{args:?}: '{name}' not in: {stderr}");
    }
}

/// While a sweep runs, a second sweep of the same study into its folder is refused naming the
/// first, and so are `--case` and `--summarise`; once it is gone, another study into that
/// folder is refused naming the first study.
#[test]
fn two_sweeps_into_one_folder_the_second_is_refused() {
    let f = fixtures("two-sweeps");
    let dir = fresh(&f, "two-sweeps");
    let out = dir.join("out");
    let path = slow_study(&f, "two-sweeps", &out);
    let first = spawn_sweep(&path, &["--jobs", "1"]);
    wait_for(&out.join("case-001/run.log"));
    let holder = format!("is being written by another run (pid {},", first.0.id());
    assert_refused(&["sweep", &path], &[&text(&out), &holder, "sweep"]);
    assert_refused(&["sweep", &path, "--case", "2"], &[&text(&out), &holder]);
    assert_refused(&["sweep", &path, "--summarise"], &[&text(&out), &holder]);
    assert!(!out.join("case-002").exists(), "a second sweep ran case 2");
    drop(first);
    let other = study(
        &f,
        "two-sweeps-other",
        "process.temperature = [300.0]",
        &out,
    );
    assert_refused(&["sweep", &other], &[&text(&out), &path, "another study"]);
}

/// The same case run twice at once (a batch job started twice) is refused, naming the process
/// that runs it; another case of the study runs beside it; the summary waits for both.
#[test]
fn the_same_case_twice_at_once_is_refused() {
    let f = fixtures("same-case");
    let dir = fresh(&f, "same-case");
    let out = dir.join("out");
    let path = slow_study(&f, "same-case", &out);
    let first = spawn_sweep(&path, &["--case", "1"]);
    wait_for(&out.join("case-001/run.log"));
    assert_refused(
        &["sweep", &path, "--case", "1"],
        &[
            &text(&out.join("case-001")),
            &format!("pid {},", first.0.id()),
            "already running",
        ],
    );
    common::run_ok(&["sweep", &path, "--case", "2"]);
    assert_refused(
        &["sweep", &path, "--summarise"],
        &[&text(&out), "share it", "--case"],
    );
    assert_refused(&["sweep", &path], &[&text(&out), "share it"]);
}

/// Cases spread over processes in parallel (`--case`, two at a time), then `--summarise`,
/// give the full factorial's summary: every case done, each row the parameters of its place
/// in the factorial; `--summarise` before then exits 1, naming the cases not run, and still
/// writes the partial summary.
#[test]
fn parallel_cases_then_summarise_give_the_full_factorial() {
    let f = fixtures("parallel");
    let dir = fresh(&f, "parallel-cases");
    let out = dir.join("out");
    let path = study(
        &f,
        "parallel-cases",
        "process.temperature = [280.0, 320.0]\nprocess.blank_holder_force = [0.0, 200.0]",
        &out,
    );
    let worker = |cases: [&'static str; 2]| {
        let path = path.clone();
        std::thread::spawn(move || {
            for n in cases {
                let out = thermostamp(&["sweep", &path, "--case", n]);
                assert!(
                    out.status.success(),
                    "--case {n}: {}",
                    String::from_utf8_lossy(&out.stderr)
                );
            }
        })
    };
    let (a, b) = (worker(["1", "4"]), worker(["2", "3"]));
    a.join().unwrap();
    b.join().unwrap();
    std::fs::remove_dir_all(out.join("case-003")).unwrap();
    let partial = thermostamp(&["sweep", &path, "--summarise"]);
    let stderr = String::from_utf8_lossy(&partial.stderr);
    assert_eq!(partial.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("1 of 4 cases not run (cases 3)"),
        "{stderr}"
    );
    let summary = std::fs::read_to_string(out.join("summary.csv")).unwrap();
    assert_eq!(summary.matches(",not run,").count(), 1, "{summary}");

    common::run_ok(&["sweep", &path, "--case", "3"]);
    common::run_ok(&["sweep", &path, "--summarise"]);
    let summary = std::fs::read_to_string(out.join("summary.csv")).unwrap();
    let rows: Vec<Vec<&str>> = summary
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    let expected = [
        ["1", "280.0", "0.0"],
        ["2", "280.0", "200.0"],
        ["3", "320.0", "0.0"],
        ["4", "320.0", "200.0"],
    ];
    assert_eq!(rows.len(), 4, "{summary}");
    for (row, want) in rows.iter().zip(expected) {
        assert_eq!(row[..3], want, "{summary}");
        assert_eq!(row[3], "done", "{summary}");
        let scenario =
            std::fs::read_to_string(out.join(format!("case-00{}/scenario.toml", want[0]))).unwrap();
        assert!(
            scenario.contains(&format!("temperature = {}", want[1]))
                && scenario.contains(&format!("blank_holder_force = {}", want[2])),
            "case {}: {scenario}",
            want[0]
        );
    }
}

/// A study of a million cases lists its first cases at once: the cases are made as they are
/// listed, and only the first case's scenario is built before.
#[test]
fn a_million_cases_list_at_once() {
    let f = fixtures("million");
    let dir = fresh(&f, "million");
    let path = study(
        &f,
        "million",
        "process.temperature = { from = 280.0, to = 320.0, count = 100 }\n\
         process.blank_holder_force = { from = 0.0, to = 300.0, count = 100 }\n\
         process.friction.punch = [0.1, 0.15, 0.2, 0.25, 0.3, 0.35, 0.4, 0.45, 0.5, 0.55] \n\
         process.friction.die = [0.1, 0.15, 0.2, 0.25, 0.3, 0.35, 0.4, 0.45, 0.5, 0.55]",
        &dir.join("out"),
    );
    let start = Instant::now();
    let mut child = Command::new(env!("CARGO_BIN_EXE_thermostamp"))
        .args(["sweep", &path, "--list"])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let lines: Vec<String> = std::io::BufReader::new(child.stdout.take().unwrap())
        .lines()
        .take(3)
        .map(Result::unwrap)
        .collect();
    let elapsed = start.elapsed();
    let _ = child.kill();
    let _ = child.wait();
    assert!(
        lines[0]
            .trim_start()
            .starts_with("1  process.temperature = 280.0"),
        "{lines:?}"
    );
    assert!(
        lines[2].contains("process.friction.die = 0.2  not run"),
        "{lines:?}"
    );
    assert!(elapsed < Duration::from_secs(10), "took {elapsed:?}");
}

/// A study file named without a folder (`thermostamp sweep study.toml` in its own folder) is
/// read from the folder the sweep runs in.
#[test]
fn a_study_file_named_without_a_folder_is_read() {
    let f = fixtures("bare");
    let dir = fresh(&f, "bare-name");
    let text = format!(
        "base = \"{}\"\n[parameters]\nprocess.temperature = [300.0]\n",
        quick_base(&f)
    );
    std::fs::write(dir.join("bare.toml"), text).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_thermostamp"))
        .args(["sweep", "bare.toml", "--list"])
        .current_dir(&dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stdout).contains("not run"));
}
