//! The sheet's last frame as NumPy arrays: the same points, cells and fields as the ParaView
//! frame `thermostamp run` writes (`io::sheet_frame`), in the layout pyvista takes.

use numpy::{PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use thermostamp::io::sheet_frame::sheet_frame;
use thermostamp::io::vtk::{Field, FieldData};
use thermostamp::mesh::cell::Cell;
use thermostamp::solver::{Model, State};

/// VTK's cell type codes: triangle and quadrilateral.
const VTK_TRIANGLE: u8 = 5;
const VTK_QUAD: u8 = 9;

/// `points` (reference, flat positions, (n, 3)), `cells` (VTK's flat list: the corner count,
/// then the corners, for each cell), `cell_types` (VTK codes), `point_data` and `cell_data`
/// (name to array: (n,) scalars, (n, 3) vectors or in-plane tensors xx, yy, xy; integer codes)
/// and `code_meanings` (the meaning of each code of a coded field).
pub fn frame_dict<'py>(
    py: Python<'py>,
    model: &Model,
    state: &State,
) -> PyResult<Bound<'py, PyDict>> {
    let frame = sheet_frame(model, state)
        .map_err(|e| crate::errors::input_error(py, format!("the last frame: {e}")))?;
    let dict = PyDict::new(py);
    dict.set_item("points", rows_of_three(py, &frame.points)?)?;
    let mut cells = Vec::new();
    let mut types = Vec::with_capacity(model.mesh.cells.len());
    for cell in &model.mesh.cells {
        let nodes = cell.nodes();
        cells.push(nodes.len() as i64);
        cells.extend(nodes.iter().map(|&n| n as i64));
        types.push(match cell {
            Cell::Triangle(_) => VTK_TRIANGLE,
            Cell::Quad(_) => VTK_QUAD,
        });
    }
    dict.set_item("cells", PyArray1::from_vec(py, cells))?;
    dict.set_item("cell_types", PyArray1::from_vec(py, types))?;
    let meanings = PyDict::new(py);
    dict.set_item("point_data", fields(py, &frame.point_data, &meanings)?)?;
    dict.set_item("cell_data", fields(py, &frame.cell_data, &meanings)?)?;
    dict.set_item("code_meanings", meanings)?;
    Ok(dict)
}

fn fields<'py>(
    py: Python<'py>,
    fields: &[Field],
    meanings: &Bound<'py, PyDict>,
) -> PyResult<Bound<'py, PyDict>> {
    let dict = PyDict::new(py);
    for field in fields {
        match &field.data {
            FieldData::Scalar(values) => {
                dict.set_item(&field.name, PyArray1::from_slice(py, values))?
            }
            FieldData::Vector(values) | FieldData::InPlaneTensor(values) => {
                dict.set_item(&field.name, rows_of_three(py, values)?)?
            }
            FieldData::Codes {
                values,
                meanings: words,
            } => {
                dict.set_item(&field.name, PyArray1::from_slice(py, values))?;
                meanings.set_item(&field.name, words.clone())?;
            }
        }
    }
    Ok(dict)
}

/// An (n, 3) array of `rows`.
fn rows_of_three<'py>(py: Python<'py>, rows: &[[f64; 3]]) -> PyResult<Bound<'py, PyAny>> {
    let flat: Vec<f64> = rows.iter().flatten().copied().collect();
    Ok(PyArray1::from_vec(py, flat)
        .reshape([rows.len(), 3])?
        .into_any())
}
