//! Scenarios from Python: read from a file with overrides, or from TOML text a program wrote;
//! either way checked as the command line checks them, and handed back as standalone text (its
//! file paths absolute) that runs from any folder and any process.

use crate::errors::scenario_error;
use pyo3::prelude::*;
use std::path::{Path, PathBuf};
use thermostamp::forming::Scenario;

/// The scenario at `path` with `overrides` (`key=value`, as `--set`) as standalone TOML text.
/// Raises `ScenarioError` naming the key.
#[pyfunction]
pub fn scenario_load(py: Python<'_>, path: PathBuf, overrides: Vec<String>) -> PyResult<String> {
    py.detach(|| Scenario::standalone_text(&path, &overrides))
        .map_err(|e| scenario_error(py, &e.origin, &e.message))
}

/// The scenario written in `text` (its paths relative to `folder`), named `origin` in
/// messages, with `overrides`, as standalone TOML text. Raises `ScenarioError`.
#[pyfunction]
pub fn scenario_from_text(
    py: Python<'_>,
    text: &str,
    origin: &str,
    folder: PathBuf,
    overrides: Vec<String>,
) -> PyResult<String> {
    py.detach(|| Scenario::standalone_from_text(text, origin, &folder, &overrides))
        .map_err(|e| scenario_error(py, &e.origin, &e.message))
}

/// The checked scenario of standalone `text`.
pub fn checked(py: Python<'_>, text: &str, origin: &str) -> PyResult<Scenario> {
    Scenario::from_text(text, origin, Path::new("."), &[])
        .map_err(|e| scenario_error(py, &e.origin, &e.message))
}

/// TOML text of a Python dictionary of tables, lists and scalars (`Scenario.from_dict`).
/// Raises `InputError` naming the key of a value TOML cannot hold.
#[pyfunction]
pub fn toml_dumps(py: Python<'_>, table: &Bound<'_, pyo3::types::PyDict>) -> PyResult<String> {
    let value = to_toml(table.as_any(), "").map_err(|e| crate::errors::input_error(py, e))?;
    toml::to_string(&value).map_err(|e| crate::errors::input_error(py, e))
}

/// A Python dictionary of TOML text (`Scenario.to_dict`).
#[pyfunction]
pub fn toml_loads<'py>(py: Python<'py>, text: &str) -> PyResult<Bound<'py, PyAny>> {
    let table: toml::Table = text
        .parse()
        .map_err(|e| crate::errors::input_error(py, e))?;
    to_python(py, &toml::Value::Table(table))
}

fn to_toml(object: &Bound<'_, PyAny>, key: &str) -> Result<toml::Value, String> {
    use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
    let named = |k: &str| {
        if key.is_empty() {
            k.to_string()
        } else {
            format!("{key}.{k}")
        }
    };
    if let Ok(dict) = object.cast::<PyDict>() {
        let mut table = toml::Table::new();
        for (k, v) in dict.iter() {
            let k: String = k
                .extract()
                .map_err(|_| format!("{}: keys must be strings", named("?")))?;
            table.insert(k.clone(), to_toml(&v, &named(&k))?);
        }
        return Ok(toml::Value::Table(table));
    }
    if object.is_instance_of::<PyBool>() {
        return Ok(toml::Value::Boolean(object.extract().unwrap_or(false)));
    }
    if object.is_instance_of::<PyInt>() {
        return object
            .extract::<i64>()
            .map(toml::Value::Integer)
            .map_err(|_| format!("{key}: the integer does not fit 64 bits"));
    }
    if object.is_instance_of::<PyFloat>() {
        return Ok(toml::Value::Float(object.extract().unwrap_or(f64::NAN)));
    }
    if let Ok(text) = object.cast::<PyString>() {
        return Ok(toml::Value::String(text.to_string()));
    }
    if object.is_instance_of::<PyList>() || object.is_instance_of::<PyTuple>() {
        let mut items = Vec::new();
        for (i, item) in object.try_iter().map_err(|e| e.to_string())?.enumerate() {
            let item = item.map_err(|e| e.to_string())?;
            items.push(to_toml(&item, &format!("{key}[{}]", i + 1))?);
        }
        return Ok(toml::Value::Array(items));
    }
    // NumPy scalars and other numbers
    if let Ok(x) = object.extract::<f64>() {
        return Ok(toml::Value::Float(x));
    }
    Err(format!(
        "{key}: a {} is not a TOML value (tables, lists, strings, numbers, booleans)",
        object
            .get_type()
            .name()
            .map_or("?".into(), |n| n.to_string())
    ))
}

pub fn to_python<'py>(py: Python<'py>, value: &toml::Value) -> PyResult<Bound<'py, PyAny>> {
    use pyo3::IntoPyObjectExt;
    Ok(match value {
        toml::Value::String(s) => s.into_bound_py_any(py)?,
        toml::Value::Integer(i) => i.into_bound_py_any(py)?,
        toml::Value::Float(x) => x.into_bound_py_any(py)?,
        toml::Value::Boolean(b) => b.into_bound_py_any(py)?,
        toml::Value::Datetime(d) => d.to_string().into_bound_py_any(py)?,
        toml::Value::Array(items) => {
            let list = pyo3::types::PyList::empty(py);
            for item in items {
                list.append(to_python(py, item)?)?;
            }
            list.into_any()
        }
        toml::Value::Table(table) => {
            let dict = pyo3::types::PyDict::new(py);
            for (k, v) in table {
                dict.set_item(k, to_python(py, v)?)?;
            }
            dict.into_any()
        }
    })
}
