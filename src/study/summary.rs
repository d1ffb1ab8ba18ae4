//! The study's summary (docs/study.md): `summary.csv`, one row per case (its parameters, how it
//! ended, the run's final measures from its `forming-result.csv`, its wall time), and charts of
//! the waviness and the largest shear angle over the parameters. Rebuilt from the case folders
//! alone, so that a sweep spread over several processes or machines has one summary.

use super::design::Design;
use super::file::{number, Case, Study};
use super::run::{finished, CaseResult};
use crate::forming::run::RESULT_CSV;
use crate::io::output_folder::ProductFiles;
use crate::io::plot::{
    write_map_png, write_png, LegendCell, LinePlot, LineStyle, MapPlot, Series, MISSING_COLOUR,
};
use plotters::style::RGBColor;
use std::path::{Path, PathBuf};

/// The run's final measures a summary row carries: the columns of its `forming-result.csv`
/// (`forming::run::RESULT_COLUMNS`) after the status, then a non-isothermal run's
/// (`forming::output::THERMAL_RESULT_COLUMNS`, empty for an isothermal case).
pub const MEASURES: [&str; 15] = [
    "stroke_reached",
    "peak_punch_force",
    "max_shear_deg",
    "area_above_locking",
    "max_thinning",
    "lift_off",
    "lifted_area",
    "waviness",
    "wavy_area",
    "draw_in",
    "energy_balance_error",
    "temperature_min",
    "temperature_mean",
    "temperature_max",
    "frozen_area",
];
pub const SUMMARY_CSV: &str = "summary.csv";
/// The charts: `study-<name>.png`.
const CHARTS: [&str; 3] = ["waviness", "max-shear", "peak-force"];

/// The files the summary writes into the study's folder, by which a later summary finds and
/// replaces them.
pub fn products() -> ProductFiles {
    ProductFiles {
        names: std::iter::once(SUMMARY_CSV.to_string())
            .chain(CHARTS.map(chart_name))
            .collect(),
        series: None,
    }
}

fn chart_name(name: &str) -> String {
    format!("study-{name}.png")
}

/// One case in the summary.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    pub case: Case,
    /// `done`, `failed` or `not run`.
    pub status: String,
    pub reason: String,
    /// [`MEASURES`], `None` where the case has no value.
    pub measures: Vec<Option<f64>>,
    pub wall_seconds: Option<f64>,
}

impl Row {
    fn measure(&self, name: &str) -> Option<f64> {
        let i = MEASURES.iter().position(|m| *m == name)?;
        self.measures[i]
    }
}

/// The summary's rows, read from the case folders.
pub fn rows(study: &Study) -> Vec<Row> {
    study
        .cases()
        .map(|case| {
            let folder = study.case_folder(case.number);
            let result = finished(&folder);
            row(case, &folder, result)
        })
        .collect()
}

fn row(case: Case, folder: &Path, result: Option<CaseResult>) -> Row {
    let measures = read_measures(&folder.join(RESULT_CSV));
    match result {
        Some(r) => Row {
            case,
            status: r.status,
            reason: r.reason,
            measures,
            wall_seconds: Some(r.wall_seconds),
        },
        None => Row {
            case,
            status: "not run".into(),
            reason: String::new(),
            measures: vec![None; MEASURES.len()],
            wall_seconds: None,
        },
    }
}

/// [`MEASURES`] from a run's `forming-result.csv`; all `None` without the file.
fn read_measures(path: &Path) -> Vec<Option<f64>> {
    let Ok(text) = std::fs::read_to_string(path) else {
        return vec![None; MEASURES.len()];
    };
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap_or("").split(',').collect();
    let values = split_csv_row(lines.next().unwrap_or(""));
    MEASURES
        .iter()
        .map(|m| {
            let i = header.iter().position(|h| h == m)?;
            values.get(i)?.parse::<f64>().ok()
        })
        .collect()
}

/// The fields of one CSV row whose first field may be quoted (and hold commas).
fn split_csv_row(line: &str) -> Vec<String> {
    if let Some(rest) = line.strip_prefix('"') {
        if let Some(end) = rest.find("\",") {
            let mut fields = vec![rest[..end].to_string()];
            fields.extend(rest[end + 2..].split(',').map(String::from));
            return fields;
        }
    }
    line.split(',').map(String::from).collect()
}

/// A CSV field: quoted when it holds a comma or a quote.
fn field(text: &str) -> String {
    if text.contains([',', '"', '\n']) {
        format!("\"{}\"", text.replace('"', "\"\"").replace('\n', " "))
    } else {
        text.to_string()
    }
}

/// The legend's cell of a wrinkled case (outlined), `threshold` the waviness above which a
/// case counts as wrinkled (mm).
fn wrinkled_legend(threshold: f64) -> LegendCell {
    LegendCell {
        label: format!("wrinkled: waviness above {threshold} mm"),
        fill: None,
        outlined: true,
    }
}

/// Writes `summary.csv` and the charts into the study's folder; returns the files written.
pub fn write_summary(study: &Study, rows: &[Row]) -> anyhow::Result<Vec<PathBuf>> {
    let mut header: Vec<String> = vec!["case".into()];
    header.extend(study.parameters.iter().map(|p| p.key.clone()));
    header.extend(["status".into(), "reason".into(), "wrinkled".into()]);
    header.extend(MEASURES.iter().map(|m| m.to_string()));
    header.push("wall_seconds".into());
    let mut text = header.join(",") + "\n";
    for r in rows {
        let mut fields = vec![r.case.number.to_string()];
        fields.extend(r.case.values.iter().map(|v| field(&value_text(v))));
        let wrinkled = r
            .measure("waviness")
            .map_or(String::new(), |w| (w > study.wrinkle_threshold).to_string());
        fields.extend([field(&r.status), field(&r.reason), wrinkled]);
        fields.extend(
            r.measures
                .iter()
                .map(|m| m.map_or(String::new(), |v| format!("{v:e}"))),
        );
        fields.push(r.wall_seconds.map_or(String::new(), |w| format!("{w:.2}")));
        text.push_str(&(fields.join(",") + "\n"));
    }
    let csv = study.folder.join(SUMMARY_CSV);
    crate::io::product_file::write(&csv, text.as_bytes())
        .map_err(|e| anyhow::anyhow!("cannot write {}: {e}", csv.display()))?;
    let mut files = vec![csv];
    files.extend(write_charts(study, rows)?);
    Ok(files)
}

/// A parameter value as text: a string without its quotes.
pub fn value_text(v: &toml::Value) -> String {
    match v {
        toml::Value::String(s) => s.clone(),
        other => other.to_string(),
    }
}

/// The charts of the waviness and of the largest shear angle: over the first two parameters a
/// heat map each (the other parameters at their first values), wrinkled cases flagged and
/// failed ones grey; over one parameter (or a non-numeric second one) a line chart each. A
/// sampled design's cases lie on no grid: a scatter of them each ([`scatter`]).
fn write_charts(study: &Study, rows: &[Row]) -> anyhow::Result<Vec<PathBuf>> {
    if matches!(study.design, Design::Sampled(_)) {
        return write_scatters(study, rows);
    }
    let numeric = |i: usize| {
        study
            .parameters
            .get(i)
            .is_some_and(|p| p.values.iter().all(|v| number(&v).is_some()))
    };
    let mut files = Vec::new();
    // cases whose parameters beyond the first two are at their first values
    let first_of_rest = |r: &&Row| {
        r.case
            .values
            .iter()
            .zip(&study.parameters)
            .skip(2)
            .all(|(v, p)| Some(v) == p.values.get(0).as_ref())
    };
    let shown: Vec<&Row> = rows.iter().filter(first_of_rest).collect();
    for (measure, label, flag, name) in charts(study) {
        let path = study.folder.join(chart_name(name));
        let _ = std::fs::remove_file(&path);
        if !shown
            .iter()
            .any(|r| r.status == "done" && r.measure(measure).is_some())
        {
            continue;
        }
        if numeric(0) && numeric(1) && study.parameters[1].values.count() > 1 {
            write_map_png(
                &path,
                &heat_map(study, &shown, measure, label, flag),
                900,
                700,
            )?;
        } else if numeric(0) {
            write_png(&path, &line_chart(study, &shown, measure, label), 900, 600)?;
        } else {
            continue;
        }
        files.push(path);
    }
    Ok(files)
}

/// Each chart: the measure, its label with units, the waviness above which a case is flagged
/// as wrinkled, and the chart's name.
fn charts(study: &Study) -> [(&'static str, &'static str, Option<f64>, &'static str); 3] {
    [
        (
            "waviness",
            "flange waviness (mm)",
            Some(study.wrinkle_threshold),
            CHARTS[0],
        ),
        ("max_shear_deg", "largest shear angle (°)", None, CHARTS[1]),
        ("peak_punch_force", "peak punch force (N)", None, CHARTS[2]),
    ]
}

/// The charts of a sampled design: a scatter each over the first two numeric parameters that
/// vary (a parameter of one value would stack every dot on one line), or over the first and
/// the measure where only one varies; none where no parameter is a number.
fn write_scatters(study: &Study, rows: &[Row]) -> anyhow::Result<Vec<PathBuf>> {
    let spans: Vec<(usize, (f64, f64))> = study
        .parameters
        .iter()
        .enumerate()
        .filter_map(|(i, p)| Some((i, p.values.span()?)))
        .collect();
    let varied: Vec<(usize, (f64, f64))> = spans
        .iter()
        .copied()
        .filter(|(_, (low, high))| high > low)
        .collect();
    let x = varied.first().or(spans.first()).copied();
    let y = varied.get(1).copied();
    let mut files = Vec::new();
    for (measure, label, flag, name) in charts(study) {
        let path = study.folder.join(chart_name(name));
        let _ = std::fs::remove_file(&path);
        if !rows
            .iter()
            .any(|r| r.status == "done" && r.measure(measure).is_some())
        {
            continue;
        }
        let Some(x) = x else {
            continue;
        };
        let chart = scatter(study, rows, (measure, label, flag), x, y);
        write_map_png(&path, &chart, 900, 700)?;
        files.push(path);
    }
    Ok(files)
}

/// A sampled design's cases as dots coloured by the measure (its name, label and the value
/// that flags a case), on the heat maps' colour scale: over the parameters `x` and `y` (each
/// its place among the parameters and its span), failed and unrun cases grey; or, without
/// `y`, over `x` and the measure itself, where a case without a value has no place (the
/// legend counts them). Wrinkled cases ringed in black, as the heat maps outline them. The
/// axes span the parameters' ranges with a margin, so that a dot at an end is whole.
fn scatter(
    study: &Study,
    rows: &[Row],
    (measure, label, flag): (&str, &str, Option<f64>),
    (x_index, x_span): (usize, (f64, f64)),
    y: Option<(usize, (f64, f64))>,
) -> MapPlot {
    let y_span = y.map(|(_, span)| span);
    let value_of = |r: &Row| {
        if r.status == "done" {
            r.measure(measure).unwrap_or(f64::NAN)
        } else {
            f64::NAN
        }
    };
    let mut dots = Vec::new();
    let mut values = Vec::new();
    let mut missing = 0;
    for r in rows {
        let value = value_of(r);
        let at_x = r.case.values.get(x_index).and_then(number);
        let at_y = match y {
            Some((y_index, _)) => r.case.values.get(y_index).and_then(number),
            None => Some(value).filter(|v| v.is_finite()),
        };
        match (at_x, at_y) {
            (Some(x), Some(y)) => {
                dots.push(vec![(x, y)]);
                values.push(value);
            }
            _ => missing += 1,
        }
    }
    // the measure's axis from 0 (where the colour scale starts) to its largest value
    let measured = values.iter().copied().filter(|v| v.is_finite());
    let measured_span = (
        measured.clone().fold(0.0, f64::min),
        measured.fold(0.0, f64::max),
    );
    let y_title = match y {
        Some((y_index, _)) => parameter_title(&study.parameters[y_index].key),
        None => label.to_string(),
    };
    let design = match &study.design {
        Design::Sampled(s) => format!(
            ", {} cases of {} (seed {})",
            rows.len(),
            s.method.name(),
            s.seed
        ),
        Design::FullFactorial => String::new(),
    };
    let outlined = values
        .iter()
        .map(|v| flag.is_some_and(|f| *v > f))
        .collect();
    let mut map = MapPlot::new(format!("Study: {label}{design}"), label, dots, values);
    map.dots = true;
    map.equal_scales = false;
    map.extent = Some((padded(x_span), padded(y_span.unwrap_or(measured_span))));
    map.axes = Some((parameter_title(&study.parameters[x_index].key), y_title));
    map.outlined = outlined;
    map.legend.extend(flag.map(wrinkled_legend));
    let RGBColor(r, g, b) = MISSING_COLOUR;
    let missing_label = match y_span {
        Some(_) => "failed or not run".to_string(),
        None => format!("failed or not run: {missing} case(s), not shown"),
    };
    map.legend.push(LegendCell {
        label: missing_label,
        fill: Some((r, g, b)),
        outlined: false,
    });
    map
}

/// A span widened by 6 % of its length at each end (an empty span by a unit, or by 6 % of
/// its value), so that dots at its ends are drawn whole.
fn padded((low, high): (f64, f64)) -> std::ops::Range<f64> {
    let length = high - low;
    let margin = if length > 0.0 {
        0.06 * length
    } else if low != 0.0 {
        0.06 * low.abs()
    } else {
        1.0
    };
    low - margin..high + margin
}

/// A cell per case at the places of its first two parameters among their values (equal
/// cells, so that the map ends at the data and uneven steps stay legible), each labelled with
/// its value, the axes ticked at the parameters' values and titled with their names and units.
fn heat_map(
    study: &Study,
    rows: &[&Row],
    measure: &str,
    label: &str,
    flag: Option<f64>,
) -> MapPlot {
    let axis = |i: usize| -> Vec<f64> {
        let mut v: Vec<f64> = study.parameters[i]
            .values
            .iter()
            .filter_map(|v| number(&v))
            .collect();
        v.sort_by(f64::total_cmp);
        v.dedup();
        v
    };
    let (xs, ys) = (axis(0), axis(1));
    let place = |values: &[f64], v: f64| values.partition_point(|x| *x < v) as f64;
    let mut cells = Vec::new();
    let mut values = Vec::new();
    let mut outlined = Vec::new();
    let mut cell_labels = Vec::new();
    for r in rows {
        let (Some(x), Some(y)) = (number(&r.case.values[0]), number(&r.case.values[1])) else {
            continue;
        };
        let (i, j) = (place(&xs, x), place(&ys, y));
        cells.push(vec![
            (i - 0.5, j - 0.5),
            (i + 0.5, j - 0.5),
            (i + 0.5, j + 0.5),
            (i - 0.5, j + 0.5),
        ]);
        let value = if r.status == "done" {
            r.measure(measure).unwrap_or(f64::NAN)
        } else {
            f64::NAN
        };
        values.push(value);
        outlined.push(flag.is_some_and(|f| value > f));
        cell_labels.push(cell_text(value, &r.status));
    }
    let rest = if study
        .parameters
        .iter()
        .skip(2)
        .any(|p| p.values.count() > 1)
    {
        " (other parameters at their first values)"
    } else {
        ""
    };
    let ticks = |values: &[f64]| -> Vec<(f64, String)> {
        values
            .iter()
            .enumerate()
            .map(|(k, v)| (k as f64, format!("{v}")))
            .collect()
    };
    let mut map = MapPlot::new(format!("Study: {label}{rest}"), label, cells, values);
    map.axes = Some((
        parameter_title(&study.parameters[0].key),
        parameter_title(&study.parameters[1].key),
    ));
    map.equal_scales = false;
    map.ticks = Some((ticks(&xs), ticks(&ys)));
    map.outlined = outlined;
    map.cell_labels = cell_labels;
    map.legend.extend(flag.map(wrinkled_legend));
    let RGBColor(r, g, b) = MISSING_COLOUR;
    map.legend.push(LegendCell {
        label: "failed or not run".into(),
        fill: Some((r, g, b)),
        outlined: false,
    });
    map
}

/// A heat map cell's text: its value to three significant digits (below 0.01 in scientific
/// notation, so that the cell stays narrow), or why it has none.
fn cell_text(value: f64, status: &str) -> String {
    if !value.is_finite() {
        return if status == "done" { "-" } else { status }.to_string();
    }
    if value == 0.0 {
        return "0".into();
    }
    if value.abs() < 0.01 {
        return format!("{value:.1e}");
    }
    let digits = 2 - value.abs().log10().floor().clamp(-2.0, 2.0) as i32;
    format!("{value:.*}", digits.max(0) as usize)
}

/// A scenario key as an axis title: its name and unit (docs/forming.md, "Scenario file"), or
/// the key itself where it is not one a study usually varies.
pub fn parameter_title(key: &str) -> String {
    let known = [
        ("process.temperature", "temperature", "°C"),
        ("process.blank_holder_force", "blank-holder force", "N"),
        ("process.blank_holder_gap", "blank-holder gap", "mm"),
        ("process.punch_speed", "punch speed", "mm/s"),
        ("process.stroke", "stroke", "mm"),
        ("process.time_scaling", "time scaling", ""),
        ("process.friction.punch", "friction blank-punch", ""),
        ("process.friction.die", "friction blank-die", ""),
        ("process.friction.holder", "friction blank-holder", ""),
        ("blank.element_size", "element size", "mm"),
        ("blank.width", "blank width", "mm"),
        ("blank.length", "blank length", "mm"),
        ("blank.ply_angle", "ply angle", "°"),
        ("blank.interply.friction", "friction between plies", ""),
        ("tools.punch_radius", "punch radius", "mm"),
        ("tools.die_opening_radius", "die opening radius", "mm"),
        ("tools.die_fillet_radius", "die fillet radius", "mm"),
        ("tools.holder_inner_radius", "holder inner radius", "mm"),
        ("process.blank_temperature", "blank out of the oven", "°C"),
        ("process.transfer_time", "transfer time in air", "s"),
        ("tools.temperature", "tool temperature", "°C"),
        ("tools.punch.temperature", "punch temperature", "°C"),
        ("tools.die.temperature", "die temperature", "°C"),
        ("tools.holder.temperature", "holder temperature", "°C"),
        (
            "thermal.contact_conductance",
            "contact conductance",
            "W/(m²·K)",
        ),
    ];
    match known.iter().find(|(k, _, _)| *k == key) {
        Some((_, name, "")) => format!("{name} ({key})"),
        Some((_, name, unit)) => format!("{name} ({unit})"),
        None => key.to_string(),
    }
}

/// The measure against the first parameter, done cases only.
fn line_chart(study: &Study, rows: &[&Row], measure: &str, label: &str) -> LinePlot {
    let mut points: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| r.status == "done")
        .filter_map(|r| Some((number(&r.case.values[0])?, r.measure(measure)?)))
        .collect();
    points.sort_by(|a, b| a.0.total_cmp(&b.0));
    LinePlot {
        title: format!("Study: {label}"),
        x_label: parameter_title(&study.parameters[0].key),
        y_label: label.into(),
        series: vec![Series::new("cases done", points, LineStyle::Solid)],
    }
}

#[cfg(test)]
mod tests {
    /// The summary's measures are the result row's, in its order: a column added there must
    /// come here.
    #[test]
    fn measures_are_the_result_columns() {
        use crate::forming::output::THERMAL_RESULT_COLUMNS;
        use crate::forming::run::RESULT_COLUMNS;
        let expected: Vec<&str> = RESULT_COLUMNS[1..]
            .iter()
            .chain(&THERMAL_RESULT_COLUMNS)
            .copied()
            .collect();
        assert_eq!(MEASURES.to_vec(), expected);
    }

    use super::*;

    /// Values print to three significant digits; a cell without one says why.
    #[test]
    fn heat_map_cells_print_their_values() {
        assert_eq!(cell_text(27.73, "done"), "27.7");
        assert_eq!(cell_text(0.05234, "done"), "0.0523");
        assert_eq!(cell_text(0.0, "done"), "0");
        assert_eq!(cell_text(2.1e-6, "done"), "2.1e-6");
        assert_eq!(cell_text(140.2, "done"), "140");
        assert_eq!(cell_text(f64::NAN, "failed"), "failed");
        assert_eq!(cell_text(f64::NAN, "done"), "-");
    }

    /// The parameters a study varies are titled with their names and units.
    #[test]
    fn parameters_are_titled_with_names_and_units() {
        assert_eq!(parameter_title("process.temperature"), "temperature (°C)");
        assert_eq!(
            parameter_title("tools.temperature"),
            "tool temperature (°C)"
        );
        assert_eq!(
            parameter_title("process.blank_holder_force"),
            "blank-holder force (N)"
        );
        assert_eq!(
            parameter_title("process.friction.die"),
            "friction blank-die (process.friction.die)"
        );
        assert_eq!(parameter_title("output.frames"), "output.frames");
    }

    /// A quoted first field keeps its commas.
    #[test]
    fn a_quoted_status_keeps_its_commas() {
        assert_eq!(
            split_csv_row("\"stopped at 3 mm, results kept\",1e0,2"),
            vec!["stopped at 3 mm, results kept", "1e0", "2"]
        );
        assert_eq!(field("a,b"), "\"a,b\"");
    }
}
