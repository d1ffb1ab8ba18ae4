//! What the long-running commands share: the worker-thread pool and the progress bar.

use crate::experiment::sheet_test::Progress;
use anyhow::Context;
use indicatif::{ProgressBar, ProgressStyle};

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
