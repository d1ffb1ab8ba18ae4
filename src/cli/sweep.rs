//! `thermostamp sweep study.toml`: a process study, every case a forming run in its own folder
//! (docs/study.md), a progress line per finished case, a summary table and charts.

use super::shared::command_line;
use crate::study::run::{finished, run_cases, CaseResult, Finished, CASE_LOG};
use crate::study::summary::{rows, write_summary, Row, SUMMARY_CSV};
use crate::study::{folder, identity, Study};
use std::io::Write;
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
#[command(after_help = "Study file (TOML; docs/study.md):\n  \
    base = \"double-dome.toml\"            # the scenario, relative to the study file\n  \
    [parameters]                          # full factorial, the last varying fastest\n  \
    \"process.temperature\" = [280.0, 300.0, 320.0]\n  \
    \"process.blank_holder_force\" = { from = 0.0, to = 300.0, count = 4 }\n  \
    [output]\n  \
    folder = \"study-results\"              # default: <study name>-results in the working directory\n  \
    wrinkle_threshold = 0.155             # mm, waviness of a wrinkled case; default half a ply\n  \
    [run]\n  \
    threads_per_case = 1                  # the cases run side by side on the other cores\n\
    At most 1000000 cases. One study per folder: a second sweep into it, or a study with other \
    parameters, is refused.\n\
    Exit code 1 when a case failed (every case is still run), or, with --summarise, when a case \
    has not run; 2 for a bad study file or a folder that is busy or holds another study.")]
pub struct Args {
    /// Study file (TOML).
    study: PathBuf,
    /// Print the cases (number, parameters, status) and run nothing.
    #[arg(long, conflicts_with_all = ["case", "summarise"])]
    list: bool,
    /// Run only case N (from 1), again if it had finished, and write no summary: for a batch
    /// scheduler (a SLURM job array, GNU parallel) spreading the study over processes or
    /// machines; `--summarise` then builds the summary.
    #[arg(long, value_name = "N")]
    case: Option<usize>,
    /// Rebuild the summary from the case folders and run nothing (exit code 1 while a case has
    /// not run: the summary lists it as `not run`).
    #[arg(long, conflicts_with = "case")]
    summarise: bool,
    /// Cases run at the same time (default: the cores divided by run.threads_per_case).
    #[arg(long)]
    jobs: Option<usize>,
}

/// A study that did not end with every case done: exit code 1, after the summary. Cases
/// `failed`, and (for `--summarise`) cases `not_run`, of `total`; `summary` is where the
/// reasons are.
#[derive(Debug, thiserror::Error)]
#[error("{}", describe_incomplete(self))]
pub struct CasesFailed {
    pub failed: usize,
    pub not_run: Vec<usize>,
    pub total: usize,
    pub summary: String,
}

fn describe_incomplete(c: &CasesFailed) -> String {
    let mut parts = Vec::new();
    if c.failed > 0 {
        parts.push(format!(
            "{} of {} cases failed (their reasons are in {})",
            c.failed, c.total, c.summary
        ));
    }
    if !c.not_run.is_empty() {
        const SHOWN: usize = 10;
        let mut numbers: Vec<String> = c.not_run.iter().take(SHOWN).map(usize::to_string).collect();
        if c.not_run.len() > SHOWN {
            numbers.push(format!("and {} more", c.not_run.len() - SHOWN));
        }
        parts.push(format!(
            "{} of {} cases not run (cases {}): {} lists them as `not run`; run them and \
             summarise again",
            c.not_run.len(),
            c.total,
            numbers.join(", "),
            c.summary
        ));
    }
    parts.join("; ")
}

pub fn run(args: &Args) -> anyhow::Result<()> {
    let study = Study::load(&args.study)?;
    if args.list {
        identity::verify(&study)?;
        return list(&study);
    }
    let command = command_line();
    if let Some(n) = args.case {
        return run_one(&study, n, &command);
    }
    if args.summarise {
        let _folder = folder::take_whole(&study, &command)?;
        return summarise(&study, true);
    }
    sweep_all(&study, args.jobs, &command)
}

/// Runs the cases not finished, each case's scenario checked before the first runs (and before
/// the folder is touched), then summarises.
fn sweep_all(study: &Study, jobs: Option<usize>, command: &str) -> anyhow::Result<()> {
    identity::verify(study)?;
    let pending = unfinished(study);
    if pending.len() > 1000 {
        eprintln!(
            "checking the scenarios of {} cases before the first runs",
            pending.len()
        );
    }
    for case in pending.iter().filter_map(|&n| study.case(n)) {
        study.check_case(&case)?;
    }
    let _folder = folder::take_whole(study, command)?;
    // a case run by another process before the folder was ours may have finished since
    let pending: Vec<usize> = pending
        .into_iter()
        .filter(|&n| finished(&study.case_folder(n)).is_none())
        .collect();
    sweep(study, &pending, jobs, command)?;
    summarise(study, false)
}

/// One case of a study spread over processes: the study's folder shared with the others, the
/// case's own lock, no summary, which `--summarise` builds once they are all done (several
/// processes writing it at once would tear it).
fn run_one(study: &Study, n: usize, command: &str) -> anyhow::Result<()> {
    let case = study.case(n).ok_or_else(|| {
        anyhow::anyhow!(
            "--case {n}: the study has cases 1 to {}",
            study.cases_count()
        )
    })?;
    identity::verify(study)?;
    study.check_case(&case)?;
    let _folder = folder::take_shared(study, command)?;
    match sweep(study, &[n], Some(1), command)?.first() {
        Some((_, r)) if !r.done() => Err(CasesFailed {
            failed: 1,
            not_run: Vec::new(),
            total: 1,
            summary: study.case_folder(n).join(CASE_LOG).display().to_string(),
        }
        .into()),
        _ => Ok(()),
    }
}

/// The cases without a result, in order.
fn unfinished(study: &Study) -> Vec<usize> {
    if !study.folder.exists() {
        return (1..=study.cases_count()).collect();
    }
    (1..=study.cases_count())
        .filter(|&n| finished(&study.case_folder(n)).is_none())
        .collect()
}

/// Writes and prints the summary from the case folders (the study's folder held whole). An
/// error (exit code 1) when a case failed, or, where `missing_too`, when a case has not run.
fn summarise(study: &Study, missing_too: bool) -> anyhow::Result<()> {
    let rows = rows(study);
    let files = write_summary(study, &rows)?;
    print_table(study, &rows);
    for f in files {
        println!("wrote {}", f.display());
    }
    let failed = rows.iter().filter(|r| r.status == "failed").count();
    let not_run: Vec<usize> = rows
        .iter()
        .filter(|r| missing_too && r.status == "not run")
        .map(|r| r.case.number)
        .collect();
    if failed > 0 || !not_run.is_empty() {
        return Err(CasesFailed {
            failed,
            not_run,
            total: rows.len(),
            summary: study.folder.join(SUMMARY_CSV).display().to_string(),
        }
        .into());
    }
    Ok(())
}

/// One line per case: number, parameters, status; each case made, and its folder looked at,
/// as its line is written, so that the first lines come at once however many cases follow
/// (up to [`crate::study::file::MAX_CASES`]).
fn list(study: &Study) -> anyhow::Result<()> {
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    let folder_exists = study.folder.exists();
    for case in study.cases() {
        let folder = study.case_folder(case.number);
        let status = match folder_exists.then(|| finished(&folder)).flatten() {
            Some(r) if r.done() => "done".to_string(),
            Some(r) => format!("failed: {}", r.reason),
            None if folder_exists && folder.exists() => "not finished".into(),
            None => "not run".into(),
        };
        writeln!(
            out,
            "{:>4}  {}  {status}",
            case.number,
            study.describe(&case)
        )?;
    }
    out.flush()?;
    Ok(())
}

/// Runs the cases numbered `numbers`, a progress line on standard error as each finishes;
/// their results in case order.
fn sweep(
    study: &Study,
    numbers: &[usize],
    jobs: Option<usize>,
    command: &str,
) -> anyhow::Result<Vec<(usize, CaseResult)>> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let jobs = jobs
        .unwrap_or((cores / study.threads_per_case).max(1))
        .max(1);
    let exe = std::env::current_exe()?;
    let total = study.cases_count();
    eprintln!(
        "study {}: {} cases, {} to run, {jobs} at a time on {} thread(s) each",
        study.origin,
        total,
        numbers.len(),
        study.threads_per_case
    );
    let report = |f: Finished| {
        let left = f.of - f.count;
        let eta = f.elapsed / f.count as f64 * left as f64;
        let outcome = if f.result.done() {
            "done".to_string()
        } else {
            format!("FAILED ({})", f.result.reason)
        };
        eprintln!(
            "[{}/{}] case {} {outcome} in {:.1} s ({}); {left} left, ETA {:.0} s",
            f.count,
            f.of,
            f.case.number,
            f.result.wall_seconds,
            study.describe(f.case),
            eta
        );
    };
    run_cases(study, numbers, jobs, &exe, command, &report)
}

/// The summary as a table on standard output.
fn print_table(study: &Study, rows: &[Row]) {
    let line = "-".repeat(64);
    println!("{line}");
    println!(
        "study {}: {} cases, summary in {}",
        study.origin,
        rows.len(),
        study.folder.display()
    );
    println!(
        "{:>4}  {:<40}  {:>9}  {:>9}  {:>9}  {:>8}",
        "case", "parameters", "waviness", "shear (°)", "force (N)", "status"
    );
    let cell = |r: &Row, name: &str| {
        crate::study::summary::MEASURES
            .iter()
            .position(|m| *m == name)
            .and_then(|i| r.measures[i])
            .map_or("-".to_string(), |v| format!("{v:.3}"))
    };
    for r in rows {
        let params: Vec<String> = r
            .case
            .values
            .iter()
            .map(crate::study::summary::value_text)
            .collect();
        println!(
            "{:>4}  {:<40}  {:>9}  {:>9}  {:>9}  {:>8}",
            r.case.number,
            params.join(", "),
            cell(r, "waviness"),
            cell(r, "max_shear_deg"),
            cell(r, "peak_punch_force"),
            r.status
        );
    }
    println!("{line}");
}
