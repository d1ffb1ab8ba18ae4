//! The study's summary (docs/study.md): `summary.csv`, one row per case (its parameters, how it
//! ended, the run's final measures from its `forming-result.csv`, its wall time), and charts of
//! the waviness and the largest shear angle over the parameters. Rebuilt from the case folders
//! alone, so that a sweep spread over several processes or machines has one summary.

use super::file::{Case, Study};
use super::run::{finished, CaseResult};
use crate::forming::run::{RESULT_COLUMNS, RESULT_CSV};
use crate::io::output_folder::ProductFiles;
use crate::io::plot::{write_map_png, write_png, LinePlot, LineStyle, MapPlot, Series};
use std::path::{Path, PathBuf};

/// The run's final measures a summary row carries: the columns of its `forming-result.csv`
/// ([`RESULT_COLUMNS`]) after the status.
pub const MEASURES: &[&str] = match RESULT_COLUMNS.split_first() {
    Some((_, measures)) => measures,
    None => &RESULT_COLUMNS,
};
pub const SUMMARY_CSV: &str = "summary.csv";
/// The charts: `study-<name>.png`.
const CHARTS: [&str; 2] = ["waviness", "max-shear"];

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
/// failed ones grey; over one parameter (or a non-numeric second one) a line chart each.
fn write_charts(study: &Study, rows: &[Row]) -> anyhow::Result<Vec<PathBuf>> {
    let numeric = |i: usize| {
        study
            .parameters
            .get(i)
            .is_some_and(|p| p.values.iter().all(|v| number(&v).is_some()))
    };
    let charts = [
        (
            "waviness",
            "flange waviness (mm)",
            Some(study.wrinkle_threshold),
            CHARTS[0],
        ),
        ("max_shear_deg", "largest shear angle (°)", None, CHARTS[1]),
    ];
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
    for (measure, label, flag, name) in charts {
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

fn number(v: &toml::Value) -> Option<f64> {
    match v {
        toml::Value::Float(f) => Some(*f),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    }
}

/// Cells centred on the values of the first two parameters, each reaching halfway to its
/// neighbours.
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
        v
    };
    let (xs, ys) = (axis(0), axis(1));
    let mut cells = Vec::new();
    let mut values = Vec::new();
    let mut outlined = Vec::new();
    for r in rows {
        let (Some(x), Some(y)) = (number(&r.case.values[0]), number(&r.case.values[1])) else {
            continue;
        };
        let ((x0, x1), (y0, y1)) = (cell_span(&xs, x), cell_span(&ys, y));
        cells.push(vec![(x0, y0), (x1, y0), (x1, y1), (x0, y1)]);
        let value = if r.status == "done" {
            r.measure(measure).unwrap_or(f64::NAN)
        } else {
            f64::NAN
        };
        values.push(value);
        outlined.push(flag.is_some_and(|f| value > f));
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
    MapPlot {
        title: format!("Study: {label}{rest}"),
        axes: (
            study.parameters[0].key.clone(),
            study.parameters[1].key.clone(),
        ),
        equal_scales: false,
        value_label: match flag {
            Some(f) => format!("{label}; wrinkled (above {f:.3}) outlined, failed grey"),
            None => format!("{label}; failed grey"),
        },
        cells,
        values,
        limit: None,
        outlined,
    }
}

/// The extent of the cell of `v` among the increasing `values`: halfway to each neighbour, an
/// end cell as wide on its open side as on the other; 1 either side of a lone value.
fn cell_span(values: &[f64], v: f64) -> (f64, f64) {
    let i = values.partition_point(|x| *x < v);
    let gap = |a: usize| 0.5 * (values[a + 1] - values[a]);
    match values.len() {
        0 | 1 => (v - 1.0, v + 1.0),
        n => {
            let left = gap(i.max(1) - 1);
            let right = gap(i.min(n - 2));
            (v - left, v + right)
        }
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
        x_label: study.parameters[0].key.clone(),
        y_label: label.into(),
        series: vec![Series::new("cases done", points, LineStyle::Solid)],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Cells reach halfway to their neighbours; end cells mirror their inner half; a lone
    /// value gets a cell of width 2.
    #[test]
    fn heat_map_cells_reach_halfway_to_their_neighbours() {
        let values = [0.0, 100.0, 300.0];
        assert_eq!(cell_span(&values, 0.0), (-50.0, 50.0));
        assert_eq!(cell_span(&values, 100.0), (50.0, 200.0));
        assert_eq!(cell_span(&values, 300.0), (200.0, 400.0));
        assert_eq!(cell_span(&[280.0], 280.0), (279.0, 281.0));
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
