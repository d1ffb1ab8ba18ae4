//! What the long-running commands share: the worker-thread pool, the progress bar, Ctrl-C,
//! the lock on the output folder and the summary table.

use crate::experiment::sheet_test::Progress;
use crate::forming::Scenario;
use crate::io::output_folder::{take_folder, FolderLock, ProductFiles};
use crate::solver::checks::CheckReport;
use crate::solver::estimate::{format_bytes, peak_memory, RunEstimate};
use crate::solver::{SolverError, State};
use anyhow::Context;
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// Where `thermostamp run --help` and `drape --help` send the reader for the scenario keys.
pub const SCENARIO_REFERENCE: &str =
    "Scenario file: every key, its unit and its default are listed in docs/guide/scenario.md.\n\
     Tutorials: examples/hemisphere.toml, examples/double-dome.toml,\n\
     examples/hemisphere-quarter.toml.";

/// Runs `job` on `threads` worker threads (default: all cores); more threads than the machine
/// has cores are cut to the cores, with a note on standard error.
pub fn with_threads(
    threads: Option<usize>,
    job: impl FnOnce() -> anyhow::Result<()> + Send,
) -> anyhow::Result<()> {
    let Some(requested) = threads else {
        return job();
    };
    let cores = std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get);
    let (n, note) = crate::solver::threads::thread_count(requested, cores)?;
    if let Some(note) = note {
        eprintln!("{note}");
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .context("cannot start the worker threads")?
        .install(job)
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

/// What Ctrl-C (SIGINT) and SIGTERM do, installed before a command's set-up. During the set-up
/// (reading, meshing, building the model, before anything is written) a signal ends the process
/// at once with the interrupted exit code (130), saying so: there is nothing to keep. Once the
/// run has started ([`Interrupt::running`]) a signal raises the flag instead: the run finishes
/// its step, records it and stops; a second signal, while the first is being honoured, ends
/// the process at once (130).
pub struct Interrupt {
    raised: Arc<AtomicBool>,
    running: Arc<AtomicBool>,
}

impl Interrupt {
    pub fn install() -> anyhow::Result<Self> {
        let raised = Arc::new(AtomicBool::new(false));
        let running = Arc::new(AtomicBool::new(false));
        let (flag, started) = (Arc::clone(&raised), Arc::clone(&running));
        ctrlc::set_handler(move || {
            if !started.load(Ordering::SeqCst) {
                eprintln!("\ninterrupted during the set-up: nothing was run or written");
                std::process::exit(super::EXIT_INTERRUPTED);
            }
            if flag.swap(true, Ordering::SeqCst) {
                std::process::exit(super::EXIT_INTERRUPTED);
            }
        })
        .context("cannot install the Ctrl-C handler")?;
        Ok(Self { raised, running })
    }

    /// From now on a signal asks the run to stop after its step: returns the flag it raises.
    pub fn running(&self) -> &AtomicBool {
        self.running.store(true, Ordering::SeqCst);
        &self.raised
    }
}

/// The progress bar of a run and the flag that stops it.
pub struct Watch<'a> {
    pub bar: &'a mut Bar,
    pub stop: &'a AtomicBool,
}

impl Progress for Watch<'_> {
    fn update(&mut self, time: f64, step: usize) {
        self.bar.update(time, step);
    }

    fn interrupted(&self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }
}

/// Locks `dir` for this run and clears an earlier run's `products` there (see
/// [`take_folder`]); the lock file records this process's command line.
pub fn take_output_folder(dir: &Path, products: &ProductFiles) -> anyhow::Result<FolderLock> {
    Ok(take_folder(dir, &command_line(), products)?)
}

/// This process's command line, as a lock file records it.
pub fn command_line() -> String {
    std::env::args().collect::<Vec<_>>().join(" ")
}

/// The summary's line on how the run ended.
pub fn status_row(outcome: &Result<State, SolverError>) -> (&'static str, String) {
    ("status", crate::solver::error::outcome_status(outcome))
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
    /// Override a scalar of the scenario, e.g. --set process.temperature=310 (repeatable;
    /// default: none, the file as written).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    overrides: Vec<String>,
    /// Output folder (default: the scenario's output.folder, itself `results` by default).
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

/// Increments, iterations, factorisations and the time split of an implicit run, one line.
pub fn implicit_summary(s: &crate::solver::implicit::ImplicitStatistics) -> String {
    format!(
        "implicit: {} increments ({} cut), {} Newton iterations ({} on the projected tangent), \
         {} factorisations and {} of the preconditioner, {} CG iterations; assembly {:.2} s, \
         factorisation and solve {:.2} s",
        s.increments,
        s.cut_increments,
        s.iterations,
        s.projected,
        s.factorisations,
        s.preconditioner_factorisations,
        s.cg_iterations,
        s.assembly_seconds,
        s.solve_seconds
    )
}
