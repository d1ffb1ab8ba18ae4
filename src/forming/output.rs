//! What a forming run writes into its output folder (docs/guide/outputs.md), for every front end
//! (the command line, the Python package): the history `forming.csv`, a row per record as the
//! run goes; the ParaView series; and once it has stopped, the result row
//! `forming-result.csv`, the pictures and the formed blank for the next analysis.

use super::export::{write_formed_blank, FORMED_INP, FORMED_VTU};
use super::pictures::{write_pictures, PICTURES};
use super::run::{ply_columns, ply_measures, shear_angles, RESULT_COLUMNS, RESULT_CSV};
use super::{FormingModel, FormingRecord, FormingRun, Scenario};
use crate::experiment::sheet_test::{FrameOutput, HistorySink, LiveOutput};
use crate::io::output_folder::ProductFiles;
use crate::io::vtk::PvdSeries;
use crate::io::CsvStream;
use crate::solver::error::outcome_status;
use anyhow::Context;
use std::path::{Path, PathBuf};

/// The history file.
pub const HISTORY_CSV: &str = "forming.csv";
/// The ParaView series: `forming.pvd` and its frames.
pub const SERIES: &str = "forming";

/// The history's columns. `time` is process time, the solver's `solver_time` times
/// `process.time_scaling`, as the frames' times are.
pub const HISTORY_COLUMNS: [&str; 27] = [
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
    "temperature_min",
    "temperature_mean",
    "temperature_max",
    "frozen_area",
    "die_force",
    "spring_force",
    "gripper_force",
    "sag",
    "solver_time",
];

/// One record as a row of [`HISTORY_COLUMNS`].
pub fn history_row(r: &FormingRecord, time_scaling: f64) -> [f64; 27] {
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
        r.temperature.min,
        r.temperature.mean,
        r.temperature.max,
        r.frozen_area,
        r.die_force,
        r.supports.springs,
        r.supports.grippers,
        r.supports.sag,
        r.time,
    ]
}

/// The files a run writes, by which a later run into the folder finds and clears them.
pub fn products() -> ProductFiles {
    ProductFiles {
        names: [HISTORY_CSV, RESULT_CSV, FORMED_INP, FORMED_VTU]
            .into_iter()
            .chain(PICTURES)
            .map(String::from)
            .collect(),
        series: Some(SERIES.into()),
    }
}

/// What the run writes while it goes into `dir`: the history and, where the scenario asks for
/// them, the ParaView frames.
pub fn live_output<'a>(
    dir: &Path,
    scenario: &Scenario,
    forming: &FormingModel,
) -> anyhow::Result<LiveOutput<'a, FormingRecord>> {
    let history = history_sink(
        CsvStream::create(&dir.join(HISTORY_CSV), &HISTORY_COLUMNS)?,
        scenario.process.time_scaling,
    );
    let frames = match scenario.output.frames {
        0 => None,
        n => Some(FrameOutput::new(
            PvdSeries::new(dir, SERIES)?,
            (n, forming.settings.end_time),
            scenario.process.time_scaling,
        )),
    };
    Ok(LiveOutput {
        history: Some(history),
        frames,
    })
}

/// The CSV history, a row written as each record is taken.
fn history_sink<'a>(mut csv: CsvStream, time_scaling: f64) -> HistorySink<'a, FormingRecord> {
    Box::new(move |records: &[FormingRecord]| {
        if let Some(newest) = records.last() {
            csv.write_row(&history_row(newest, time_scaling))?;
        }
        Ok(())
    })
}

/// What a run writes once it has stopped: the result row, the pictures and the formed blank.
/// Returns every file of the run, the history and the series first.
pub fn write_final_results(
    dir: &Path,
    scenario: &Scenario,
    forming: &FormingModel,
    result: &FormingRun,
) -> anyhow::Result<Vec<PathBuf>> {
    let mut files = vec![dir.join(HISTORY_CSV)];
    files.push(write_result_row(
        dir,
        &result_row(scenario, forming, result),
    )?);
    let pictures = write_pictures(dir, scenario, forming, result)?;
    files.extend(pictures.into_iter().map(|p| p.path));
    if let Some(state) = result.formed_state() {
        files.extend(write_formed_blank(dir, &forming.model, state)?);
    }
    if scenario.output.frames > 0 {
        files.push(dir.join(format!("{SERIES}.pvd")));
    }
    Ok(files)
}

/// The columns a non-isothermal run adds to its result row, after the plies': the blank's
/// coldest, mean and hottest temperature (°C) and its frozen area (mm²) at the end.
pub const THERMAL_RESULT_COLUMNS: [&str; 4] = [
    "temperature_min",
    "temperature_mean",
    "temperature_max",
    "frozen_area",
];

/// The run's final measures: how it ended and [`RESULT_COLUMNS`] after the status, then five
/// columns per ply of a layup ([`ply_columns`]); `None` where the run has no value (a flange
/// measure on tools without a flange, a run stopped before its first record).
#[derive(Clone, Debug, PartialEq)]
pub struct ResultRow {
    pub status: String,
    /// The names of `values`: [`RESULT_COLUMNS`] without `status`, then the plies' columns.
    pub names: Vec<String>,
    pub values: Vec<Option<f64>>,
}

/// [`ResultRow`] of a run. The area above the locking angle is the reference area (mm^2) of
/// the elements sheared beyond `output.locking_angle`; the largest thinning is `1 - t / t0`
/// of the thinnest element.
pub fn result_row(scenario: &Scenario, forming: &FormingModel, result: &FormingRun) -> ResultRow {
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
    let peak = result
        .records
        .iter()
        .map(|r| r.punch_force)
        .fold(0.0, f64::max);
    let mut values = vec![
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
    let mut names: Vec<String> = RESULT_COLUMNS[1..].iter().map(|c| c.to_string()).collect();
    if model.plies.len() > 1 {
        let plies = result
            .formed_state()
            .map(|state| ply_measures(forming, state));
        for k in 0..model.plies.len() {
            names.extend(ply_columns(k + 1));
            let ply = plies.as_ref().map(|p| p[k]);
            values.extend([
                ply.map(|p| p.max_shear),
                ply.map(|p| p.max_slip),
                ply.map(|p| p.draw_in),
                ply.and_then(|p| flange(p.wrinkles.height)),
                ply.and_then(|p| flange(p.wrinkles.waviness)),
            ]);
        }
    }
    if model.heat.is_some() {
        names.extend(THERMAL_RESULT_COLUMNS.map(String::from));
        values.extend([
            last.map(|r| r.temperature.min),
            last.map(|r| r.temperature.mean),
            last.map(|r| r.temperature.max),
            last.map(|r| r.frozen_area),
        ]);
    }
    ResultRow {
        status: outcome_status(&result.outcome),
        names,
        values,
    }
}

/// `forming-result.csv`: a header and one row, the status quoted.
fn write_result_row(dir: &Path, row: &ResultRow) -> anyhow::Result<PathBuf> {
    let number = |v: &Option<f64>| v.map_or(String::new(), |v| format!("{v:e}"));
    let header: Vec<&str> = std::iter::once(RESULT_COLUMNS[0])
        .chain(row.names.iter().map(String::as_str))
        .collect();
    let fields: Vec<String> = std::iter::once(format!("\"{}\"", row.status.replace('"', "'")))
        .chain(row.values.iter().map(number))
        .collect();
    let path = dir.join(RESULT_CSV);
    crate::io::product_file::write(
        &path,
        format!("{}\n{}\n", header.join(","), fields.join(",")).as_bytes(),
    )
    .with_context(|| format!("cannot write {}", path.display()))?;
    Ok(path)
}
