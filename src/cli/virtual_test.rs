//! `thermostamp test ...`: the virtual material tests, with CSV, ParaView and PNG output, a
//! progress bar and a summary table.

use super::shared::{
    implicit_summary, print_checked_table, status_row, with_threads, Bar, Interrupt,
};
use crate::experiment::bias_extension::BiasExtension;
use crate::experiment::picture_frame::PictureFrame;
use crate::experiment::sheet_test::{Progress, RunSummary, TestProcess, TestRun};
use crate::experiment::uniaxial::UniaxialTension;
use crate::experiment::virtual_test::{cli_names, prepare, Specimen, TestOptions, DRY_TEMPERATURE};
use crate::limits::{
    ranges_help, Range, ANGLE, DAMPING, FRAMES, HISTORY_POINTS, LENGTH, SPEED, TEMPERATURE,
    TIME_SCALING, TIME_STEP,
};
use crate::mesh::DiagonalPattern;
use crate::solver::estimate::RunEstimate;
use crate::solver::SolverKind;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};

#[derive(clap::Subcommand, Debug)]
pub enum TestCommand {
    /// Bias-extension test: ±45° specimen clamped at both ends and pulled (docs/model.md §5).
    #[command(after_help = process_defaults(
        &BiasExtension::benchmark(DRY_TEMPERATURE).process,
        &[("--width, --length", LENGTH)]
    ))]
    BiasExtension(BiasArgs),
    /// Uniaxial (strip) tension test: bottom edge clamped, top edge pulled, yarns at any angle.
    #[command(after_help = process_defaults(
        &UniaxialTension::standard(DRY_TEMPERATURE).process,
        &[("--width, --length", LENGTH), ("--ply-angle", ANGLE)]
    ))]
    Uniaxial(UniaxialArgs),
    /// Picture-frame test: square specimen in a pin-jointed frame pulled along its diagonal.
    #[command(after_help = process_defaults(
        &PictureFrame::standard(DRY_TEMPERATURE).process,
        &[("--side", LENGTH)]
    ))]
    PictureFrame(PictureFrameArgs),
}

/// Options every virtual test shares.
#[derive(clap::Args, Debug)]
pub struct CommonArgs {
    /// Material card (TOML).
    #[arg(long)]
    card: PathBuf,
    /// Test temperature (°C); required when the card has a matrix, default 20 °C for a dry
    /// fabric.
    #[arg(long, allow_negative_numbers = true)]
    temperature: Option<f64>,
    /// Physical crosshead speed (mm/s); 0.333 mm/s is 20 mm/min. Default: the test's, below.
    #[arg(long, allow_negative_numbers = true)]
    speed: Option<f64>,
    /// Run the process this many times faster, with eta1 divided by it (docs/model.md §6).
    /// Default: the test's, below.
    #[arg(long, allow_negative_numbers = true)]
    time_scaling: Option<f64>,
    /// Mass scaling to this time step (s); 0 for none. Default: the test's, below.
    #[arg(long, allow_negative_numbers = true)]
    target_step: Option<f64>,
    /// Global mass-proportional damping (1/s).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    damping: f64,
    /// Target element size (mm). Default: the test's, below.
    #[arg(long, allow_negative_numbers = true)]
    element_size: Option<f64>,
    /// How rectangular cells are meshed: quad keeps them as 4-node quadrilaterals, the others
    /// cut them into triangles.
    #[arg(long, value_enum, default_value_t = DiagonalPattern::Crossed)]
    pattern: DiagonalPattern,
    /// Crosshead travel at the end (mm). Default: the test's, below.
    #[arg(long, allow_negative_numbers = true)]
    end_displacement: Option<f64>,
    /// Number of ParaView frames (0 for none).
    #[arg(long, default_value_t = 20)]
    frames: usize,
    /// Number of rows of the CSV history.
    #[arg(long, default_value_t = 120)]
    history_points: usize,
    /// Output folder.
    #[arg(long, default_value = "results")]
    output: PathBuf,
    /// Worker threads for the element loop (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Solver: explicit (central differences; the test's time and mass scaling) or implicit
    /// (quasi-static Newton increments at the physical speed; --time-scaling and
    /// --target-step are refused with it), docs/solver.md.
    #[arg(long, value_enum, default_value_t = SolverKind::Explicit)]
    solver: SolverKind,
}

impl CommonArgs {
    /// The options as the library takes them.
    fn options(&self) -> TestOptions {
        TestOptions {
            temperature: self.temperature,
            speed: self.speed,
            time_scaling: self.time_scaling,
            target_step: self.target_step,
            damping: self.damping,
            element_size: self.element_size,
            pattern: self.pattern,
            end_displacement: self.end_displacement,
            frames: self.frames,
            history_points: self.history_points,
            solver: self.solver,
        }
    }
}

#[derive(clap::Args, Debug)]
pub struct BiasArgs {
    #[command(flatten)]
    common: CommonArgs,
    /// Specimen width (mm).
    #[arg(long, default_value_t = 150.0, allow_negative_numbers = true)]
    width: f64,
    /// Free length between the clamps (mm).
    #[arg(long, default_value_t = 450.0, allow_negative_numbers = true)]
    length: f64,
}

#[derive(clap::Args, Debug)]
pub struct UniaxialArgs {
    #[command(flatten)]
    common: CommonArgs,
    /// Strip width (mm).
    #[arg(long, default_value_t = 25.0, allow_negative_numbers = true)]
    width: f64,
    /// Free length between the clamps (mm).
    #[arg(long, default_value_t = 150.0, allow_negative_numbers = true)]
    length: f64,
    /// Angle of the warp to the pulling direction (degrees): 0 warp, 90 weft, 45 bias.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    ply_angle: f64,
}

#[derive(clap::Args, Debug)]
pub struct PictureFrameArgs {
    #[command(flatten)]
    common: CommonArgs,
    /// Side of the frame and of the square specimen, hinge to hinge (mm).
    #[arg(long, default_value_t = 150.0, allow_negative_numbers = true)]
    side: f64,
}

pub fn run(command: &TestCommand) -> anyhow::Result<()> {
    let interrupt = Interrupt::install()?;
    let i = &interrupt;
    let (common, specimen) = match command {
        TestCommand::BiasExtension(a) => (
            &a.common,
            Specimen::BiasExtension {
                width: a.width,
                length: a.length,
            },
        ),
        TestCommand::Uniaxial(a) => (
            &a.common,
            Specimen::Uniaxial {
                width: a.width,
                length: a.length,
                ply_angle: a.ply_angle,
            },
        ),
        TestCommand::PictureFrame(a) => (&a.common, Specimen::PictureFrame { side: a.side }),
    };
    with_threads(common.threads, || sheet_test(common, specimen, i))
}

/// The defaults of a test's process for its `--help`, read from the test itself so that the
/// help says what the test does; then the ranges of the options, the test's `own` among them.
fn process_defaults(p: &TestProcess, own: &[(&str, Range)]) -> String {
    let mass_scaling = match p.target_time_step {
        Some(dt) => format!("{dt:e} s"),
        None => "none (physical mass)".into(),
    };
    let ranges: Vec<(&str, Range)> = own
        .iter()
        .copied()
        .chain([
            ("--temperature", TEMPERATURE),
            ("--speed", SPEED),
            ("--time-scaling", TIME_SCALING),
            ("--target-step (or 0)", TIME_STEP),
            ("--damping", DAMPING),
            ("--element-size, --end-displacement", LENGTH),
            ("--frames", FRAMES),
            ("--history-points", HISTORY_POINTS),
        ])
        .collect();
    format!(
        "Defaults of this test:\n  \
         --speed {:.3} mm/s ({:.0} mm/min)\n  \
         --time-scaling {}\n  \
         --target-step {mass_scaling}\n  \
         --element-size {} mm\n  \
         --end-displacement {} mm\n\n{}",
        p.speed,
        p.speed * 60.0,
        p.time_scaling,
        p.element_size,
        p.end_displacement,
        ranges_help(&ranges)
    )
}

/// The progress bar of a run and the flag Ctrl-C raises.
struct Watch<'a> {
    bar: Bar,
    stop: &'a AtomicBool,
}

impl Progress for Watch<'_> {
    fn update(&mut self, time: f64, step: usize) {
        self.bar.update(time, step);
    }

    fn interrupted(&self) -> bool {
        self.stop.load(Ordering::Relaxed)
    }
}

/// Checks, sets up and runs a virtual test (`experiment::virtual_test`) with the shared
/// outputs: the notes and the estimate on standard error, a progress bar while it runs, then
/// the summary table. A run that went unstable or was interrupted keeps what it wrote and
/// returns its solver error.
fn sheet_test(c: &CommonArgs, specimen: Specimen, interrupt: &Interrupt) -> anyhow::Result<()> {
    let test = prepare(&c.card, specimen, &c.options(), cli_names, &mut |line| {
        eprintln!("{line}")
    })?;
    let command = super::shared::command_line();
    let start = |end_time| Watch {
        bar: Bar::new(end_time),
        stop: interrupt.running(),
    };
    let (outcome, watch) = test.run(Some((&c.output, &command)), start)?;
    watch.bar.finish();
    let run = outcome.run;
    if run.records.is_empty() {
        // stopped before its first record: nothing to write
        return run.outcome.map(|_| ()).map_err(anyhow::Error::from);
    }
    print_summary(
        &run,
        (test.time_scaling, &test.chosen),
        &test.estimate,
        &outcome.files,
    );
    run.outcome.map(|_| ()).map_err(anyhow::Error::from)
}

fn print_summary(
    run: &TestRun,
    (time_scaling, chosen): (f64, &[String]),
    estimate: &RunEstimate,
    files: &[PathBuf],
) {
    let s = &run.summary;
    let defaults = if chosen.is_empty() {
        "none (all given)".to_string()
    } else {
        chosen.join("; ")
    };
    let rows = [
        status_row(&run.outcome),
        ("defaults chosen", defaults),
        ("solver", solver_summary(s)),
        ("steps", format!("{}", s.steps)),
        ("elements", format!("{}", s.elements)),
        (
            "last time step",
            known(s.time_step, || format!("{:.3e} s", s.time_step)),
        ),
        (
            "added mass (mass scaling)",
            known(s.added_mass, || {
                format!(
                    "{:.3e} t ({:.1} x the physical {:.3e} t)",
                    s.added_mass,
                    s.added_mass / s.physical_mass,
                    s.physical_mass
                )
            }),
        ),
        (
            "time scaling",
            format!("{time_scaling} (eta1 divided by it)"),
        ),
        (
            "energy balance error",
            format!("{:.3} % of external work", 100.0 * s.worst_balance_error),
        ),
        (
            "wall time",
            format!("{:.2} s on {} threads", s.wall_seconds, s.threads),
        ),
        (
            "element-steps per second",
            format!("{:.3e}", s.element_steps_per_second()),
        ),
    ];
    print_checked_table(&rows, &run.checks, estimate, files);
}

/// `text()` for a figure the run got to, a dash for one a stopped run did not.
fn known(value: f64, text: impl FnOnce() -> String) -> String {
    if value.is_finite() {
        text()
    } else {
        "- (the run stopped)".into()
    }
}

/// The solver, and for the implicit one its increments, iterations and time split.
fn solver_summary(s: &RunSummary) -> String {
    match &s.implicit {
        Some(i) => implicit_summary(i),
        None => "explicit".to_string(),
    }
}
