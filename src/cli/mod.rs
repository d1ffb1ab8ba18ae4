//! The `thermostamp` command line.
//!
//! Exit codes: 0 success; 1 a run that failed, diagnosed (the results so far are kept), a
//! study with a failed case, or a blank outline that does not cover its trim line;
//! 2 bad input of any kind (usage, files, values, settings, or a history the material cannot
//! follow), an output folder held by another run, or a result that could not be written (full
//! disk, a folder that cannot be created); 130 interrupted by Ctrl-C or SIGTERM (the results so
//! far are kept); killed by SIGPIPE when standard output is closed by its reader, as any Unix
//! tool. Errors are one line on standard error.

mod blank_outline;
mod drape;
mod fit;
mod fit_fabric_tension;
mod forming_run;
mod material_point;
mod shared;
mod sweep;
mod virtual_test;

use crate::io::message::tidy_message;
use crate::solver::SolverError;
use clap::{Parser, Subcommand};

#[derive(Parser, Debug)]
#[command(
    name = "thermostamp",
    version,
    about = "Thermo-stamping simulation of woven-fabric thermoplastic prepregs (lamination model)",
    long_about = "Thermo-stamping simulation of woven-fabric-reinforced thermoplastic prepregs with \
                  the lamination model of Gong et al. (Composite Structures 2018).\n\
                  Units everywhere: mm, N, s, MPa, tonne/mm^3, °C."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Drive one material point through a deformation history and print its stress as CSV.
    MaterialPoint(material_point::Args),
    /// Virtual material tests of a sheet, run with the explicit solver or (`--solver implicit`) the implicit one.
    #[command(subcommand)]
    Test(virtual_test::TestCommand),
    /// A thermo-stamping run described by a scenario file (blank, tools, process).
    Run(forming_run::Args),
    /// Kinematic draping preview of a scenario: the pin-jointed net on the formed punch.
    Drape(drape::Args),
    /// The flat blank outline that gives a trimmed part: the trim line mapped back onto the
    /// flat blank (kinematic drape, then forming runs) and offset by a margin; CSV and DXF.
    BlankOutline(blank_outline::Args),
    /// A process study: a base scenario run over the full factorial of parameter values, each
    /// case in its own folder, resumable, summarised in a table and charts (docs/study.md).
    Sweep(sweep::Args),
    /// Parameter identification from test curves (docs/model.md §5): `fit matrix`,
    /// `fit fabric-tension`, `fit shear`.
    #[command(subcommand)]
    Fit(fit::FitCommand),
}

/// Runs the command line and returns the process exit code.
pub fn main() -> i32 {
    end_quietly_on_a_closed_pipe();
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            let _ = e.print();
            return if e.use_stderr() { 2 } else { 0 };
        }
    };
    let result = match cli.command {
        Command::MaterialPoint(args) => material_point::run(&args),
        Command::Test(command) => virtual_test::run(&command),
        Command::Run(args) => forming_run::run(&args),
        Command::Drape(args) => drape::run(&args),
        Command::BlankOutline(args) => blank_outline::run(&args),
        Command::Fit(command) => fit::run(&command),
        Command::Sweep(args) => sweep::run(&args),
    };
    match result {
        Ok(()) => 0,
        Err(e) => {
            let code = exit_code(&e);
            let message = tidy_message(&format!("{e:#}"));
            if code == EXIT_INTERRUPTED {
                eprintln!("{message}, results so far kept");
            } else {
                eprintln!("error: {message}");
            }
            code
        }
    }
}

/// Standard output closed by its reader (`thermostamp ... | head`) ends the process as it
/// ends any Unix tool, by SIGPIPE, instead of a panic on the failed write (Rust ignores the
/// signal by default). The results a command writes to files are written before it prints
/// them.
fn end_quietly_on_a_closed_pipe() {
    #[cfg(unix)]
    // SAFETY: called first thing in `main`, before any thread is spawned; restoring a signal's
    // default disposition touches no memory of this process.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

/// Exit code of a run stopped by Ctrl-C or SIGTERM (128 + SIGINT, as shells report it).
pub const EXIT_INTERRUPTED: i32 = 130;

/// 1 for a run that the solver stopped (a diagnosed failure, results so far kept), 130 for one
/// interrupted, 2 for everything else: bad input (found before the first step wherever it can
/// be), and results that could not be written.
fn exit_code(e: &anyhow::Error) -> i32 {
    if e.downcast_ref::<sweep::CasesFailed>().is_some()
        || e.downcast_ref::<blank_outline::NotCovered>().is_some()
    {
        return 1;
    }
    match e.downcast_ref::<SolverError>() {
        Some(SolverError::Interrupted { .. }) => EXIT_INTERRUPTED,
        Some(SolverError::Output { .. } | SolverError::Settings(_)) | None => 2,
        Some(_) => 1,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settings_are_bad_input_and_a_stopped_run_a_failure() {
        let settings = anyhow::Error::from(SolverError::Settings("x".into()));
        assert_eq!(exit_code(&settings), 2);
        assert_eq!(exit_code(&anyhow::anyhow!("bad file")), 2);
        let uncovered = blank_outline::NotCovered("the trim line is not covered".into());
        assert_eq!(exit_code(&anyhow::Error::from(uncovered)), 1);
        // blank-outline names the iteration of a forming run that stopped: the code stays
        let interrupted = SolverError::Interrupted { step: 3, time: 0.1 };
        let named = anyhow::Error::from(interrupted).context("iteration 2: the run stopped");
        assert_eq!(exit_code(&named), EXIT_INTERRUPTED);
    }
}
