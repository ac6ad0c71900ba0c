//! `pacs.Command`: what one safety step of the shield returns.

use crate::convert::to_py;
use crate::shield::py_bool;
use numpy::PyArray1;
use pacs_shield::shield::{BindingNames, ChunkProgress, Command};
use pyo3::prelude::*;
use std::sync::Arc;

/// The command of one safety step: joint targets for the low-level controller at `t` and the
/// step's diagnostics.
#[pyclass(name = "Command", module = "pacs", frozen)]
pub struct PyCommand {
    pub cmd: Command,
    pub progress: ChunkProgress,
    /// What the binding's indices stand for.
    pub names: Arc<BindingNames>,
}

#[pymethods]
impl PyCommand {
    /// Time the command is for (s): the step's t + safety_step.
    #[getter]
    fn t(&self) -> f64 {
        self.cmd.t
    }
    /// Joint positions (rad), shape (dof,).
    #[getter]
    fn q<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.cmd.q())
    }
    /// Joint velocities (rad/s), shape (dof,).
    #[getter]
    fn dq<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.cmd.dq())
    }
    /// Joint accelerations (rad/s²), shape (dof,).
    #[getter]
    fn ddq<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.cmd.ddq())
    }
    /// The intended step was verified and is executed.
    #[getter]
    fn verified(&self) -> bool {
        self.cmd.diag.verified
    }
    /// The robot follows the stored verified failsafe (braking along the path) this step.
    #[getter]
    fn on_failsafe(&self) -> bool {
        self.cmd.diag.on_failsafe
    }
    /// What decided the step: {"kind": "none" | "no-measurement" | "contradicted-measurement" |
    /// "contradicted-object" | "no-profile" | "ssm" |
    /// "pfl" | "object", ...indices, energies (J)}, with beside each index the name it stands
    /// for: `link_name`, `person` (the person's id), `body_part_name`, `object_id`.
    #[getter]
    fn binding<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, &self.names.describe(&self.cmd.diag.binding))
    }
    /// Lower bound of the robot–human separation over the first interval (m; negative: the
    /// occupancies may overlap; inf where not computed: without a human, and on an unverified
    /// step whose check stopped before the first interval, docs/shield.md "Diagnostics").
    #[getter]
    fn min_separation(&self) -> f64 {
        self.cmd.diag.min_separation
    }
    /// Largest kinetic-energy bound where contact was possible (J; 0 if none).
    #[getter]
    fn contact_energy(&self) -> f64 {
        self.cmd.diag.contact_energy
    }
    /// The threshold belonging to `contact_energy` (J).
    #[getter]
    fn contact_threshold(&self) -> f64 {
        self.cmd.diag.contact_threshold
    }
    /// Path speed after the step (1 = intended timing, 0 = stopped).
    #[getter]
    fn path_speed(&self) -> f64 {
        self.cmd.diag.path_speed
    }
    /// Time (s) at which the monitored trajectory reaches standstill.
    #[getter]
    fn stop_time(&self) -> f64 {
        self.cmd.diag.stop_time
    }
    /// Serial number of the chunk the command follows (0: the start's standstill).
    #[getter]
    fn chunk(&self) -> u64 {
        self.progress.chunk
    }
    /// Actions of that chunk executed so far (waypoints q̂_1 … passed).
    #[getter]
    fn passed(&self) -> usize {
        self.progress.passed
    }
    /// As a dict of plain values (arrays as lists).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let d = &self.cmd.diag;
        let v = serde_json::json!({
            "t": self.cmd.t,
            "q": self.cmd.q(),
            "dq": self.cmd.dq(),
            "ddq": self.cmd.ddq(),
            "verified": d.verified,
            "on_failsafe": d.on_failsafe,
            "binding": self.names.describe(&d.binding),
            "min_separation": if d.min_separation.is_finite() { serde_json::json!(d.min_separation) } else { serde_json::json!("inf") },
            "contact_energy": d.contact_energy,
            "contact_threshold": d.contact_threshold,
            "path_speed": d.path_speed,
            "stop_time": d.stop_time,
            "chunk": self.progress.chunk,
            "passed": self.progress.passed,
        });
        let out = to_py(py, &v)?;
        if !d.min_separation.is_finite() {
            out.set_item("min_separation", d.min_separation)?;
        }
        Ok(out)
    }
    fn __repr__(&self) -> String {
        format!(
            "Command(t={:.4}, verified={}, on_failsafe={}, path_speed={:.3}, chunk={}, passed={}, q={:?})",
            self.cmd.t,
            py_bool(self.cmd.diag.verified),
            py_bool(self.cmd.diag.on_failsafe),
            self.cmd.diag.path_speed,
            self.progress.chunk,
            self.progress.passed,
            self.cmd.q()
        )
    }
}
