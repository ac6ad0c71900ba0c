//! `pacs.Shield` and `pacs.Command`: the PACS shield between a policy and a robot.
//!
//! The shield state lives behind a mutex ([`Inner`]) so that [`crate::runner`] can run its step
//! loop on a Rust thread; a direct `step` takes the (uncontended) lock and releases the GIL.

use crate::convert::{finite, floats, points, show, to_py, vector};
use crate::errors::{Kind, err, input, type_err};
use crate::models::scene;
use numpy::PyArray1;
use pacs_log::Header;
use pacs_models::human::HumanModel;
use pacs_motion::chunk::{ActionKind, Chunk};
use pacs_reach::human::HumanMeasurement;
use pacs_reach::object::ObjectMeasurement;
use pacs_shield::settings::ShieldSettings;
use pacs_shield::shield::{ChunkProgress, Command, Shield};
use pacs_shield::shield_log::ShieldLog;
use pyo3::prelude::*;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::PathBuf;
use std::sync::{Arc, Mutex, MutexGuard};

/// An error of the shield state, raised as `pacs.<kind>` once the GIL is held again.
pub type Fail = (Kind, String);

/// Everything a shield needs between calls.
pub struct Inner {
    pub shield: Shield,
    pub dof: usize,
    pub humans: Vec<HumanModel>,
    pub object_ids: Vec<String>,
    pub header: Header,
    pub log_path: Option<PathBuf>,
    pub log: Option<ShieldLog<BufWriter<File>>>,
    /// The newest measurement of human 0 not yet handed to a step (the shield takes it at the
    /// first step at or after its time stamp).
    pub pending: Option<HumanMeasurement>,
    /// Time of the last step (s).
    pub last_t: Option<f64>,
    pub start_t: f64,
    pub started: bool,
    /// A `ShieldLoop` steps this shield: direct steps are refused.
    pub running: bool,
    pub settings: ShieldSettings,
}

impl Inner {
    /// Start at rest at `q` (rad) at `t` (s); opens the log if one was asked for.
    pub fn start(&mut self, t: f64, q: &[f64]) -> Result<(), Fail> {
        self.shield
            .start(t, q)
            .map_err(|e| (Kind::Input, e.to_string()))?;
        if let Some(p) = &self.log_path {
            let f = File::create(p).map_err(|e| {
                (
                    Kind::Output,
                    format!("log: cannot create {}: {e}", p.display()),
                )
            })?;
            let log = ShieldLog::new(BufWriter::new(f), &self.header, t, q)
                .map_err(|e| (Kind::Output, format!("log {}: {e}", p.display())))?;
            self.log = Some(log);
        }
        self.started = true;
        self.last_t = None;
        self.start_t = t;
        self.pending = None;
        Ok(())
    }

    /// The time of the latest step (or the start time).
    pub fn now(&self) -> f64 {
        self.last_t.unwrap_or(self.start_t)
    }

    /// Hand over a chunk (rows of `dof` values); returns its serial number.
    pub fn set_chunk(
        &mut self,
        t: f64,
        actions: Vec<Vec<f64>>,
        h: usize,
        kind: ActionKind,
    ) -> Result<u64, Fail> {
        if !self.started {
            return Err((Kind::State, "set_chunk: call start(t, q) first".into()));
        }
        let chunk = Chunk {
            kind,
            actions,
            execute: h,
            gripper: None,
        };
        let t_log = t.max(self.now());
        if let Err(e) = self.shield.set_chunk(&chunk) {
            if let Some(log) = &mut self.log {
                let _ = log.event(t_log, "chunk_rejected");
            }
            return Err((Kind::Chunk, format!("set_chunk: {e}")));
        }
        if let Some(log) = &mut self.log {
            log.event(t_log, "chunk")
                .map_err(|e| (Kind::Output, format!("log: {e}")))?;
        }
        Ok(self.shield.chunk_progress().map_or(0, |p| p.accepted))
    }

    /// Record a human measurement.
    pub fn measure(&mut self, id: usize, m: HumanMeasurement) -> Result<(), Fail> {
        if id >= self.humans.len() {
            return Err((
                Kind::Input,
                format!(
                    "human: {id} is not a human of this shield ({} humans)",
                    self.humans.len()
                ),
            ));
        }
        if id == 0 {
            if self.pending.as_ref().is_none_or(|p| p.time() < m.time()) {
                self.pending = Some(m);
            }
            Ok(())
        } else {
            self.shield
                .measure_human(id, &m)
                .map_err(|e| (Kind::Input, e.to_string()))
        }
    }

    /// Record an object measurement.
    pub fn measure_object(&mut self, k: usize, m: ObjectMeasurement) -> Result<(), Fail> {
        self.shield
            .measure_object(k, &m)
            .map_err(|e| (Kind::Input, e.to_string()))?;
        let now = self.now();
        if let Some(log) = &mut self.log {
            log.object(now, &self.object_ids[k], &m)
                .map_err(|e| (Kind::Output, format!("log: {e}")))?;
        }
        Ok(())
    }

    /// One safety step at `t` (s): the command for `t + α_s` and the chunk progress after it.
    pub fn step(&mut self, t: f64) -> Result<(Command, ChunkProgress), Fail> {
        if !self.started {
            return Err((Kind::State, "step: call start(t, q) first".into()));
        }
        if !t.is_finite() {
            return Err((Kind::Input, format!("t: value {t} is not finite")));
        }
        if let Some(last) = self.last_t
            && t <= last
        {
            return Err((
                Kind::Input,
                format!("t: {t} s is not after the previous step at {last} s"),
            ));
        }
        if t < self.start_t {
            return Err((
                Kind::Input,
                format!("t: {t} s is before the start at {} s", self.start_t),
            ));
        }
        let take = self.pending.as_ref().is_some_and(|m| m.time() <= t);
        let meas = if take { self.pending.take() } else { None };
        let cmd = self
            .shield
            .step(t, meas.as_ref())
            .map_err(|e| (Kind::State, e.to_string()))?;
        self.last_t = Some(t);
        if let Some(log) = &mut self.log {
            log.record(t, meas.as_ref(), &cmd)
                .map_err(|e| (Kind::Output, format!("log: {e}")))?;
        }
        let progress = self
            .shield
            .chunk_progress()
            .expect("started shields report progress");
        Ok((cmd, progress))
    }

    /// Flush and close the log (idempotent).
    pub fn close(&mut self) -> Result<(), Fail> {
        if let Some(log) = self.log.take() {
            let t = self.now();
            let mut log = log;
            log.event(t, "end")
                .map_err(|e| (Kind::Output, format!("log: {e}")))?;
            log.finish()
                .map_err(|e| (Kind::Output, format!("log: {e}")))?
                .flush()
                .map_err(|e| (Kind::Output, format!("log: {e}")))?;
        }
        Ok(())
    }
}

fn py_bool(b: bool) -> &'static str {
    if b { "True" } else { "False" }
}

/// Raise a [`Fail`].
pub fn raise(f: Fail) -> PyErr {
    err(f.0, f.1)
}

/// Lock the shared state (a poisoned lock is reported, never unwrapped).
pub fn lock(inner: &Mutex<Inner>) -> PyResult<MutexGuard<'_, Inner>> {
    inner
        .lock()
        .map_err(|_| err(Kind::State, "the shield's state was poisoned by a panic"))
}

/// The PACS shield: give it action chunks, human (and object) measurements, and call `step(t)`
/// every safety step (default 1 ms); each step returns the joint command for `t + α_s`, which
/// lies on the intended path of the latest verified chunk or on the verified failsafe braking
/// along it.
///
/// Arguments (units: m, s, rad, kg, J):
///   robot: a built-in name ("fr3"), a robot spec dict, a URDF path (with `side`), or
///     {"urdf": path, "side": path}.
///   humans: a built-in human model name ("default"), a spec dict, a list of them, or None
///     (no human in the scene).
///   constraints: the ISO/TS 15066 task constraints: a built-in name ("sorting" = SSM,
///     "handover" = PFL hand, "feeding", "ssm", "pfl", ...) or a spec dict.
///   objects: dynamic objects, a list of {"id": str, "object": "ball" | spec dict,
///     "contact": "no_contact" | "ssm" | {"pfl": {"threshold": J}}}.
///   environment: static capsules [{"p1": [x, y, z], "p2": [x, y, z], "radius": r}] (clamping).
///   config: shield settings {"mode": "pacs" | "off" | "single-action", "safety_step": s,
///     "tracking_error": m, "velocity_tracking_error": rad/s, "rest_speed": rad/s,
///     "human_model": "combined" | "pos" | "vel" | "acc", "out_of_limits": "reject" | "project",
///     "chunk_motion": "stop" | "continuous"}.
///   side: the side file of a URDF robot (masses, capsules, limits URDF lacks).
///   log: a path: the run is written there as an audit log (format v1, JSON Lines) that
///     `pacs.audit` / `pacs audit` check.
#[pyclass(name = "Shield", module = "pacs")]
pub struct PyShield {
    pub inner: Arc<Mutex<Inner>>,
    dof: usize,
    safety_step: f64,
}

fn chunk_rows(deltas: &Bound<'_, PyAny>, dof: usize) -> PyResult<Vec<Vec<f64>>> {
    let (shape, v) = floats(deltas, "deltas", &[None, Some(dof)])?;
    if shape[0] == 0 {
        return Err(input(
            "deltas: shape [0, _]: a chunk needs at least one action",
        ));
    }
    Ok(v.chunks_exact(dof).map(<[f64]>::to_vec).collect())
}

fn horizon(h: Option<&Bound<'_, PyAny>>, rows: usize) -> PyResult<usize> {
    match h {
        None => Ok(rows),
        Some(h) if h.is_none() => Ok(rows),
        Some(h) => {
            let v: i64 = h
                .extract()
                .map_err(|_| type_err(format!("h: expected an int, got {}", show(h))))?;
            if v < 1 || v as usize > rows {
                return Err(input(format!(
                    "h: {v} is outside 1..={rows} (the number of actions in the chunk)"
                )));
            }
            Ok(v as usize)
        }
    }
}

/// Parse set_chunk arguments (shared with the loop).
pub fn chunk_args(
    dof: usize,
    deltas: &Bound<'_, PyAny>,
    h: Option<&Bound<'_, PyAny>>,
    absolute: bool,
) -> PyResult<(Vec<Vec<f64>>, usize, ActionKind)> {
    let rows = chunk_rows(deltas, dof)?;
    let h = horizon(h, rows.len())?;
    let kind = if absolute {
        ActionKind::Absolute
    } else {
        ActionKind::Delta
    };
    Ok((rows, h, kind))
}

/// Parse measure arguments (shared with the loop).
pub fn measurement(
    inner: &Inner,
    human: usize,
    t_meas: &Bound<'_, PyAny>,
    positions: &Bound<'_, PyAny>,
    velocities: Option<&Bound<'_, PyAny>>,
) -> PyResult<HumanMeasurement> {
    let Some(model) = inner.humans.get(human) else {
        return Err(input(format!(
            "human: {human} is not a human of this shield ({} humans)",
            inner.humans.len()
        )));
    };
    let t = finite(t_meas, "t_meas")?;
    let k = model.keypoint_count();
    let p = points(positions, "positions", Some(k))?;
    let v = match velocities {
        Some(v) if !v.is_none() => Some(points(v, "velocities", Some(k))?),
        _ => None,
    };
    HumanMeasurement::new(model, t, &p, v.as_deref()).map_err(|e| input(e.to_string()))
}

/// Parse measure_object arguments (shared with the loop).
pub fn object_measurement(
    inner: &Inner,
    id: &Bound<'_, PyAny>,
    t_meas: &Bound<'_, PyAny>,
    position: &Bound<'_, PyAny>,
    velocity: Option<&Bound<'_, PyAny>>,
) -> PyResult<(usize, ObjectMeasurement)> {
    let k = if let Ok(s) = id.extract::<String>() {
        inner
            .object_ids
            .iter()
            .position(|o| *o == s)
            .ok_or_else(|| {
                input(format!(
                    "id: no object `{s}` in this shield (objects: {:?})",
                    inner.object_ids
                ))
            })?
    } else if let Ok(i) = id.extract::<usize>() {
        if i >= inner.object_ids.len() {
            return Err(input(format!(
                "id: object {i} does not exist ({} objects)",
                inner.object_ids.len()
            )));
        }
        i
    } else {
        return Err(type_err(format!(
            "id: expected an object id (str) or index, got {}",
            show(id)
        )));
    };
    let t = finite(t_meas, "t_meas")?;
    let p = vector(position, "position", 3)?;
    let v = match velocity {
        Some(v) if !v.is_none() => {
            let v = vector(v, "velocity", 3)?;
            Some([v[0], v[1], v[2]])
        }
        _ => None,
    };
    Ok((
        k,
        ObjectMeasurement {
            time: t,
            position: [p[0], p[1], p[2]],
            velocity: v,
        },
    ))
}

fn time_arg(t: &Bound<'_, PyAny>) -> PyResult<f64> {
    finite(t, "t")
}

#[pymethods]
impl PyShield {
    #[new]
    #[pyo3(signature = (robot=None, humans=None, constraints=None, objects=None, environment=None, config=None, side=None, log=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        robot: Option<&Bound<'_, PyAny>>,
        humans: Option<&Bound<'_, PyAny>>,
        constraints: Option<&Bound<'_, PyAny>>,
        objects: Option<&Bound<'_, PyAny>>,
        environment: Option<&Bound<'_, PyAny>>,
        config: Option<&Bound<'_, PyAny>>,
        side: Option<&Bound<'_, PyAny>>,
        log: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let fr3 = "fr3".into_pyobject(py)?.into_any();
        let default = "default".into_pyobject(py)?.into_any();
        let sorting = "sorting".into_pyobject(py)?.into_any();
        let humans_arg = match humans {
            Some(h) => h.clone(),
            None => default,
        };
        let s = scene(
            robot.unwrap_or(&fr3),
            side,
            &humans_arg,
            constraints.unwrap_or(&sorting),
            objects,
            environment,
        )?;
        let settings: ShieldSettings = match config {
            Some(c) if !c.is_none() => crate::convert::from_py(c, "config")?,
            _ => ShieldSettings::default(),
        };
        let cfg = settings.config().map_err(|e| input(e.to_string()))?;
        let m = &s.models;
        let env = m
            .environment
            .iter()
            .map(pacs_shield::shield::EnvShape::from)
            .collect();
        let first = s.humans.first().map(|h| (h.clone(), &m.constraints));
        let mut shield =
            Shield::new(m.robot.clone(), first, env, cfg).map_err(|e| input(e.to_string()))?;
        for (i, h) in s.humans.iter().enumerate().skip(1) {
            shield
                .add_human(h.clone(), &m.constraints)
                .map_err(|e| input(format!("humans[{i}]: {e}")))?;
        }
        for (id, model, contact) in &m.objects {
            shield
                .add_object(*model, *contact)
                .map_err(|e| input(format!("objects `{id}`: {e}")))?;
        }
        let log_path = match log {
            Some(l) if !l.is_none() => Some(
                l.extract::<PathBuf>()
                    .map_err(|_| type_err(format!("log: expected a path, got {}", show(l))))?,
            ),
            _ => None,
        };
        let dof = m.robot.dof();
        let safety_step = cfg.safety_step;
        let object_ids = m.objects.iter().map(|(id, _, _)| id.clone()).collect();
        let mut header = s.header;
        header.meta.insert(
            "shield_config".into(),
            serde_json::to_value(&settings).unwrap_or_default(),
        );
        Ok(Self {
            inner: Arc::new(Mutex::new(Inner {
                shield,
                dof,
                humans: s.humans,
                object_ids,
                header,
                log_path,
                log: None,
                pending: None,
                last_t: None,
                start_t: 0.0,
                started: false,
                running: false,
                settings,
            })),
            dof,
            safety_step,
        })
    }

    /// Start at rest at joint positions `q` (rad, shape (dof,)) at time `t` (s). The shield only
    /// starts from rest; standing still is the first verified failsafe.
    fn start(&self, t: &Bound<'_, PyAny>, q: &Bound<'_, PyAny>) -> PyResult<()> {
        let t = time_arg(t)?;
        let q = vector(q, "q", self.dof)?;
        let mut g = lock(&self.inner)?;
        if g.running {
            return Err(err(
                Kind::State,
                "start: a ShieldLoop is running this shield",
            ));
        }
        g.start(t, &q).map_err(raise)
    }

    /// Hand over an action chunk: `deltas` (shape (H, dof), rad) are the policy's joint-position
    /// deltas, integrated from the current commanded state into waypoints q̂_1 … q̂_h as in the
    /// paper (`absolute=True`: the rows are joint positions). `h` (default H) actions are
    /// executed; the rest only shape the end of the motion. `t` (s) is when the policy hands
    /// it over (logged). The chunk is planned at once into a jerk-limited intended trajectory
    /// and takes over at the first verified step. Returns the chunk's serial number (1, 2, …;
    /// `Command.chunk`). Raises `pacs.ChunkRejected` if it cannot be planned (e.g. a waypoint
    /// outside the joint limits): the robot keeps its verified motion.
    #[pyo3(signature = (deltas, t, h=None, absolute=false))]
    fn set_chunk(
        &self,
        py: Python<'_>,
        deltas: &Bound<'_, PyAny>,
        t: &Bound<'_, PyAny>,
        h: Option<&Bound<'_, PyAny>>,
        absolute: bool,
    ) -> PyResult<u64> {
        let t = time_arg(t)?;
        let (rows, h, kind) = chunk_args(self.dof, deltas, h, absolute)?;
        let inner = &self.inner;
        let r = py.detach(|| -> Result<u64, Fail> {
            let mut g = inner
                .lock()
                .map_err(|_| (Kind::State, "poisoned shield state".to_string()))?;
            g.set_chunk(t, rows, h, kind)
        });
        r.map_err(raise)
    }

    /// A measurement of human `human`'s keypoints taken at `t_meas` (s): `positions` (m, shape
    /// (K, 3), the model's keypoint order), optional `velocities` (m/s). Older measurements than
    /// the latest are ignored; a measurement reaches the shield at the first step at or after
    /// its time stamp. Until every human has a measurement, no intended step verifies.
    #[pyo3(signature = (t_meas, positions, velocities=None, human=0))]
    fn measure(
        &self,
        t_meas: &Bound<'_, PyAny>,
        positions: &Bound<'_, PyAny>,
        velocities: Option<&Bound<'_, PyAny>>,
        human: usize,
    ) -> PyResult<()> {
        let mut g = lock(&self.inner)?;
        let m = measurement(&g, human, t_meas, positions, velocities)?;
        g.measure(human, m).map_err(raise)
    }

    /// A measurement of object `id` (its id string or index) taken at `t_meas` (s): position
    /// (m, shape (3,)) and, if measured, velocity (m/s).
    #[pyo3(signature = (id, t_meas, position, velocity=None))]
    fn measure_object(
        &self,
        id: &Bound<'_, PyAny>,
        t_meas: &Bound<'_, PyAny>,
        position: &Bound<'_, PyAny>,
        velocity: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<()> {
        let mut g = lock(&self.inner)?;
        let (k, m) = object_measurement(&g, id, t_meas, position, velocity)?;
        g.measure_object(k, m).map_err(raise)
    }

    /// One safety step at time `t` (s; one safety step after the previous one): verifies the
    /// monitored trajectory (one intended step, then braking along the path) against every
    /// human's and object's reachable occupancy and returns the command for `t + safety_step`:
    /// the intended step if verified, else the stored verified failsafe's. Releases the GIL.
    fn step(&self, py: Python<'_>, t: &Bound<'_, PyAny>) -> PyResult<PyCommand> {
        let t = time_arg(t)?;
        let inner = &self.inner;
        let r = py.detach(|| -> Result<(Command, ChunkProgress), Fail> {
            let mut g = inner
                .lock()
                .map_err(|_| (Kind::State, "poisoned shield state".to_string()))?;
            if g.running {
                return Err((
                    Kind::State,
                    "step: a ShieldLoop is running this shield".into(),
                ));
            }
            g.step(t)
        });
        let (cmd, progress) = r.map_err(raise)?;
        Ok(PyCommand { cmd, progress })
    }

    /// Which chunk the commands follow and how many of its actions were executed:
    /// {"chunk": serial (0 = standstill), "passed": actions executed, "executed": h,
    /// "accepted": chunks accepted so far}. What real-time-chunking policies need.
    fn progress<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let g = lock(&self.inner)?;
        match g.shield.chunk_progress() {
            Some(p) => to_py(py, &p),
            None => Err(err(Kind::State, "progress: call start(t, q) first")),
        }
    }

    /// Intended time (s) left until the current chunk's last executed waypoint (None before
    /// start): hand the next chunk over when this drops to about one safety step to keep
    /// `chunk_motion="continuous"` moving across chunks.
    #[getter]
    fn remaining(&self) -> PyResult<Option<f64>> {
        Ok(lock(&self.inner)?.shield.remaining())
    }

    /// Number of joints.
    #[getter]
    fn dof(&self) -> usize {
        self.dof
    }

    /// Safety step α_s (s).
    #[getter]
    fn safety_step(&self) -> f64 {
        self.safety_step
    }

    /// Time of the latest step (s; the start time before the first step).
    #[getter]
    fn time(&self) -> PyResult<f64> {
        Ok(lock(&self.inner)?.now())
    }

    /// Number of humans.
    #[getter]
    fn humans(&self) -> PyResult<usize> {
        Ok(lock(&self.inner)?.humans.len())
    }

    /// Keypoint count of each human (the rows `measure` expects).
    #[getter]
    fn keypoints(&self) -> PyResult<Vec<usize>> {
        Ok(lock(&self.inner)?
            .humans
            .iter()
            .map(HumanModel::keypoint_count)
            .collect())
    }

    /// Object ids, in index order.
    #[getter]
    fn object_ids(&self) -> PyResult<Vec<String>> {
        Ok(lock(&self.inner)?.object_ids.clone())
    }

    /// The log header (dict) the run is logged with: robot, human, constraints, objects.
    #[getter]
    fn header<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let g = lock(&self.inner)?;
        to_py(py, &g.header)
    }

    /// Flush and close the log (if any). The shield can still step; nothing more is logged.
    fn close(&self) -> PyResult<()> {
        lock(&self.inner)?.close().map_err(raise)
    }

    fn __enter__(slf: Py<Self>) -> Py<Self> {
        slf
    }

    #[pyo3(signature = (*_args))]
    fn __exit__(&self, _args: &Bound<'_, pyo3::types::PyTuple>) -> PyResult<bool> {
        self.close()?;
        Ok(false)
    }

    fn __repr__(&self) -> PyResult<String> {
        let g = lock(&self.inner)?;
        Ok(format!(
            "Shield(robot={:?}, dof={}, humans={}, objects={:?}, safety_step={} s, started={})",
            g.shield.robot().name(),
            self.dof,
            g.humans.len(),
            g.object_ids,
            self.safety_step,
            py_bool(g.started)
        ))
    }
}

/// The command of one safety step: joint targets for the low-level controller at `t` and the
/// step's diagnostics.
#[pyclass(name = "Command", module = "pacs", frozen)]
pub struct PyCommand {
    pub cmd: Command,
    pub progress: ChunkProgress,
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
        PyArray1::from_slice(py, &self.cmd.state.q[..self.cmd.dof])
    }
    /// Joint velocities (rad/s), shape (dof,).
    #[getter]
    fn dq<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.cmd.state.dq[..self.cmd.dof])
    }
    /// Joint accelerations (rad/s²), shape (dof,).
    #[getter]
    fn ddq<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.cmd.state.ddq[..self.cmd.dof])
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
    /// What decided the step: {"kind": "none" | "no-measurement" | "no-profile" | "ssm" |
    /// "pfl" | "object", ...indices, energies (J)}.
    #[getter]
    fn binding<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, &self.cmd.diag.binding)
    }
    /// Lower bound of the robot–human separation over the first interval (m; inf without a
    /// human; negative: the occupancies may overlap).
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
        let n = self.cmd.dof;
        let d = &self.cmd.diag;
        let v = serde_json::json!({
            "t": self.cmd.t,
            "q": &self.cmd.state.q[..n],
            "dq": &self.cmd.state.dq[..n],
            "ddq": &self.cmd.state.ddq[..n],
            "verified": d.verified,
            "on_failsafe": d.on_failsafe,
            "binding": d.binding,
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
        let n = self.cmd.dof;
        format!(
            "Command(t={:.4}, verified={}, on_failsafe={}, path_speed={:.3}, chunk={}, passed={}, q={:?})",
            self.cmd.t,
            py_bool(self.cmd.diag.verified),
            py_bool(self.cmd.diag.on_failsafe),
            self.cmd.diag.path_speed,
            self.progress.chunk,
            self.progress.passed,
            &self.cmd.state.q[..n]
        )
    }
}
