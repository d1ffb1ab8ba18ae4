//! `thermostamp sweep study.toml`: a process study, every case a forming run in its own folder
//! (docs/study.md), a progress line per finished case, a summary table and charts.

use crate::study::run::{finished, run_cases, CaseResult, Finished};
use crate::study::summary::{rows, write_summary, Row};
use crate::study::{Case, Study};
use std::path::PathBuf;

#[derive(clap::Args, Debug)]
#[command(after_help = "Study file (TOML; docs/study.md):\n  \
    base = \"double-dome.toml\"            # the scenario, relative to the study file\n  \
    [parameters]                          # full factorial, the last varying fastest\n  \
    \"process.temperature\" = [280.0, 300.0, 320.0]\n  \
    \"process.blank_holder_force\" = { from = 0.0, to = 300.0, count = 4 }\n  \
    [output]\n  \
    folder = \"study-results\"              # default: <study name>-results beside the file\n  \
    wrinkle_threshold = 0.155             # mm, waviness of a wrinkled case; default half a ply\n  \
    [run]\n  \
    threads_per_case = 1                  # the cases run side by side on the other cores\n\
    Exit code 1 when a case failed (every case is still run), 2 for a bad study file.")]
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
    /// Rebuild the summary from the case folders and run nothing.
    #[arg(long, conflicts_with = "case")]
    summarise: bool,
    /// Cases run at the same time (default: the cores divided by run.threads_per_case).
    #[arg(long)]
    jobs: Option<usize>,
}

/// A sweep in which some cases failed: exit code 1, after the summary.
#[derive(Debug, thiserror::Error)]
#[error("{failed} of {total} cases failed (their reasons are in {summary})")]
pub struct CasesFailed {
    pub failed: usize,
    pub total: usize,
    pub summary: String,
}

pub fn run(args: &Args) -> anyhow::Result<()> {
    let study = Study::load(&args.study)?;
    let cases = study.cases();
    if args.list {
        list(&study, &cases);
        return Ok(());
    }
    if let Some(n) = args.case {
        // one case of a study spread over processes: no summary, which --summarise builds once
        // they are all done (several processes writing it at once would tear it)
        let case = cases.get(n.wrapping_sub(1)).ok_or_else(|| {
            anyhow::anyhow!("--case {n}: the study has cases 1 to {}", cases.len())
        })?;
        return match sweep(&study, &[case], Some(1))?.first() {
            Some((_, r)) if !r.done() => Err(CasesFailed {
                failed: 1,
                total: 1,
                summary: study
                    .case_folder(case)
                    .join(crate::study::run::CASE_LOG)
                    .display()
                    .to_string(),
            }
            .into()),
            _ => Ok(()),
        };
    }
    if !args.summarise {
        let pending: Vec<&Case> = cases
            .iter()
            .filter(|c| finished(&study.case_folder(c)).is_none())
            .collect();
        sweep(&study, &pending, args.jobs)?;
    }
    let rows = rows(&study);
    let files = write_summary(&study, &rows)?;
    print_table(&study, &rows);
    for f in files {
        println!("wrote {}", f.display());
    }
    let failed = rows.iter().filter(|r| r.status == "failed").count();
    if failed > 0 {
        return Err(CasesFailed {
            failed,
            total: rows.len(),
            summary: study
                .folder
                .join(crate::study::summary::SUMMARY_CSV)
                .display()
                .to_string(),
        }
        .into());
    }
    Ok(())
}

/// One line per case: number, parameters, status.
fn list(study: &Study, cases: &[Case]) {
    for case in cases {
        let status = match finished(&study.case_folder(case)) {
            Some(r) if r.done() => "done".to_string(),
            Some(r) => format!("failed: {}", r.reason),
            None if study.case_folder(case).exists() => "not finished".into(),
            None => "not run".into(),
        };
        println!("{:>4}  {}  {status}", case.number, study.describe(case));
    }
}

/// Runs `cases`, a progress line on standard error as each finishes; their results in case
/// order.
fn sweep(
    study: &Study,
    cases: &[&Case],
    jobs: Option<usize>,
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
        cases.len(),
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
    run_cases(study, cases, jobs, &exe, &report)
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
