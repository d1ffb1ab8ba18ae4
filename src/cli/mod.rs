//! The `thermostamp` command line.
//!
//! Exit codes: 0 success; 1 a simulation that went unstable (the results so far are kept);
//! 2 bad input (usage, files, values, or a history the material cannot follow), an output
//! folder held by another run, or a result that could not be written (full disk, a folder
//! that cannot be created); 130 interrupted by Ctrl-C or SIGTERM (the results so far are
//! kept). Errors are one line on standard error.

mod drape;
mod fit;
mod fit_fabric_tension;
mod forming_run;
mod material_point;
mod shared;
mod virtual_test;

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
    /// Virtual material tests of a sheet, run with the explicit solver.
    #[command(subcommand)]
    Test(virtual_test::TestCommand),
    /// A thermo-stamping run described by a scenario file (blank, tools, process).
    Run(forming_run::Args),
    /// Kinematic draping preview of a scenario: the pin-jointed net on the formed punch.
    Drape(drape::Args),
    /// Parameter identification from test curves (MODEL.md §5): `fit matrix`, `fit shear`.
    #[command(subcommand)]
    Fit(fit::FitCommand),
}

/// Runs the command line and returns the process exit code.
pub fn main() -> i32 {
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
        Command::Fit(command) => fit::run(&command),
    };
    match result {
        Ok(()) => 0,
        Err(e) => {
            let code = exit_code(&e);
            let message = one_line(&format!("{e:#}"));
            if code == EXIT_INTERRUPTED {
                eprintln!("{message}, results so far kept");
            } else {
                eprintln!("error: {message}");
            }
            code
        }
    }
}

/// Exit code of a run stopped by Ctrl-C or SIGTERM (128 + SIGINT, as shells report it).
pub const EXIT_INTERRUPTED: i32 = 130;

/// 1 for a run that went unstable, 130 for one interrupted, 2 for everything else: bad
/// input, and results that could not be written.
fn exit_code(e: &anyhow::Error) -> i32 {
    match e.downcast_ref::<SolverError>() {
        Some(SolverError::Interrupted { .. }) => EXIT_INTERRUPTED,
        Some(SolverError::Output { .. }) => 2,
        Some(_) => 1,
        None => 2,
    }
}

fn one_line(message: &str) -> String {
    message.split_whitespace().collect::<Vec<_>>().join(" ")
}
