//! What the long-running commands share: the worker-thread pool and the progress bar.

use crate::experiment::sheet_test::Progress;
use crate::forming::Scenario;
use crate::solver::checks::CheckReport;
use crate::solver::estimate::{format_bytes, peak_memory, RunEstimate};
use anyhow::Context;
use indicatif::{ProgressBar, ProgressStyle};
use std::path::PathBuf;

/// Runs `job` on `threads` worker threads (default: all cores).
pub fn with_threads(
    threads: Option<usize>,
    job: impl FnOnce() -> anyhow::Result<()> + Send,
) -> anyhow::Result<()> {
    match threads {
        None => job(),
        Some(0) => anyhow::bail!("--threads must be at least 1"),
        Some(n) => rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .context("cannot start the worker threads")?
            .install(job),
    }
}

/// Progress bar over simulated time; hidden when standard error is not a terminal.
pub struct Bar {
    bar: ProgressBar,
    end_time: f64,
}

impl Bar {
    pub fn new(end_time: f64) -> Self {
        let bar = ProgressBar::new(1000);
        bar.set_style(
            ProgressStyle::with_template("{bar:40} {percent:>3}%  {msg}  ETA {eta}")
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        Self { bar, end_time }
    }

    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

impl Progress for Bar {
    fn update(&mut self, time: f64, step: usize) {
        self.bar
            .set_position((1000.0 * time / self.end_time) as u64);
        self.bar
            .set_message(format!("step {step}, t = {time:.4e} s"));
    }
}

/// The summary table of a run, `(name, value)` per row, then the files written.
pub fn print_table(rows: &[(&str, String)], files: &[PathBuf]) {
    println!("{:-<64}", "");
    for (name, value) in rows {
        println!("{name:<28}{value}");
    }
    println!("{:-<64}", "");
    for f in files {
        println!("wrote {}", f.display());
    }
}

/// What the scenario commands (`run`, `drape`) share: the scenario, its overrides, the output
/// folder.
#[derive(clap::Args, Debug)]
pub struct ScenarioArgs {
    /// Scenario file (TOML): blank, tools, process, output.
    scenario: PathBuf,
    /// Override a scalar of the scenario, e.g. --set process.temperature=310 (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    overrides: Vec<String>,
    /// Output folder (overrides output.folder).
    #[arg(long)]
    output: Option<PathBuf>,
}

impl ScenarioArgs {
    /// The checked scenario and the output folder.
    pub fn load(&self) -> anyhow::Result<(Scenario, PathBuf)> {
        let scenario = Scenario::load(&self.scenario, &self.overrides)?;
        let dir = self
            .output
            .clone()
            .unwrap_or_else(|| scenario.output.folder.clone());
        Ok((scenario, dir))
    }
}

/// [`print_table`] with the memory (peak against the estimate) and the checks section after
/// `rows`; each check that is not OK is also a warning line on standard error.
pub fn print_checked_table(
    rows: &[(&str, String)],
    checks: &CheckReport,
    estimate: &RunEstimate,
    files: &[PathBuf],
) {
    let mut all: Vec<(String, String)> = rows
        .iter()
        .map(|(name, value)| (name.to_string(), value.clone()))
        .collect();
    let peak = peak_memory().map_or("unknown".into(), format_bytes);
    all.push((
        "memory".into(),
        format!("{peak} peak (estimated {})", format_bytes(estimate.memory)),
    ));
    all.push(("checks".into(), String::new()));
    for (name, value) in checks.rows() {
        all.push((format!("  {name}"), value));
    }
    let borrowed: Vec<(&str, String)> = all.iter().map(|(n, v)| (n.as_str(), v.clone())).collect();
    print_table(&borrowed, files);
    for line in checks.warnings() {
        eprintln!("warning: {}: {}: {}", line.name, line.status, line.figure);
    }
}
