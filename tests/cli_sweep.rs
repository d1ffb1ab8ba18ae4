//! `thermostamp sweep` as a user runs it (issue 17): every case of the full factorial in its
//! own folder with its own scenario, a summary and charts; a sweep killed part-way resumes to
//! the same summary; a failing case is recorded with its reason and the others still run;
//! `--case N` on two processes gives the same summary as one sweep; bad study files are
//! refused before any case runs. The cases are the hemisphere example on 10 mm cells over 3 mm
//! of stroke (about a second each).

mod common;

use common::{repo_path, scratch_dir, thermostamp};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// A study file `study.toml` in `dir` on `base` (a repository path) with the `parameters`
/// lines, writing to `dir/out` (the sweeps run in the repository's folder).
fn study(dir: &Path, base: &str, parameters: &str) -> PathBuf {
    let text = format!(
        "base = \"{}\"\n[parameters]\nblank.element_size = [10.0]\nprocess.stroke = [3.0]\n\
         output.frames = [0]\n{parameters}\n[output]\nfolder = \"{}\"\n",
        repo_path(base).display(),
        dir.join("out").display()
    );
    let path = dir.join("study.toml");
    std::fs::write(&path, text).unwrap();
    path
}

const TWO_BY_TWO: &str =
    "process.temperature = [280.0, 320.0]\nprocess.blank_holder_force = [0.0, 200.0]";

/// The summary's rows without the wall time (the last column), which no two runs share.
fn summary_without_times(dir: &Path) -> Vec<String> {
    std::fs::read_to_string(dir.join("out/summary.csv"))
        .unwrap()
        .lines()
        .map(|l| l.rsplit_once(',').unwrap().0.to_string())
        .collect()
}

/// The value of column `name` in every row of the summary.
fn column(dir: &Path, name: &str) -> Vec<String> {
    let text = std::fs::read_to_string(dir.join("out/summary.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let i = header.iter().position(|h| *h == name).unwrap();
    lines
        .map(|l| l.split(',').nth(i).unwrap().to_string())
        .collect()
}

fn sweep(study: &Path, extra: &[&str]) -> std::process::Output {
    let mut args = vec!["sweep", study.to_str().unwrap()];
    args.extend_from_slice(extra);
    thermostamp(&args)
}

/// Four cases, all done; each case folder holds its scenario, which runs by itself to the same
/// result; at each temperature the waviness falls as the holder force rises; the heat maps are
/// written; `--list` says every case is done.
#[test]
fn a_sweep_runs_every_case_and_summarises_them() {
    let dir = scratch_dir("sweep", "full");
    let _ = std::fs::remove_dir_all(dir.join("out"));
    let path = study(&dir, "examples/hemisphere.toml", TWO_BY_TWO);
    let out = sweep(&path, &[]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("[4/4]"), "{stderr}");
    assert_eq!(column(&dir, "status"), vec!["done"; 4]);
    let waviness: Vec<f64> = column(&dir, "waviness")
        .iter()
        .map(|v| v.parse().unwrap())
        .collect();
    // cases 1, 2: 280 °C at 0 and 200 N; cases 3, 4: 320 °C
    assert!(
        waviness[0] > waviness[1] && waviness[2] > waviness[3],
        "{waviness:?}"
    );
    for png in ["study-waviness.png", "study-max-shear.png"] {
        assert!(std::fs::metadata(dir.join("out").join(png)).unwrap().len() > 1000);
    }
    let case = dir.join("out/case-003");
    let again = dir.join("again");
    let _ = std::fs::remove_dir_all(&again);
    common::run_ok(&[
        "run",
        case.join("scenario.toml").to_str().unwrap(),
        "--threads",
        "1",
        "--output",
        again.to_str().unwrap(),
    ]);
    let measures = |folder: &Path| {
        let text = std::fs::read_to_string(folder.join("forming-result.csv")).unwrap();
        text.lines().nth(1).unwrap().to_string()
    };
    assert_eq!(measures(&case), measures(&again));
    let list = String::from_utf8_lossy(&sweep(&path, &["--list"]).stdout).to_string();
    assert_eq!(
        list.lines().filter(|l| l.ends_with("done")).count(),
        4,
        "{list}"
    );
}

/// A sweep killed with SIGKILL (the sweep and its running case) after its first case resumes:
/// finished cases are kept, the half-written one runs again, and the summary is that of a sweep
/// never interrupted.
#[test]
fn a_killed_sweep_resumes_to_the_same_summary() {
    use std::os::unix::process::CommandExt;
    let whole = scratch_dir("sweep", "uninterrupted");
    let _ = std::fs::remove_dir_all(whole.join("out"));
    let reference = study(&whole, "examples/hemisphere.toml", TWO_BY_TWO);
    assert!(sweep(&reference, &["--jobs", "1"]).status.success());

    let dir = scratch_dir("sweep", "killed");
    let _ = std::fs::remove_dir_all(dir.join("out"));
    let path = study(&dir, "examples/hemisphere.toml", TWO_BY_TWO);
    let mut child = Command::new(env!("CARGO_BIN_EXE_thermostamp"))
        .args(["sweep", path.to_str().unwrap(), "--jobs", "1"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .process_group(0)
        .spawn()
        .unwrap();
    let first = dir.join("out/case-001/case-result.toml");
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(120);
    while !first.exists() && std::time::Instant::now() < deadline {
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    assert!(first.exists(), "the first case did not finish");
    let group = format!("-{}", child.id());
    let killed = Command::new("kill")
        .args(["-9", "--", &group])
        .status()
        .unwrap();
    assert!(killed.success());
    let _ = child.wait();
    let unfinished = (1..=4)
        .filter(|n| {
            !dir.join(format!("out/case-{n:03}/case-result.toml"))
                .exists()
        })
        .count();
    assert!(unfinished > 0, "killed too late: every case had finished");

    let out = sweep(&path, &["--jobs", "1"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(summary_without_times(&dir), summary_without_times(&whole));
}

/// A case that its run refuses (a punch so fast that the explicit solver would cover the stroke
/// in a few steps) is recorded as failed with the run's reason; the other case is done; the
/// sweep says how many failed and exits 1.
#[test]
fn a_failing_case_is_recorded_and_the_sweep_goes_on() {
    let dir = scratch_dir("sweep", "failing");
    let _ = std::fs::remove_dir_all(dir.join("out"));
    let path = study(
        &dir,
        "tests/data/hemisphere-explicit.toml",
        "process.punch_speed = [10.0, 2000.0]",
    );
    let out = sweep(&path, &[]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("1 of 2 cases failed"), "{stderr}");
    assert_eq!(column(&dir, "status"), vec!["done", "failed"]);
    let summary = std::fs::read_to_string(dir.join("out/summary.csv")).unwrap();
    let failed = summary.lines().nth(2).unwrap();
    assert!(failed.contains("process.punch_speed"), "{failed}");
}

/// `--case N` run by two processes side by side, then `--summarise`, gives the summary of one
/// sweep; `--case` out of range is refused.
#[test]
fn cases_spread_over_two_processes_give_the_same_summary() {
    let one = scratch_dir("sweep", "one-process");
    let _ = std::fs::remove_dir_all(one.join("out"));
    let reference = study(&one, "examples/hemisphere.toml", TWO_BY_TWO);
    assert!(sweep(&reference, &[]).status.success());

    let dir = scratch_dir("sweep", "two-processes");
    let _ = std::fs::remove_dir_all(dir.join("out"));
    let path = study(&dir, "examples/hemisphere.toml", TWO_BY_TWO);
    let list = String::from_utf8_lossy(&sweep(&path, &["--list"]).stdout).to_string();
    assert_eq!(
        list.lines().filter(|l| l.ends_with("not run")).count(),
        4,
        "{list}"
    );
    let worker = |cases: [&'static str; 2]| {
        let path = path.clone();
        std::thread::spawn(move || {
            for n in cases {
                let out = sweep(&path, &["--case", n]);
                assert!(
                    out.status.success(),
                    "{}",
                    String::from_utf8_lossy(&out.stderr)
                );
            }
        })
    };
    let (a, b) = (worker(["1", "3"]), worker(["2", "4"]));
    a.join().unwrap();
    b.join().unwrap();
    assert!(sweep(&path, &["--summarise"]).status.success());
    assert_eq!(summary_without_times(&dir), summary_without_times(&one));
    let out = sweep(&path, &["--case", "5"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--case 5"));
}

/// Bad study files: exit code 2, one line naming the key and the value, and no case run.
#[test]
fn bad_study_files_are_refused_before_any_case_runs() {
    let dir = scratch_dir("sweep", "bad");
    let cases: [(&str, &str, &[&str]); 6] = [
        ("process.temprature = [300.0]", "", &["temprature"]),
        (
            "process.temperature = []",
            "",
            &["process.temperature", "at least one value"],
        ),
        (
            "process.blank_holder_force = [0.0, -5.0]",
            "",
            &["blank_holder_force", "-5"],
        ),
        (
            "process.temperature = [300.0, 400.0]",
            "",
            &["process.temperature", "400"],
        ),
        (
            "process.temperature = { from = 280.0, to = 320.0 }",
            "",
            &["process.temperature", "count"],
        ),
        (
            "process.temperature = [300.0]",
            "colour = \"red\"\n",
            &["colour"],
        ),
    ];
    for (parameters, extra, expected) in cases {
        let _ = std::fs::remove_dir_all(dir.join("out"));
        let path = study(&dir, "examples/hemisphere.toml", parameters);
        let text = std::fs::read_to_string(&path).unwrap();
        std::fs::write(&path, format!("{extra}{text}")).unwrap();
        let out = sweep(&path, &[]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{parameters}: {stderr}");
        assert_eq!(stderr.trim().lines().count(), 1, "{parameters}: {stderr}");
        for e in expected {
            assert!(stderr.contains(e), "{parameters}: {stderr}");
        }
        assert!(!dir.join("out").exists(), "{parameters}: a case ran");
    }
    let missing = dir.join("missing-base.toml");
    std::fs::write(
        &missing,
        "base = \"nowhere.toml\"\n[parameters]\nprocess.stroke = [3.0]\n",
    )
    .unwrap();
    let out = sweep(&missing, &[]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("nowhere.toml"), "{stderr}");
}

/// The tutorial `examples/study-temperature-bhf.toml` in a reduced form (10 mm cells, 5 mm of
/// stroke, into a scratch folder): its 12 cases run, and at every temperature the holder keeps
/// the flange flatter than no holder does.
#[test]
fn the_example_study_runs_in_reduced_form() {
    let dir = scratch_dir("sweep", "example");
    let _ = std::fs::remove_dir_all(dir.join("out"));
    let text = std::fs::read_to_string(repo_path("examples/study-temperature-bhf.toml")).unwrap();
    let base = repo_path("examples/double-dome.toml");
    let reduced = text
        .replace(
            "base = \"double-dome.toml\"",
            &format!("base = \"{}\"", base.display()),
        )
        .replace(
            "blank.element_size = [8.0]",
            "blank.element_size = [10.0]\nprocess.stroke = [5.0]",
        )
        .replace(
            "folder = \"study-temperature-bhf-results\"",
            &format!("folder = \"{}\"", dir.join("out").display()),
        );
    assert_ne!(reduced, text);
    let path = dir.join("study.toml");
    std::fs::write(&path, reduced).unwrap();
    let out = sweep(&path, &[]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(column(&dir, "status"), vec!["done"; 12]);
    let waviness: Vec<f64> = column(&dir, "waviness")
        .iter()
        .map(|v| v.parse().unwrap())
        .collect();
    for t in 0..3 {
        let (none, most) = (waviness[4 * t], waviness[4 * t + 3]);
        assert!(none > most, "temperature #{t}: {waviness:?}");
    }
}

/// The tutorial `examples/study-tool-temperature-transfer.toml` in a reduced form (two tool
/// temperatures, one transfer time, 3 mm of stroke): both cases run, the summary
/// carries the stack's temperatures, the colder tools leave it colder, and the peak-force chart
/// is written.
#[test]
fn the_thermal_example_study_runs_in_reduced_form() {
    let dir = scratch_dir("sweep", "thermal-example");
    let _ = std::fs::remove_dir_all(dir.join("out"));
    let text = std::fs::read_to_string(repo_path("examples/study-tool-temperature-transfer.toml"))
        .unwrap();
    let base = repo_path("examples/double-dome-nonisothermal.toml");
    let reduced = text
        .replace(
            "base = \"double-dome-nonisothermal.toml\"",
            &format!("base = \"{}\"", base.display()),
        )
        .replace(
            "tools.temperature = [150.0, 190.0, 230.0]",
            "tools.temperature = [170.0, 230.0]",
        )
        .replace(
            "process.transfer_time = [2.0, 5.0, 10.0]",
            "process.transfer_time = [2.0]",
        )
        .replace("process.stroke = [20.0]", "process.stroke = [3.0]")
        .replace(
            "folder = \"study-tool-temperature-transfer-results\"",
            &format!("folder = \"{}\"", dir.join("out").display()),
        );
    let path = dir.join("study.toml");
    std::fs::write(&path, reduced).unwrap();
    let out = sweep(&path, &[]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(column(&dir, "status"), vec!["done"; 2]);
    let coldest: Vec<f64> = column(&dir, "temperature_min")
        .iter()
        .map(|v| v.parse().unwrap())
        .collect();
    assert!(coldest[0] < coldest[1], "tools 170 and 230 °C: {coldest:?}");
    assert!(dir.join("out/study-peak-force.png").exists());
}

/// `study.toml` in `dir` with a `[design]` section before the parameters of [`study`].
fn designed_study(dir: &Path, design: &str, parameters: &str) -> PathBuf {
    let path = study(dir, "examples/hemisphere.toml", parameters);
    let text = std::fs::read_to_string(&path).unwrap();
    let text = text.replace("[parameters]", &format!("[design]\n{design}\n[parameters]"));
    std::fs::write(&path, text).unwrap();
    path
}

const TWO_RANGES: &str = "process.temperature = { from = 280.0, to = 320.0 }\n\
                          process.blank_holder_force = { from = 0.0, to = 200.0 }";

/// The lines `--list` prints, which must succeed.
fn listed(study: &Path) -> Vec<String> {
    let out = sweep(study, &["--list"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(String::from)
        .collect()
}

/// The value of `key` on a `--list` line (`key = value, ...`).
fn listed_value(line: &str, key: &str) -> f64 {
    let start = line.find(&format!("{key} = ")).unwrap() + key.len() + 3;
    line[start..]
        .split([',', ' '])
        .next()
        .unwrap()
        .parse()
        .unwrap()
}

/// A sampled design lists `samples` cases, each value within its range (a list's values from
/// the list); the same seed lists the same cases again, another seed other ones, and so does
/// the other method.
#[test]
fn sampled_designs_list_reproducible_cases() {
    let dir = scratch_dir("sweep", "designs-list");
    let _ = std::fs::remove_dir_all(dir.join("out"));
    let parameters = format!("{TWO_RANGES}\nprocess.punch_speed = [5.0, 10.0]");
    let list_of = |design: &str| listed(&designed_study(&dir, design, &parameters));
    let lhs = list_of("method = \"latin-hypercube\"\nsamples = 6\nseed = 7");
    assert_eq!(lhs.len(), 6, "{lhs:?}");
    for line in &lhs {
        assert!(line.ends_with("not run"), "{line}");
        let t = listed_value(line, "process.temperature");
        let f = listed_value(line, "process.blank_holder_force");
        let speed = listed_value(line, "process.punch_speed");
        assert!(
            (280.0..=320.0).contains(&t) && (0.0..=200.0).contains(&f),
            "{line}"
        );
        assert!(speed == 5.0 || speed == 10.0, "{line}");
    }
    assert_eq!(
        lhs,
        list_of("method = \"latin-hypercube\"\nsamples = 6\nseed = 7")
    );
    assert_ne!(
        lhs,
        list_of("method = \"latin-hypercube\"\nsamples = 6\nseed = 8")
    );
    let sobol = list_of("method = \"sobol\"\nsamples = 6\nseed = 7");
    assert_eq!(sobol.len(), 6);
    assert_ne!(lhs, sobol);
}

/// Designs a study cannot run: exit code 2, one line naming the key and saying why, no case.
#[test]
fn bad_designs_are_refused_naming_the_key() {
    let dir = scratch_dir("sweep", "designs-bad");
    let counted = "process.temperature = { from = 280.0, to = 320.0, count = 3 }";
    let cases: [(&str, &str, &[&str]); 6] = [
        (
            "method = \"latin-hypercube\"\nsamples = 4",
            counted,
            &["parameters.process.temperature.count", "no count"],
        ),
        (
            "method = \"latin-hypercube\"",
            TWO_RANGES,
            &["design.samples is missing"],
        ),
        (
            "method = \"sobol\"\nsamples = 0",
            TWO_RANGES,
            &["design.samples = 0", "from 1 to 1000000"],
        ),
        (
            "samples = 4",
            counted,
            &["design.samples", "full-factorial"],
        ),
        (
            "method = \"full-factorial\"\nseed = 4",
            counted,
            &["design.seed", "full-factorial"],
        ),
        (
            "method = \"monte-carlo\"\nsamples = 4",
            TWO_RANGES,
            &["design.method = \"monte-carlo\"", "latin-hypercube"],
        ),
    ];
    for (design, parameters, expected) in cases {
        let _ = std::fs::remove_dir_all(dir.join("out"));
        let path = designed_study(&dir, design, parameters);
        for extra in [&[][..], &["--list"]] {
            let out = sweep(&path, extra);
            let stderr = String::from_utf8_lossy(&out.stderr);
            assert_eq!(out.status.code(), Some(2), "{design}: {stderr}");
            assert_eq!(stderr.trim().lines().count(), 1, "{design}: {stderr}");
            for e in expected {
                assert!(stderr.contains(e), "{design}: {stderr}");
            }
        }
        assert!(!dir.join("out").exists(), "{design}: a case ran");
    }
}

/// Three Latin-hypercube cases run: the summary holds the listed values, every case done, and
/// the scatter charts; `--list` of the same study then lists them done (a list after the
/// ranges, which TOML writes before tables, keeps its place in the folder's record), and the
/// same folder refuses the study with another seed as another study.
#[test]
fn a_sampled_sweep_runs_its_cases_and_charts_them() {
    let dir = scratch_dir("sweep", "designs-run");
    let _ = std::fs::remove_dir_all(dir.join("out"));
    // the ply at 0°, as in the example: a list after the ranges
    let parameters = format!("{TWO_RANGES}\nblank.ply_angle = [0.0]");
    let path = designed_study(
        &dir,
        "method = \"latin-hypercube\"\nsamples = 3\nseed = 11",
        &parameters,
    );
    let list = listed(&path);
    let out = sweep(&path, &[]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(column(&dir, "status"), vec!["done"; 3]);
    let summary: Vec<f64> = column(&dir, "process.temperature")
        .iter()
        .map(|v| v.parse().unwrap())
        .collect();
    let in_list: Vec<f64> = list
        .iter()
        .map(|l| listed_value(l, "process.temperature"))
        .collect();
    assert_eq!(summary, in_list);
    for png in ["study-waviness.png", "study-max-shear.png"] {
        assert!(std::fs::metadata(dir.join("out").join(png)).unwrap().len() > 1000);
    }
    let again = listed(&path);
    assert!(again.iter().all(|l| l.ends_with("done")), "{again:?}");
    let text = std::fs::read_to_string(&path).unwrap();
    std::fs::write(&path, text.replace("seed = 11", "seed = 12")).unwrap();
    let out = sweep(&path, &["--list"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("another study") && stderr.contains("design differs"),
        "{stderr}"
    );
}

/// `--emit slurm` prints a script that bash parses, with an array of one task per case that
/// `--list` lists, at most K (`--throttle`, default 32) at once; it runs nothing.
#[test]
fn emit_slurm_prints_a_job_array_of_the_cases() {
    let dir = scratch_dir("sweep", "emit");
    let _ = std::fs::remove_dir_all(dir.join("out"));
    let path = study(&dir, "examples/hemisphere.toml", TWO_BY_TWO);
    let cases = listed(&path).len();
    let script = |extra: &[&str]| {
        let mut args = vec!["--emit", "slurm"];
        args.extend_from_slice(extra);
        let out = sweep(&path, &args);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8(out.stdout).unwrap()
    };
    let text = script(&["--throttle", "3"]);
    assert!(text.starts_with("#!/bin/bash\n"), "{text}");
    assert!(
        text.contains(&format!("\n#SBATCH --array=1-{cases}%3\n")),
        "{text}"
    );
    assert!(text.contains("\n#SBATCH --job-name=study\n"), "{text}");
    assert!(text.contains("\n#SBATCH --cpus-per-task=1\n"), "{text}");
    assert!(text.contains("--case \"$SLURM_ARRAY_TASK_ID\"\n"), "{text}");
    assert!(
        text.contains("sbatch --dependency=afterany:") && text.contains("--summarise"),
        "{text}"
    );
    bash_parses(&dir, &text);
    // the default throttle, 32, is capped at the 4 cases
    assert!(script(&[]).contains(&format!("\n#SBATCH --array=1-{cases}%{cases}\n")));
    assert!(!dir.join("out").exists(), "--emit ran something");
    for (extra, expected) in [
        (&["--emit", "pbs"][..], "pbs"),
        (&["--emit", "slurm", "--case", "1"], "--case"),
        (&["--emit", "slurm", "--list"], "--list"),
        (&["--emit", "slurm", "--summarise"], "--summarise"),
        (&["--emit", "slurm", "--throttle", "0"], "--throttle"),
        (&["--throttle", "4"], "--emit"),
    ] {
        let out = sweep(&path, extra);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{extra:?}: {stderr}");
        assert!(stderr.contains(expected), "{extra:?}: {stderr}");
    }
}

/// `bash -n` accepts `script`.
fn bash_parses(dir: &Path, script: &str) {
    let file = dir.join("emitted.sh");
    std::fs::write(&file, script).unwrap();
    let out = Command::new("bash").arg("-n").arg(&file).output().unwrap();
    assert!(
        out.status.success(),
        "{}\n{script}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// A study in a folder whose name holds a space and a quote, emitted from that folder: the
/// script parses, and its last lines, run by bash with `exec` standing in for the run (it
/// prints the folder it is in and its arguments), reach that folder with the executable, the
/// study's path and the array task's number intact; the log goes into the study's folder.
#[test]
fn emit_slurm_quotes_paths_with_spaces_and_quotes() {
    let dir = scratch_dir("sweep", "it's a \"study\" $HOME");
    let _ = std::fs::remove_dir_all(dir.join("out"));
    let path = study(&dir, "examples/hemisphere.toml", TWO_BY_TWO);
    let text = std::fs::read_to_string(&path).unwrap();
    let folder_line = text.lines().find(|l| l.starts_with("folder = ")).unwrap();
    std::fs::write(&path, text.replace(folder_line, "folder = \"out\"")).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_thermostamp"))
        .args(["sweep", "study.toml", "--emit", "slurm"])
        .current_dir(&dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let script = String::from_utf8(out.stdout).unwrap();
    bash_parses(&dir, &script);
    let ran = Command::new("bash")
        .arg("-c")
        .arg("exec() { printf '%s\\n' \"$PWD\" \"$@\"; exit 0; }; . \"$0\"")
        .arg(dir.join("emitted.sh"))
        .env("SLURM_ARRAY_TASK_ID", "3")
        .current_dir(std::env::temp_dir())
        .output()
        .unwrap();
    assert!(
        ran.status.success(),
        "{}",
        String::from_utf8_lossy(&ran.stderr)
    );
    let printed = String::from_utf8(ran.stdout).unwrap();
    let lines: Vec<&str> = printed.lines().collect();
    let exe = std::fs::canonicalize(env!("CARGO_BIN_EXE_thermostamp")).unwrap();
    assert_eq!(lines.len(), 6, "{printed}");
    assert_eq!(Path::new(lines[0]), dir, "{printed}");
    assert_eq!(std::fs::canonicalize(lines[1]).unwrap(), exe, "{printed}");
    assert_eq!(
        &lines[2..],
        ["sweep", path.to_str().unwrap(), "--case", "3"]
    );
    let output = format!(
        "#SBATCH --output=\"{}/slurm-%A_%a.log\"",
        dir.join("out").display().to_string().replace('"', "\\\"")
    );
    assert!(script.lines().any(|l| l == output), "{output}\n{script}");
}
