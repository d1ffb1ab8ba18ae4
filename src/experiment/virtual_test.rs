//! `thermostamp test ...` after its options are read, for every front end (the command line,
//! the Python package): the options checked and applied to a test's defaults, the defaults
//! that depend on the specimen and the card chosen, the run with its CSV history, ParaView
//! frames and plots, and the history as rows of numbers. Messages name the options through
//! an [`OptionNames`], `--time-scaling` on the command line, `time_scaling` in Python.

use crate::experiment::bias_extension::{BiasExtension, BiasRow};
use crate::experiment::picture_frame::{PictureFrame, PictureFrameRow};
use crate::experiment::sheet_test::{
    quasi_static_time_scaling, FrameOutput, HistorySink, LiveOutput, Progress, Record, SheetTest,
    TestProcess, TestRun, QUASI_STATIC_SPEED_RATIO,
};
use crate::experiment::uniaxial::{UniaxialRow, UniaxialTension};
use crate::io::output_folder::{take_folder, ProductFiles};
use crate::io::plot::{write_png, LinePlot, LineStyle, Series};
use crate::io::vtk::PvdSeries;
use crate::io::CsvStream;
use crate::limits::{
    check_given, ANGLE, DAMPING, FRAMES, HISTORY_POINTS, LENGTH, SPEED, TEMPERATURE, TIME_SCALING,
    TIME_STEP,
};
use crate::material::MaterialCard;
use crate::mesh::DiagonalPattern;
use crate::solver::estimate::{self, RunEstimate};
use crate::solver::SolverKind;
use std::path::{Path, PathBuf};

/// How a front end spells an option in messages, from its command-line name without the
/// dashes (`time-scaling`).
pub type OptionNames = fn(&str) -> String;

/// The command line's spelling: `--time-scaling`.
pub fn cli_names(option: &str) -> String {
    format!("--{option}")
}

/// The test temperature of a dry fabric when none is given (°C): room temperature.
pub const DRY_TEMPERATURE: f64 = 20.0;

/// The options every virtual test shares (`None`: the test's default).
#[derive(Clone, Debug, PartialEq)]
pub struct TestOptions {
    /// Test temperature (°C); required when the card has a matrix, [`DRY_TEMPERATURE`] for a
    /// dry fabric.
    pub temperature: Option<f64>,
    /// Physical crosshead speed (mm/s).
    pub speed: Option<f64>,
    pub time_scaling: Option<f64>,
    /// Mass scaling to this time step (s); 0 for none.
    pub target_step: Option<f64>,
    /// Global mass-proportional damping (1/s).
    pub damping: f64,
    pub element_size: Option<f64>,
    pub pattern: DiagonalPattern,
    /// Crosshead travel at the end (mm).
    pub end_displacement: Option<f64>,
    /// ParaView frames (0 for none), written only into an output folder.
    pub frames: usize,
    /// Rows of the history.
    pub history_points: usize,
    pub solver: SolverKind,
}

impl Default for TestOptions {
    /// The command line's defaults.
    fn default() -> Self {
        Self {
            temperature: None,
            speed: None,
            time_scaling: None,
            target_step: None,
            damping: 0.0,
            element_size: None,
            pattern: DiagonalPattern::Crossed,
            end_displacement: None,
            frames: 20,
            history_points: 120,
            solver: SolverKind::Explicit,
        }
    }
}

impl TestOptions {
    /// The numbers given, each inside its range (`crate::limits`) and named by its option,
    /// before the test's own checks (which name them as the library does).
    fn check_numbers(&self, names: OptionNames) -> Result<(), String> {
        // 0 turns mass scaling off; any other step is one
        let target_step = self.target_step.filter(|&dt| dt != 0.0);
        let n = |o: &str| names(o);
        check_given([
            (n("temperature").as_str(), self.temperature, TEMPERATURE),
            (n("speed").as_str(), self.speed, SPEED),
            (n("time-scaling").as_str(), self.time_scaling, TIME_SCALING),
            (n("target-step").as_str(), target_step, TIME_STEP),
            (n("damping").as_str(), Some(self.damping), DAMPING),
            (n("element-size").as_str(), self.element_size, LENGTH),
            (
                n("end-displacement").as_str(),
                self.end_displacement,
                LENGTH,
            ),
            (n("frames").as_str(), Some(self.frames as f64), FRAMES),
            (
                n("history-points").as_str(),
                Some(self.history_points as f64),
                HISTORY_POINTS,
            ),
        ])
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

/// The test and its specimen (mm; the ply angle in degrees).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Specimen {
    Uniaxial {
        width: f64,
        length: f64,
        ply_angle: f64,
    },
    BiasExtension {
        width: f64,
        length: f64,
    },
    PictureFrame {
        side: f64,
    },
}

impl Specimen {
    /// The command line's defaults.
    pub const UNIAXIAL: Self = Self::Uniaxial {
        width: 25.0,
        length: 150.0,
        ply_angle: 0.0,
    };
    pub const BIAS_EXTENSION: Self = Self::BiasExtension {
        width: 150.0,
        length: 450.0,
    };
    pub const PICTURE_FRAME: Self = Self::PictureFrame { side: 150.0 };

    /// The test in messages and the stem of its files.
    pub fn names(&self) -> (&'static str, &'static str) {
        match self {
            Self::Uniaxial { .. } => ("uniaxial test", "uniaxial"),
            Self::BiasExtension { .. } => ("bias extension", "bias-extension"),
            Self::PictureFrame { .. } => ("picture frame", "picture-frame"),
        }
    }
}

/// The test made from its specimen and options.
enum AnyTest {
    Uniaxial(UniaxialTension),
    BiasExtension(BiasExtension),
    PictureFrame(PictureFrame),
}

/// A test checked and set up, its run estimated: [`PreparedTest::run`] runs it.
pub struct PreparedTest {
    test: AnyTest,
    card: MaterialCard,
    options: TestOptions,
    /// The test in messages, and the stem of its files.
    pub label: &'static str,
    pub name: &'static str,
    /// The defaults chosen for what the options left open, one line each.
    pub chosen: Vec<String>,
    pub estimate: RunEstimate,
    /// Simulated time at the end of the travel (s), and the time scaling of the run.
    pub end_time: f64,
    pub time_scaling: f64,
}

/// What a test run gave: the run, its history (one row of `header` per record, as the CSV
/// has them) and the files written.
pub struct TestOutcome {
    pub run: TestRun,
    pub header: Vec<&'static str>,
    pub history: Vec<Vec<f64>>,
    pub files: Vec<PathBuf>,
}

/// Checks the options and sets the test up on the card at `card_path`: the
/// command line's checks and messages, options spelled by `names`. `say` gets the lines the
/// command line writes on standard error before the run (defaults chosen, a warning on the
/// speed, the estimate), as they come.
pub fn prepare(
    card_path: &Path,
    specimen: Specimen,
    options: &TestOptions,
    names: OptionNames,
    say: &mut dyn FnMut(String),
) -> anyhow::Result<PreparedTest> {
    options.check_numbers(names).map_err(anyhow::Error::msg)?;
    let card = MaterialCard::load(card_path)?;
    let card_origin = card_path.display().to_string();
    let temperature = test_temperature(&card, &card_origin, options, names)?;
    let dimension = |option: &str, value: f64| -> anyhow::Result<f64> {
        LENGTH
            .check(&names(option), value)
            .map_err(anyhow::Error::msg)?;
        Ok(value)
    };
    let (test, extent) = match specimen {
        Specimen::Uniaxial {
            width,
            length,
            ply_angle,
        } => {
            let mut test = UniaxialTension::standard(temperature);
            test.width = dimension("width", width)?;
            test.length = dimension("length", length)?;
            ANGLE
                .check(&names("ply-angle"), ply_angle)
                .map_err(anyhow::Error::msg)?;
            test.ply_angle = ply_angle;
            test.process.element_size = test.default_element_size();
            options.apply(&mut test.process);
            let extent = (test.width, test.length);
            (AnyTest::Uniaxial(test), extent)
        }
        Specimen::BiasExtension { width, length } => {
            let mut test = BiasExtension::benchmark(temperature);
            test.width = dimension("width", width)?;
            test.length = dimension("length", length)?;
            test.process.element_size = test.default_element_size();
            options.apply(&mut test.process);
            let extent = (test.width, test.length);
            (AnyTest::BiasExtension(test), extent)
        }
        Specimen::PictureFrame { side } => {
            let mut test = PictureFrame::standard(temperature);
            test.side = dimension("side", side)?;
            test.process.element_size = test.default_element_size();
            options.apply(&mut test.process);
            (AnyTest::PictureFrame(test), (side, side))
        }
    };
    let (label, name) = specimen.names();
    let refuse = |e: String| anyhow::anyhow!("{label}: {e}");
    let mut test = test;
    let setup = match &mut test {
        AnyTest::Uniaxial(t) => set_up(t, &card, options, extent, names, say),
        AnyTest::BiasExtension(t) => set_up(t, &card, options, extent, names, say),
        AnyTest::PictureFrame(t) => set_up(t, &card, options, extent, names, say),
    };
    let (chosen, estimate, end_time, time_scaling) = setup.map_err(refuse)?;
    Ok(PreparedTest {
        test,
        card,
        options: options.clone(),
        label,
        name,
        chosen,
        estimate,
        end_time,
        time_scaling,
    })
}

/// The test temperature: given, or for a dry fabric [`DRY_TEMPERATURE`].
fn test_temperature(
    card: &MaterialCard,
    card_origin: &str,
    options: &TestOptions,
    names: OptionNames,
) -> anyhow::Result<f64> {
    let option = names("temperature");
    let temperature = match (options.temperature, card.temperature_range()) {
        (Some(t), _) => t,
        (None, None) => DRY_TEMPERATURE,
        (None, Some((lo, hi))) => anyhow::bail!(
            "{option} is required: the card's matrix is tabulated from {lo} to {hi} °C"
        ),
    };
    card.check_temperature(&option, temperature)
        .map_err(|e| anyhow::anyhow!("{card_origin}: {e}"))?;
    Ok(temperature)
}

/// Validates a test, chooses its open defaults and estimates its run: the chosen lines, the
/// estimate, the end time and the time scaling.
fn set_up<T: SheetTest>(
    test: &mut T,
    card: &MaterialCard,
    options: &TestOptions,
    extent: (f64, f64),
    names: OptionNames,
    say: &mut dyn FnMut(String),
) -> Result<(Vec<String>, RunEstimate, f64, f64), String> {
    test.validate()?;
    check_specimen_memory(test.process(), extent, card, names)?;
    let chosen = choose_defaults(options, test, extent, card, names)?;
    for line in &chosen {
        say(format!("note: {line}"));
    }
    let estimate = test.estimate(&card.laminate, card.density)?;
    match test.process().solver {
        SolverKind::Explicit => {
            if let Some(warning) = dynamic_warning(test, card, names)? {
                say(warning);
            }
            let keys = (
                format!(
                    "{} or {} (the step)",
                    names("element-size"),
                    names("target-step")
                ),
                format!("{} or {}", names("speed"), names("time-scaling")),
                names("target-step"),
            );
            estimate::check_steps(&estimate, (&keys.0, &keys.1, &keys.2))?;
            say(estimate.describe());
        }
        SolverKind::Implicit => say(format!(
            "implicit quasi-static run of {} elements at the physical crosshead speed",
            estimate.size.elements
        )),
    }
    let end_time = test.settings().end_time;
    let time_scaling = test.process().time_scaling;
    Ok((chosen, estimate, end_time, time_scaling))
}

/// The defaults that depend on the specimen and the card, for what the options leave open: the
/// element size (set relative to the specimen by the test, reported here) and, with neither
/// speed nor time scaling given, a time scaling low enough for a quasi-static test
/// ([`quasi_static_time_scaling`]). One line each of what was chosen.
fn choose_defaults<T: SheetTest>(
    c: &TestOptions,
    test: &mut T,
    (width, length): (f64, f64),
    card: &MaterialCard,
    names: OptionNames,
) -> Result<Vec<String>, String> {
    let mut chosen = Vec::new();
    if c.element_size.is_none() {
        let h = test.process().element_size;
        chosen.push(format!(
            "element size {h:.4} mm ({:.0} x {:.0} cells on the {width} x {length} mm specimen; \
             {} to change)",
            width / h,
            length / h,
            names("element-size")
        ));
    }
    if c.speed.is_none() && c.time_scaling.is_none() && c.solver == SolverKind::Explicit {
        let ratio = test.speed_to_shear_wave(&card.laminate, card.density)?;
        let scaling = test.process().time_scaling;
        if let Some(lower) = quasi_static_time_scaling(ratio, scaling) {
            test.process_mut().time_scaling = lower;
            chosen.push(format!(
                "time scaling {lower:.4} instead of {scaling}: the crosshead at {:.2} % of the \
                 card's shear wave speed, quasi-static ({} to change)",
                100.0 * ratio * lower / scaling,
                names("time-scaling")
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
    names: OptionNames,
) -> Result<(), String> {
    let cells = |side: f64| (side / p.element_size).round().max(1.0);
    let (nx, ny) = (cells(width), cells(length));
    let (elements, nodes) = p.pattern.counts(nx, ny);
    let layers = card.laminate.initial_state().thickness_stretch.len();
    let (per_element, per_node, _) = estimate::item_bytes(layers, false, 0);
    estimate::check_memory(
        elements * per_element + nodes * per_node,
        &names("element-size"),
    )
}

/// A warning when the crosshead is too fast for a quasi-static test.
fn dynamic_warning<T: SheetTest>(
    test: &T,
    card: &MaterialCard,
    names: OptionNames,
) -> Result<Option<String>, String> {
    let ratio = test.speed_to_shear_wave(&card.laminate, card.density)?;
    Ok((ratio > QUASI_STATIC_SPEED_RATIO).then(|| {
        format!(
            "warning: the crosshead moves at {:.1} % of the specimen's shear wave speed (more \
             than {} %): its inertia will show in the force; lower {}, {} or {}",
            100.0 * ratio,
            100.0 * QUASI_STATIC_SPEED_RATIO,
            names("speed"),
            names("time-scaling"),
            names("target-step")
        )
    }))
}

impl PreparedTest {
    /// The columns of the history: time, displacement, force, the test's own, the energies
    /// and the solver's time.
    pub fn header(&self) -> Vec<&'static str> {
        let columns = match &self.test {
            AnyTest::Uniaxial(_) => uniaxial_report(&[]).columns,
            AnyTest::BiasExtension(_) => bias_report(&[]).columns,
            AnyTest::PictureFrame(_) => picture_frame_report(&[]).columns,
        };
        ["time", "displacement", "force"]
            .into_iter()
            .chain(columns)
            .chain(ENERGY_COLUMNS)
            .chain(["solver_time"])
            .collect()
    }

    /// Runs the test. With `output` (a folder and the command that takes it, as its lock
    /// file records it), writes the command line's files: the CSV history and the ParaView
    /// frames while it runs, the plots at the end (none for a run stopped before its first
    /// record). `start` makes the progress reporter once the run is about to start (the
    /// folder taken, the files open), given the end time; it is handed back with the outcome.
    /// A run that went unstable or was interrupted keeps its records: its solver error is in
    /// the outcome's run.
    pub fn run<P: Progress>(
        &self,
        output: Option<(&Path, &str)>,
        start: impl FnOnce(f64) -> P,
    ) -> anyhow::Result<(TestOutcome, P)> {
        match &self.test {
            AnyTest::Uniaxial(t) => self.run_test(t, uniaxial_report, output, start),
            AnyTest::BiasExtension(t) => self.run_test(t, bias_report, output, start),
            AnyTest::PictureFrame(t) => self.run_test(t, picture_frame_report, output, start),
        }
    }

    fn run_test<T: SheetTest, P: Progress>(
        &self,
        test: &T,
        report: fn(&[T::Row]) -> TestReport,
        output: Option<(&Path, &str)>,
        start: impl FnOnce(f64) -> P,
    ) -> anyhow::Result<(TestOutcome, P)> {
        let name = self.name;
        let header = self.header();
        let time_scaling = self.time_scaling;
        let _lock = match output {
            Some((dir, command)) => Some(take_folder(dir, command, &products(name))?),
            None => None,
        };
        let csv = output.map(|(dir, _)| dir.join(format!("{name}.csv")));
        let stream = match &csv {
            Some(path) => Some(CsvStream::create(path, &header)?),
            None => None,
        };
        let frames = match output {
            Some((dir, _)) => frame_output(
                dir,
                name,
                (self.options.frames, self.end_time),
                time_scaling,
            )?,
            None => None,
        };
        let wrote_frames = frames.is_some();
        let history = |mut csv: CsvStream| -> HistorySink<'_, Record> {
            Box::new(move |records: &[Record]| {
                if let Some(row) = newest_row(test, report, records, time_scaling) {
                    csv.write_row(&row)?;
                }
                Ok(())
            })
        };
        let live = LiveOutput {
            history: stream.map(history),
            frames,
        };
        let mut progress = start(self.end_time);
        let card = &self.card;
        let result = test
            .run(
                &card.laminate,
                card.density,
                Some(live),
                Some(&mut progress),
            )
            .map_err(|e| anyhow::anyhow!("{}: {e}", self.label))?;
        let run = result.run;
        let own = report(&result.rows);
        let history: Vec<Vec<f64>> = run
            .records
            .iter()
            .zip(&own.rows)
            .map(|(record, own)| history_row(record, own, time_scaling))
            .collect();
        let mut files = Vec::new();
        if let (Some((dir, _)), Some(csv)) = (output, csv) {
            if !run.records.is_empty() {
                files.push(csv);
                files.extend(write_plots(dir, name, &own, &run.records)?);
                if wrote_frames {
                    files.push(dir.join(format!("{name}.pvd")));
                }
            }
        }
        let outcome = TestOutcome {
            run,
            header,
            history,
            files,
        };
        Ok((outcome, progress))
    }
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
