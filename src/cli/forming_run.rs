//! `thermostamp run scenario.toml`: a thermo-stamping run with CSV history, ParaView frames, the
//! pictures (`forming_pictures`), a progress bar and a summary table.

use super::forming_pictures::{write_pictures, PICTURES};
use super::shared::{
    print_checked_table, status_row, take_output_folder, with_threads, Bar, Interrupt,
    ScenarioArgs, Watch,
};
use crate::experiment::sheet_test::{FrameOutput, HistorySink, LiveOutput};
use crate::forming::advice::stop_advice;
use crate::forming::export::{write_formed_blank, FORMED_INP, FORMED_VTU};
use crate::forming::preflight::implicit_advice;
use crate::forming::run::{ply_columns, ply_measures, shear_angles, RESULT_COLUMNS, RESULT_CSV};
use crate::forming::{run::FormingRun, FormingModel, FormingRecord, Scenario};
use crate::io::output_folder::ProductFiles;
use crate::io::vtk::PvdSeries;
use crate::io::CsvStream;
use crate::solver::estimate::RunEstimate;
use crate::solver::SolverKind;
use anyhow::Context;
use std::path::{Path, PathBuf};

#[derive(clap::Args, Debug)]
#[command(after_help = super::shared::SCENARIO_REFERENCE)]
pub struct Args {
    #[command(flatten)]
    scenario: ScenarioArgs,
    /// Worker threads for the element loop (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
}

/// Cells from which the estimate from the scenario's keys is printed before the set-up: the
/// set-up of such a blank takes seconds (its bending patches choose their nodes at about a
/// millisecond a cell), of a smaller one a fraction of a second, after which the estimate of
/// the built model is printed anyway.
const EARLY_ESTIMATE_ELEMENTS: usize = 5_000;

/// The estimate's line: the explicit solver's steps, or the implicit solver's increments.
fn describe(estimate: &RunEstimate, solver: SolverKind) -> String {
    match solver {
        SolverKind::Explicit => estimate.describe(),
        SolverKind::Implicit => estimate.describe_increments(),
    }
}

pub fn run(args: &Args) -> anyhow::Result<()> {
    with_threads(args.threads, || forming(args))
}

fn forming(args: &Args) -> anyhow::Result<()> {
    let interrupt = Interrupt::install()?;
    let (scenario, dir) = args.scenario.load()?;
    let forming = FormingModel::reporting(&scenario, &mut |estimate| {
        if estimate.size.elements >= EARLY_ESTIMATE_ELEMENTS {
            eprintln!(
                "{} (from the scenario, before set-up; Ctrl-C stops it)",
                describe(estimate, scenario.process.solver)
            );
        }
    })
    .map_err(|e| anyhow::anyhow!(e))?;
    let stop = interrupt.running();
    for note in &forming.notes {
        eprintln!("note: {note}");
    }
    let _lock = take_output_folder(&dir, &products())?;
    let csv = dir.join(CSV);
    let output = LiveOutput {
        history: Some(history(
            CsvStream::create(&csv, &COLUMNS)?,
            scenario.process.time_scaling,
        )),
        frames: match scenario.output.frames {
            0 => None,
            n => Some(FrameOutput::new(
                PvdSeries::new(&dir, SERIES)?,
                (n, forming.settings.end_time),
                scenario.process.time_scaling,
            )),
        },
    };
    eprintln!("{}", describe(&forming.estimate, forming.solver));
    if let Some(advice) = implicit_advice(&scenario, &forming.estimate) {
        eprintln!("note: {advice}");
    }
    let mut bar = Bar::new(forming.settings.end_time);
    let mut watch = Watch {
        bar: &mut bar,
        stop,
    };
    let result = crate::forming::run::run(&forming, Some(output), Some(&mut watch));
    bar.finish();
    if result.records.is_empty() {
        return result.outcome.map(|_| ()).map_err(anyhow::Error::from);
    }
    let files = match write_final_results(&dir, &scenario, &forming, &result) {
        Ok(files) => files,
        // a run stopped by a result it could not write (a full disk) says so, not what failed
        // after it for the same reason
        Err(later) => match result.outcome {
            Ok(_) => return Err(later),
            Err(stopped) => return Err(anyhow::Error::from(stopped)),
        },
    };
    let mut files = std::iter::once(csv).chain(files).collect::<Vec<_>>();
    if scenario.output.frames > 0 {
        files.push(dir.join(format!("{SERIES}.pvd")));
    }
    print_summary(&scenario, &forming, &result, &files);
    if let Some(advice) = stop_advice(&scenario, &forming, &result) {
        eprintln!("{advice}");
    }
    result.outcome.map(|_| ()).map_err(anyhow::Error::from)
}

/// What a run writes once it has stopped: the result row, the pictures and the formed blank;
/// the files written.
fn write_final_results(
    dir: &Path,
    scenario: &Scenario,
    forming: &FormingModel,
    result: &FormingRun,
) -> anyhow::Result<Vec<PathBuf>> {
    let mut files = vec![write_result_row(dir, scenario, forming, result)?];
    let pictures = write_pictures(dir, scenario, forming, result)?;
    files.extend(pictures.into_iter().map(|p| p.path));
    if let Some(state) = result.formed_state() {
        files.extend(write_formed_blank(dir, &forming.model, state)?);
    }
    Ok(files)
}

/// `time` is process time, the solver's `solver_time` times `process.time_scaling`, as the
/// frames' times are.
const COLUMNS: [&str; 19] = [
    "time",
    "stroke",
    "punch_force",
    "holder_force",
    "holder_travel",
    "draw_in",
    "max_shear_deg",
    "wrinkle_height",
    "wrinkle_area",
    "waviness",
    "wavy_area",
    "kinetic",
    "internal_work",
    "elastic",
    "viscous_dissipation",
    "tool_work",
    "external_work",
    "energy_balance_error",
    "solver_time",
];

fn row(r: &FormingRecord, time_scaling: f64) -> [f64; 19] {
    let e = &r.energies;
    [
        r.time * time_scaling,
        r.stroke,
        r.punch_force,
        r.holder_force,
        r.holder_travel,
        r.draw_in,
        r.max_shear,
        r.wrinkles.height,
        r.wrinkles.area,
        r.wrinkles.waviness,
        r.wrinkles.wavy_area,
        e.kinetic,
        e.internal_work,
        e.elastic,
        e.viscous_dissipation(),
        e.tool_work,
        e.external_work,
        e.balance_error(),
        r.time,
    ]
}

/// The files a run writes, by which a later run into the folder finds and clears them.
const CSV: &str = "forming.csv";

const SERIES: &str = "forming";

fn products() -> ProductFiles {
    ProductFiles {
        names: [CSV, RESULT_CSV, FORMED_INP, FORMED_VTU]
            .into_iter()
            .chain(PICTURES)
            .map(String::from)
            .collect(),
        series: Some(SERIES.into()),
    }
}

/// The CSV history, a row written as each record is taken.
fn history<'a>(mut csv: CsvStream, time_scaling: f64) -> HistorySink<'a, FormingRecord> {
    Box::new(move |records: &[FormingRecord]| {
        if let Some(newest) = records.last() {
            csv.write_row(&row(newest, time_scaling))?;
        }
        Ok(())
    })
}

/// `forming-result.csv`: a header and one row, [`RESULT_COLUMNS`]. The area above the locking
/// angle is the reference area (mm^2) of the elements sheared beyond `output.locking_angle`; the
/// largest thinning is `1 - t / t0` of the thinnest element.
fn write_result_row(
    dir: &Path,
    scenario: &Scenario,
    forming: &FormingModel,
    result: &FormingRun,
) -> anyhow::Result<PathBuf> {
    let last = result.records.last();
    let model = &forming.model;
    let (above_locking, thinning) = match result.formed_state() {
        Some(state) => {
            let gamma = shear_angles(model, state);
            let above = scenario.output.locking_angle.map(|limit| {
                model
                    .elements
                    .iter()
                    .zip(&gamma)
                    .filter(|(_, g)| g.abs() > limit)
                    .map(|(e, _)| e.area)
                    .fold(0.0, |sum, a| sum + a)
            });
            let thinnest = state
                .membrane
                .iter()
                .enumerate()
                .map(|(k, m)| m.thickness / model.thickness(k))
                .fold(f64::INFINITY, f64::min);
            (above, Some(1.0 - thinnest))
        }
        None => (None, None),
    };
    let flange = |v: f64| forming.measures_flange().then_some(v);
    let number = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v:e}"));
    let peak = result
        .records
        .iter()
        .map(|r| r.punch_force)
        .fold(0.0, f64::max);
    let status = status_row(&result.outcome).1.replace('"', "'");
    let values = [
        last.map(|r| r.stroke),
        Some(peak),
        last.map(|r| r.max_shear),
        above_locking,
        thinning,
        last.and_then(|r| flange(r.wrinkles.height)),
        last.and_then(|r| flange(r.wrinkles.area)),
        last.and_then(|r| flange(r.wrinkles.waviness)),
        last.and_then(|r| flange(r.wrinkles.wavy_area)),
        last.map(|r| r.draw_in),
        last.map(|r| r.energies.balance_error()),
    ];
    let mut row: Vec<String> = std::iter::once(format!("\"{status}\""))
        .chain(values.into_iter().map(number))
        .collect();
    let mut header: Vec<String> = RESULT_COLUMNS.iter().map(|c| c.to_string()).collect();
    if model.plies.len() > 1 {
        let plies = result
            .formed_state()
            .map(|state| ply_measures(forming, state));
        for k in 0..model.plies.len() {
            header.extend(ply_columns(k + 1));
            let ply = plies.as_ref().map(|p| p[k]);
            row.extend(
                [
                    ply.map(|p| p.max_shear),
                    ply.map(|p| p.max_slip),
                    ply.map(|p| p.draw_in),
                    ply.and_then(|p| flange(p.wrinkles.height)),
                    ply.and_then(|p| flange(p.wrinkles.waviness)),
                ]
                .map(number),
            );
        }
    }
    let path = dir.join(RESULT_CSV);
    crate::io::product_file::write(
        &path,
        format!("{}\n{}\n", header.join(","), row.join(",")).as_bytes(),
    )
    .with_context(|| format!("cannot write {}", path.display()))?;
    Ok(path)
}

/// A flange measure, or why there is none (tools from files without `tools.flange_radius`).
fn flange_measure(forming: &FormingModel, value: impl Fn() -> String) -> String {
    if forming.measures_flange() {
        value()
    } else {
        "not measured: give tools.flange_radius (where the die's flat face begins)".into()
    }
}

fn print_summary(
    scenario: &Scenario,
    forming: &FormingModel,
    result: &FormingRun,
    files: &[PathBuf],
) {
    let last = result.records.last();
    let peak_force = result
        .records
        .iter()
        .map(|r| r.punch_force)
        .fold(0.0, f64::max);
    let elements = forming.model.elements.len();
    let mut rows = vec![
        status_row(&result.outcome),
        ("scenario", scenario.origin.clone()),
    ];
    rows.extend(scenario.output.note.clone().map(|n| ("note", n)));
    rows.extend([
        (
            "blank",
            format!(
                "{} elements, {} nodes, bending {}",
                elements,
                forming.model.mesh.nodes.len(),
                if forming.model.bending.is_some() {
                    "on"
                } else {
                    "off (the card has no [bending])"
                }
            ),
        ),
        ("solver", solver_row(forming, result)),
        ("steps", format!("{}", result.steps)),
        (
            "stroke reached",
            format!("{:.2} mm", last.map_or(0.0, |r| r.stroke)),
        ),
        ("peak punch force", format!("{peak_force:.2} N")),
        (
            "largest shear angle",
            format!("{:.1}°", last.map_or(0.0, |r| r.max_shear)),
        ),
        (
            "flange off the die",
            flange_measure(forming, || {
                format!(
                    "{:.2} mm at most, {:.0} mm^2 lifted by more than half the ply",
                    last.map_or(0.0, |r| r.wrinkles.height),
                    last.map_or(0.0, |r| r.wrinkles.area)
                )
            }),
        ),
        (
            "flange waviness",
            flange_measure(forming, || {
                format!(
                    "{:.2} mm amplitude around the part, over {:.0} mm^2",
                    last.map_or(0.0, |r| r.wrinkles.waviness),
                    last.map_or(0.0, |r| r.wrinkles.wavy_area)
                )
            }),
        ),
        (
            "draw-in of the edge",
            format!("{:.2} mm", last.map_or(0.0, |r| r.draw_in)),
        ),
        (
            "energy balance error",
            format!(
                "{:.3} % of external work",
                100.0 * last.map_or(0.0, |r| r.energies.balance_error())
            ),
        ),
        (
            "time scaling",
            format!("{} (eta1 divided by it)", scenario.process.time_scaling),
        ),
        (
            "wall time",
            format!(
                "{:.1} s on {} threads ({:.2e} element-steps/s)",
                result.wall_seconds,
                rayon::current_num_threads(),
                (result.steps * elements) as f64 / result.wall_seconds.max(1e-9)
            ),
        ),
    ]);
    if let Some(state) = result.formed_state() {
        rows.extend(ply_rows(forming, state));
    }
    print_checked_table(&rows, &result.checks, &forming.estimate, files);
}

/// A layup's row per ply: its largest shear angle, how far it slid over its neighbours, its
/// edge's draw-in and its flange's lift-off and waviness.
fn ply_rows(forming: &FormingModel, state: &crate::solver::State) -> Vec<(&'static str, String)> {
    let model = &forming.model;
    if model.plies.len() < 2 {
        return Vec::new();
    }
    model
        .plies
        .iter()
        .zip(ply_measures(forming, state))
        .map(|(ply, m)| {
            let mut line = format!(
                "{}: largest shear {:.1}°, slid up to {:.2} mm over its neighbours, draw-in \
                 {:.2} mm",
                ply.name, m.max_shear, m.max_slip, m.draw_in
            );
            if forming.measures_flange() {
                line += &format!(
                    ", flange lift-off {:.2} mm, waviness {:.2} mm",
                    m.wrinkles.height, m.wrinkles.waviness
                );
            }
            ("ply", line)
        })
        .collect()
}

/// The solver, and for the implicit one its increments, iterations and time split.
fn solver_row(forming: &FormingModel, result: &FormingRun) -> String {
    match &result.implicit {
        Some(s) => super::shared::implicit_summary(s),
        None => forming.solver.name().to_string(),
    }
}
