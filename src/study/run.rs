//! Running a study's cases (docs/study.md): each case is `thermostamp run` of its own scenario
//! file in its own folder, a child process whose output goes to the folder's `run.log`. When
//! it ends, the case's outcome is written to `case-result.toml` in one step (written aside,
//! then renamed): a folder with that file is a finished case and is not run again; a folder
//! without it (a sweep killed part-way) is cleared and its case run again from the start.

use super::file::{Case, Study};
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

/// Runs `case` from the start in its folder with `exe run` (the thermostamp executable) on
/// `threads` threads, and records how it ended. Errors: the folder or its files cannot be
/// written, the executable cannot be started.
pub fn run_case(study: &Study, case: &Case, exe: &Path) -> anyhow::Result<CaseResult> {
    let folder = study.case_folder(case);
    if folder.exists() {
        std::fs::remove_dir_all(&folder)
            .map_err(|e| anyhow::anyhow!("cannot clear {}: {e}", folder.display()))?;
    }
    std::fs::create_dir_all(&folder)
        .map_err(|e| anyhow::anyhow!("cannot create {}: {e}", folder.display()))?;
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
    let log = std::fs::File::create(folder.join(CASE_LOG))?;
    let start = Instant::now();
    let output = Command::new(exe)
        .arg("run")
        .arg(&scenario)
        .arg("--output")
        .arg(&folder)
        .arg("--threads")
        .arg(study.threads_per_case.to_string())
        .stdout(log)
        .stderr(Stdio::piped())
        .output()
        .map_err(|e| anyhow::anyhow!("cannot start {}: {e}", exe.display()))?;
    let stderr = String::from_utf8_lossy(&output.stderr);
    std::fs::OpenOptions::new()
        .append(true)
        .open(folder.join(CASE_LOG))
        .and_then(|mut f| std::io::Write::write_all(&mut f, stderr.as_bytes()))?;
    let result = CaseResult {
        status: if output.status.success() {
            "done".into()
        } else {
            "failed".into()
        },
        reason: if output.status.success() {
            String::new()
        } else {
            failure_reason(&stderr, output.status.code())
        },
        wall_seconds: start.elapsed().as_secs_f64(),
    };
    let aside = folder.join(format!("{CASE_RESULT}.part"));
    write(&aside, &toml::to_string(&result)?)?;
    std::fs::rename(&aside, folder.join(CASE_RESULT))?;
    Ok(result)
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
    std::fs::write(path, text).map_err(|e| anyhow::anyhow!("cannot write {}: {e}", path.display()))
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

/// Runs `cases` on `jobs` cases at a time, calling `report` as each one finishes (in the order
/// they finish). A case that cannot even be started is an error that ends the sweep after the
/// running cases.
pub fn run_cases(
    study: &Study,
    cases: &[&Case],
    jobs: usize,
    exe: &Path,
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
        for _ in 0..jobs.clamp(1, cases.len().max(1)) {
            scope.spawn(|| {
                while let Some(case) = cases.get(next.fetch_add(1, Ordering::SeqCst)) {
                    if lock().error.is_some() {
                        break;
                    }
                    let outcome = run_case(study, case, exe);
                    let mut p = lock();
                    match outcome {
                        Ok(result) => {
                            p.done.push((case.number, result.clone()));
                            report(Finished {
                                case,
                                result,
                                count: p.done.len(),
                                of: cases.len(),
                                elapsed: start.elapsed().as_secs_f64(),
                            });
                        }
                        Err(e) => {
                            p.error.get_or_insert(format!("case {}: {e}", case.number));
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

/// Every case of `study` with its folder and, for a finished case, its result.
pub fn finished_cases(study: &Study) -> Vec<(Case, PathBuf, Option<CaseResult>)> {
    study
        .cases()
        .into_iter()
        .map(|case| {
            let folder = study.case_folder(&case);
            let result = finished(&folder);
            (case, folder, result)
        })
        .collect()
}
