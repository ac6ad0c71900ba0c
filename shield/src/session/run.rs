//! [`Session`]: one shield run as every runner drives it.

use super::inbox::{Due, InboxError, MeasurementInbox, Pending};
use crate::shield::{ChunkProgress, Command, Shield, ShieldError, time_tolerance};
use crate::shield_log::ShieldLog;
use pacs_log::{Header, WriteError};
use pacs_motion::chunk::Chunk;
use pacs_reach::human::HumanMeasurement;
use pacs_reach::object::ObjectMeasurement;
use std::io::Write;
use thiserror::Error;

/// Measurements of people (and, separately, of objects) that may wait for a step at or after
/// their arrival: a bound on the inbox's memory; more are refused ([`SessionError::InboxFull`]).
pub const MAX_WAITING: usize = 4096;

/// Errors of a [`Session`]. Each message starts with the call or argument it concerns.
#[derive(Debug, Error)]
pub enum SessionError {
    /// A call that needs a started session.
    #[error("{0}: call start(t, q) first")]
    NotStarted(&'static str),
    /// A session that writes a log runs once (its log holds one run).
    #[error("start: a shield that logs (log=...) runs once; create a new Shield for a new run")]
    LoggedRunsOnce,
    /// A restart (s) before the session's time (s).
    #[error(
        "t: a restart at {t} s is before the shield's time {now} s (its measurements would look newer than the new ones)"
    )]
    RestartBefore { t: f64, now: f64 },
    /// The shield refused the start (a configuration outside the limits, a wrong length).
    #[error(transparent)]
    Start(ShieldError),
    /// The log file could not be created.
    #[error("log: cannot create {name}: {error}")]
    LogCreate { name: String, error: std::io::Error },
    /// The log's header could not be written.
    #[error("log {name}: {error}")]
    LogHeader { name: String, error: WriteError },
    /// A step time (s) that is NaN or infinite.
    #[error("t: value {0} is not finite")]
    NotFinite(f64),
    /// A step time (s) off the safety-step grid: steps follow each other by exactly one
    /// safety step.
    #[error(
        "t: {t} s, but steps follow each other by the safety step: the previous step was at {last} s, so this one is at {expected} s"
    )]
    OffGrid { t: f64, last: f64, expected: f64 },
    /// A first step (s) before the start (s).
    #[error("t: {t} s is before the start at {start} s")]
    BeforeStart { t: f64, start: f64 },
    /// A first step (s) off the grid of safety steps from the start (s).
    #[error(
        "t: {t} s, but steps run on the grid of safety steps from the start at {start} s: the nearest step time is {expected} s"
    )]
    FirstOffGrid { t: f64, start: f64, expected: f64 },
    /// [`MAX_WAITING`] measurements of this kind already wait (the message names the default
    /// bound; [`Session::with_max_waiting`] sets another).
    #[error(
        "{0}: {MAX_WAITING} measurements already wait for a step at or after their time stamps (are they stamped ahead of the shield's clock?)"
    )]
    InboxFull(&'static str),
    /// The inbox refused a measurement (an unknown index, an arrival before its stamp).
    #[error("{call}: {error}")]
    Queue {
        call: &'static str,
        error: InboxError,
    },
    /// The shield refused a delivered measurement.
    #[error(transparent)]
    Delivery(InboxError),
    /// The step itself failed.
    #[error(transparent)]
    Step(ShieldError),
    /// The chunk was not taken over (it could not be planned); the robot keeps its motion.
    #[error("set_chunk: {0}")]
    ChunkRejected(ShieldError),
    /// A log write failed: the run went on, nothing was logged after it.
    #[error("log {name}: {error} (nothing was logged after this)")]
    Log { name: String, error: String },
    /// A lock of a shared session was poisoned by a panic.
    #[error("poisoned {0} state")]
    Poisoned(&'static str),
    /// Paced hand-over: the real-time loop stopped before the chunk was handed over.
    #[error("set_chunk: the ShieldLoop stopped before the chunk's handover (hand it over again)")]
    LoopStopped,
    /// Paced hand-over: the session was restarted during the hand-over.
    #[error("set_chunk: the shield was restarted during the handover")]
    Restarted,
    /// Paced hand-over: the shield refused the offer.
    #[error("set_chunk: {0}")]
    Offer(ShieldError),
    /// Paced hand-over: every attempt of the re-plan policy failed.
    #[error(
        "set_chunk: not handed over in {attempts} attempts: {moved} times the commands left the predicted path before the handover (steps not verified: a person near the robot?), {dropped} times the chunk's first step was not verified, {late} times planning took longer than the lead; the robot keeps its verified motion"
    )]
    NotHandedOver {
        attempts: u32,
        moved: u32,
        dropped: u32,
        late: u32,
    },
}

/// One shield run: the shield, its measurement inbox and its log.
///
/// Guarantees (each tested in this module):
/// - **Grid**: steps follow the start and each other by exactly one safety step (within
///   [`time_tolerance`]); other step times are refused and change nothing.
/// - **Delivery**: a measurement reaches the shield and the log at the first step at or after
///   its arrival ([`MeasurementInbox`]), never earlier.
/// - **Evidence**: while a log is written, every delivered measurement, every command and every
///   chunk event is in it; [`Self::close`] also writes the measurements still waiting that are
///   stamped within the run (late frames: the audit judges them), then the `end` record the
///   header promises. A log write failure stops the log, not the run; it is reported by
///   [`Self::log_failure`] and by [`Self::close`].
/// - **Once**: a session that writes a log is started once (one log, one run).
pub struct Session<W: Write> {
    shield: Shield,
    inbox: MeasurementInbox,
    log: Option<ShieldLog<W>>,
    /// How messages name the log (its path).
    log_name: String,
    /// The first log write that failed.
    log_failure: Option<String>,
    /// A log was opened (the session runs once).
    logged: bool,
    started: bool,
    start_t: f64,
    last_t: Option<f64>,
    /// A real-time loop steps the session: chunks are handed over by [`super::PacedHandover`].
    paced: bool,
    /// The loop that steps the session, if one does (its id).
    driver: Option<u64>,
    /// Measurements of people (and of objects) that may wait at once.
    max_waiting: usize,
}

impl<W: Write> std::fmt::Debug for Session<W> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Session")
            .field("shield", &self.shield)
            .field("waiting", &self.inbox.len())
            .field("logging", &self.log.is_some())
            .field("started", &self.started)
            .field("last_t", &self.last_t)
            .finish()
    }
}

impl<W: Write> Session<W> {
    /// A session of `shield` (its people and objects as added; `object_ids` name its objects in
    /// the log, in the shield's object order). Not started.
    pub fn new(shield: Shield, object_ids: Vec<String>) -> Self {
        let people = shield.human_count();
        Self {
            shield,
            inbox: MeasurementInbox::new(people, object_ids),
            log: None,
            log_name: String::new(),
            log_failure: None,
            logged: false,
            started: false,
            start_t: 0.0,
            last_t: None,
            paced: false,
            driver: None,
            max_waiting: MAX_WAITING,
        }
    }

    /// The same session with room for `n` waiting measurements of people (and as many of
    /// objects) instead of [`MAX_WAITING`]: for runners that know every input in advance (a
    /// scene file, whose size bounds them).
    pub fn with_max_waiting(mut self, n: usize) -> Self {
        self.max_waiting = n;
        self
    }

    /// The shield.
    pub fn shield(&self) -> &Shield {
        &self.shield
    }

    /// The shield, for calls the session does not wrap (e.g. a paced offer).
    pub fn shield_mut(&mut self) -> &mut Shield {
        &mut self.shield
    }

    /// The measurements waiting for their step.
    pub fn inbox(&self) -> &MeasurementInbox {
        &self.inbox
    }

    /// Whether [`Self::start`] (or [`Self::start_logged`]) succeeded.
    pub fn started(&self) -> bool {
        self.started
    }

    /// The time (s) of the latest step, or the start time before the first step.
    pub fn now(&self) -> f64 {
        self.last_t.unwrap_or(self.start_t)
    }

    /// The time (s) of the next step on the grid.
    pub fn next_step(&self) -> f64 {
        self.last_t
            .map_or(self.start_t, |t| t + self.shield.config().safety_step)
    }

    /// The chunk progress after the latest step (`None` before the start).
    pub fn progress(&self) -> Option<ChunkProgress> {
        self.shield.chunk_progress()
    }

    /// Whether a real-time loop steps the session (chunks are then handed over paced).
    pub fn paced(&self) -> bool {
        self.paced
    }

    /// Mark whether a real-time loop steps the session.
    pub fn set_paced(&mut self, paced: bool) {
        self.paced = paced;
    }

    /// The id of the loop that steps the session, if one does.
    pub fn driver(&self) -> Option<u64> {
        self.driver
    }

    /// Claim (`Some(id)`) or release (`None`) the session for a stepping loop.
    pub fn set_driver(&mut self, driver: Option<u64>) {
        self.driver = driver;
    }

    /// The checks every start makes: once if logged, never back in time.
    fn may_start(&self, t: f64) -> Result<(), SessionError> {
        if self.logged {
            return Err(SessionError::LoggedRunsOnce);
        }
        if self.started && t < self.now() {
            return Err(SessionError::RestartBefore { t, now: self.now() });
        }
        Ok(())
    }

    fn started_at(&mut self, t: f64) {
        self.started = true;
        self.last_t = None;
        self.start_t = t;
    }

    /// Start (or restart) at rest at `q` (rad) at `t` (s), without a log.
    pub fn start(&mut self, t: f64, q: &[f64]) -> Result<(), SessionError> {
        self.may_start(t)?;
        self.shield.start(t, q).map_err(SessionError::Start)?;
        self.started_at(t);
        Ok(())
    }

    /// Start at rest at `q` (rad) at `t` (s) and write the run to a log made by `create`
    /// (called once the shield has started) with `header`; `name` (the path) names the log in
    /// messages.
    pub fn start_logged(
        &mut self,
        t: f64,
        q: &[f64],
        header: &Header,
        name: &str,
        create: impl FnOnce() -> std::io::Result<W>,
    ) -> Result<(), SessionError> {
        self.may_start(t)?;
        self.shield.start(t, q).map_err(SessionError::Start)?;
        let name = name.to_string();
        let out = create().map_err(|error| SessionError::LogCreate {
            name: name.clone(),
            error,
        })?;
        let log = ShieldLog::new(out, header, t, q).map_err(|error| SessionError::LogHeader {
            name: name.clone(),
            error,
        })?;
        self.log = Some(log);
        self.log_name = name;
        self.logged = true;
        self.started_at(t);
        Ok(())
    }

    /// A measurement of person `person` (the shield's human index) arriving at its stamp.
    pub fn measure_person(
        &mut self,
        person: usize,
        m: HumanMeasurement,
    ) -> Result<(), SessionError> {
        self.measure_person_at(m.time(), person, m)
    }

    /// A measurement of person `person` arriving at `arrival` (s, not before its stamp).
    pub fn measure_person_at(
        &mut self,
        arrival: f64,
        person: usize,
        m: HumanMeasurement,
    ) -> Result<(), SessionError> {
        if self.inbox.people_waiting() >= self.max_waiting {
            return Err(SessionError::InboxFull("measure"));
        }
        self.inbox
            .push_person(arrival, person, m)
            .map_err(|error| SessionError::Queue {
                call: "measure",
                error,
            })
    }

    /// A measurement of object `object` (the shield's object index) arriving at its stamp.
    pub fn measure_object(
        &mut self,
        object: usize,
        m: ObjectMeasurement,
    ) -> Result<(), SessionError> {
        self.measure_object_at(m.time, object, m)
    }

    /// A measurement of object `object` arriving at `arrival` (s, not before its stamp).
    pub fn measure_object_at(
        &mut self,
        arrival: f64,
        object: usize,
        m: ObjectMeasurement,
    ) -> Result<(), SessionError> {
        if self.inbox.objects_waiting() >= self.max_waiting {
            return Err(SessionError::InboxFull("measure_object"));
        }
        self.inbox
            .push_object(arrival, object, m)
            .map_err(|error| SessionError::Queue {
                call: "measure_object",
                error,
            })
    }

    /// Record the first log failure and stop logging; the run goes on.
    fn log_failed(&mut self, e: impl std::fmt::Display) {
        stop_log(&mut self.log, &mut self.log_failure, e);
    }

    /// The first log write that failed, if one did (nothing was logged after it).
    pub fn log_failure(&self) -> Option<&str> {
        self.log_failure.as_deref()
    }

    /// Log a chunk event (taken over or rejected) at the session's time.
    pub(super) fn log_chunk(&mut self, taken: bool) {
        let now = self.now();
        let event = if taken { "chunk" } else { "chunk_rejected" };
        if let Some(log) = &mut self.log
            && let Err(e) = log.event(now, event)
        {
            self.log_failed(e);
        }
    }

    /// Hand over `chunk` at once: planned from the current commanded state, tried at the next
    /// step; logged as a `chunk` (or `chunk_rejected`) event. Returns the number of chunks taken
    /// over so far (this one's serial number).
    pub fn set_chunk(&mut self, chunk: &Chunk) -> Result<u64, SessionError> {
        if !self.started {
            return Err(SessionError::NotStarted("set_chunk"));
        }
        let r = self.shield.set_chunk(chunk);
        self.log_chunk(r.is_ok());
        r.map_err(SessionError::ChunkRejected)?;
        Ok(self.shield.chunk_progress().map_or(0, |p| p.accepted))
    }

    /// Whether `t` (s) is the next step time on the grid.
    fn on_grid(&self, t: f64) -> Result<(), SessionError> {
        if !t.is_finite() {
            return Err(SessionError::NotFinite(t));
        }
        let alpha = self.shield.config().safety_step;
        // Float rounding of t = t_0 + k·α_s grows with |t| (a Unix-time t_0 has ulps of 2e-7 s).
        let tol = time_tolerance(t);
        match self.last_t {
            Some(last) if (t - (last + alpha)).abs() > tol => Err(SessionError::OffGrid {
                t,
                last,
                expected: last + alpha,
            }),
            None if t < self.start_t - tol => Err(SessionError::BeforeStart {
                t,
                start: self.start_t,
            }),
            None => {
                // The grid t₀ + k·α_s, k ≥ 0 (the first step may come steps after the start).
                let k = ((t - self.start_t) / alpha).round().max(0.0);
                let expected = self.start_t + k * alpha;
                if (t - expected).abs() > tol {
                    Err(SessionError::FirstOffGrid {
                        t,
                        start: self.start_t,
                        expected,
                    })
                } else {
                    Ok(())
                }
            }
            _ => Ok(()),
        }
    }

    /// One safety step at `t` (s, the next on the grid): every measurement that arrived at or
    /// before `t` is delivered and logged, then the shield steps. Returns the command for
    /// `t + α_s`, which is logged.
    pub fn step(&mut self, t: f64) -> Result<Command, SessionError> {
        if !self.started {
            return Err(SessionError::NotStarted("step"));
        }
        self.on_grid(t)?;
        // Every measurement stamped at or before t reaches the shield and is logged, also those
        // the shield will not use (it keeps the newest): the audit checks each against its model
        // beside its neighbours in time and uses the newest, as the shield does, so a
        // measurement that the others contradict cannot hide behind a newer one.
        let Session {
            inbox,
            shield,
            log,
            log_failure,
            last_t,
            ..
        } = self;
        let Due { first, log_error } = inbox
            .deliver(t, shield, log.as_mut())
            .map_err(SessionError::Delivery)?;
        if let Some(e) = log_error {
            stop_log(log, log_failure, e);
        }
        let cmd = shield.step(t, first).map_err(SessionError::Step)?;
        *last_t = Some(t);
        if let Some(l) = log.as_mut()
            && let Err(e) = l.record(t, first, &cmd)
        {
            // The step happened: its command is returned; the log stops.
            stop_log(log, log_failure, e);
        }
        Ok(cmd)
    }

    /// Close the run's log (idempotent): the measurements still waiting that are stamped within
    /// the run are written (at the end of the last command), then the `end` record; the writer
    /// is flushed. Reports the first log failure of the run, once.
    pub fn close(&mut self) -> Result<(), SessionError> {
        if let Some(log) = self.log.take() {
            let r = self.write_tail(log);
            if let Err(e) = r {
                self.log_failed(e);
            }
        }
        match self.log_failure.take() {
            Some(error) => Err(SessionError::Log {
                name: self.log_name.clone(),
                error,
            }),
            None => Ok(()),
        }
    }

    /// What [`Self::close`] writes: late measurements stamped within the run, the `end` record.
    fn write_tail(&self, mut log: ShieldLog<W>) -> Result<(), WriteError> {
        // Late frames of a camera with latency (stamped at or before the last command's time):
        // the audit checks them against the model and calls the run inconclusive if they
        // describe a time it covers, instead of never seeing them.
        if self.last_t.is_some() {
            let t_end = self.next_step();
            for (_, p) in self.inbox.pending() {
                match p {
                    Pending::Person(id, m) if m.time() <= t_end => log.person(t_end, id, m),
                    Pending::Object(k, m) if m.time <= t_end => {
                        log.object(t_end, &self.inbox.object_ids()[k], m)
                    }
                    _ => Ok(()),
                }?;
            }
        }
        let mut out = log.finish()?;
        Ok(out.flush()?)
    }
}

/// Record the first log failure (in `failure`) and stop logging (`log` cleared).
fn stop_log<L>(log: &mut Option<L>, failure: &mut Option<String>, e: impl std::fmt::Display) {
    if failure.is_none() {
        *failure = Some(e.to_string());
    }
    *log = None;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shield::ShieldConfig;
    use pacs_log::{Header, ModelRef};
    use pacs_models::{ConstraintSpec, default_human, fr3};
    use std::sync::{Arc, Mutex};

    const DT: f64 = 0.001;

    /// A writer into shared memory (readable after the session consumed it) that fails once
    /// `fail_after` bytes were written.
    #[derive(Clone)]
    struct Memory {
        bytes: Arc<Mutex<Vec<u8>>>,
        fail_after: usize,
    }

    impl Write for Memory {
        fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
            let mut b = self.bytes.lock().unwrap();
            if b.len() + buf.len() > self.fail_after {
                return Err(std::io::Error::other("disk full"));
            }
            b.extend_from_slice(buf);
            Ok(buf.len())
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    fn session() -> Session<Memory> {
        let spec = ConstraintSpec::builtin("sorting").unwrap();
        let sh = Shield::new(
            fr3::fr3(),
            Some((default_human(), &spec)),
            vec![],
            ShieldConfig::default(),
        )
        .unwrap();
        Session::new(sh, vec![])
    }

    fn header() -> Header {
        Header::new(
            ModelRef::Name("fr3".into()),
            ModelRef::Name("default".into()),
            ModelRef::Name("sorting".into()),
        )
    }

    fn logged(s: &mut Session<Memory>, fail_after: usize) -> Arc<Mutex<Vec<u8>>> {
        let bytes = Arc::new(Mutex::new(Vec::new()));
        let out = Memory {
            bytes: bytes.clone(),
            fail_after,
        };
        s.start_logged(0.0, &fr3::Q_READY, &header(), "mem", || Ok(out))
            .unwrap();
        bytes
    }

    fn person(t: f64) -> HumanMeasurement {
        let kp = pacs_testkit::human_reaching(3.0, 0.0, [2.8, -0.2, 1.0]);
        HumanMeasurement::new(&default_human(), t, &kp, None).unwrap()
    }

    /// The record types of a log, in order.
    fn types(bytes: &Mutex<Vec<u8>>) -> Vec<String> {
        String::from_utf8(bytes.lock().unwrap().clone())
            .unwrap()
            .lines()
            .map(|l| {
                let v: serde_json::Value = serde_json::from_str(l).unwrap();
                match v["type"].as_str().unwrap() {
                    "event" => format!("event:{}", v["name"].as_str().unwrap()),
                    t => t.to_string(),
                }
            })
            .collect()
    }

    #[test]
    fn steps_keep_to_the_safety_step_grid() {
        let mut s = session();
        assert!(matches!(s.step(0.0), Err(SessionError::NotStarted("step"))));
        s.start(1.0, &fr3::Q_READY).unwrap();
        assert!(matches!(
            s.step(0.999),
            Err(SessionError::BeforeStart { .. })
        ));
        assert!(matches!(s.step(f64::NAN), Err(SessionError::NotFinite(_))));
        // The first step keeps to the grid from the start too (it may come steps later).
        for t in [1.0005, 1.0025] {
            assert!(
                matches!(s.step(t), Err(SessionError::FirstOffGrid { .. })),
                "{t}"
            );
        }
        s.step(1.0).unwrap();
        // Refused steps change nothing: the next is still 1.001 s.
        for t in [1.0, 1.0005, 1.002] {
            match s.step(t) {
                Err(SessionError::OffGrid { expected, .. }) => assert_eq!(expected, 1.0 + DT),
                r => panic!("{t}: {r:?}"),
            }
        }
        assert_eq!(s.next_step(), 1.0 + DT);
        s.step(1.0 + DT).unwrap();
        assert_eq!(s.now(), 1.0 + DT);
        // A restart goes on from the session's time, never back.
        assert!(matches!(
            s.start(1.0, &fr3::Q_READY),
            Err(SessionError::RestartBefore { .. })
        ));
        s.start(2.0, &fr3::Q_READY).unwrap();
        assert_eq!(s.next_step(), 2.0);
    }

    #[test]
    fn a_logged_session_writes_every_input_and_its_end_and_runs_once() {
        let mut s = session();
        let bytes = logged(&mut s, usize::MAX);
        s.measure_person(0, person(0.0)).unwrap();
        // Stamped within the run, arriving after its last step: written by close.
        s.measure_person_at(0.5, 0, person(DT)).unwrap();
        // Stamped after the run: never written.
        s.measure_person(0, person(1.0)).unwrap();
        let chunk = Chunk {
            kind: pacs_motion::chunk::ActionKind::Delta,
            actions: vec![vec![0.01; 7]],
            execute: 1,
            gripper: None,
        };
        assert_eq!(s.set_chunk(&chunk).unwrap(), 1);
        s.step(0.0).unwrap();
        s.step(DT).unwrap();
        s.close().unwrap();
        s.close().unwrap();
        assert_eq!(
            types(&bytes),
            [
                "header",
                "event:chunk",
                "human",
                "event:start",
                "robot",
                "robot",
                "shield",
                "robot",
                "shield",
                "human",
                "event:end"
            ]
        );
        assert!(matches!(
            s.start(5.0, &fr3::Q_READY),
            Err(SessionError::LoggedRunsOnce)
        ));
    }

    #[test]
    fn a_failing_log_stops_the_log_not_the_run_and_is_reported_once() {
        let mut s = session();
        let bytes = logged(&mut s, 4000);
        for k in 0..50 {
            s.step(k as f64 * DT).unwrap();
        }
        assert!(s.log_failure().is_some());
        let written = bytes.lock().unwrap().len();
        assert!(written > 0 && written <= 4000, "{written}");
        s.step(50.0 * DT).unwrap();
        assert_eq!(bytes.lock().unwrap().len(), written);
        match s.close() {
            Err(SessionError::Log { name, error }) => {
                assert_eq!(name, "mem");
                assert!(error.contains("disk full"), "{error}");
            }
            r => panic!("{r:?}"),
        }
        s.close().unwrap();
    }

    #[test]
    fn the_inbox_bound_refuses_more_waiting_measurements() {
        let mut s = session();
        s.start(0.0, &fr3::Q_READY).unwrap();
        let mut s = s.with_max_waiting(3);
        for k in 0..3 {
            s.measure_person(0, person(k as f64)).unwrap();
        }
        assert!(matches!(
            s.measure_person(0, person(9.0)),
            Err(SessionError::InboxFull("measure"))
        ));
        assert!(matches!(
            s.measure_person(1, person(9.0)),
            Err(SessionError::InboxFull("measure"))
        ));
    }
}
