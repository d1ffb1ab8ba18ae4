//! `thermostamp test ...`: the virtual material tests, with CSV, ParaView and PNG output, a
//! progress bar and a summary table.

use crate::experiment::bias_extension::{BiasExtension, BiasExtensionRun};
use crate::experiment::sheet_test::{FrameOutput, Progress, RunSummary};
use crate::io::plot::{write_png, LinePlot, LineStyle, Series};
use crate::io::vtk::PvdSeries;
use crate::io::write_csv;
use crate::material::MaterialCard;
use crate::mesh::DiagonalPattern;
use anyhow::Context;
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};

#[derive(clap::Subcommand, Debug)]
pub enum TestCommand {
    /// Bias-extension test: ±45° specimen clamped at both ends and pulled (MODEL.md §5).
    BiasExtension(BiasArgs),
}

/// Options every virtual test shares.
#[derive(clap::Args, Debug)]
pub struct CommonArgs {
    /// Material card (TOML).
    #[arg(long)]
    card: PathBuf,
    /// Test temperature (°C); required when the card has a matrix.
    #[arg(long)]
    temperature: Option<f64>,
    /// Physical crosshead speed (mm/s); 0.333 mm/s is 20 mm/min.
    #[arg(long)]
    speed: Option<f64>,
    /// Run the process this many times faster, with eta1 divided by it (MODEL.md §6).
    #[arg(long)]
    time_scaling: Option<f64>,
    /// Mass scaling to this time step (s); 0 for none.
    #[arg(long)]
    target_step: Option<f64>,
    /// Global mass-proportional damping (1/s).
    #[arg(long, default_value_t = 0.0)]
    damping: f64,
    /// Target element size (mm).
    #[arg(long)]
    element_size: Option<f64>,
    /// How rectangular cells are cut into triangles.
    #[arg(long, value_enum, default_value_t = DiagonalPattern::Crossed)]
    pattern: DiagonalPattern,
    /// Crosshead travel at the end (mm).
    #[arg(long)]
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
}

#[derive(clap::Args, Debug)]
pub struct BiasArgs {
    #[command(flatten)]
    common: CommonArgs,
    /// Specimen width (mm).
    #[arg(long, default_value_t = 150.0)]
    width: f64,
    /// Free length between the clamps (mm).
    #[arg(long, default_value_t = 450.0)]
    length: f64,
}

pub fn run(command: &TestCommand) -> anyhow::Result<()> {
    match command {
        TestCommand::BiasExtension(args) => {
            with_threads(args.common.threads, || bias_extension(args))
        }
    }
}

fn with_threads(
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

/// The card, and the test temperature: given, or for a dry fabric room temperature.
fn card_and_temperature(common: &CommonArgs) -> anyhow::Result<(MaterialCard, f64)> {
    let card = MaterialCard::load(&common.card)?;
    let temperature = match (common.temperature, &card.matrix) {
        (Some(t), _) => t,
        (None, None) => 20.0,
        (None, Some(matrix)) => {
            let (lo, hi) = matrix.parameters_range();
            anyhow::bail!(
                "--temperature is required: the card's matrix is tabulated from {lo} to {hi} °C"
            )
        }
    };
    Ok((card, temperature))
}

fn bias_extension(args: &BiasArgs) -> anyhow::Result<()> {
    let c = &args.common;
    let (card, temperature) = card_and_temperature(c)?;
    let mut test = BiasExtension::benchmark(temperature);
    test.width = args.width;
    test.length = args.length;
    test.pattern = c.pattern;
    test.damping = c.damping;
    test.history_points = c.history_points.max(2);
    if let Some(v) = c.speed {
        test.speed = v;
    }
    if let Some(s) = c.time_scaling {
        test.time_scaling = s;
    }
    if let Some(h) = c.element_size {
        test.element_size = h;
    }
    if let Some(d) = c.end_displacement {
        test.end_displacement = d;
    }
    if let Some(dt) = c.target_step {
        test.target_time_step = (dt > 0.0).then_some(dt);
    }
    test.validate()
        .map_err(|e| anyhow::anyhow!("bias extension: {e}"))?;
    let frames = frame_output(&c.output, "bias-extension", c.frames, test.history_points)?;
    let mut bar = Bar::new(test.settings().end_time);
    let result = test
        .run(&card.laminate, card.density, frames, Some(&mut bar))
        .map_err(|e| anyhow::anyhow!("bias extension: {e}"))?;
    bar.finish();
    let files = write_bias_outputs(&c.output, &result)?;
    print_summary(&result.run.summary, test.time_scaling, &files);
    result.run.outcome.map(|_| ()).map_err(anyhow::Error::from)
}

fn frame_output(
    dir: &Path,
    name: &str,
    frames: usize,
    records: usize,
) -> anyhow::Result<Option<FrameOutput>> {
    std::fs::create_dir_all(dir)
        .with_context(|| format!("cannot create the output folder {}", dir.display()))?;
    if frames == 0 {
        return Ok(None);
    }
    Ok(Some(FrameOutput {
        series: PvdSeries::new(dir, name)?,
        every: (records / frames).max(1),
    }))
}

/// CSV history and the two plots; returns the files written.
fn write_bias_outputs(dir: &Path, result: &BiasExtensionRun) -> anyhow::Result<Vec<PathBuf>> {
    let csv = dir.join("bias-extension.csv");
    let header = [
        "time",
        "displacement",
        "force",
        "shear_angle_deg",
        "shear_angle_pin_jointed_deg",
        "normalised_shear_force",
        "kinetic",
        "internal_work",
        "elastic",
        "viscous_dissipation",
        "damping",
        "external_work",
        "energy_balance_error",
    ];
    let rows = result.rows.iter().zip(&result.run.records).map(|(r, rec)| {
        let e = &rec.energies;
        [
            r.time,
            r.displacement,
            r.force,
            r.shear_angle,
            r.shear_angle_pin_jointed,
            r.normalised_shear_force,
            e.kinetic,
            e.internal_work,
            e.elastic,
            e.viscous_dissipation(),
            e.damping,
            e.external_work,
            e.balance_error(),
        ]
    });
    let file =
        std::fs::File::create(&csv).with_context(|| format!("cannot create {}", csv.display()))?;
    write_csv(&mut std::io::BufWriter::new(file), &header, rows)
        .with_context(|| format!("cannot write {}", csv.display()))?;
    let force_png = dir.join("bias-extension-force.png");
    let points =
        |f: &dyn Fn(&crate::experiment::bias_extension::BiasRow) -> f64| -> Vec<(f64, f64)> {
            result.rows.iter().map(|r| (r.displacement, f(r))).collect()
        };
    write_png(
        &force_png,
        &LinePlot {
            title: "Bias extension: crosshead force".into(),
            x_label: "crosshead displacement d (mm)".into(),
            y_label: "force F (N)".into(),
            series: vec![Series::new(
                "simulation",
                points(&|r| r.force),
                LineStyle::Solid,
            )],
        },
        900,
        600,
    )?;
    let shear_png = dir.join("bias-extension-shear-angle.png");
    write_png(
        &shear_png,
        &LinePlot {
            title: "Bias extension: shear angle of the central zone".into(),
            x_label: "crosshead displacement d (mm)".into(),
            y_label: "shear angle (°)".into(),
            series: vec![
                Series::new(
                    "simulation (central zone)",
                    points(&|r| r.shear_angle),
                    LineStyle::Solid,
                ),
                Series::new(
                    "pin-jointed net",
                    points(&|r| r.shear_angle_pin_jointed),
                    LineStyle::Dashed,
                ),
            ],
        },
        900,
        600,
    )?;
    Ok(vec![
        csv,
        force_png,
        shear_png,
        dir.join("bias-extension.pvd"),
    ])
}

fn print_summary(s: &RunSummary, time_scaling: f64, files: &[PathBuf]) {
    let rows = [
        ("steps", format!("{}", s.steps)),
        ("elements", format!("{}", s.elements)),
        ("last time step", format!("{:.3e} s", s.time_step)),
        (
            "added mass (mass scaling)",
            format!(
                "{:.3e} t ({:.1} x the physical {:.3e} t)",
                s.added_mass,
                s.added_mass / s.physical_mass,
                s.physical_mass
            ),
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
            "kinetic / internal energy",
            format!(
                "{:.3} % at most after the start",
                100.0 * s.worst_kinetic_ratio
            ),
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
    println!("{:-<64}", "");
    for (name, value) in rows {
        println!("{name:<28}{value}");
    }
    println!("{:-<64}", "");
    for f in files {
        println!("wrote {}", f.display());
    }
}

/// Progress bar over simulated time; hidden when standard error is not a terminal.
struct Bar {
    bar: ProgressBar,
    end_time: f64,
}

impl Bar {
    fn new(end_time: f64) -> Self {
        let bar = ProgressBar::new(1000);
        bar.set_style(
            ProgressStyle::with_template("{bar:40} {percent:>3}%  {msg}  ETA {eta}")
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        Self { bar, end_time }
    }

    fn finish(&self) {
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
