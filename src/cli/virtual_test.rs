//! `thermostamp test ...`: the virtual material tests, with CSV, ParaView and PNG output, a
//! progress bar and a summary table.

use super::shared::{
    implicit_summary, print_checked_table, status_row, take_output_folder, with_threads, Bar,
    Interrupt, Watch,
};
use crate::experiment::bias_extension::{BiasExtension, BiasRow};
use crate::experiment::picture_frame::{PictureFrame, PictureFrameRow};
use crate::experiment::sheet_test::{
    quasi_static_time_scaling, FrameOutput, HistorySink, LiveOutput, Progress, Record, RunSummary,
    SheetTest, TestProcess, TestRun, QUASI_STATIC_SPEED_RATIO,
};
use crate::experiment::uniaxial::{UniaxialRow, UniaxialTension};
use crate::io::output_folder::ProductFiles;
use crate::io::plot::{write_png, LinePlot, LineStyle, Series};
use crate::io::vtk::PvdSeries;
use crate::io::CsvStream;
use crate::limits::{
    check_given, ranges_help, Range, ANGLE, DAMPING, FRAMES, HISTORY_POINTS, LENGTH, SPEED,
    TEMPERATURE, TIME_SCALING, TIME_STEP,
};
use crate::material::MaterialCard;
use crate::mesh::DiagonalPattern;
use crate::solver::estimate::{self, RunEstimate};
use crate::solver::SolverKind;
use std::path::{Path, PathBuf};

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
    /// The numbers given on the command line, each inside its range (`crate::limits`) and
    /// named by its option, before the test's own checks (which name them as the library does).
    fn check_numbers(&self) -> anyhow::Result<()> {
        // 0 turns mass scaling off; any other step is one
        let target_step = self.target_step.filter(|&dt| dt != 0.0);
        check_given([
            ("--temperature", self.temperature, TEMPERATURE),
            ("--speed", self.speed, SPEED),
            ("--time-scaling", self.time_scaling, TIME_SCALING),
            ("--target-step", target_step, TIME_STEP),
            ("--damping", Some(self.damping), DAMPING),
            ("--element-size", self.element_size, LENGTH),
            ("--end-displacement", self.end_displacement, LENGTH),
            ("--frames", Some(self.frames as f64), FRAMES),
            (
                "--history-points",
                Some(self.history_points as f64),
                HISTORY_POINTS,
            ),
        ])
        .map_err(anyhow::Error::msg)
    }

    /// Overrides a test's default process with the options given.
    fn apply(&self, p: &mut TestProcess) {
        p.solver = self.solver;
        if self.solver == SolverKind::Implicit {
            // the implicit run has no inertia: the test's scalings are left out unless given
            // (and then refused by the test's checks, naming them)
            p.time_scaling = 1.0;
            p.target_time_step = None;
        }
        p.pattern = self.pattern;
        p.damping = self.damping;
        p.history_points = self.history_points.max(2);
        if let Some(v) = self.speed {
            p.speed = v;
        }
        if let Some(s) = self.time_scaling {
            p.time_scaling = s;
        }
        if let Some(h) = self.element_size {
            p.element_size = h;
        }
        if let Some(d) = self.end_displacement {
            p.end_displacement = d;
        }
        if let Some(dt) = self.target_step {
            // 0 turns mass scaling off; a negative step is left for the validation to refuse
            p.target_time_step = (dt != 0.0).then_some(dt);
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
    match command {
        TestCommand::BiasExtension(args) => {
            with_threads(args.common.threads, || bias_extension(args, i))
        }
        TestCommand::Uniaxial(args) => with_threads(args.common.threads, || uniaxial(args, i)),
        TestCommand::PictureFrame(args) => {
            with_threads(args.common.threads, || picture_frame(args, i))
        }
    }
}

/// The test temperature of a dry fabric when none is given (°C): room temperature.
const DRY_TEMPERATURE: f64 = 20.0;

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

/// The card, and the test temperature: given, or for a dry fabric [`DRY_TEMPERATURE`].
fn card_and_temperature(common: &CommonArgs) -> anyhow::Result<(MaterialCard, f64)> {
    common.check_numbers()?;
    let card = MaterialCard::load(&common.card)?;
    let temperature = match (common.temperature, card.temperature_range()) {
        (Some(t), _) => t,
        (None, None) => DRY_TEMPERATURE,
        (None, Some((lo, hi))) => anyhow::bail!(
            "--temperature is required: the card's matrix is tabulated from {lo} to {hi} °C"
        ),
    };
    card.check_temperature("--temperature", temperature)
        .map_err(|e| anyhow::anyhow!("{}: {e}", common.card.display()))?;
    Ok((card, temperature))
}

/// A specimen dimension given on the command line: a length (`crate::limits::LENGTH`), or an
/// error naming the option.
fn dimension(option: &str, value: f64) -> anyhow::Result<f64> {
    LENGTH.check(option, value).map_err(anyhow::Error::msg)?;
    Ok(value)
}

fn bias_extension(args: &BiasArgs, interrupt: &Interrupt) -> anyhow::Result<()> {
    let c = &args.common;
    let (card, temperature) = card_and_temperature(c)?;
    let mut test = BiasExtension::benchmark(temperature);
    test.width = dimension("--width", args.width)?;
    test.length = dimension("--length", args.length)?;
    test.process.element_size = test.default_element_size();
    c.apply(&mut test.process);
    let names = ("bias extension", "bias-extension");
    let specimen = (test.width, test.length);
    sheet_test(
        c,
        &card,
        (names, specimen),
        &mut test,
        bias_report,
        interrupt,
    )
}

fn uniaxial(args: &UniaxialArgs, interrupt: &Interrupt) -> anyhow::Result<()> {
    let c = &args.common;
    let (card, temperature) = card_and_temperature(c)?;
    let mut test = UniaxialTension::standard(temperature);
    test.width = dimension("--width", args.width)?;
    test.length = dimension("--length", args.length)?;
    ANGLE
        .check("--ply-angle", args.ply_angle)
        .map_err(anyhow::Error::msg)?;
    test.ply_angle = args.ply_angle;
    test.process.element_size = test.default_element_size();
    c.apply(&mut test.process);
    let names = ("uniaxial test", "uniaxial");
    let specimen = (test.width, test.length);
    sheet_test(
        c,
        &card,
        (names, specimen),
        &mut test,
        uniaxial_report,
        interrupt,
    )
}

fn picture_frame(args: &PictureFrameArgs, interrupt: &Interrupt) -> anyhow::Result<()> {
    let c = &args.common;
    let (card, temperature) = card_and_temperature(c)?;
    let mut test = PictureFrame::standard(temperature);
    test.side = dimension("--side", args.side)?;
    test.process.element_size = test.default_element_size();
    c.apply(&mut test.process);
    let names = ("picture frame", "picture-frame");
    let specimen = (test.side, test.side);
    sheet_test(
        c,
        &card,
        (names, specimen),
        &mut test,
        picture_frame_report,
        interrupt,
    )
}

/// Validates and runs a [`SheetTest`] with the shared outputs; `names` as for
/// [`run_and_report`], `specimen` its width and length (mm), `report` turns its rows into
/// columns and plots.
fn sheet_test<T: SheetTest>(
    c: &CommonArgs,
    card: &MaterialCard,
    (names, specimen): ((&str, &str), (f64, f64)),
    test: &mut T,
    report: fn(&[T::Row]) -> TestReport,
    interrupt: &Interrupt,
) -> anyhow::Result<()> {
    let refuse = |e: String| anyhow::anyhow!("{}: {e}", names.0);
    test.validate().map_err(refuse)?;
    check_specimen_memory(test.process(), specimen, card).map_err(refuse)?;
    let chosen = choose_defaults(c, test, specimen, card).map_err(refuse)?;
    for line in &chosen {
        eprintln!("note: {line}");
    }
    let test = &*test;
    let estimate = test
        .estimate(&card.laminate, card.density)
        .map_err(refuse)?;
    match test.process().solver {
        SolverKind::Explicit => {
            warn_if_dynamic(test, card).map_err(refuse)?;
            estimate::check_steps(
                &estimate,
                (
                    "--element-size or --target-step (the step)",
                    "--speed or --time-scaling",
                    "--target-step",
                ),
            )
            .map_err(refuse)?;
            eprintln!("{}", estimate.describe());
        }
        SolverKind::Implicit => eprintln!(
            "implicit quasi-static run of {} elements at the physical crosshead speed",
            estimate.size.elements
        ),
    }
    let p = test.process();
    let shape = (test.settings().end_time, p.time_scaling);
    let history = |mut csv: CsvStream| -> HistorySink<'_, Record> {
        Box::new(move |records: &[Record]| {
            if let Some(row) = newest_row(test, report, records, shape.1) {
                csv.write_row(&row)?;
            }
            Ok(())
        })
    };
    let columns = report(&[]).columns;
    run_and_report(
        c,
        (names, &estimate, &chosen),
        shape,
        columns,
        |output, bar| {
            let output = LiveOutput {
                history: output.csv.map(history),
                frames: output.frames,
            };
            let result = test.run(&card.laminate, card.density, Some(output), Some(bar))?;
            Ok((result.run, report(&result.rows)))
        },
        interrupt,
    )
}

/// The defaults that depend on the specimen and the card, for what the options leave open: the
/// element size (set relative to the specimen by the test, reported here) and, with neither
/// --speed nor --time-scaling given, a time scaling low enough for a quasi-static test
/// ([`quasi_static_time_scaling`]). One line each of what was chosen.
fn choose_defaults<T: SheetTest>(
    c: &CommonArgs,
    test: &mut T,
    (width, length): (f64, f64),
    card: &MaterialCard,
) -> Result<Vec<String>, String> {
    let mut chosen = Vec::new();
    if c.element_size.is_none() {
        let h = test.process().element_size;
        chosen.push(format!(
            "element size {h:.4} mm ({:.0} x {:.0} cells on the {width} x {length} mm specimen; \
             --element-size to change)",
            width / h,
            length / h
        ));
    }
    if c.speed.is_none() && c.time_scaling.is_none() && c.solver == SolverKind::Explicit {
        let ratio = test.speed_to_shear_wave(&card.laminate, card.density)?;
        let scaling = test.process().time_scaling;
        if let Some(lower) = quasi_static_time_scaling(ratio, scaling) {
            test.process_mut().time_scaling = lower;
            chosen.push(format!(
                "time scaling {lower:.4} instead of {scaling}: the crosshead at {:.2} % of the \
                 card's shear wave speed, quasi-static (--time-scaling to change)",
                100.0 * ratio * lower / scaling
            ));
        }
    }
    Ok(chosen)
}

/// Refuses a specimen whose mesh would not fit the memory the machine has free, from the
/// element size before the mesh is made.
fn check_specimen_memory(
    p: &TestProcess,
    (width, length): (f64, f64),
    card: &MaterialCard,
) -> Result<(), String> {
    let cells = |side: f64| (side / p.element_size).round().max(1.0);
    let (nx, ny) = (cells(width), cells(length));
    let (elements, nodes) = p.pattern.counts(nx, ny);
    let layers = card.laminate.initial_state().thickness_stretch.len();
    let (per_element, per_node, _) = estimate::item_bytes(layers, false, 0);
    estimate::check_memory(elements * per_element + nodes * per_node, "--element-size")
}

/// The CSV row of the newest of `records`: its test's rows are computed from the records so
/// far (a row depends on the records up to its own only).
fn newest_row<T: SheetTest>(
    test: &T,
    report: fn(&[T::Row]) -> TestReport,
    records: &[Record],
    time_scaling: f64,
) -> Option<Vec<f64>> {
    let rows = test.rows(records);
    let own = *report(rows.get(rows.len().checked_sub(1)?..)?)
        .rows
        .first()?;
    Some(history_row(records.last()?, &own, time_scaling))
}

/// What [`run_and_report`] opens before the run, for the test to write as it goes.
struct OpenOutput {
    csv: Option<CsvStream>,
    frames: Option<FrameOutput>,
}

/// A warning on standard error when the crosshead is too fast for a quasi-static test.
fn warn_if_dynamic<T: SheetTest>(test: &T, card: &MaterialCard) -> Result<(), String> {
    let ratio = test.speed_to_shear_wave(&card.laminate, card.density)?;
    if ratio > QUASI_STATIC_SPEED_RATIO {
        eprintln!(
            "warning: the crosshead moves at {:.1} % of the specimen's shear wave speed (more \
             than {} %): its inertia will show in the force; lower --speed, --time-scaling or \
             --target-step",
            100.0 * ratio,
            100.0 * QUASI_STATIC_SPEED_RATIO
        );
    }
    Ok(())
}

/// Runs a virtual test with the shared outputs: the CSV history (`columns` are the test's
/// own), ParaView frames and a progress bar while it runs, then the plots and the summary
/// table. `(label, name)`: the test in messages and the stem of its files; `(end_time,
/// time_scaling)` of the run. `run` returns the test's run and its report; a run that went
/// unstable or was interrupted keeps what it wrote and returns its solver error.
fn run_and_report(
    c: &CommonArgs,
    ((label, name), estimate, chosen): ((&str, &str), &RunEstimate, &[String]),
    (end_time, time_scaling): (f64, f64),
    columns: [&str; 3],
    run: impl FnOnce(OpenOutput, &mut dyn Progress) -> Result<(TestRun, TestReport), String>,
    interrupt: &Interrupt,
) -> anyhow::Result<()> {
    let _lock = take_output_folder(&c.output, &products(name))?;
    let csv = c.output.join(format!("{name}.csv"));
    let header: Vec<&str> = ["time", "displacement", "force"]
        .into_iter()
        .chain(columns)
        .chain(ENERGY_COLUMNS)
        .chain(["solver_time"])
        .collect();
    let output = OpenOutput {
        csv: Some(CsvStream::create(&csv, &header)?),
        frames: frame_output(&c.output, name, (c.frames, end_time), time_scaling)?,
    };
    let wrote_frames = output.frames.is_some();
    let stop = interrupt.running();
    let mut bar = Bar::new(end_time);
    let mut watch = Watch {
        bar: &mut bar,
        stop,
    };
    let (run, report) = run(output, &mut watch).map_err(|e| anyhow::anyhow!("{label}: {e}"))?;
    bar.finish();
    if run.records.is_empty() {
        // stopped before its first record: nothing to write
        return run.outcome.map(|_| ()).map_err(anyhow::Error::from);
    }
    let mut files = vec![csv];
    files.extend(write_plots(&c.output, name, &report, &run.records)?);
    if wrote_frames {
        files.push(c.output.join(format!("{name}.pvd")));
    }
    print_summary(&run, (time_scaling, chosen), estimate, &files);
    run.outcome.map(|_| ()).map_err(anyhow::Error::from)
}

/// The files a test named `name` writes, by which a later run into the folder finds and
/// clears them.
fn products(name: &str) -> ProductFiles {
    let csv = format!("{name}.csv");
    let plots = PLOT_SUFFIXES.map(|suffix| format!("{name}-{suffix}.png"));
    ProductFiles {
        names: std::iter::once(csv).chain(plots).collect(),
        series: Some(name.into()),
    }
}

/// The plots of the tests: `<name>-<suffix>.png`.
const PLOT_SUFFIXES: [&str; 2] = ["force", "shear-angle"];

/// `frames` frames over a run of `end_time` simulated seconds, at process times (the run's
/// times times `time_scaling`).
fn frame_output(
    dir: &Path,
    name: &str,
    (frames, end_time): (usize, f64),
    time_scaling: f64,
) -> anyhow::Result<Option<FrameOutput>> {
    if frames == 0 {
        return Ok(None);
    }
    Ok(Some(FrameOutput::new(
        PvdSeries::new(dir, name)?,
        (frames, end_time),
        time_scaling,
    )))
}

/// What a finished test hands to the writer besides its records (which give the time,
/// displacement, force and energy columns and the force plot): its name in titles, its own
/// columns with one row of them per record, and its other plots, each `(file suffix, plot)`.
struct TestReport {
    title: &'static str,
    columns: [&'static str; 3],
    rows: Vec<[f64; 3]>,
    plots: Vec<(&'static str, LinePlot)>,
}

/// Energy columns every history ends with.
const ENERGY_COLUMNS: [&str; 7] = [
    "kinetic",
    "internal_work",
    "elastic",
    "viscous_dissipation",
    "damping",
    "external_work",
    "energy_balance_error",
];

/// One CSV row: time, displacement and force of the record, the test's own cells, the
/// energies and the solver's time. `time` is process time, the solver's times `time_scaling`,
/// as the frames' times are.
fn history_row(record: &Record, own: &[f64; 3], time_scaling: f64) -> Vec<f64> {
    let e = &record.energies;
    let r = &record.reading;
    let energies = [
        e.kinetic,
        e.internal_work,
        e.elastic,
        e.viscous_dissipation(),
        e.damping,
        e.external_work,
        e.balance_error(),
    ];
    [record.time * time_scaling, r.displacement, r.force]
        .into_iter()
        .chain(own.iter().copied())
        .chain(energies)
        .chain([record.time])
        .collect()
}

/// `<name>-force.png` and `<name>-<suffix>.png` per further plot; returns the files written.
fn write_plots(
    dir: &Path,
    name: &str,
    report: &TestReport,
    records: &[Record],
) -> anyhow::Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    let force = (PLOT_SUFFIXES[0], force_plot(report.title, records));
    for (suffix, plot) in std::iter::once(&force).chain(&report.plots) {
        let png = dir.join(format!("{name}-{suffix}.png"));
        write_png(&png, plot, 900, 600)?;
        files.push(png);
    }
    Ok(files)
}

/// The crosshead force against the displacement.
fn force_plot(test: &str, records: &[Record]) -> LinePlot {
    let points = records
        .iter()
        .map(|r| (r.reading.displacement, r.reading.force))
        .collect();
    LinePlot {
        title: format!("{test}: crosshead force"),
        x_label: DISPLACEMENT_LABEL.into(),
        y_label: "force F (N)".into(),
        series: vec![Series::new("simulation", points, LineStyle::Solid)],
    }
}

const DISPLACEMENT_LABEL: &str = "crosshead displacement d (mm)";

/// What names the columns and curves of a shear test (bias extension, picture frame).
struct ShearTestNames {
    title: &'static str,
    /// The elements whose mean shear angle is watched.
    zone: &'static str,
    /// Column and curve label of the kinematic reference angle.
    reference: (&'static str, &'static str),
}

const BIAS_EXTENSION: ShearTestNames = ShearTestNames {
    title: "Bias extension",
    zone: "central zone",
    reference: ("shear_angle_pin_jointed_deg", "pin-jointed net"),
};

const PICTURE_FRAME: ShearTestNames = ShearTestNames {
    title: "Picture frame",
    zone: "interior",
    reference: ("shear_angle_frame_deg", "frame (pin-jointed)"),
};

/// Report of a shear test whose rows give `(displacement, [shear angle, reference angle,
/// normalised shear force])`: the three columns and a plot of the two angles.
fn shear_test_report<R>(
    names: &ShearTestNames,
    rows: &[R],
    values: fn(&R) -> (f64, [f64; 3]),
) -> TestReport {
    let rows: Vec<_> = rows.iter().map(values).collect();
    let angle = |k: usize| rows.iter().map(|(d, v)| (*d, v[k])).collect::<Vec<_>>();
    let plot = LinePlot {
        title: format!("{}: shear angle of the {}", names.title, names.zone),
        x_label: DISPLACEMENT_LABEL.into(),
        y_label: "shear angle (°)".into(),
        series: vec![
            Series::new(
                format!("simulation ({})", names.zone),
                angle(0),
                LineStyle::Solid,
            ),
            Series::new(names.reference.1, angle(1), LineStyle::Dashed),
        ],
    };
    TestReport {
        title: names.title,
        columns: [
            "shear_angle_deg",
            names.reference.0,
            "normalised_shear_force",
        ],
        rows: rows.into_iter().map(|(_, v)| v).collect(),
        plots: vec![(PLOT_SUFFIXES[1], plot)],
    }
}

fn bias_report(rows: &[BiasRow]) -> TestReport {
    shear_test_report(&BIAS_EXTENSION, rows, |r| {
        let cells = [
            r.shear_angle,
            r.shear_angle_pin_jointed,
            r.normalised_shear_force,
        ];
        (r.displacement, cells)
    })
}

fn picture_frame_report(rows: &[PictureFrameRow]) -> TestReport {
    shear_test_report(&PICTURE_FRAME, rows, |r| {
        let cells = [r.shear_angle, r.shear_angle_frame, r.normalised_shear_force];
        (r.displacement, cells)
    })
}

fn uniaxial_report(rows: &[UniaxialRow]) -> TestReport {
    TestReport {
        title: "Uniaxial tension",
        columns: ["strain", "stress_resultant", "shear_angle_deg"],
        rows: rows
            .iter()
            .map(|r| [r.strain, r.stress_resultant, r.shear_angle])
            .collect(),
        plots: Vec::new(),
    }
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
