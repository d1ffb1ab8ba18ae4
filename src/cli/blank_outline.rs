//! `thermostamp blank-outline scenario.toml --trim trim.csv --margin 5`: the flat outline to
//! cut so that the formed part covers a trim line with a margin (`forming::outline`), with a
//! line per iteration and a summary.

use super::forming_run::watched_run;
use super::shared::{print_table, take_output_folder, with_threads, Interrupt};
use crate::forming::outline::iterate::{outline_csv_name, write_outline_csv, HISTORY_CSV};
use crate::forming::outline::{
    iterate, polygon, read_trim_csv, trim_circle, IterationRecord, OutlineResult, OutlineSettings,
    TrimLine,
};
use crate::forming::output::{live_output, products, write_final_results};
use crate::forming::{FormingModel, Scenario};
use crate::io::output_folder::ProductFiles;
use crate::io::plot::{write_png, LinePlot, LineStyle, Series};
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

/// The most iterations: each is a forming run.
const MAX_ITERATIONS: usize = 99;

/// The layer of the outline in `outline.dxf`.
pub const DXF_LAYER: &str = "OUTLINE";

#[derive(clap::Args, Debug)]
#[command(after_help = format!(
    "{}\n\nWrites to --output (default: the scenario's output.folder + /outline): outline.csv and \
     outline.dxf (the flat outline, mm), outline-history.csv, outline-NN.csv and iteration-NN/ \
     (the blank's mesh and the forming run of each iteration). Exit code 1 when the last blank \
     does not cover the trim line with the margin (files kept). Guide: \
     docs/guide/blank-outline.md.",
    super::shared::SCENARIO_REFERENCE
))]
#[command(group(clap::ArgGroup::new("trim_line").required(true).args(["trim", "trim_circle"])))]
pub struct Args {
    /// Scenario file (TOML): blank, tools, process, output.
    scenario: PathBuf,
    /// The trim line, a closed curve: CSV with the header x,y,z (points on the formed part,
    /// mm) or x,y (its plan view along the stroke axis z).
    #[arg(long, value_name = "CSV")]
    trim: Option<PathBuf>,
    /// The trim line as a circle of this radius (mm) about the stroke axis, in plan.
    #[arg(long, value_name = "MM", allow_hyphen_values = true, value_parser = positive("--trim-circle"))]
    trim_circle: Option<f64>,
    /// How far inside the formed blank's edge the trim line should lie, along the part (mm).
    #[arg(long, value_name = "MM", allow_hyphen_values = true, value_parser = not_negative("--margin"))]
    margin: f64,
    /// The most forming runs.
    #[arg(long, default_value_t = 6, value_parser = clap::value_parser!(u32).range(1..=MAX_ITERATIONS as i64))]
    iterations: u32,
    /// Stop once every trim point's margin is within this of --margin (mm; default: a quarter
    /// of the blank's element size).
    #[arg(long, value_name = "MM", allow_hyphen_values = true, value_parser = positive("--tolerance"))]
    tolerance: Option<f64>,
    /// Override a scalar of the scenario, e.g. --set blank.element_size=10 (repeatable;
    /// default: none, the file as written).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    overrides: Vec<String>,
    /// Output folder (default: the scenario's output.folder + /outline).
    #[arg(long)]
    output: Option<PathBuf>,
    /// Worker threads for the element loop (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
}

/// A length given on the command line: a finite number, above zero or at least zero.
fn length(option: &'static str, zero: bool) -> impl Fn(&str) -> Result<f64, String> + Clone {
    move |text: &str| {
        let v: f64 = text
            .trim()
            .parse()
            .map_err(|_| format!("'{text}': {option} takes a length in mm"))?;
        if v.is_finite() && (v > 0.0 || (zero && v == 0.0)) {
            Ok(v)
        } else {
            let bound = if zero { "0 or more" } else { "above 0" };
            Err(format!("'{text}': {option} is a length in mm, {bound}"))
        }
    }
}

fn positive(option: &'static str) -> impl Fn(&str) -> Result<f64, String> + Clone {
    length(option, false)
}

fn not_negative(option: &'static str) -> impl Fn(&str) -> Result<f64, String> + Clone {
    length(option, true)
}

/// A blank that does not cover the trim line with the margin: exit code 1, files kept.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct NotCovered(pub String);

pub fn run(args: &Args) -> anyhow::Result<()> {
    with_threads(args.threads, || outline(args))
}

fn outline(args: &Args) -> anyhow::Result<()> {
    let interrupt = Interrupt::install()?;
    let scenario = Scenario::load(&args.scenario, &args.overrides)?;
    if !scenario.boundary.is_empty() {
        anyhow::bail!(
            "{}: blank-outline meshes the whole blank to its outline and has no node sets for \
             [[boundary]] (symmetry planes, clamps): give it the full part's scenario",
            scenario.origin
        );
    }
    let trim = trim_line(args)?;
    let size = crate::forming::outline::iterate::element_size(&scenario)
        .map_err(|e| anyhow::anyhow!(e))?;
    let settings = OutlineSettings {
        margin: args.margin,
        iterations: args.iterations as usize,
        tolerance: args.tolerance.unwrap_or(0.25 * size),
    };
    let dir = args
        .output
        .clone()
        .unwrap_or_else(|| scenario.output.folder.join("outline"));
    let _lock = take_output_folder(&dir, &outline_products())?;
    println!(
        "trim line {} ({} points, {}), margin {} mm, tolerance {} mm, at most {} forming runs \
         on {} mm cells",
        trim.origin,
        trim.points.len(),
        if trim.in_plan {
            "plan view"
        } else {
            "on the part"
        },
        settings.margin,
        settings.tolerance,
        settings.iterations,
        size
    );
    let stop = interrupt.running();
    let mut runner = |s: &Scenario, folder: &Path| forming_run(s, folder, stop);
    let result = iterate(&scenario, &trim, &settings, &dir, &mut runner, &mut |r| {
        print_iteration(r, &settings)
    })?;
    let mut files = write_outline(&dir, &result)?;
    files.push(write_picture(&dir, &trim, &result)?);
    print_summary(&trim, &settings, &result, &dir, &files);
    if !result.covered {
        let chosen = result.chosen();
        return Err(NotCovered(format!(
            "after {} iterations the blank does not cover the trim line with the margin: the \
             trim line lies {:.2} mm inside the edge at the least (asked {} mm, tolerance {} mm); \
             more --iterations, or a finer blank (blank.element_size); files kept in {}",
            result.history.len(),
            chosen.coverage.min,
            settings.margin,
            settings.tolerance,
            dir.display()
        ))
        .into());
    }
    Ok(())
}

/// The trim line of `--trim` or `--trim-circle`.
fn trim_line(args: &Args) -> anyhow::Result<TrimLine> {
    match (&args.trim, args.trim_circle) {
        (Some(path), _) => Ok(read_trim_csv(path)?),
        // chords of about a degree: the circle is resampled finer where the cells ask for it
        (None, Some(radius)) => Ok(trim_circle(radius, 360)),
        (None, None) => anyhow::bail!("give the trim line: --trim trim.csv or --trim-circle R"),
    }
}

/// The files of the outline folder, by which a later command clears them.
fn outline_products() -> ProductFiles {
    let mut names: Vec<String> = ["outline.csv", "outline.dxf", "outline.png", HISTORY_CSV]
        .into_iter()
        .map(String::from)
        .collect();
    names.extend((1..=MAX_ITERATIONS).map(outline_csv_name));
    ProductFiles {
        names,
        series: None,
    }
}

/// One forming run into `folder`, as `thermostamp run` makes it: its lock, its live files,
/// a progress bar, its pictures and formed blank.
fn forming_run(
    s: &Scenario,
    folder: &Path,
    stop: &AtomicBool,
) -> anyhow::Result<(FormingModel, crate::forming::FormingRun)> {
    let forming = FormingModel::new(s).map_err(|e| anyhow::anyhow!(e))?;
    for note in &forming.notes {
        eprintln!("note: {note}");
    }
    let _lock = take_output_folder(folder, &products())?;
    let output = live_output(folder, s, &forming)?;
    let result = watched_run(&forming, output, stop);
    if !result.records.is_empty() {
        write_final_results(folder, s, &forming, &result)?;
    }
    Ok((forming, result))
}

fn print_iteration(r: &IterationRecord, settings: &OutlineSettings) {
    println!(
        "iteration {}: margin {:.2} to {:.2} mm (asked {} mm), error {:.2} mm{}, blank {:.0} \
         mm^2, {:.1} s",
        r.iteration,
        r.coverage.min,
        r.coverage.max,
        settings.margin,
        r.coverage.error,
        if r.coverage.error < settings.tolerance {
            " (within the tolerance)"
        } else {
            ""
        },
        r.area,
        r.wall_seconds
    );
}

/// `outline.csv` and `outline.dxf` of the chosen iteration's outline.
fn write_outline(dir: &Path, result: &OutlineResult) -> anyhow::Result<Vec<PathBuf>> {
    let outline = &result.chosen().outline;
    let csv = dir.join("outline.csv");
    write_outline_csv(&csv, outline)?;
    let dxf = dir.join("outline.dxf");
    let points: Vec<[f64; 2]> = outline.iter().map(|p| [p.x, p.y]).collect();
    crate::io::dxf::write_dxf(&dxf, &points, DXF_LAYER)
        .map_err(|e| anyhow::anyhow!("cannot write {}: {e}", dxf.display()))?;
    Ok(vec![csv, dxf, dir.join(HISTORY_CSV)])
}

/// `outline.png`: the trim line in plan, each iteration's outline and the trim line mapped
/// onto the flat blank by the chosen iteration's run, on the flat blank's axes.
fn write_picture(dir: &Path, trim: &TrimLine, result: &OutlineResult) -> anyhow::Result<PathBuf> {
    let closed = |p: &[nalgebra::Vector2<f64>]| -> Vec<(f64, f64)> {
        p.iter().chain(p.first()).map(|v| (v.x, v.y)).collect()
    };
    let mut series = vec![Series::new(
        "trim line, plan view of the part",
        closed(&trim.plan()),
        LineStyle::Dashed,
    )];
    for r in &result.history {
        series.push(Series::new(
            format!("outline {}", r.iteration),
            closed(&r.outline),
            LineStyle::Solid,
        ));
    }
    let chosen = result.chosen();
    series.push(Series::new(
        format!("trim line on the flat blank (run {})", chosen.iteration),
        closed(&chosen.mapped),
        LineStyle::Dashed,
    ));
    let plot = LinePlot {
        title: "Flat blank outline".into(),
        x_label: "x (mm)".into(),
        y_label: "y (mm)".into(),
        series,
    };
    let path = dir.join("outline.png");
    write_png(&path, &plot, 800, 800)?;
    Ok(path)
}

fn print_summary(
    trim: &TrimLine,
    settings: &OutlineSettings,
    result: &OutlineResult,
    dir: &Path,
    files: &[PathBuf],
) {
    let chosen = result.chosen();
    let status = match (result.converged, result.covered) {
        (true, _) => format!("converged in {} iterations", result.history.len()),
        (false, true) => format!(
            "covered, not converged in {} iterations: the margin is up to {:.2} mm wider than \
             asked",
            result.history.len(),
            chosen.coverage.max - settings.margin
        ),
        (false, false) => format!("NOT covered after {} iterations", result.history.len()),
    };
    let (lo, hi) = extent(&chosen.outline);
    let wall: f64 = result.history.iter().map(|r| r.wall_seconds).sum();
    let rows = vec![
        ("status", status),
        (
            "trim line",
            format!("{} ({} points)", trim.origin, trim.points.len()),
        ),
        ("first guess", result.first_guess.1.clone()),
        (
            "outline",
            format!(
                "{} ({}), {} points, x {:.1} to {:.1} mm, y {:.1} to {:.1} mm",
                outline_csv_name(chosen.iteration),
                chosen.folder.display(),
                chosen.outline.len(),
                lo.x,
                hi.x,
                lo.y,
                hi.y
            ),
        ),
        (
            "blank area",
            format!(
                "{:.0} mm^2 (outline {:.0} mm^2)",
                chosen.area,
                polygon::signed_area(&chosen.outline)
            ),
        ),
        (
            "margin achieved",
            format!(
                "{:.2} to {:.2} mm (asked {} mm, tolerance {} mm)",
                chosen.coverage.min, chosen.coverage.max, settings.margin, settings.tolerance
            ),
        ),
        (
            "wall time",
            format!("{wall:.1} s in {} forming runs", result.history.len()),
        ),
        ("folder", dir.display().to_string()),
    ];
    print_table(&rows, files);
}

fn extent(p: &[nalgebra::Vector2<f64>]) -> (nalgebra::Vector2<f64>, nalgebra::Vector2<f64>) {
    p.iter().fold(
        (
            nalgebra::Vector2::repeat(f64::INFINITY),
            nalgebra::Vector2::repeat(f64::NEG_INFINITY),
        ),
        |(lo, hi), x| (lo.inf(x), hi.sup(x)),
    )
}
