//! The Rust side of thermostamp's Python package (`thermostamp._core`): the same engine as the
//! command line, called in-process. The Python side (`python/thermostamp/`) holds the classes
//! users meet (`Scenario`, `Result`, `Study`); this module hands them the engine's answers as
//! dictionaries of NumPy arrays and raises the package's typed exceptions
//! (`thermostamp.errors`).

mod errors;
mod frame;
mod material;
mod run;
mod scenario;
mod study;
mod watch;

use pyo3::prelude::*;

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add(
        "HISTORY_COLUMNS",
        thermostamp::forming::output::HISTORY_COLUMNS.to_vec(),
    )?;
    m.add_function(wrap_pyfunction!(scenario::scenario_load, m)?)?;
    m.add_function(wrap_pyfunction!(scenario::scenario_from_text, m)?)?;
    m.add_function(wrap_pyfunction!(scenario::toml_dumps, m)?)?;
    m.add_function(wrap_pyfunction!(scenario::toml_loads, m)?)?;
    m.add_function(wrap_pyfunction!(run::run_scenario, m)?)?;
    material::register(m)?;
    study::register(m)?;
    Ok(())
}
