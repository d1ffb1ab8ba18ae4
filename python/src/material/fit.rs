//! `thermostamp.fit_matrix`, `fit_fabric_tension`, `fit_shear`: the fits of `thermostamp fit
//! ...` in this process, each curve a CSV file or a table from Python (handed over as CSV
//! text with every digit of its values).

use super::{columns_dict, python_names};
use crate::errors::{input_error, output_error};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::{Path, PathBuf};
use thermostamp::experiment::virtual_test::OptionNames;
use thermostamp::fit::commands::{
    fit_fabric_tension_card, fit_matrix_card, fit_shear_card, CurveSource, MatrixCurves,
    ShearOptions,
};
use thermostamp::fit::matrix::Eta1;
use thermostamp::fit::tension_data::CurveSpec;
use thermostamp::io::plot::{write_png, LinePlot};
use thermostamp::io::InputError;

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(fit_fabric_tension, m)?)?;
    m.add_function(wrap_pyfunction!(fit_matrix, m)?)?;
    m.add_function(wrap_pyfunction!(fit_shear, m)?)?;
    Ok(())
}

const NAMES: OptionNames = python_names;

/// A curve from Python: `(path, None)` for a file, `(origin, Some(text))` for a table made
/// into CSV text (its header on line 1, row `i` on line `i + 1`).
type Curve = (String, Option<String>);

fn source((name, text): &Curve) -> CurveSource {
    match text {
        None => CurveSource::File(PathBuf::from(name)),
        Some(text) => CurveSource::Text {
            origin: name.clone(),
            text: text.clone(),
        },
    }
}

/// An error as `InputError`; one located in a table from Python names its row (line 1, the
/// header made from the dictionary's keys, names its columns).
fn fit_error(py: Python<'_>, e: anyhow::Error, tables: &[&Curve]) -> PyErr {
    if let Some(InputError {
        origin,
        line: Some(line),
        message,
    }) = e.downcast_ref::<InputError>()
    {
        if tables
            .iter()
            .any(|(name, text)| text.is_some() && name == origin)
        {
            let at = match line {
                1 => "columns".to_string(),
                _ => format!("row {}", line - 1),
            };
            return input_error(py, format!("{origin}: {at}: {message}"));
        }
    }
    input_error(py, e)
}

/// Writes the card text to `output` and the plot to `plot`, as the command line does; the
/// files written.
fn write_files(
    py: Python<'_>,
    text: &str,
    output: Option<&Path>,
    plot: Option<(&Path, LinePlot)>,
) -> PyResult<Vec<PathBuf>> {
    let mut files = Vec::new();
    if let Some(path) = output {
        std::fs::write(path, text)
            .map_err(|e| output_error(py, format!("cannot write {}: {e}", path.display())))?;
        files.push(path.to_path_buf());
    }
    if let Some((png, figure)) = plot {
        write_png(png, &figure, 900, 600).map_err(|e| output_error(py, format!("{e:#}")))?;
        files.push(png.to_path_buf());
    }
    Ok(files)
}

/// The name of the card written, in messages: its path, or `<the fitted card>` without one.
fn output_name(output: Option<&Path>) -> String {
    output.map_or("<the fitted card>".into(), |p| p.display().to_string())
}

/// `fit fabric-tension`: parameters `warp_A2, ...`, `weft_A2, ...`, their standard errors,
/// and per direction the points fitted and the RMS residual (N/mm).
#[pyfunction]
#[pyo3(signature = (card, warp, weft, terms, width, output, plot))]
#[allow(clippy::too_many_arguments)]
fn fit_fabric_tension<'py>(
    py: Python<'py>,
    card: PathBuf,
    warp: Option<Curve>,
    weft: Option<Curve>,
    terms: Option<i64>,
    width: Option<f64>,
    output: Option<PathBuf>,
    plot: Option<PathBuf>,
) -> PyResult<Bound<'py, PyDict>> {
    let terms = match terms {
        Some(n) => Some(usize::try_from(n).map_err(|_| {
            input_error(py, format!("terms {n}: at least one coefficient is needed"))
        })?),
        None => None,
    };
    let (warp_source, weft_source) = (warp.as_ref().map(source), weft.as_ref().map(source));
    let tables: Vec<&Curve> = warp.iter().chain(weft.iter()).collect();
    let mut notes = Vec::new();
    let name = output_name(output.as_deref());
    let fitted = py
        .detach(|| {
            fit_fabric_tension_card(
                &card,
                (warp_source.as_ref(), weft_source.as_ref()),
                (terms, width),
                &name,
                NAMES,
                &mut |line| notes.push(line),
            )
        })
        .map_err(|e| fit_error(py, e, &tables))?;
    let parameters = PyDict::new(py);
    let errors = PyDict::new(py);
    let quality = PyDict::new(py);
    for d in &fitted.fits {
        let direction = d.key.trim_end_matches("_tension");
        for (i, (a, se)) in d
            .fit
            .coefficients
            .iter()
            .zip(&d.fit.standard_errors)
            .enumerate()
        {
            parameters.set_item(format!("{direction}_A{}", i + 2), a)?;
            errors.set_item(format!("{direction}_A{}", i + 2), se)?;
        }
        quality.set_item(format!("{direction}_points"), d.fit.points)?;
        quality.set_item(format!("{direction}_rms_residual"), d.fit.rms_residual)?;
    }
    quality.set_item("fabric_thickness", fitted.thickness)?;
    let figure = plot.as_deref().map(|p| (p, fitted.plot()));
    let files = write_files(py, &fitted.card, output.as_deref(), figure)?;
    result(py, parameters, errors, quality, &fitted.card, files, notes)
}

/// `fit matrix`: per temperature (`temperature`, ascending as the table prints them) `C10`,
/// `eta1`, `D1`, their standard errors (`eta1`'s NaN where it comes from the card), curves,
/// points and RMS residual (MPa).
#[pyfunction]
#[pyo3(signature = (manifest, curves, card, bulk_modulus, poisson, output, plot))]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
fn fit_matrix<'py>(
    py: Python<'py>,
    manifest: Option<PathBuf>,
    curves: Vec<(Curve, f64, Option<f64>, Option<f64>, Option<f64>)>,
    card: Option<PathBuf>,
    bulk_modulus: Option<f64>,
    poisson: Option<f64>,
    output: Option<PathBuf>,
    plot: Option<PathBuf>,
) -> PyResult<Bound<'py, PyDict>> {
    let given = match manifest {
        Some(path) => MatrixCurves::Manifest(path),
        None => MatrixCurves::Given {
            origin: "curves".into(),
            curves: curves
                .iter()
                .map(|(curve, temperature, rate, speed, gauge)| {
                    let spec = CurveSpec {
                        temperature: *temperature,
                        strain_rate: *rate,
                        crosshead_speed: *speed,
                        gauge_length: *gauge,
                    };
                    (source(curve), spec)
                })
                .collect(),
        },
    };
    let tables: Vec<&Curve> = curves.iter().map(|c| &c.0).collect();
    let name = output_name(output.as_deref());
    let fitted = py
        .detach(|| {
            fit_matrix_card(
                card.as_deref(),
                &given,
                (bulk_modulus, poisson),
                &name,
                NAMES,
            )
        })
        .map_err(|e| fit_error(py, e, &tables))?;
    let header = [
        "temperature",
        "c10",
        "eta1",
        "d1",
        "c10_error",
        "eta1_error",
        "curves",
        "points",
        "rms_residual",
    ];
    let rows: Vec<[f64; 9]> = fitted
        .fits
        .iter()
        .map(|f| {
            let eta1_error = match f.eta1 {
                Eta1::Fitted { standard_error, .. } => standard_error,
                Eta1::FromCard { .. } => f64::NAN,
            };
            [
                f.temperature,
                f.c10,
                f.eta1.value(),
                f.d1,
                f.c10_standard_error,
                eta1_error,
                f.curves.len() as f64,
                f.points as f64,
                f.rms_residual,
            ]
        })
        .collect();
    let table = columns_dict(py, &header, &rows)?;
    let parameters = PyDict::new(py);
    let errors = PyDict::new(py);
    let quality = PyDict::new(py);
    for name in ["temperature", "c10", "eta1", "d1"] {
        parameters.set_item(name, table.get_item(name)?)?;
    }
    errors.set_item("c10", table.get_item("c10_error")?)?;
    errors.set_item("eta1", table.get_item("eta1_error")?)?;
    for name in ["temperature", "curves", "points", "rms_residual"] {
        quality.set_item(name, table.get_item(name)?)?;
    }
    let figure = plot.as_deref().map(|p| (p, fitted.plot()));
    let files = write_files(py, &fitted.card, output.as_deref(), figure)?;
    result(
        py,
        parameters,
        errors,
        quality,
        &fitted.card,
        files,
        Vec::new(),
    )
}

/// `fit shear` (the analytic fit; the FE refinement is the command line's): the coefficients
/// by term name (`c1`, `friction`, `locking`, MPa), their standard errors, and the misfit
/// with the table of fitted points.
#[pyfunction]
#[pyo3(signature = (card, data, options, output, plot))]
fn fit_shear<'py>(
    py: Python<'py>,
    card: PathBuf,
    data: Curve,
    options: &Bound<'py, PyDict>,
    output: Option<PathBuf>,
    plot: Option<PathBuf>,
) -> PyResult<Bound<'py, PyDict>> {
    let get = |key: &str| -> PyResult<Option<f64>> {
        match options.get_item(key)? {
            Some(v) => v.extract::<Option<f64>>(),
            None => Ok(None),
        }
    };
    let defaults = ShearOptions::default();
    let test: String = match options.get_item("test")? {
        Some(v) => v.extract()?,
        None => "bias-extension".into(),
    };
    let bias_extension = match test.as_str() {
        "bias-extension" => true,
        "picture-frame" => false,
        other => {
            return Err(input_error(
                py,
                format!("test '{other}': bias-extension or picture-frame"),
            ))
        }
    };
    let terms: String = match options.get_item("terms")? {
        Some(v) if v.extract::<i64>().is_ok() => v.extract::<i64>()?.to_string(),
        Some(v) if v.extract::<String>().is_ok() => v.extract()?,
        Some(v) => {
            let names: Vec<String> = v.extract()?;
            names.join(",")
        }
        None => defaults.terms.clone(),
    };
    let shear = ShearOptions {
        bias_extension,
        width: get("width")?,
        length: get("length")?,
        frame_side: get("frame_side")?,
        fabric_side: get("fabric_side")?,
        temperature: get("temperature")?,
        speed: get("speed")?,
        terms,
        friction_onset: get("friction_onset")?.unwrap_or(defaults.friction_onset),
        locking_angle: get("locking_angle")?,
        max_shear: get("max_shear")?.unwrap_or(defaults.max_shear),
        refine_fe: false,
        fe_element_size: None,
    };
    let data_source = source(&data);
    let mut notes = Vec::new();
    let name = output_name(output.as_deref());
    let done = py.detach(|| {
        let fitted = fit_shear_card(&card, &data_source, &shear, NAMES, &mut |line| {
            notes.push(line)
        })?;
        let text = fitted.card_with(&fitted.fit.law(), Vec::new(), &name)?;
        let figure = fitted.plot(None)?;
        anyhow::Ok((fitted, text, figure))
    });
    let (fitted, text, figure) = done.map_err(|e| fit_error(py, e, &[&data]))?;
    let fit = &fitted.fit;
    let parameters = PyDict::new(py);
    let errors = PyDict::new(py);
    for ((term, c), se) in fit
        .terms
        .iter()
        .zip(&fit.result.parameters)
        .zip(&fit.result.standard_errors)
    {
        parameters.set_item(term.name(), c)?;
        errors.set_item(term.name(), se)?;
    }
    let quality = PyDict::new(py);
    quality.set_item("points", fit.points.len())?;
    quality.set_item("quantity", fit.quantity)?;
    quality.set_item("rms", fit.rms)?;
    quality.set_item("rms_relative", fit.result.rms_residual)?;
    quality.set_item("rms_of_mean", fit.rms_of_mean)?;
    quality.set_item("rms_of_range", fit.rms_of_range)?;
    let fitted_rows: Vec<[f64; 4]> = fit
        .fitted
        .iter()
        .map(|p| [p.line as f64, p.gamma.to_degrees(), p.data, p.model])
        .collect();
    quality.set_item(
        "fitted",
        columns_dict(py, &["line", "shear_deg", "data", "model"], &fitted_rows)?,
    )?;
    if let (Some(m), Some(last)) = (&fitted.matrix, fit.points.last()) {
        if let Some(i) = m.fabric.lines.iter().position(|&l| l == last.line) {
            quality.set_item("matrix_force_at_last_point", m.force[i])?;
            quality.set_item(
                "measured_force_at_last_point",
                m.fabric.force[i] + m.force[i],
            )?;
        }
    }
    let files = write_files(
        py,
        &text,
        output.as_deref(),
        plot.as_deref().map(|p| (p, figure)),
    )?;
    result(py, parameters, errors, quality, &text, files, notes)
}

fn result<'py>(
    py: Python<'py>,
    parameters: Bound<'py, PyDict>,
    errors: Bound<'py, PyDict>,
    quality: Bound<'py, PyDict>,
    card: &str,
    files: Vec<PathBuf>,
    notes: Vec<String>,
) -> PyResult<Bound<'py, PyDict>> {
    let dict = PyDict::new(py);
    dict.set_item("parameters", parameters)?;
    dict.set_item("standard_errors", errors)?;
    dict.set_item("quality", quality)?;
    dict.set_item("card", card)?;
    dict.set_item("files", files)?;
    dict.set_item("notes", notes)?;
    Ok(dict)
}
