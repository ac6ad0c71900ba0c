//! `pacs.ShieldLoop`: the shield's step loop on a Rust thread, at the safety step's rate in
//! real time (or as fast as possible in simulated time), so that a Python policy loop at its
//! own rate only hands over chunks and measurements and reads the latest command.
//!
//! Locking: the shield state sits behind a mutex that Python threads only take with the GIL
//! released ([`with_inner`]) and that is never held while Python code runs; the loop's output
//! mutex is held only for copies, and its only other user (the loop thread) never waits for the
//! GIL. Neither can deadlock with the GIL.

use crate::command::PyCommand;
use crate::convert::{finite, flag, index, show};
use crate::errors::{Kind, err, input, type_err};
use crate::shield::{Fail, Handle, Inner, PyShield, step, with_inner};
use numpy::{PyArray1, PyArrayMethods};
use pacs_shield::shield::{ChunkProgress, Command};
use pyo3::prelude::*;
use std::collections::VecDeque;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Most steps one `run_until` call may take (10⁹ s of 1 ms steps is 31 years).
const MAX_RUN_STEPS: f64 = 1e9;

static NEXT_LOOP_ID: AtomicU64 = AtomicU64::new(1);

/// What the loop thread reports.
#[derive(Default)]
struct LoopOut {
    latest: Option<(Command, ChunkProgress)>,
    history: VecDeque<Command>,
    capacity: usize,
    error: Option<Fail>,
    steps: u64,
    /// Steps that began more than one safety step after their deadline (real time only).
    overruns: u64,
    max_step_us: f64,
    total_step_us: f64,
    /// The latest start of a step after its deadline (µs; real time only).
    max_late_us: f64,
    /// The SCHED_FIFO priority the loop thread got (0: none asked or refused).
    rt_priority: i32,
    /// Why the requested priority was refused.
    rt_error: Option<String>,
}

struct Shared {
    stop: AtomicBool,
    out: Mutex<LoopOut>,
}

/// Runs `shield.step` every safety step on a Rust thread. `realtime=True`: step k runs at wall
/// time start + k·α_s (the steps keep their grid t_k = t_0 + k·α_s; a late step is counted in
/// `stats()["overruns"]`). `realtime=False`: simulated time, as fast as possible, on the calling
/// thread with the GIL released, until `run_until(t)` returns. While the loop runs, the shield's
/// own `step` refuses; `set_chunk`, `measure` and `measure_object` go through the loop. Use as
/// a context manager or call `stop()`. The last `history` commands are kept for `commands()`.
/// A step that fails (it should not) stops the loop; the next call raises its error.
/// `priority` (1–99, Linux): run the loop thread under SCHED_FIFO at that priority (needs
/// CAP_SYS_NICE or root; refused requests leave it at normal priority, `stats()` tells).
#[pyclass(name = "ShieldLoop", module = "pacs")]
pub struct PyShieldLoop {
    id: u64,
    /// The shield it steps (shared with the `Shield` object).
    h: Handle,
    shared: Arc<Shared>,
    handle: Mutex<Option<JoinHandle<()>>>,
    realtime: bool,
    priority: i32,
}

/// Why the loop thread runs at normal priority although a real-time one was asked for.
#[derive(Debug)]
enum RtPriorityError {
    /// The system refused SCHED_FIFO at this priority (1–99).
    #[cfg_attr(not(target_os = "linux"), allow(dead_code))]
    Refused {
        priority: i32,
        error: std::io::Error,
    },
    /// Not a Linux system.
    #[cfg_attr(target_os = "linux", allow(dead_code))]
    Unsupported,
}

impl std::fmt::Display for RtPriorityError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RtPriorityError::Refused { priority, error } => write!(
                f,
                "SCHED_FIFO priority {priority} refused: {error} (needs CAP_SYS_NICE or an rtprio limit)"
            ),
            RtPriorityError::Unsupported => {
                f.write_str("real-time priority is supported on Linux only")
            }
        }
    }
}

/// Put the calling thread under SCHED_FIFO at `priority` (1–99).
#[cfg(target_os = "linux")]
fn set_rt_priority(priority: i32) -> Result<(), RtPriorityError> {
    let param = libc::sched_param {
        sched_priority: priority,
    };
    // SAFETY: `pthread_self` is the calling thread; `param` lives across the call.
    let rc = unsafe { libc::pthread_setschedparam(libc::pthread_self(), libc::SCHED_FIFO, &param) };
    if rc == 0 {
        Ok(())
    } else {
        Err(RtPriorityError::Refused {
            priority,
            error: std::io::Error::from_raw_os_error(rc),
        })
    }
}

#[cfg(not(target_os = "linux"))]
fn set_rt_priority(_priority: i32) -> Result<(), RtPriorityError> {
    Err(RtPriorityError::Unsupported)
}

/// Step the shield from its current time for `steps` steps (None: until stopped) while loop
/// `id` owns it; real time paces them.
fn run_steps(
    id: u64,
    inner: &Mutex<Inner>,
    shared: &Shared,
    realtime: bool,
    steps: Option<u64>,
    alpha: f64,
) {
    let t0 = match inner.lock() {
        Ok(mut g) => {
            // Wall-clock pacing: chunks are planned off the lock from then on.
            let paced = realtime && g.driver() == Some(id);
            g.set_paced(paced);
            g.next_step()
        }
        Err(_) => return,
    };
    // Cleared however the loop ends (stop, an error, a panic outside the step).
    struct Unpace<'a>(&'a Mutex<Inner>, u64);
    impl Drop for Unpace<'_> {
        fn drop(&mut self) {
            if let Ok(mut g) = self.0.lock()
                && (g.driver() == Some(self.1) || g.driver().is_none())
            {
                g.set_paced(false);
            }
        }
    }
    let _unpace = realtime.then_some(Unpace(inner, id));
    let wall0 = Instant::now();
    let mut k: u64 = 0;
    while !shared.stop.load(Ordering::Relaxed) && steps.is_none_or(|n| k < n) {
        if realtime {
            let deadline = wall0 + Duration::from_secs_f64(k as f64 * alpha);
            let now = Instant::now();
            if deadline > now {
                std::thread::sleep(deadline - now);
            }
            let late = Instant::now().saturating_duration_since(deadline);
            if let Ok(mut o) = shared.out.lock() {
                o.max_late_us = o.max_late_us.max(late.as_secs_f64() * 1e6);
                if late > Duration::from_secs_f64(alpha) {
                    o.overruns += 1;
                }
            }
        }
        let t = t0 + k as f64 * alpha;
        let clock = Instant::now();
        let r = match inner.lock() {
            // Only the loop that claimed the shield steps it (a stop() racing a start() may
            // have released the claim).
            Ok(g) if g.driver() != Some(id) => Err((
                Kind::State,
                "this ShieldLoop no longer owns the shield (stopped)".to_string(),
            )),
            Ok(mut g) => std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| step(&mut g, t)))
                .unwrap_or_else(|_| {
                    Err((
                        Kind::State,
                        format!("internal error: the step at {t} s panicked"),
                    ))
                }),
            Err(_) => Err((Kind::State, "poisoned shield state".into())),
        };
        let us = clock.elapsed().as_secs_f64() * 1e6;
        let Ok(mut o) = shared.out.lock() else { return };
        match r {
            Ok((cmd, p)) => {
                o.latest = Some((cmd, p));
                if o.capacity > 0 {
                    if o.history.len() == o.capacity {
                        o.history.pop_front();
                    }
                    o.history.push_back(cmd);
                }
                o.steps += 1;
                o.max_step_us = o.max_step_us.max(us);
                o.total_step_us += us;
            }
            Err(e) => {
                o.error = Some(e);
                return;
            }
        }
        k += 1;
    }
}

impl PyShieldLoop {
    /// The loop's output. Locked with the GIL held: its other user, the loop thread, never
    /// waits for the GIL, and no Python code runs while it is held.
    fn out(&self, _py: Python<'_>) -> PyResult<MutexGuard<'_, LoopOut>> {
        self.shared
            .out
            .lock()
            .map_err(|_| err(Kind::State, "poisoned loop state"))
    }

    fn check_error(&self, py: Python<'_>) -> PyResult<()> {
        // Copy the error out first: building the Python exception runs Python code.
        let e = self.out(py)?.error.clone();
        match e {
            Some(e) => Err(err(e.0, format!("the shield loop stopped: {}", e.1))),
            None => Ok(()),
        }
    }

    /// Make this loop the one that steps the shield (refused if another one does).
    fn claim(&self, py: Python<'_>) -> PyResult<()> {
        let id = self.id;
        with_inner(py, &self.h.inner, move |g| match g.driver() {
            Some(other) if other != id => Err((
                Kind::State,
                "ShieldLoop: another ShieldLoop runs this shield".into(),
            )),
            _ => {
                g.set_driver(Some(id));
                Ok(())
            }
        })
    }

    fn release(&self) {
        if let Ok(mut g) = self.h.inner.lock()
            && g.driver() == Some(self.id)
        {
            g.set_driver(None);
        }
    }
}

#[pymethods]
impl PyShieldLoop {
    #[new]
    #[pyo3(signature = (shield, realtime=None, history=None, priority=None))]
    fn new(
        py: Python<'_>,
        shield: &Bound<'_, PyAny>,
        realtime: Option<&Bound<'_, PyAny>>,
        history: Option<&Bound<'_, PyAny>>,
        priority: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let s = shield.cast::<PyShield>().map_err(|_| {
            type_err(format!(
                "shield: expected a pacs.Shield, got {}",
                show(shield)
            ))
        })?;
        let realtime = match realtime {
            Some(r) => flag(r, "realtime")?,
            None => true,
        };
        let history = match history {
            Some(h) => index(h, "history")?,
            None => 10_000,
        };
        let priority = match priority {
            Some(p) if !p.is_none() => {
                let v = index(p, "priority")?;
                if !(1..=99).contains(&v) {
                    return Err(input(format!(
                        "priority: value {v} is outside the SCHED_FIFO range 1..=99"
                    )));
                }
                v as i32
            }
            _ => 0,
        };
        let h = s.borrow().h.clone();
        let started = with_inner(py, &h.inner, |g| Ok(g.started()))?;
        if !started {
            return Err(err(
                Kind::State,
                "ShieldLoop: call shield.start(t, q) first",
            ));
        }
        Ok(Self {
            id: NEXT_LOOP_ID.fetch_add(1, Ordering::Relaxed),
            h,
            shared: Arc::new(Shared {
                stop: AtomicBool::new(false),
                out: Mutex::new(LoopOut {
                    capacity: history,
                    ..Default::default()
                }),
            }),
            handle: Mutex::new(None),
            realtime,
            priority,
        })
    }

    /// Start stepping on the Rust thread (real time); with `realtime=False`, claim the shield
    /// and step only in `run_until`.
    fn start(&self, py: Python<'_>) -> PyResult<()> {
        self.check_error(py)?;
        self.claim(py)?;
        self.shared.stop.store(false, Ordering::Relaxed);
        if !self.realtime {
            return Ok(());
        }
        // Only Python threads (holding the GIL) take the handle's lock; nothing below releases
        // the GIL while it is held.
        let Ok(mut handle) = self.handle.lock() else {
            return Err(err(Kind::State, "poisoned loop state"));
        };
        if handle.is_some() {
            drop(handle);
            return Err(err(Kind::State, "ShieldLoop.start: already running"));
        }
        let (id, inner, shared, alpha, priority) = (
            self.id,
            self.h.inner.clone(),
            self.shared.clone(),
            self.h.safety_step,
            self.priority,
        );
        *handle = Some(
            std::thread::Builder::new()
                .name("pacs-shield-loop".into())
                .spawn(move || {
                    if priority > 0
                        && let Ok(mut o) = shared.out.lock()
                    {
                        match set_rt_priority(priority) {
                            Ok(()) => o.rt_priority = priority,
                            Err(e) => o.rt_error = Some(e.to_string()),
                        }
                    }
                    run_steps(id, &inner, &shared, true, None, alpha)
                })
                .map_err(|e| err(Kind::State, format!("cannot start the loop thread: {e}")))?,
        );
        Ok(())
    }

    /// Simulated time (`realtime=False`): step (in Rust, the GIL released) until the shield's
    /// time reaches `t` (s), then return.
    fn run_until(&self, py: Python<'_>, t: &Bound<'_, PyAny>) -> PyResult<()> {
        if self.realtime {
            return Err(err(
                Kind::State,
                "run_until: only for ShieldLoop(realtime=False)",
            ));
        }
        let t = finite(t, "t")?;
        self.check_error(py)?;
        self.claim(py)?;
        let alpha = self.h.safety_step;
        let now = with_inner(py, &self.h.inner, move |g| Ok(g.next_step()))?;
        if t < now {
            return Ok(());
        }
        // (t on the grid: (t − now)/α may round just below an integer.)
        let n = ((t - now) / alpha + 1e-6).floor() + 1.0;
        if n > MAX_RUN_STEPS {
            return Err(input(format!(
                "t: {t} s is {n:.3e} steps ahead of the shield's time {now} s (at most {MAX_RUN_STEPS:.0e} per call)"
            )));
        }
        self.shared.stop.store(false, Ordering::Relaxed);
        let (inner, shared) = (&self.h.inner, &self.shared);
        let id = self.id;
        py.detach(|| run_steps(id, inner, shared, false, Some(n as u64), alpha));
        self.check_error(py)
    }

    /// Stop the thread (after its current step) and hand the shield back to direct `step`s.
    fn stop(&self, py: Python<'_>) -> PyResult<()> {
        self.shared.stop.store(true, Ordering::Relaxed);
        let h = self
            .handle
            .lock()
            .map_err(|_| err(Kind::State, "poisoned loop state"))?
            .take();
        let joined = match h {
            Some(h) => py.detach(|| h.join()).is_ok(),
            None => true,
        };
        py.detach(|| self.release());
        if !joined {
            return Err(err(Kind::State, "the loop thread panicked"));
        }
        self.check_error(py)
    }

    /// `Shield.set_chunk` through the loop (`t`, if given, is checked finite; the log records
    /// the handover at the loop's time). While the real-time thread runs, the chunk is planned
    /// on the calling thread without holding the shield (the loop's steps never wait for the
    /// planner) from the commanded state predicted a few steps ahead, and taken over by the
    /// step at that time if the commands got there (if not — a step was not verified, or the
    /// chunk's own first step was not — it is planned again, up to 5 times, then
    /// `pacs.ChunkRejected`). Returns once a verified step follows it (typically 2–3 ms later).
    #[pyo3(signature = (deltas, t=None, h=None, absolute=None))]
    fn set_chunk(
        &self,
        py: Python<'_>,
        deltas: &Bound<'_, PyAny>,
        t: Option<&Bound<'_, PyAny>>,
        h: Option<&Bound<'_, PyAny>>,
        absolute: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<u64> {
        self.check_error(py)?;
        if let Some(t) = t.filter(|t| !t.is_none()) {
            finite(t, "t")?;
        }
        self.h.set_chunk(py, deltas, h, absolute)
    }

    /// `Shield.measure` through the loop.
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

    /// `Shield.measure_object` through the loop.
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

    /// The newest command (None before the first step).
    fn latest(&self, py: Python<'_>) -> PyResult<Option<PyCommand>> {
        self.check_error(py)?;
        let o = self.out(py)?;
        Ok(o.latest.map(|(cmd, progress)| PyCommand {
            cmd,
            progress,
            names: self.h.names.clone(),
        }))
    }

    /// The loop's current time (s): the time of the latest step.
    #[getter]
    fn time(&self, py: Python<'_>) -> PyResult<f64> {
        self.h.time(py)
    }

    /// `Shield.progress()`: which chunk runs and how many of its actions were executed.
    fn progress<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.h.progress(py)
    }

    /// The commands since the last call (at most `history`), drained: {"t": (N,) s,
    /// "q": (N, dof) rad, "dq": (N, dof) rad/s, "ddq": (N, dof) rad/s², "verified": (N,) bool}.
    fn commands<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, pyo3::types::PyDict>> {
        let cmds: Vec<Command> = self.out(py)?.history.drain(..).collect();
        let n = self.h.dof;
        let rows = |f: &dyn Fn(&Command) -> &[f64]| -> Vec<f64> {
            cmds.iter()
                .flat_map(|c| f(c)[..n].iter().copied())
                .collect()
        };
        let d = pyo3::types::PyDict::new(py);
        let t: Vec<f64> = cmds.iter().map(|c| c.t).collect();
        d.set_item("t", PyArray1::from_vec(py, t))?;
        for (name, v) in [
            ("q", rows(&|c| &c.state.q)),
            ("dq", rows(&|c| &c.state.dq)),
            ("ddq", rows(&|c| &c.state.ddq)),
        ] {
            let a = PyArray1::from_vec(py, v)
                .reshape([cmds.len(), n])
                .map_err(|e| input(e.to_string()))?;
            d.set_item(name, a)?;
        }
        let verified: Vec<bool> = cmds.iter().map(|c| c.diag.verified).collect();
        d.set_item("verified", PyArray1::from_vec(py, verified))?;
        Ok(d)
    }

    /// {"steps": int, "overruns": int (steps begun more than a safety step late),
    /// "max_step_us": the longest step (µs), "mean_step_us": the mean step (µs; the Rust step
    /// alone: lock + `Shield::step`), "max_late_us": the latest start of a step after its
    /// deadline (µs), "rt_priority": the SCHED_FIFO priority the thread runs at (0: normal),
    /// and "rt_priority_error" (str) when a requested priority was refused}.
    fn stats<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, pyo3::types::PyDict>> {
        let (steps, overruns, max, total, late, prio, rt_error) = {
            let o = self.out(py)?;
            (
                o.steps,
                o.overruns,
                o.max_step_us,
                o.total_step_us,
                o.max_late_us,
                o.rt_priority,
                o.rt_error.clone(),
            )
        };
        let d = pyo3::types::PyDict::new(py);
        d.set_item("steps", steps)?;
        d.set_item("overruns", overruns)?;
        d.set_item("max_step_us", max)?;
        d.set_item(
            "mean_step_us",
            if steps > 0 { total / steps as f64 } else { 0.0 },
        )?;
        d.set_item("max_late_us", late)?;
        d.set_item("rt_priority", prio)?;
        if let Some(e) = rt_error {
            d.set_item("rt_priority_error", e)?;
        }
        Ok(d)
    }

    fn __enter__<'a>(slf: PyRef<'a, Self>, py: Python<'a>) -> PyResult<PyRef<'a, Self>> {
        slf.start(py)?;
        Ok(slf)
    }

    #[pyo3(signature = (*_args))]
    fn __exit__(&self, py: Python<'_>, _args: &Bound<'_, pyo3::types::PyTuple>) -> PyResult<bool> {
        self.stop(py)?;
        Ok(false)
    }
}

impl Drop for PyShieldLoop {
    fn drop(&mut self) {
        self.shared.stop.store(true, Ordering::Relaxed);
        if let Ok(mut h) = self.handle.lock()
            && let Some(h) = h.take()
        {
            let _ = h.join();
        }
        self.release();
    }
}
