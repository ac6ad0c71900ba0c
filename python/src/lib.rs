//! The `pacs._pacs` extension module behind the Python package `pacs` (python/python/pacs):
//! the PACS shield ([`shield`]), its 1 kHz loop on a Rust thread ([`runner`]) and the offline
//! audit with its log writer and reports ([`audit`]). Every invalid argument raises a
//! `pacs.Error` subclass naming the argument and the value ([`errors`]); nothing panics across
//! the boundary.

mod audit;
mod convert;
mod errors;
mod models;
mod runner;
mod shield;
mod sim;

use pyo3::prelude::*;

/// The extension module (imported as `pacs._pacs`; use the package `pacs`).
#[pymodule]
fn _pacs(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<shield::PyShield>()?;
    m.add_class::<shield::PyCommand>()?;
    m.add_class::<runner::PyShieldLoop>()?;
    m.add_class::<audit::PyRun>()?;
    m.add_class::<audit::PyLogWriter>()?;
    m.add_class::<sim::PyDemo>()?;
    m.add_function(wrap_pyfunction!(audit::audit, m)?)?;
    m.add_function(wrap_pyfunction!(audit::report, m)?)?;
    m.add_function(wrap_pyfunction!(models::robot_spec, m)?)?;
    Ok(())
}
