//! `thermostamp run scenario.toml`: a thermo-stamping run writing its files
//! (`forming::output`), with a progress bar and a summary table.

use super::shared::{
    print_checked_table, status_row, take_output_folder, with_threads, Bar, Interrupt,
    ScenarioArgs, Watch,
};
use crate::experiment::sheet_test::LiveOutput;
use crate::forming::advice::stop_advice;
use crate::forming::output::{live_output, products, write_final_results};
use crate::forming::preflight::implicit_advice;
use crate::forming::run::{frozen_areas, ply_measures};
use crate::forming::FormingRecord;
use crate::forming::{run::FormingRun, FormingModel, Scenario};
use crate::solver::estimate::RunEstimate;
use crate::solver::SolverKind;
use crate::thermal::blank::FieldExtremes;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;

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
    let output = live_output(&dir, &scenario, &forming)?;
    eprintln!("{}", describe(&forming.estimate, forming.solver));
    if let Some(advice) = implicit_advice(&scenario, &forming.estimate) {
        eprintln!("note: {advice}");
    }
    let result = watched_run(&forming, output, stop);
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
    print_summary(&scenario, &forming, &result, &files);
    if let Some(warning) = frozen_warning(&forming, &result) {
        eprintln!("{warning}");
    }
    if let Some(advice) = stop_advice(&scenario, &forming, &result) {
        eprintln!("{advice}");
    }
    result.outcome.map(|_| ()).map_err(anyhow::Error::from)
}

/// The forming run of `forming` writing `output` as it goes, with a progress bar, stopped
/// when `stop` is raised (Ctrl-C): what `thermostamp run` and `blank-outline` both run.
pub(super) fn watched_run(
    forming: &FormingModel,
    output: LiveOutput<'_, FormingRecord>,
    stop: &AtomicBool,
) -> FormingRun {
    let mut bar = Bar::new(forming.settings.end_time);
    let mut watch = Watch {
        bar: &mut bar,
        stop,
    };
    let result = crate::forming::run::run(forming, Some(output), Some(&mut watch));
    bar.finish();
    result
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
    rows.extend(motion_rows(forming, result));
    if let Some(state) = result.formed_state() {
        rows.extend(ply_rows(forming, state));
        rows.extend(heat_rows(scenario, forming, result, state));
    }
    print_checked_table(&rows, &result.checks, &forming.estimate, files);
}

/// The stages, the dies' closing force, the sag under gravity before the tools touch and what
/// the springs and grippers hold; none of them in a single stroke without supports.
fn motion_rows(forming: &FormingModel, result: &FormingRun) -> Vec<(&'static str, String)> {
    let mut rows = Vec::new();
    if !forming.stages.is_empty() {
        let stages: Vec<String> = forming
            .stages
            .iter()
            .enumerate()
            .map(|(i, (from, to, travel))| format!("{} {from:.3}-{to:.3} s, {travel:.3} mm", i + 1))
            .collect();
        rows.push(("stages", stages.join("; ")));
    }
    let records = &result.records;
    let peak = |f: fn(&FormingRecord) -> f64| records.iter().map(f).fold(0.0, f64::max);
    if forming.punch_path.is_some() || !forming.stages.is_empty() {
        rows.push((
            "peak die closing force",
            format!("{:.2} N", peak(|r| r.die_force)),
        ));
    }
    let supports = &forming.model.supports;
    if let Some(g) = &supports.gravity {
        let masses: f64 = forming.model.physical_nodal_masses().iter().sum();
        let weight = masses * g.acceleration.norm();
        rows.push((
            "sag before the tools touch",
            sag_before_contact(records, weight),
        ));
    }
    let holds: [(&'static str, usize, Measure); 2] = [
        ("springs", supports.springs.len(), |r| r.supports.springs),
        ("grippers", supports.grippers.len(), |r| r.supports.grippers),
    ];
    for (name, count, force) in holds {
        if let (Some(last), true) = (records.last(), count > 0) {
            rows.push((
                name,
                format!(
                    "{count} holding {:.3} N at the end, {:.3} N at most",
                    force(last),
                    peak(force)
                ),
            ));
        }
    }
    rows
}

/// What a summary row reads of each record.
type Measure = fn(&FormingRecord) -> f64;

/// The blank's sag at the last record before any tool touched it: before the tools carry a
/// hundredth of the blank's `weight` (N), as the contact's springs engage a little before the
/// faces meet.
fn sag_before_contact(records: &[FormingRecord], weight: f64) -> String {
    let free = records
        .iter()
        .take_while(|r| {
            r.punch_force.abs() + r.holder_force.abs() + r.die_force.abs() < 0.01 * weight
        })
        .last();
    match free {
        Some(r) => format!("{:.3} mm (at {:.3} s)", r.supports.sag, r.time),
        None => "the tools touch the blank from the start".into(),
    }
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

/// A non-isothermal run's rows: the blank's temperatures at the start and the end of the
/// stroke, the area that froze (layer by layer) and where the heat went.
fn heat_rows(
    scenario: &Scenario,
    forming: &FormingModel,
    result: &FormingRun,
    state: &crate::solver::State,
) -> Vec<(&'static str, String)> {
    let (Some(heat), Some(thermal), Some(first), Some(last)) = (
        &scenario.heat,
        &state.thermal,
        result.records.first(),
        result.records.last(),
    ) else {
        return Vec::new();
    };
    let range = |t: &FieldExtremes| format!("{:.1} to {:.1} °C (mean {:.1})", t.min, t.max, t.mean);
    let mut tools = format!("punch {} °C, die {} °C", heat.punch, heat.die);
    if let (Some(h), true) = (heat.holder, forming.holder_tool.is_some()) {
        tools += &format!(", holder {h} °C");
    }
    let mut rows = vec![
        (
            "blank temperature",
            format!(
                "{} °C out of the oven, {} s in air: {} at the stroke's start, {} at its end",
                heat.blank_temperature,
                heat.transfer_time,
                range(&first.temperature),
                range(&last.temperature)
            ),
        ),
        ("tools", tools),
    ];
    if let Some((per_layer, any)) = frozen_areas(&forming.model, state) {
        let layers = forming.model.plies[0].laminate.layers();
        let by_layer: Vec<String> = per_layer
            .iter()
            .zip(layers)
            .enumerate()
            .map(|(l, (a, layer))| format!("layer {} ({}) {a:.0}", l + 1, layer.law.name()))
            .collect();
        rows.push((
            "frozen",
            format!(
                "{any:.0} mm^2 of the blank froze before the end of the stroke ({} mm^2)",
                by_layer.join(", ")
            ),
        ));
    }
    let q = &thermal.heat;
    let joules = |x: f64| x * 1e-3;
    let to_tools: f64 = q.to_tools.iter().sum();
    rows.push((
        "heat equation",
        format!(
            "{:.2} s of the run's {:.1} s of wall time ({:.1} %)",
            thermal.wall_seconds,
            result.wall_seconds,
            100.0 * thermal.wall_seconds / result.wall_seconds.max(1e-9)
        ),
    ));
    rows.push((
        "heat",
        format!(
            "{:.2} J into the tools, {:.2} J into the air, {:.2} J released by crystallisation, \
             {:.2} J of friction; the blank's heat content changed by {:.2} J (balance {:.1e} \
             of the largest flow)",
            joules(to_tools),
            joules(q.to_air),
            joules(q.latent),
            joules(q.friction),
            joules(q.stored),
            q.imbalance().abs() / q.scale().max(f64::MIN_POSITIVE)
        ),
    ));
    rows
}

/// Where a non-isothermal run left frozen layers before the end of the stroke: what an engineer
/// must know before trusting the part's shape there.
fn frozen_warning(forming: &FormingModel, result: &FormingRun) -> Option<String> {
    let state = result.formed_state()?;
    let (_, any) = frozen_areas(&forming.model, state)?;
    (any > 0.0).then(|| {
        format!(
            "warning: {any:.0} mm^2 of the blank froze before the end of the stroke (a layer's \
             crystallinity past the card's frozen_at): it stopped flowing there, and the part \
             may not take the tool's shape; see the frames' `frozen` and temperature-map.png \
             (hotter blank, warmer tools or a shorter transfer)"
        )
    })
}

/// The solver, and for the implicit one its increments, iterations and time split.
fn solver_row(forming: &FormingModel, result: &FormingRun) -> String {
    match &result.implicit {
        Some(s) => super::shared::implicit_summary(s),
        None => forming.solver.name().to_string(),
    }
}
