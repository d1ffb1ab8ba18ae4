//! Running a study's cases (docs/study.md): each case is `thermostamp run` of its own scenario
//! file in its own folder, a child process whose output goes to the folder's `run.log`
//! ([`run_case`]); another front end (one that forms in its own process) gives its own way of
//! running the scenario to [`run_case_with`] and keeps the same folders and records. When
//! it ends, the case's outcome is written to `case-result.toml` in one step (written aside,
//! then renamed): a folder with that file is a finished case and is not run again; a folder
//! without it (a sweep killed part-way) is cleared and its case run again from the start.
//! While a case runs, its process holds the case's lock, so that the same case is never run
//! by two processes at once (a batch scheduler that starts a job twice).

use super::file::{Case, Study};
use crate::io::output_folder::{lock_folder, FolderError, Hold, LOCK_FILE};
use crate::io::product_file;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Instant;

/// The file that marks a finished case.
pub const CASE_RESULT: &str = "case-result.toml";
/// The case's scenario, as it ran.
pub const CASE_SCENARIO: &str = "scenario.toml";
/// Standard output and error of the case's run.
pub const CASE_LOG: &str = "run.log";
/// The lock a case's process holds while the case runs (the run inside it holds the folder's
/// own [`LOCK_FILE`]).
pub const CASE_LOCK: &str = ".thermostamp-case.lock";

/// How a finished case ended.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CaseResult {
    /// `done` or `failed`.
    pub status: String,
    /// Why it failed (the run's last line on standard error); empty when done.
    pub reason: String,
    pub wall_seconds: f64,
}

impl CaseResult {
    pub fn done(&self) -> bool {
        self.status == "done"
    }
}

/// The result of a finished case, `None` for a case that has not finished (never started, or
/// stopped part-way).
pub fn finished(folder: &Path) -> Option<CaseResult> {
    let text = std::fs::read_to_string(folder.join(CASE_RESULT)).ok()?;
    toml::from_str(&text).ok()
}

/// What a case's run is given: the case's scenario file (written, standalone), the folder its
/// results go to (the case's own, cleared, its lock held), the threads it may use, and its log
/// file (created empty; the runner writes the run's output into it).
#[derive(Clone, Debug, PartialEq)]
pub struct CaseRun {
    pub scenario: PathBuf,
    pub folder: PathBuf,
    pub threads: usize,
    pub log: PathBuf,
}

/// How a case's run ended: whether it succeeded, its standard-error text (the failure reason is
/// its last error or warning line) and its exit code, if it had one (`None`: killed by a
/// signal, or a run in the same process).
#[derive(Clone, Debug, PartialEq)]
pub struct RunEnd {
    pub success: bool,
    pub stderr: String,
    pub exit_code: Option<i32>,
}

/// A way of running a case's scenario: an error is a run that could not even be started (it
/// ends the sweep), not a run that failed (a [`RunEnd`] without success, recorded).
pub type CaseRunner<'a> = dyn Fn(&CaseRun) -> anyhow::Result<RunEnd> + Sync + 'a;

/// The cases without a result, in order.
pub fn unfinished(study: &Study) -> Vec<usize> {
    if !study.folder.exists() {
        return (1..=study.cases_count()).collect();
    }
    (1..=study.cases_count())
        .filter(|&n| finished(&study.case_folder(n)).is_none())
        .collect()
}

/// How case `number` stands, as `sweep --list` shows it: `done`, `failed: <reason>`, `not
/// finished` (a folder without a result: stopped part-way, or running) or `not run`;
/// `folder_exists` is whether the study's folder exists (looked at once for all cases).
pub fn case_status(study: &Study, number: usize, folder_exists: bool) -> String {
    let folder = study.case_folder(number);
    match folder_exists.then(|| finished(&folder)).flatten() {
        Some(r) if r.done() => "done".to_string(),
        Some(r) => format!("failed: {}", r.reason),
        None if folder_exists && folder.exists() => "not finished".into(),
        None => "not run".into(),
    }
}

/// Runs `case` from the start in its folder with `exe run` (the thermostamp executable) on
/// the study's threads per case, and records how it ended; `command` is the command line the
/// case's lock records. Errors: the case is being run by another process, its folder is a
/// symbolic link or cannot be written, the executable cannot be started.
pub fn run_case(
    study: &Study,
    case: &Case,
    exe: &Path,
    command: &str,
) -> anyhow::Result<CaseResult> {
    run_case_with(study, case, command, &|run: &CaseRun| spawn_run(exe, run))
}

/// Runs `run.scenario` as a child process `exe run SCENARIO --output FOLDER --threads T`: its
/// standard output into the log as it comes, then its standard error appended.
pub fn spawn_run(exe: &Path, run: &CaseRun) -> anyhow::Result<RunEnd> {
    let log = product_file::append(&run.log).map_err(|e| cannot_write(&run.log, e))?;
    let output = Command::new(exe)
        .arg("run")
        .arg(&run.scenario)
        .arg("--output")
        .arg(&run.folder)
        .arg("--threads")
        .arg(run.threads.to_string())
        .stdout(log)
        .stderr(Stdio::piped())
        .output()
        .map_err(|e| anyhow::anyhow!("cannot start {}: {e}", exe.display()))?;
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    product_file::append(&run.log)
        .and_then(|mut f| std::io::Write::write_all(&mut f, stderr.as_bytes()))
        .map_err(|e| cannot_write(&run.log, e))?;
    Ok(RunEnd {
        success: output.status.success(),
        stderr,
        exit_code: output.status.code(),
    })
}

/// Runs `case` from the start in its folder with `run` and records how it ended: takes the
/// case's lock (`command` is the command line it records), clears what an unfinished try
/// left, writes the case's standalone `scenario.toml` and an empty `run.log`, calls `run`, and
/// writes `case-result.toml` in one step. Errors: the case is being run by another process,
/// its folder is a symbolic link or cannot be written, `run` could not start the run.
pub fn run_case_with(
    study: &Study,
    case: &Case,
    command: &str,
    run: &CaseRunner,
) -> anyhow::Result<CaseResult> {
    let folder = study.case_folder(case.number);
    if let Some(link) = product_file::link_at(&folder) {
        anyhow::bail!("{}: {link}", folder.display());
    }
    let _lock = lock_folder(&folder, CASE_LOCK, Hold::Whole, command).map_err(|e| match e {
        FolderError::Busy { folder, holder } => anyhow::anyhow!(
            "{} is being written by {holder}: the case is already running; wait for it to end",
            folder.display()
        ),
        other => other.into(),
    })?;
    clear_case_folder(&folder)?;
    let scenario = folder.join(CASE_SCENARIO);
    let text = crate::forming::Scenario::standalone_text(&study.base, &study.overrides(case))?;
    let header = format!(
        "# Case {} of the study {}: {} on {}\n",
        case.number,
        study.origin,
        study.describe(case),
        study.base.display()
    );
    write(&scenario, &format!("{header}{text}"))?;
    let log = folder.join(CASE_LOG);
    product_file::create(&log).map_err(|e| cannot_write(&log, e))?;
    let start = Instant::now();
    let end = run(&CaseRun {
        scenario,
        folder: folder.clone(),
        threads: study.threads_per_case,
        log,
    })?;
    let result = CaseResult {
        status: if end.success { "done" } else { "failed" }.into(),
        reason: if end.success {
            String::new()
        } else {
            failure_reason(&end.stderr, end.exit_code)
        },
        wall_seconds: start.elapsed().as_secs_f64(),
    };
    let path = folder.join(CASE_RESULT);
    product_file::replace(&path, toml::to_string(&result)?.as_bytes())
        .map_err(|e| cannot_write(&path, e))?;
    Ok(result)
}

/// Removes what an earlier, unfinished try of the case left in its folder (the folder is the
/// case's own), all but the locks: the case's, held by this process, and the run's, which a
/// run still writing there (left over from a killed sweep) holds and so refuses the new one.
fn clear_case_folder(folder: &Path) -> anyhow::Result<()> {
    let entries = std::fs::read_dir(folder)
        .map_err(|e| anyhow::anyhow!("cannot list {}: {e}", folder.display()))?;
    for entry in entries.flatten() {
        if [CASE_LOCK, LOCK_FILE]
            .map(std::ffi::OsStr::new)
            .contains(&entry.file_name().as_os_str())
        {
            continue;
        }
        let path = entry.path();
        let removed = if entry.file_type().is_ok_and(|t| t.is_dir()) {
            std::fs::remove_dir_all(&path)
        } else {
            std::fs::remove_file(&path)
        };
        removed.map_err(|e| anyhow::anyhow!("cannot clear {}: {e}", path.display()))?;
    }
    Ok(())
}

fn cannot_write(path: &Path, e: std::io::Error) -> anyhow::Error {
    anyhow::anyhow!("cannot write {}: {e}", path.display())
}

/// The last line of a failed run's standard error that says what went wrong (a warning or the
/// error), or its exit code.
fn failure_reason(stderr: &str, code: Option<i32>) -> String {
    stderr
        .lines()
        .rev()
        .map(str::trim)
        .find(|l| l.starts_with("error") || l.starts_with("warning"))
        .map(String::from)
        .unwrap_or_else(|| match code {
            Some(c) => format!("exit code {c}"),
            None => "killed by a signal".into(),
        })
}

fn write(path: &Path, text: &str) -> anyhow::Result<()> {
    product_file::write(path, text.as_bytes()).map_err(|e| cannot_write(path, e))
}

/// One finished case, as the sweep reports it.
pub struct Finished<'a> {
    pub case: &'a Case,
    pub result: CaseResult,
    /// Cases finished so far in this sweep, and to run in it.
    pub count: usize,
    pub of: usize,
    /// Seconds since the sweep began.
    pub elapsed: f64,
}

/// Runs the cases numbered `numbers` with `exe run` on `jobs` cases at a time ([`run_case`]),
/// calling `report` as each one finishes; see [`run_cases_with`].
pub fn run_cases(
    study: &Study,
    numbers: &[usize],
    jobs: usize,
    exe: &Path,
    command: &str,
    report: &(dyn Fn(Finished) + Sync),
) -> anyhow::Result<Vec<(usize, CaseResult)>> {
    let spawn = |run: &CaseRun| spawn_run(exe, run);
    run_cases_with(study, numbers, jobs, command, &spawn, report)
}

/// Runs the cases numbered `numbers` with `run` ([`run_case_with`]) on `jobs` cases at a
/// time, calling `report` as each one finishes (in the order they finish); `command` is the
/// command line their locks record. A case that cannot even be started is an error that ends
/// the sweep after the running cases.
pub fn run_cases_with(
    study: &Study,
    numbers: &[usize],
    jobs: usize,
    command: &str,
    run: &CaseRunner,
    report: &(dyn Fn(Finished) + Sync),
) -> anyhow::Result<Vec<(usize, CaseResult)>> {
    /// The cases finished so far, and the first case that could not be run.
    struct Progress {
        done: Vec<(usize, CaseResult)>,
        error: Option<String>,
    }
    let next = AtomicUsize::new(0);
    let progress = Mutex::new(Progress {
        done: Vec::new(),
        error: None,
    });
    let lock = || progress.lock().unwrap_or_else(|e| e.into_inner());
    let start = Instant::now();
    std::thread::scope(|scope| {
        for _ in 0..jobs.clamp(1, numbers.len().max(1)) {
            scope.spawn(|| {
                while let Some(&number) = numbers.get(next.fetch_add(1, Ordering::SeqCst)) {
                    if lock().error.is_some() {
                        break;
                    }
                    let Some(case) = study.case(number) else {
                        continue;
                    };
                    let outcome = run_case_with(study, &case, command, run);
                    let mut p = lock();
                    match outcome {
                        Ok(result) => {
                            p.done.push((number, result.clone()));
                            report(Finished {
                                case: &case,
                                result,
                                count: p.done.len(),
                                of: numbers.len(),
                                elapsed: start.elapsed().as_secs_f64(),
                            });
                        }
                        Err(e) => {
                            p.error.get_or_insert(format!("case {number}: {e:#}"));
                        }
                    }
                }
            });
        }
    });
    let Progress { mut done, error } = progress.into_inner().unwrap_or_else(|e| e.into_inner());
    if let Some(error) = error {
        anyhow::bail!("{error}");
    }
    done.sort_by_key(|(n, _)| *n);
    Ok(done)
}
