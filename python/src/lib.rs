//! The `pacs._pacs` extension module behind the Python package `pacs` (python/python/pacs):
//! the PACS shield ([`shield`]), its 1 kHz loop on a Rust thread ([`runner`]) and the offline
//! audit with its log writer and reports ([`audit`]), and what `pacs.fleet` runs on workers
//! ([`fleet`]: pickled runs, the fleet report, simulation rollouts in parts). Every invalid
//! argument raises a `pacs.Error` subclass naming the argument and the value ([`errors`]);
//! nothing panics across the boundary.

mod audit;
mod command;
mod convert;
mod errors;
mod fleet;
mod inputs;
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
    m.add_class::<command::PyCommand>()?;
    m.add_class::<runner::PyShieldLoop>()?;
    m.add_class::<audit::PyRun>()?;
    m.add_class::<audit::PyLogWriter>()?;
    m.add_class::<sim::PyDemo>()?;
    m.add_function(wrap_pyfunction!(sim::teleop_demonstrations, m)?)?;
    m.add_function(wrap_pyfunction!(sim::paced_replay, m)?)?;
    m.add_function(wrap_pyfunction!(sim::replay_event, m)?)?;
    m.add_function(wrap_pyfunction!(audit::audit, m)?)?;
    m.add_function(wrap_pyfunction!(audit::report, m)?)?;
    m.add_function(wrap_pyfunction!(models::robot_spec, m)?)?;
    m.add_function(wrap_pyfunction!(fleet::_run_from_state, m)?)?;
    m.add_function(wrap_pyfunction!(fleet::_fleet_logs, m)?)?;
    m.add_function(wrap_pyfunction!(fleet::_takes_header, m)?)?;
    m.add_function(wrap_pyfunction!(fleet::_fleet_report, m)?)?;
    m.add_function(wrap_pyfunction!(fleet::_simulate_check, m)?)?;
    m.add_function(wrap_pyfunction!(fleet::_simulate_rollouts, m)?)?;
    m.add_function(wrap_pyfunction!(fleet::_simulate_merge, m)?)?;
    m.add_function(wrap_pyfunction!(fleet::_simulate_external, m)?)?;
    m.add_function(wrap_pyfunction!(fleet::_tolerance, m)?)?;
    Ok(())
}
