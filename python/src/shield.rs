//! `pacs.Shield` and `pacs.Command`: the PACS shield between a policy and a robot.
//!
//! The shield state lives behind a mutex ([`Inner`]) so that [`crate::runner`] can run its step
//! loop on a Rust thread; a direct `step` takes the (uncontended) lock and releases the GIL.

use crate::convert::{Given, finite, flag, floats, index, path, points, show, to_py, vector};
use crate::errors::{Kind, err, input, type_err};
use crate::models::scene;
use numpy::PyArray1;
use pacs_log::Header;
use pacs_models::human::HumanModel;
use pacs_motion::chunk::{ActionKind, Chunk};
use pacs_reach::human::HumanMeasurement;
use pacs_reach::object::ObjectMeasurement;
use pacs_shield::ReplanPolicy;
use pacs_shield::session::{Due, MeasurementInbox, Pending};
use pacs_shield::settings::ShieldSettings;
use pacs_shield::shield::{
    BindingNames, ChunkPlanner, ChunkProgress, Command, OfferState, Shield, ShieldError,
};
use pacs_shield::shield_log::ShieldLog;
use pyo3::prelude::*;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// An error of the shield state, raised as `pacs.<kind>` once the GIL is held again.
pub type Fail = (Kind, String);

/// How `set_chunk` plans a chunk again after a failed hand-over (attempts, lead).
const REPLAN: ReplanPolicy = ReplanPolicy::DEFAULT;

/// Measurements waiting for a step at or after their time stamp (people's, objects').
const MAX_PENDING: usize = 4096;

/// Everything a shield needs between calls.
pub struct Inner {
    pub shield: Shield,
    pub dof: usize,
    pub header: Header,
    pub log_path: Option<PathBuf>,
    pub log: Option<ShieldLog<BufWriter<File>>>,
    /// The first log write that failed (the run goes on; `close` reports it).
    pub log_error: Option<String>,
    /// The log was opened (a logging shield starts once).
    pub log_opened: bool,
    /// Human and object measurements not yet handed to a step: each arrives at its time stamp
    /// and reaches the shield (and the log) at the first step at or after it.
    pub inbox: MeasurementInbox,
    /// Time of the last step (s).
    pub last_t: Option<f64>,
    pub start_t: f64,
    pub started: bool,
    /// The `ShieldLoop` (its id) that steps this shield: direct steps are refused meanwhile.
    pub running: Option<u64>,
    /// A real-time `ShieldLoop` thread is stepping the shield: chunks are planned off the lock
    /// and handed over a few steps ahead ([`Handle::set_chunk`]).
    pub paced: bool,
    pub settings: ShieldSettings,
}

impl Inner {
    /// Start at rest at `q` (rad) at `t` (s); opens the log if one was asked for.
    pub fn start(&mut self, t: f64, q: &[f64]) -> Result<(), Fail> {
        if self.running.is_some() {
            return Err((
                Kind::State,
                "start: a ShieldLoop is running this shield".into(),
            ));
        }
        if self.log_opened {
            return Err((
                Kind::State,
                "start: a shield that logs (log=...) runs once; create a new Shield for a new run"
                    .into(),
            ));
        }
        if self.started && t < self.now() {
            return Err((
                Kind::Input,
                format!(
                    "t: a restart at {t} s is before the shield's time {} s (its measurements would look newer than the new ones)",
                    self.now()
                ),
            ));
        }
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
            self.log_opened = true;
        }
        self.started = true;
        self.last_t = None;
        self.start_t = t;
        Ok(())
    }

    /// The time of the latest step (or the start time).
    pub fn now(&self) -> f64 {
        self.last_t.unwrap_or(self.start_t)
    }

    /// Record a log failure (the first one) and stop logging; the run goes on.
    fn log_failed(&mut self, e: impl std::fmt::Display) {
        log_failed(
            &mut self.log,
            &mut self.log_error,
            self.log_path.as_ref(),
            e,
        );
    }

    /// Hand over a chunk (rows of `dof` values); returns its serial number.
    pub fn set_chunk(&mut self, chunk: &Chunk) -> Result<u64, Fail> {
        if !self.started {
            return Err((Kind::State, "set_chunk: call start(t, q) first".into()));
        }
        let r = self.shield.set_chunk(chunk);
        self.log_chunk(r.is_ok());
        r.map_err(|e| (Kind::Chunk, format!("set_chunk: {e}")))?;
        Ok(self.shield.chunk_progress().map_or(0, |p| p.accepted))
    }

    /// Log a chunk event (taken over or rejected) at the shield's time.
    fn log_chunk(&mut self, taken: bool) {
        let now = self.now();
        let event = if taken { "chunk" } else { "chunk_rejected" };
        if let Some(log) = &mut self.log
            && let Err(e) = log.event(now, event)
        {
            self.log_failed(e);
        }
    }

    fn queue_full(len: usize, what: &str) -> Result<(), Fail> {
        if len >= MAX_PENDING {
            return Err((
                Kind::Input,
                format!(
                    "{what}: {MAX_PENDING} measurements already wait for a step at or after their time stamps (are they stamped ahead of the shield's clock?)"
                ),
            ));
        }
        Ok(())
    }

    /// Queue a human measurement (human index validated by the caller).
    pub fn measure(&mut self, id: usize, m: HumanMeasurement) -> Result<(), Fail> {
        Self::queue_full(self.inbox.people_waiting(), "measure")?;
        self.inbox
            .push_person(m.time(), id, m)
            .map_err(|e| (Kind::Input, format!("measure: {e}")))
    }

    /// Queue an object measurement (object index validated by the caller).
    pub fn measure_object(&mut self, k: usize, m: ObjectMeasurement) -> Result<(), Fail> {
        Self::queue_full(self.inbox.objects_waiting(), "measure_object")?;
        self.inbox
            .push_object(m.time, k, m)
            .map_err(|e| (Kind::Input, format!("measure_object: {e}")))
    }

    /// One safety step at `t` (s): the command for `t + α_s` and the chunk progress after it.
    /// Steps follow each other by exactly one safety step (the grid the shield verifies).
    pub fn step(&mut self, t: f64) -> Result<(Command, ChunkProgress), Fail> {
        if !self.started {
            return Err((Kind::State, "step: call start(t, q) first".into()));
        }
        if !t.is_finite() {
            return Err((Kind::Input, format!("t: value {t} is not finite")));
        }
        let alpha = self.shield.config().safety_step;
        // Float rounding of t = t_0 + k·α_s grows with |t| (a Unix-time t_0 has ulps of 2e-7 s).
        let tol = pacs_shield::shield::time_tolerance(t);
        match self.last_t {
            Some(last) if (t - (last + alpha)).abs() > tol => {
                return Err((
                    Kind::Input,
                    format!(
                        "t: {t} s, but steps follow each other by the safety step: the previous step was at {last} s, so this one is at {} s",
                        last + alpha
                    ),
                ));
            }
            None if t < self.start_t - tol => {
                return Err((
                    Kind::Input,
                    format!("t: {t} s is before the start at {} s", self.start_t),
                ));
            }
            _ => {}
        }
        // Every measurement stamped at or before t reaches the shield and is logged, also
        // those the shield will not use (it keeps the newest): the audit checks each against its
        // model beside its neighbours in time and uses the newest, as the shield does, so a
        // measurement that the others contradict cannot hide behind a newer one.
        let Inner {
            inbox,
            shield,
            log,
            log_error,
            log_path,
            ..
        } = self;
        let Due {
            first,
            log_error: failed,
        } = inbox
            .deliver(t, shield, log.as_mut())
            .map_err(|e| (Kind::State, e.to_string()))?;
        if let Some(e) = failed {
            log_failed(log, log_error, log_path.as_ref(), e);
        }
        let cmd = shield
            .step(t, first)
            .map_err(|e| (Kind::State, e.to_string()))?;
        self.last_t = Some(t);
        if let Some(l) = log.as_mut()
            && let Err(e) = l.record(t, first, &cmd)
        {
            // The step happened: its command is returned; the log stops (reported by close).
            log_failed(log, log_error, log_path.as_ref(), e);
        }
        let progress = shield
            .chunk_progress()
            .ok_or((Kind::State, "step: shield not started".to_string()))?;
        Ok((cmd, progress))
    }

    /// Flush and close the log (idempotent); reports a log failure of the run once.
    pub fn close(&mut self) -> Result<(), Fail> {
        if let Some(mut log) = self.log.take() {
            let t = self.now();
            // Measurements still waiting for a step but stamped within the run (at or before
            // the last command's time: late frames of a camera with latency) are logged too:
            // the audit checks them against the model and calls the run inconclusive if they
            // describe a time it covers, instead of never seeing them.
            let t_end = self
                .last_t
                .map_or(self.start_t, |l| l + self.shield.config().safety_step);
            let mut r: Result<(), String> = Ok(());
            for (_, p) in self.inbox.pending() {
                if r.is_err() || self.last_t.is_none() {
                    break;
                }
                r = match p {
                    Pending::Person(id, m) if m.time() <= t_end => log.person(t_end, id, m),
                    Pending::Object(k, m) if m.time <= t_end => {
                        log.object(t_end, &self.inbox.object_ids()[k], m)
                    }
                    _ => Ok(()),
                }
                .map_err(|e| e.to_string());
            }
            // `finish` writes the `end` event the header promises.
            let _ = t;
            let r = r
                .and_then(|()| log.finish().map_err(|e| e.to_string()))
                .and_then(|mut w| w.flush().map_err(|e| e.to_string()));
            if let Err(e) = r {
                self.log_failed(e);
            }
        }
        match self.log_error.take() {
            Some(e) => Err((Kind::Output, e)),
            None => Ok(()),
        }
    }
}

/// Record a log failure (the first one, in `log_error`) and stop logging (`log` cleared).
fn log_failed<W>(
    log: &mut Option<W>,
    log_error: &mut Option<String>,
    log_path: Option<&PathBuf>,
    e: impl std::fmt::Display,
) {
    if log_error.is_none() {
        let p = log_path
            .map(|p| p.display().to_string())
            .unwrap_or_default();
        *log_error = Some(format!("log {p}: {e} (nothing was logged after this)"));
    }
    *log = None;
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

fn py_bool(b: bool) -> &'static str {
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
///   log: a path: the run is written there as an audit log (format v1, JSON Lines) that
///     `pacs.audit` / `pacs audit` check (one human at most: the log format carries one).
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
    /// Plans chunks off the shield's lock while a real-time loop steps it.
    pub planner: Arc<Mutex<ChunkPlanner>>,
    /// The longest recent planning time (µs), for the handover's lead.
    pub plan_us: Arc<AtomicU64>,
    /// Held for a whole `set_chunk`: one hand-over at a time per shield.
    pub handover: Arc<Mutex<()>>,
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

    /// Hand `chunk` over (the GIL released). Without a real-time loop: planned from the current
    /// commanded state at once ([`Shield::set_chunk`]). While a real-time loop steps the shield:
    /// planned off the shield's lock from the state predicted a few steps ahead
    /// ([`Shield::likely_handover`]), offered, and awaited until a step follows it (planned again if
    /// the commands went elsewhere) — the loop's steps never wait for the planner.
    fn hand_over(&self, chunk: &Chunk) -> Result<u64, Fail> {
        // One hand-over at a time per shield: the shield reports the state of its latest offer
        // only, so concurrent callers would read each other's.
        let _one = self
            .handover
            .lock()
            .map_err(|_| (Kind::State, "poisoned hand-over state".to_string()))?;
        let lock = || {
            self.inner
                .lock()
                .map_err(|_| (Kind::State, "poisoned shield state".to_string()))
        };
        let mut lead = self.lead();
        let (mut late, mut moved, mut dropped) = (0, 0, 0);
        for _ in 0..REPLAN.attempts {
            let ho = {
                let mut g = lock()?;
                if !g.started {
                    return Err((Kind::State, "set_chunk: call start(t, q) first".into()));
                }
                if !g.paced {
                    return g.set_chunk(chunk);
                }
                // Where the commands will be if the next steps go as the latest one did (the
                // shield's one prediction rule, also the ChunkWorker's).
                g.shield
                    .likely_handover(lead)
                    .ok_or((Kind::State, "set_chunk: shield not started".to_string()))?
            };
            let prepared = {
                let mut planner = self
                    .planner
                    .lock()
                    .map_err(|_| (Kind::State, "poisoned planner state".to_string()))?;
                let clock = Instant::now();
                let p = planner.prepare(&ho, chunk);
                // The lead follows the recent planning times: the longest, decaying by a quarter
                // per chunk (one slow plan does not fix a long lead for good).
                let us = clock.elapsed().as_micros().min(u64::MAX as u128) as u64;
                let old = self.plan_us.load(Ordering::Relaxed);
                self.plan_us.store(us.max(old - old / 4), Ordering::Relaxed);
                p
            };
            let prepared = match prepared {
                Ok(p) => p,
                Err(e) => {
                    lock()?.log_chunk(false);
                    return Err((Kind::Chunk, format!("set_chunk: {e}")));
                }
            };
            match lock()?.shield.offer(prepared) {
                Ok(()) => {}
                Err(ShieldError::Stale { .. }) => {
                    // Planned too late: look further ahead.
                    late += 1;
                    lead = REPLAN.longer_lead(lead);
                    continue;
                }
                Err(e) => return Err((Kind::State, format!("set_chunk: {e}"))),
            }
            // Wait for the shield's record of the offer's fate: followed (a step verified its
            // first monitored step), dropped (that step did not), or stale.
            loop {
                let mut g = lock()?;
                match g.shield.offer_state() {
                    OfferState::Followed(n) => {
                        g.log_chunk(true);
                        return Ok(n);
                    }
                    OfferState::Taken(n) if !g.paced => {
                        // Installed with nobody stepping: the next step tries it.
                        g.log_chunk(true);
                        return Ok(n);
                    }
                    OfferState::Taken(_) => {}
                    OfferState::Dropped(_) => {
                        dropped += 1;
                        break;
                    }
                    OfferState::Stale => {
                        moved += 1;
                        break;
                    }
                    OfferState::Waiting if !g.paced => {
                        // Nobody steps the shield now: withdraw, so that no later step takes
                        // over a chunk its caller was told was not handed over.
                        g.shield.withdraw_offer();
                        return Err((
                            Kind::State,
                            "set_chunk: the ShieldLoop stopped before the chunk's handover (hand it over again)".into(),
                        ));
                    }
                    OfferState::Waiting => {}
                    OfferState::None => {
                        return Err((
                            Kind::State,
                            "set_chunk: the shield was restarted during the handover".into(),
                        ));
                    }
                }
                drop(g);
                std::thread::sleep(Duration::from_secs_f64(self.safety_step / 4.0));
            }
        }
        lock()?.log_chunk(false);
        Err((
            Kind::Chunk,
            format!(
                "set_chunk: not handed over in {} attempts: {moved} times the commands left the predicted path before the handover (steps not verified: a person near the robot?), {dropped} times the chunk's first step was not verified, {late} times planning took longer than the lead; the robot keeps its verified motion",
                REPLAN.attempts
            ),
        ))
    }

    /// Safety steps between a handover's prediction and the step that takes the chunk over:
    /// twice the recent longest planning time (decaying per chunk), plus one step (at least 2).
    fn lead(&self) -> usize {
        let plan_s = self.plan_us.load(Ordering::Relaxed) as f64 * 1e-6;
        REPLAN.lead_for(plan_s, self.safety_step)
    }

    /// `measure` (see `Shield.measure`; `human` None: the first).
    pub fn measure(
        &self,
        py: Python<'_>,
        t_meas: &Bound<'_, PyAny>,
        positions: &Bound<'_, PyAny>,
        velocities: Option<&Bound<'_, PyAny>>,
        human: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<()> {
        let (id, m) = measurement(&self.humans, human, t_meas, positions, velocities)?;
        with_inner(py, &self.inner, move |g| g.measure(id, m))
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
        with_inner(py, &self.inner, move |g| g.measure_object(k, m))
    }

    /// `progress()` as a dict.
    pub fn progress<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let p = with_inner(py, &self.inner, |g| {
            g.shield
                .chunk_progress()
                .ok_or((Kind::State, "progress: call start(t, q) first".into()))
        })?;
        to_py(py, &p)
    }

    /// The time of the latest step (s).
    pub fn time(&self, py: Python<'_>) -> PyResult<f64> {
        with_inner(py, &self.inner, |g| Ok(g.now()))
    }
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
        Some(h) if !h.is_none() => {
            let v = index(h, "h")?;
            if v < 1 || v > rows {
                return Err(input(format!(
                    "h: {v} is outside 1..={rows} (the number of actions in the chunk)"
                )));
            }
            Ok(v)
        }
        _ => Ok(rows),
    }
}

/// Parse measure arguments: the human index (default 0) and the measurement.
fn measurement(
    humans: &[HumanModel],
    human: Option<&Bound<'_, PyAny>>,
    t_meas: &Bound<'_, PyAny>,
    positions: &Bound<'_, PyAny>,
    velocities: Option<&Bound<'_, PyAny>>,
) -> PyResult<(usize, HumanMeasurement)> {
    let id = match human {
        Some(h) if !h.is_none() => index(h, "human")?,
        _ => 0,
    };
    let Some(model) = humans.get(id) else {
        return Err(input(format!(
            "human: {id} is not a human of this shield ({} humans)",
            humans.len()
        )));
    };
    let t = finite(t_meas, "t_meas")?;
    let k = model.keypoint_count();
    let p = points(positions, "positions", Some(k))?;
    let v = match velocities {
        Some(v) if !v.is_none() => Some(points(v, "velocities", Some(k))?),
        _ => None,
    };
    let m = HumanMeasurement::new(model, t, &p, v.as_deref()).map_err(|e| input(e.to_string()))?;
    Ok((id, m))
}

/// Parse measure_object arguments.
fn object_measurement(
    object_ids: &[String],
    id: &Bound<'_, PyAny>,
    t_meas: &Bound<'_, PyAny>,
    position: &Bound<'_, PyAny>,
    velocity: Option<&Bound<'_, PyAny>>,
) -> PyResult<(usize, ObjectMeasurement)> {
    let k = if let Ok(s) = id.extract::<String>() {
        object_ids.iter().position(|o| *o == s).ok_or_else(|| {
            input(format!(
                "id: no object `{s}` in this shield (objects: {object_ids:?})"
            ))
        })?
    } else if id.is_instance_of::<pyo3::types::PyInt>() {
        let i = index(id, "id")?;
        if i >= object_ids.len() {
            return Err(input(format!(
                "id: object {i} does not exist ({} objects)",
                object_ids.len()
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
        let planner = shield.chunk_planner();
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
        Ok(Self {
            h: Handle {
                inner: Arc::new(Mutex::new(Inner {
                    shield,
                    dof,
                    header,
                    log_path,
                    log: None,
                    log_error: None,
                    log_opened: false,
                    inbox: MeasurementInbox::new(s.humans.len(), object_ids.clone()),
                    last_t: None,
                    start_t: 0.0,
                    started: false,
                    running: None,
                    paced: false,
                    settings,
                })),
                planner: Arc::new(Mutex::new(planner)),
                plan_us: Arc::new(AtomicU64::new(1000)),
                handover: Arc::new(Mutex::new(())),
                dof,
                safety_step,
                humans: s.humans,
                object_ids,
                names,
            },
        })
    }

    /// Start at rest at joint positions `q` (rad, shape (dof,)) at time `t` (s). The shield only
    /// starts from rest; standing still is the first verified failsafe. Steps then run at
    /// t, t + α_s, t + 2·α_s, … A shield that logs starts once.
    fn start(&self, py: Python<'_>, t: &Bound<'_, PyAny>, q: &Bound<'_, PyAny>) -> PyResult<()> {
        let t = finite(t, "t")?;
        let q = vector(q, "q", self.h.dof)?;
        with_inner(py, &self.h.inner, |g| g.start(t, &q))
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

    /// A measurement of human `human`'s keypoints taken at `t_meas` (s): `positions` (m, shape
    /// (K, 3), the model's keypoint order), optional `velocities` (m/s). It reaches the shield
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
            if g.running.is_some() {
                return Err((
                    Kind::State,
                    "step: a ShieldLoop is running this shield".into(),
                ));
            }
            g.step(t)
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
        with_inner(py, &self.h.inner, |g| Ok(g.shield.remaining()))
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

    /// The log header (dict) the run is logged with: robot, human, constraints, objects.
    #[getter]
    fn header<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let h = with_inner(py, &self.h.inner, |g| Ok(g.header.clone()))?;
        to_py(py, &h)
    }

    /// Flush and close the log (if any); raises `pacs.OutputError` if a log write failed
    /// during the run (the run went on; nothing was logged after the failure). The shield can
    /// still step; nothing more is logged.
    fn close(&self, py: Python<'_>) -> PyResult<()> {
        with_inner(py, &self.h.inner, |g| g.close())
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
            Ok((g.shield.robot().name().to_string(), g.started))
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
    /// What decided the step: {"kind": "none" | "no-measurement" | "no-profile" | "ssm" |
    /// "pfl" | "object", ...indices, energies (J)}, with beside each index the name it stands
    /// for: `link_name`, `person` (the person's id), `body_part_name`, `object_id`.
    #[getter]
    fn binding<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, &self.names.describe(&self.cmd.diag.binding))
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
