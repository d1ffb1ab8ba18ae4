//! The `thermostamp` command line.
//!
//! Exit codes: 0 success; 1 a run that failed, diagnosed (the results so far are kept), or a
//! study with a failed case;
//! 2 bad input of any kind (usage, files, values, settings, or a history the material cannot
//! follow), an output folder held by another run, or a result that could not be written (full
//! disk, a folder that cannot be created); 130 interrupted by Ctrl-C or SIGTERM (the results so
//! far are kept); killed by SIGPIPE when standard output is closed by its reader, as any Unix
//! tool. Errors are one line on standard error.

mod drape;
mod fit;
mod fit_fabric_tension;
mod forming_run;
mod material_point;
mod shared;
mod sweep;
mod virtual_test;

use crate::limits::{shown, SHOWN_DIGITS};
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
    if e.downcast_ref::<sweep::CasesFailed>().is_some() {
        return 1;
    }
    match e.downcast_ref::<SolverError>() {
        Some(SolverError::Interrupted { .. }) => EXIT_INTERRUPTED,
        Some(SolverError::Output { .. } | SolverError::Settings(_)) | None => 2,
        Some(_) => 1,
    }
}

/// The message on one line, without a cause repeated by its context, and with every number
/// written with many digits rounded to [`SHOWN_DIGITS`] significant ones (`1e300`, not 301
/// digits).
fn tidy_message(message: &str) -> String {
    let words: Vec<String> = message.split_whitespace().map(round_long_numbers).collect();
    drop_repeated_causes(&words.join(" "))
}

/// Numbers of `word` written with more than [`SHOWN_DIGITS`] + 6 digits rounded to
/// [`SHOWN_DIGITS`]; names with digits in them (`run_2026.csv`, `node12`) are left alone.
fn round_long_numbers(word: &str) -> String {
    let mut out = String::with_capacity(word.len());
    let chars: Vec<char> = word.chars().collect();
    let mut i = 0;
    while i < chars.len() {
        let starts_number = chars[i].is_ascii_digit()
            && (i == 0 || !(chars[i - 1].is_alphanumeric() || "_./\\".contains(chars[i - 1])));
        if !starts_number {
            out.push(chars[i]);
            i += 1;
            continue;
        }
        let end = number_end(&chars, i);
        let token: String = chars[i..end].iter().collect();
        let followed_by_name = chars
            .get(end)
            .is_some_and(|c| c.is_alphabetic() || *c == '_');
        match token.parse::<f64>() {
            Ok(x) if !followed_by_name && written_digits(&token) > SHOWN_DIGITS + 6 => {
                out.push_str(&shown(x))
            }
            _ => out.push_str(&token),
        }
        i = end;
    }
    out
}

/// End of the decimal number (`123`, `1.5`, `2.5e-7`) starting at `start`.
fn number_end(chars: &[char], start: usize) -> usize {
    let digits_from = |mut i: usize| {
        while chars.get(i).is_some_and(char::is_ascii_digit) {
            i += 1;
        }
        i
    };
    let mut end = digits_from(start);
    if chars.get(end) == Some(&'.') && chars.get(end + 1).is_some_and(char::is_ascii_digit) {
        end = digits_from(end + 1);
    }
    if matches!(chars.get(end), Some('e' | 'E')) {
        let sign = usize::from(matches!(chars.get(end + 1), Some('-' | '+')));
        if chars.get(end + 1 + sign).is_some_and(char::is_ascii_digit) {
            end = digits_from(end + 1 + sign);
        }
    }
    end
}

/// Digits written in the mantissa of `token` (leading zeros too: `0.000...01` is as long to
/// read as any other).
fn written_digits(token: &str) -> usize {
    let mantissa = token.split(['e', 'E']).next().unwrap_or(token);
    let digits: String = mantissa.chars().filter(char::is_ascii_digit).collect();
    digits.len()
}

/// anyhow's `{:#}` joins contexts and causes with `: `; a cause that a context already
/// quotes in full is said once.
fn drop_repeated_causes(message: &str) -> String {
    let parts: Vec<&str> = message.split(": ").collect();
    let mut kept: Vec<&str> = Vec::with_capacity(parts.len());
    for (k, part) in parts.iter().enumerate() {
        let rest = parts[k..].join(": ");
        let said_before = kept.join(": ");
        if k > 0 && rest.len() >= 10 && said_before.contains(&rest) {
            break;
        }
        kept.push(part);
    }
    kept.join(": ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_numbers_are_rounded_and_names_left_alone() {
        let huge = format!("blank.width = {} must be", 1e300);
        assert_eq!(tidy_message(&huge), "blank.width = 1e300 must be");
        let tiny = format!("x = {}", 1.0e-300);
        assert_eq!(tidy_message(&tiny), "x = 1e-300");
        assert_eq!(tidy_message("v = 0.30000000000000004 mm"), "v = 0.3 mm");
        assert_eq!(tidy_message("at 12345.678 s"), "at 12345.678 s");
        let name = "results_123456789012345678/x.csv: run 1234567890123456789x";
        assert_eq!(tidy_message(name), name);
        assert_eq!(
            tidy_message("f = 1.2345678901234567e-12 N"),
            "f = 1.23457e-12 N"
        );
    }

    #[test]
    fn a_cause_quoted_by_its_context_is_said_once() {
        let message = "cannot write a.csv: No space left on device: No space left on device";
        assert_eq!(
            tidy_message(message),
            "cannot write a.csv: No space left on device"
        );
        let distinct = "a.toml: line 3: bad value";
        assert_eq!(tidy_message(distinct), distinct);
    }

    #[test]
    fn settings_are_bad_input_and_a_stopped_run_a_failure() {
        let settings = anyhow::Error::from(SolverError::Settings("x".into()));
        assert_eq!(exit_code(&settings), 2);
        assert_eq!(exit_code(&anyhow::anyhow!("bad file")), 2);
    }
}
