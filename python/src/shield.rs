//! `pacs.Shield` and `pacs.Command`: the PACS shield between a policy and a robot.
//!
//! The shield state lives behind a mutex ([`Inner`]) so that [`crate::runner`] can run its step
//! loop on a Rust thread; a direct `step` takes the (uncontended) lock and releases the GIL.

use crate::command::PyCommand;
use crate::convert::{Given, finite, flag, path, show, to_py, vector};
use crate::errors::{Kind, err, input, type_err};
use crate::inputs::{chunk_rows, horizon, measurement, object_measurement};
use crate::models::scene;
use pacs_log::Header;
use pacs_models::human::HumanModel;
use pacs_motion::chunk::{ActionKind, Chunk};
use pacs_shield::ReplanPolicy;
use pacs_shield::session::{PacedHandover, Session, SessionError};
use pacs_shield::settings::ShieldSettings;
use pacs_shield::shield::{BindingNames, ChunkProgress, Command, Shield};
use pyo3::prelude::*;
use std::fs::File;
use std::io::BufWriter;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

/// An error of the shield state, raised as `pacs.<kind>` once the GIL is held again.
pub type Fail = (Kind, String);

/// The shield state between calls: one [`Session`] (shield, measurement inbox, log).
pub type Inner = Session<BufWriter<File>>;

/// A session error as the Python exception it raises.
pub fn fail(e: SessionError) -> Fail {
    use SessionError as E;
    let kind = match &e {
        E::RestartBefore { .. }
        | E::Start(_)
        | E::NotFinite(_)
        | E::OffGrid { .. }
        | E::BeforeStart { .. }
        | E::FirstOffGrid { .. }
        | E::InboxFull(_)
        | E::Queue { .. } => Kind::Input,
        E::ChunkRejected(_) | E::NotHandedOver { .. } => Kind::Chunk,
        E::LogCreate { .. } | E::LogHeader { .. } | E::Log { .. } => Kind::Output,
        E::NotStarted(_)
        | E::LoggedRunsOnce
        | E::Delivery(_)
        | E::Step(_)
        | E::Poisoned(_)
        | E::LoopStopped
        | E::Restarted
        | E::Offer(_) => Kind::State,
    };
    (kind, e.to_string())
}

/// One step of the session at `t` (s) and the chunk progress after it.
pub fn step(g: &mut Inner, t: f64) -> Result<(Command, ChunkProgress), Fail> {
    let cmd = g.step(t).map_err(fail)?;
    let progress = g
        .progress()
        .ok_or((Kind::State, "step: shield not started".to_string()))?;
    Ok((cmd, progress))
}

/// Run `f` on the shield state with the GIL released (so that no thread ever waits for the
/// lock while holding the GIL, and no Python code runs while the lock is held).
pub fn with_inner<R: Send>(
    py: Python<'_>,
    inner: &Mutex<Inner>,
    f: impl FnOnce(&mut Inner) -> Result<R, Fail> + Send,
) -> PyResult<R> {
    py.detach(|| {
        let mut g = inner.lock().map_err(|_| {
            (
                Kind::State,
                "the shield's state was poisoned by a panic".to_string(),
            )
        })?;
        f(&mut g)
    })
    .map_err(raise)
}

pub fn py_bool(b: bool) -> &'static str {
    if b { "True" } else { "False" }
}

/// Raise a [`Fail`].
pub fn raise(f: Fail) -> PyErr {
    err(f.0, f.1)
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
///   log: a path: the run is written there as an audit log (format v2, JSON Lines, every
///     person with an id) that `pacs.audit` / `pacs audit` check.
///
/// Timing: `step(t)` is called every safety step, t_k = t_0 + k·α_s (other times are refused);
/// a measurement (human or object) reaches the shield at the first step at or after its time
/// stamp; a chunk is planned at once and tried at the next step: if that step does not verify
/// it, the chunk is dropped (the robot keeps its verified failsafe; `Command.chunk` and
/// `progress()` tell which chunk runs) and the policy should hand over a new one.
#[pyclass(name = "Shield", module = "pacs")]
pub struct PyShield {
    pub h: Handle,
}

/// What `Shield` and `ShieldLoop` share: the shield state and the immutable facts its
/// arguments are checked against (read without the lock); the calls both classes offer.
#[derive(Clone)]
pub struct Handle {
    pub inner: Arc<Mutex<Inner>>,
    pub dof: usize,
    pub safety_step: f64,
    /// Human models, in index order.
    pub humans: Vec<HumanModel>,
    /// Object ids, in index order.
    pub object_ids: Vec<String>,
    /// The names a command's binding indices stand for.
    pub names: Arc<BindingNames>,
    /// Hands chunks over while a `ShieldLoop` steps the shield.
    pub paced: Arc<PacedHandover>,
    /// The log header the run is written with.
    pub header: Arc<Header>,
    /// Where the run is logged, if it is.
    pub log_path: Option<PathBuf>,
    /// The human model `acc` needs every measurement's velocities.
    pub needs_velocities: bool,
}

impl Handle {
    /// `set_chunk` (see `Shield.set_chunk`).
    pub fn set_chunk(
        &self,
        py: Python<'_>,
        deltas: &Bound<'_, PyAny>,
        h: Option<&Bound<'_, PyAny>>,
        absolute: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<u64> {
        let rows = chunk_rows(deltas, self.dof)?;
        let h = horizon(h, rows.len())?;
        let kind = match absolute {
            Some(a) if flag(a, "absolute")? => ActionKind::Absolute,
            _ => ActionKind::Delta,
        };
        let chunk = Chunk {
            kind,
            actions: rows,
            execute: h,
            gripper: None,
        };
        py.detach(|| self.hand_over(&chunk)).map_err(raise)
    }

    /// Hand `chunk` over (the GIL released): at once without a real-time loop, else paced
    /// ([`PacedHandover`]: planned off the shield's lock, the loop's steps never wait for it).
    fn hand_over(&self, chunk: &Chunk) -> Result<u64, Fail> {
        self.paced.hand_over(&self.inner, chunk).map_err(fail)
    }

    /// Start at rest at `q` (rad) at `t` (s); opens the log if one was asked for.
    pub fn start(&self, py: Python<'_>, t: f64, q: &[f64]) -> PyResult<()> {
        with_inner(py, &self.inner, |g| {
            if g.driver().is_some() {
                return Err((
                    Kind::State,
                    "start: a ShieldLoop is running this shield".into(),
                ));
            }
            match &self.log_path {
                Some(p) => g.start_logged(t, q, &self.header, &p.display().to_string(), || {
                    File::create(p).map(BufWriter::new)
                }),
                None => g.start(t, q),
            }
            .map_err(fail)
        })
    }

    /// `measure` (see `Shield.measure`; `human` None: the only person).
    pub fn measure(
        &self,
        py: Python<'_>,
        t_meas: &Bound<'_, PyAny>,
        positions: &Bound<'_, PyAny>,
        velocities: Option<&Bound<'_, PyAny>>,
        human: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<()> {
        if self.needs_velocities && velocities.is_none_or(|v| v.is_none()) {
            return Err(input(
                "velocities: required with human_model `acc` (a measurement without them would never let a step verify; use `combined`, the default, to measure positions alone)"
                    .to_string(),
            ));
        }
        let ids: Vec<&str> = self.header.people().into_iter().map(|(id, _)| id).collect();
        let (id, m) = measurement(&self.humans, &ids, human, t_meas, positions, velocities)?;
        with_inner(py, &self.inner, move |g| {
            g.measure_person(id, m).map_err(fail)
        })
    }

    /// `measure_object` (see `Shield.measure_object`).
    pub fn measure_object(
        &self,
        py: Python<'_>,
        id: &Bound<'_, PyAny>,
        t_meas: &Bound<'_, PyAny>,
        position: &Bound<'_, PyAny>,
        velocity: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<()> {
        let (k, m) = object_measurement(&self.object_ids, id, t_meas, position, velocity)?;
        with_inner(py, &self.inner, move |g| {
            g.measure_object(k, m).map_err(fail)
        })
    }

    /// `progress()` as a dict.
    pub fn progress<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let p = with_inner(py, &self.inner, |g| {
            g.progress()
                .ok_or((Kind::State, "progress: call start(t, q) first".into()))
        })?;
        to_py(py, &p)
    }

    /// The time of the latest step (s).
    pub fn time(&self, py: Python<'_>) -> PyResult<f64> {
        with_inner(py, &self.inner, |g| Ok(g.now()))
    }
}

#[pymethods]
impl PyShield {
    #[new]
    #[pyo3(signature = (robot=None, humans=Given::Missing, constraints=None, objects=None, environment=None, config=None, side=None, log=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        robot: Option<&Bound<'_, PyAny>>,
        humans: Given<'_>,
        constraints: Option<&Bound<'_, PyAny>>,
        objects: Option<&Bound<'_, PyAny>>,
        environment: Option<&Bound<'_, PyAny>>,
        config: Option<&Bound<'_, PyAny>>,
        side: Option<&Bound<'_, PyAny>>,
        log: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let s = scene(py, robot, side, humans, constraints, objects, environment)?;
        let settings: ShieldSettings = match config {
            // A dict only: a list would fill the fields in order, silently.
            Some(c) if !c.is_none() && !c.is_instance_of::<pyo3::types::PyDict>() => {
                return Err(type_err(format!(
                    "config: expected a dict of shield settings, got {}",
                    show(c)
                )));
            }
            Some(c) if !c.is_none() => crate::convert::from_py(c, "config")?,
            _ => ShieldSettings::default(),
        };
        let cfg = settings.config().map_err(|e| input(e.to_string()))?;
        let m = &s.models;
        // Person ids as the log names them: the header's (several people), else `human`.
        let person_ids: Vec<String> = if s.header.humans.is_empty() {
            vec![pacs_log::V1_PERSON.to_string()]
        } else {
            s.header.humans.iter().map(|p| p.id.clone()).collect()
        };
        let object_ids: Vec<String> = m.objects.iter().map(|(id, _, _)| id.clone()).collect();
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
            Some(l) if !l.is_none() => Some(path(l, "log")?),
            _ => None,
        };
        let dof = m.robot.dof();
        let safety_step = cfg.safety_step;
        let names = Arc::new(shield.binding_names(&person_ids, &object_ids));
        let mut header = s.header;
        header.meta.insert(
            "shield_config".into(),
            serde_json::to_value(&settings).unwrap_or_default(),
        );
        // The filter that ran (reports group runs by it), as `pacs shield` records it.
        header.meta.insert("filter".into(), cfg.mode.label().into());
        header
            .meta
            .insert("tool".into(), "pacs python Shield".into());
        let paced = Arc::new(PacedHandover::new(&shield, ReplanPolicy::DEFAULT));
        Ok(Self {
            h: Handle {
                inner: Arc::new(Mutex::new(Session::new(shield, object_ids.clone()))),
                paced,
                header: Arc::new(header),
                log_path,
                dof,
                safety_step,
                humans: s.humans,
                object_ids,
                names,
                needs_velocities: cfg.human_model == pacs_reach::human::HumanReachModel::Acc,
            },
        })
    }

    /// Start at rest at joint positions `q` (rad, shape (dof,)) at time `t` (s). The shield only
    /// starts from rest; standing still is the first verified failsafe. Steps then run at
    /// t, t + α_s, t + 2·α_s, … A shield that logs starts once.
    fn start(&self, py: Python<'_>, t: &Bound<'_, PyAny>, q: &Bound<'_, PyAny>) -> PyResult<()> {
        let t = finite(t, "t")?;
        let q = vector(q, "q", self.h.dof)?;
        self.h.start(py, t, &q)
    }

    /// Hand over an action chunk: `deltas` (shape (H, dof), rad) are the policy's joint-position
    /// deltas, integrated from the current commanded state into waypoints q̂_1 … q̂_h as in the
    /// paper (`absolute=True`: the rows are joint positions). `h` (default H) actions are
    /// executed; the rest only shape the end of the motion. `t` (s) is when the policy hands
    /// it over (checked finite; the log records the handover at the shield's time). The chunk
    /// is planned at once into a jerk-limited intended trajectory and tried at the next step;
    /// if that step does not verify it, the chunk is dropped (see the class doc). Returns the
    /// chunk's serial number (1, 2, …; `Command.chunk`). Raises `pacs.ChunkRejected` if it
    /// cannot be planned (e.g. a waypoint outside the joint limits, or a start state braking
    /// harder than the intended limits): the robot keeps its verified motion.
    #[pyo3(signature = (deltas, t, h=None, absolute=None))]
    fn set_chunk(
        &self,
        py: Python<'_>,
        deltas: &Bound<'_, PyAny>,
        t: &Bound<'_, PyAny>,
        h: Option<&Bound<'_, PyAny>>,
        absolute: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<u64> {
        finite(t, "t")?;
        self.h.set_chunk(py, deltas, h, absolute)
    }

    /// A measurement of person `human`'s keypoints (its id, as in `header["humans"]`, or its
    /// index; required with several people, default the only one) taken at `t_meas` (s):
    /// `positions` (m, shape (K, 3), the model's keypoint order), optional `velocities` (m/s).
    /// It reaches the shield
    /// at the first step at or after `t_meas`; per step the newest is used, older ones than the
    /// shield's latest are ignored. Until every human has a measurement, no intended step
    /// verifies.
    #[pyo3(signature = (t_meas, positions, velocities=None, human=None))]
    fn measure(
        &self,
        py: Python<'_>,
        t_meas: &Bound<'_, PyAny>,
        positions: &Bound<'_, PyAny>,
        velocities: Option<&Bound<'_, PyAny>>,
        human: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<()> {
        self.h.measure(py, t_meas, positions, velocities, human)
    }

    /// A measurement of object `id` (its id string or index) taken at `t_meas` (s): position
    /// (m, shape (3,)) and, if measured, velocity (m/s). It reaches the shield at the first
    /// step at or after `t_meas`.
    #[pyo3(signature = (id, t_meas, position, velocity=None))]
    fn measure_object(
        &self,
        py: Python<'_>,
        id: &Bound<'_, PyAny>,
        t_meas: &Bound<'_, PyAny>,
        position: &Bound<'_, PyAny>,
        velocity: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<()> {
        self.h.measure_object(py, id, t_meas, position, velocity)
    }

    /// One safety step at time `t` (s; the start time, then one safety step after the previous
    /// one): verifies the monitored trajectory (one intended step, then braking along the path)
    /// against every human's and object's reachable occupancy and returns the command for
    /// `t + safety_step`: the intended step if verified, else the stored verified failsafe's.
    /// Releases the GIL.
    fn step(&self, py: Python<'_>, t: &Bound<'_, PyAny>) -> PyResult<PyCommand> {
        let t = finite(t, "t")?;
        let (cmd, progress) = with_inner(py, &self.h.inner, |g| {
            if g.driver().is_some() {
                return Err((
                    Kind::State,
                    "step: a ShieldLoop is running this shield".into(),
                ));
            }
            step(g, t)
        })?;
        Ok(PyCommand {
            cmd,
            progress,
            names: self.h.names.clone(),
        })
    }

    /// Which chunk the commands follow and how many of its actions were executed:
    /// {"chunk": serial (0 = standstill), "passed": actions executed, "executed": h,
    /// "accepted": chunks accepted so far}. What real-time-chunking policies need.
    fn progress<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.h.progress(py)
    }

    /// Intended time (s) left until the current chunk's last executed waypoint (None before
    /// start): hand the next chunk over when this drops to about one safety step to keep
    /// `chunk_motion="continuous"` moving across chunks.
    #[getter]
    fn remaining(&self, py: Python<'_>) -> PyResult<Option<f64>> {
        with_inner(py, &self.h.inner, |g| Ok(g.shield().remaining()))
    }

    /// Number of joints.
    #[getter]
    fn dof(&self) -> usize {
        self.h.dof
    }

    /// Safety step α_s (s).
    #[getter]
    fn safety_step(&self) -> f64 {
        self.h.safety_step
    }

    /// Time of the latest step (s; the start time before the first step).
    #[getter]
    fn time(&self, py: Python<'_>) -> PyResult<f64> {
        self.h.time(py)
    }

    /// Number of humans.
    #[getter]
    fn humans(&self) -> usize {
        self.h.humans.len()
    }

    /// Keypoint count of each human (the rows `measure` expects).
    #[getter]
    fn keypoints(&self) -> Vec<usize> {
        self.h
            .humans
            .iter()
            .map(HumanModel::keypoint_count)
            .collect()
    }

    /// Object ids, in index order.
    #[getter]
    fn object_ids(&self) -> Vec<String> {
        self.h.object_ids.clone()
    }

    /// The log header (dict) the run is logged with, as the log's first line holds it: version
    /// 2, the robot, the people (`humans`, each with its id), constraints, objects, and the
    /// `start_event` / `end_event` promises (the log writes the `start` event before its first
    /// robot sample and the `end` event on `close()`).
    #[getter]
    fn header<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, &(*self.h.header).clone().promising_end())
    }

    /// Flush and close the log (if any); raises `pacs.OutputError` if a log write failed
    /// during the run (the run went on; nothing was logged after the failure). The shield can
    /// still step; nothing more is logged.
    fn close(&self, py: Python<'_>) -> PyResult<()> {
        with_inner(py, &self.h.inner, |g| g.close().map_err(fail))
    }

    fn __enter__(slf: Py<Self>) -> Py<Self> {
        slf
    }

    #[pyo3(signature = (*_args))]
    fn __exit__(&self, py: Python<'_>, _args: &Bound<'_, pyo3::types::PyTuple>) -> PyResult<bool> {
        self.close(py)?;
        Ok(false)
    }

    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        let (name, started) = with_inner(py, &self.h.inner, |g| {
            Ok((g.shield().robot().name().to_string(), g.started()))
        })?;
        Ok(format!(
            "Shield(robot={name:?}, dof={}, humans={}, objects={:?}, safety_step={} s, started={})",
            self.h.dof,
            self.h.humans.len(),
            self.h.object_ids,
            self.h.safety_step,
            py_bool(started)
        ))
    }
}
