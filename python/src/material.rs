//! The material point, the virtual tests and the fits from Python: the same library functions
//! as `thermostamp material-point`, `thermostamp test ...` and `thermostamp fit ...`, with
//! tables as NumPy arrays and the command line's messages in the package's exceptions.

mod fit;
mod virtual_test;

use crate::errors::input_error;
use numpy::{PyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;
use thermostamp::experiment::material_point::{material_point, PointLayer};
use thermostamp::io::{CsvTable, InputError};
use thermostamp::material::MaterialCard;

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(material_point_table, m)?)?;
    m.add_function(wrap_pyfunction!(point_history_columns, m)?)?;
    virtual_test::register(m)?;
    fit::register(m)?;
    Ok(())
}

/// Python's spelling of an option in messages: `time_scaling` for the command line's
/// `--time-scaling`.
fn python_names(option: &str) -> String {
    option.replace('-', "_")
}

/// The material card at `path`, or `InputError` with the command line's message.
pub fn load_card(py: Python<'_>, path: &std::path::Path) -> PyResult<MaterialCard> {
    MaterialCard::load(path).map_err(|e| input_error(py, e))
}

/// A table of values handed in from Python (`origin` naming it), as the library reads a CSV
/// file: its "lines" are the rows, from 1.
pub fn table_of(origin: &str, rows: &PyReadonlyArray2<'_, f64>) -> CsvTable {
    let view = rows.as_array();
    CsvTable {
        origin: origin.to_string(),
        lines: (1..=view.nrows()).collect(),
        rows: view.outer_iter().map(|r| r.to_vec()).collect(),
    }
}

/// An error of the library as `InputError`; one located in a table handed in from Python
/// names the row (`history: row 3: ...`) where the command line names the file's line.
pub fn table_error(py: Python<'_>, e: anyhow::Error) -> PyErr {
    match e.downcast_ref::<InputError>() {
        Some(InputError {
            origin,
            line: Some(line),
            message,
        }) => input_error(py, format!("{origin}: row {line}: {message}")),
        _ => input_error(py, e),
    }
}

/// `thermostamp.material_point`: `rows` the history's columns in the order of the layer's
/// history columns (checked by the Python side: present, finite); returns the output columns.
#[pyfunction]
#[pyo3(signature = (card, layer, rows, angle))]
fn material_point_table<'py>(
    py: Python<'py>,
    card: PathBuf,
    layer: &str,
    rows: PyReadonlyArray2<'py, f64>,
    angle: f64,
) -> PyResult<Bound<'py, PyDict>> {
    thermostamp::limits::ANGLE
        .check("angle", angle)
        .map_err(|e| input_error(py, e))?;
    let layer = point_layer(py, layer)?;
    let loaded = load_card(py, &card)?;
    let history = table_of("history", &rows);
    let origin = card.display().to_string();
    let table = py
        .detach(|| material_point(&loaded, &origin, layer, angle, &history))
        .map_err(|e| table_error(py, e))?;
    columns_dict(py, table.header, &table.rows)
}

fn point_layer(py: Python<'_>, layer: &str) -> PyResult<PointLayer> {
    match layer {
        "matrix" => Ok(PointLayer::Matrix),
        "fabric" => Ok(PointLayer::Fabric),
        "laminate" => Ok(PointLayer::Laminate),
        other => Err(input_error(
            py,
            format!("layer '{other}': expected matrix, fabric or laminate"),
        )),
    }
}

/// Column name to NumPy array, for rows of `header`'s columns.
pub fn columns_dict<'py, R: AsRef<[f64]>>(
    py: Python<'py>,
    header: &[&str],
    rows: &[R],
) -> PyResult<Bound<'py, PyDict>> {
    let dict = PyDict::new(py);
    for (j, name) in header.iter().enumerate() {
        let column: Vec<f64> = rows.iter().map(|r| r.as_ref()[j]).collect();
        dict.set_item(name, PyArray1::from_vec(py, column))?;
    }
    Ok(dict)
}

/// The history columns of `layer` (for the Python side's checks).
#[pyfunction]
pub fn point_history_columns(py: Python<'_>, layer: &str) -> PyResult<Vec<&'static str>> {
    Ok(point_layer(py, layer)?.history_columns().to_vec())
}
