//! The package's exceptions are Python classes (`thermostamp/errors.py`, so that they can also
//! be `ValueError`s or `OSError`s); this raises them from Rust.

use pyo3::prelude::*;

/// An exception of `thermostamp.errors` named `class`, made with `args`.
pub fn raise<'py, A>(py: Python<'py>, class: &str, args: A) -> PyErr
where
    A: pyo3::call::PyCallArgs<'py>,
{
    let made = py
        .import("thermostamp.errors")
        .and_then(|m| m.getattr(class))
        .and_then(|c| c.call1(args));
    match made {
        Ok(exception) => PyErr::from_value(exception),
        Err(e) => e,
    }
}

/// A bad scenario: its origin and the message (which names the key).
pub fn scenario_error(py: Python<'_>, origin: &str, message: &str) -> PyErr {
    raise(
        py,
        "ScenarioError",
        (origin.to_string(), message.to_string()),
    )
}

/// Bad input other than a scenario (a material card, a table, a study file): the message.
pub fn input_error(py: Python<'_>, message: impl std::fmt::Display) -> PyErr {
    raise(py, "InputError", (format!("{message:#}"),))
}

/// A result that could not be written, or an output folder held by another run.
pub fn output_error(py: Python<'_>, message: impl std::fmt::Display) -> PyErr {
    raise(py, "OutputError", (format!("{message:#}"),))
}
