//! `thermostamp sweep study.toml`: a process study, every case a forming run in its own folder
//! (docs/study.md), a progress line per finished case, a summary table and charts; or, with
//! `--emit slurm`, the job-array script that runs its cases on a cluster.

use super::shared::command_line;
use crate::study::run::{
    case_status, finished, run_cases, unfinished, CaseResult, Finished, CASE_LOG,
};
use crate::study::summary::{rows, write_summary, Row, SUMMARY_CSV};
use crate::study::{folder, identity, Study};
use std::io::Write;
use std::num::NonZeroUsize;
use std::path::{Path, PathBuf};

#[derive(clap::Args, Debug)]
#[command(after_help = "Study file (TOML; docs/study.md):\n  \
    base = \"double-dome.toml\"            # the scenario, relative to the study file\n  \
    [parameters]                          # full factorial, the last varying fastest\n  \
    \"process.temperature\" = [280.0, 300.0, 320.0]\n  \
    \"process.blank_holder_force\" = { from = 0.0, to = 300.0, count = 4 }\n  \
    [design]                              # optional; without it the full factorial\n  \
    method = \"latin-hypercube\"            # or \"sobol\", \"full-factorial\"\n  \
    samples = 16                          # cases of a sampled design (sobol: at most 65536)\n  \
    seed = 7                              # default 0: the same seed gives the same cases\n  \
                                          # a sampled design's ranges: { from = a, to = b }, no count\n  \
    [output]\n  \
    folder = \"study-results\"              # default: <study name>-results in the working directory\n  \
    wrinkle_threshold = 0.155             # mm, waviness of a wrinkled case; default half a ply\n  \
    [run]\n  \
    threads_per_case = 1                  # the cases run side by side on the other cores\n\
    At most 1000000 cases. One study per folder: a second sweep into it, or a study with other \
    parameters or another design, is refused.\n\
    On a SLURM cluster: `thermostamp sweep study.toml --emit slurm > study.sbatch`, \
    `sbatch study.sbatch`, then `thermostamp sweep study.toml --summarise` once its tasks \
    have ended.\n\
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
    /// Print a batch scheduler's script that runs every case as one task (`--case N`), and run
    /// nothing: `slurm`, a job array (submit it with sbatch, then `--summarise`).
    #[arg(long, value_enum, value_name = "SCHEDULER", conflicts_with_all = ["case", "summarise", "list"])]
    emit: Option<Scheduler>,
    /// With --emit: the most array tasks running at once (default 32, at most the cases).
    #[arg(long, value_name = "K", requires = "emit")]
    throttle: Option<NonZeroUsize>,
}

/// The batch schedulers `--emit` writes a script for.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scheduler {
    Slurm,
}

/// Array tasks of an emitted script running at once, unless `--throttle` says: enough to fill
/// a few nodes, few enough that one study does not take a shared cluster's whole queue.
pub const DEFAULT_THROTTLE: usize = 32;

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
    if let Some(Scheduler::Slurm) = args.emit {
        identity::verify(&study)?;
        let throttle = args.throttle.map_or(DEFAULT_THROTTLE, NonZeroUsize::get);
        let script = slurm_script(
            &study,
            &std::path::absolute(&args.study)?,
            &std::env::current_exe()?,
            &std::env::current_dir()?,
            throttle,
        )?;
        print!("{script}");
        return Ok(());
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

/// A SLURM job array running each case of `study` (its file at `study_path`, absolute) as one
/// task, `exe sweep STUDY --case $SLURM_ARRAY_TASK_ID` in `run_dir` (where the study's
/// `output.folder` was resolved), at most `throttle` tasks at once, each with the study's
/// threads per case, each task's output in the study's folder. Paths on shell lines are
/// single-quoted (any character but a newline survives); on `#SBATCH` lines, which sbatch
/// reads itself and not a shell, double-quoted with `"` and `\` escaped, and `%`, which sbatch
/// expands in file names, doubled. A path with a newline is refused: no quoting carries it on
/// a `#SBATCH` line.
pub fn slurm_script(
    study: &Study,
    study_path: &Path,
    exe: &Path,
    run_dir: &Path,
    throttle: usize,
) -> anyhow::Result<String> {
    let text = |path: &Path| -> anyhow::Result<String> {
        let text = path
            .to_str()
            .ok_or_else(|| anyhow::anyhow!("--emit slurm: {} is not UTF-8 text", path.display()))?;
        if text.contains(['\n', '\r']) {
            anyhow::bail!(
                "--emit slurm: {} holds a line break, which a #SBATCH line cannot carry",
                path.display()
            );
        }
        Ok(text.to_string())
    };
    let name = study_path.file_stem().map_or("study".into(), |s| {
        s.to_string_lossy().replace(['\n', '\r'], " ")
    });
    let (study_text, exe_text, dir) = (text(study_path)?, text(exe)?, text(run_dir)?);
    let log = text(&study.folder)?.replace('%', "%%") + "/slurm-%A_%a.log";
    let summary_log = text(&study.folder)?.replace('%', "%%") + "/slurm-summary-%j.log";
    let cases = study.cases_count();
    let throttle = throttle.min(cases);
    let summarise = format!(
        "cd {} && exec {} sweep {} --summarise",
        shell_quote(&dir),
        shell_quote(&exe_text),
        shell_quote(&study_text)
    );
    Ok(format!(
        "#!/bin/bash\n\
         # SLURM job array of the study {study}: {cases} cases, one array task each\n\
         # (written by `thermostamp sweep --emit slurm`, docs/study.md). Submit it with\n\
         #   sbatch THIS-FILE\n\
         # which prints the job's id; then build the summary once every task has ended:\n\
         #   sbatch --dependency=afterany:JOBID --output={summary} --wrap {wrap}\n\
         # A task that fails records its case as failed; one that is killed leaves its case\n\
         # unfinished (`thermostamp sweep STUDY --list` shows which): run those again with\n\
         #   sbatch --array=3,7 THIS-FILE\n\
         #SBATCH --job-name={job}\n\
         #SBATCH --array=1-{cases}%{throttle}\n\
         #SBATCH --cpus-per-task={threads}\n\
         #SBATCH --output={output}\n\
         cd {dir_quoted} || exit 1\n\
         exec {exe_quoted} sweep {study_quoted} --case \"$SLURM_ARRAY_TASK_ID\"\n",
        study = study_text,
        summary = shell_quote(&summary_log),
        wrap = double_quote(&summarise),
        job = sbatch_quote(&name),
        threads = study.threads_per_case,
        output = sbatch_quote(&log),
        dir_quoted = shell_quote(&dir),
        exe_quoted = shell_quote(&exe_text),
        study_quoted = shell_quote(&study_text),
    ))
}

/// `text` as one word of a POSIX shell: single-quoted, each `'` written `'\''`.
pub fn shell_quote(text: &str) -> String {
    format!("'{}'", text.replace('\'', r"'\''"))
}

/// `text` in double quotes for a shell, `\`, `"`, `$` and backquote escaped (a command line
/// given to `sbatch --wrap`, readable where its paths are single-quoted inside it).
fn double_quote(text: &str) -> String {
    let mut out = String::from('"');
    for c in text.chars() {
        if matches!(c, '\\' | '"' | '$' | '`') {
            out.push('\\');
        }
        out.push(c);
    }
    out.push('"');
    out
}

/// `text` as one argument of a `#SBATCH` line: sbatch splits those at spaces outside double
/// quotes and takes a backslash to escape the next character.
fn sbatch_quote(text: &str) -> String {
    if !text.is_empty()
        && text
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_./%+:,@".contains(c))
    {
        return text.to_string();
    }
    let mut out = String::from('"');
    for c in text.chars() {
        if matches!(c, '\\' | '"') {
            out.push('\\');
        }
        out.push(c);
    }
    out.push('"');
    out
}

/// One line per case: number, parameters, status; each case made, and its folder looked at,
/// as its line is written, so that the first lines come at once however many cases follow
/// (up to [`crate::study::file::MAX_CASES`]).
fn list(study: &Study) -> anyhow::Result<()> {
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    let folder_exists = study.folder.exists();
    for case in study.cases() {
        let status = case_status(study, case.number, folder_exists);
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
