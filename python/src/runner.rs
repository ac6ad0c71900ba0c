//! `pacs.ShieldLoop`: the shield's step loop on a Rust thread, at the safety step's rate in
//! real time (or as fast as possible in simulated time), so that a Python policy loop at its
//! own rate only hands over chunks and measurements and reads the latest command.

use crate::convert::{finite, show, to_py};
use crate::errors::{Kind, err, input, type_err};
use crate::shield::{
    Fail, Inner, PyCommand, PyShield, chunk_args, lock, measurement, object_measurement, raise,
};
use numpy::{PyArray1, PyArray2};
use pacs_shield::shield::{ChunkProgress, Command};
use pyo3::prelude::*;
use std::collections::VecDeque;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

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
}

struct Shared {
    stop: AtomicBool,
    out: Mutex<LoopOut>,
}

/// Runs `shield.step` every safety step on a Rust thread. `realtime=True`: step k runs at wall
/// time start + k·α_s (the steps keep their grid t_k = t_0 + k·α_s; a late step is counted in
/// `stats()["overruns"]`). `realtime=False`: simulated time, as fast as possible, until
/// `run_until(t)` returns. While the loop runs, the shield's own `step` refuses; `set_chunk`,
/// `measure` and `measure_object` go through the loop. Use as a context manager or call
/// `stop()`. The last `history` commands are kept for `commands()`.
#[pyclass(name = "ShieldLoop", module = "pacs")]
pub struct PyShieldLoop {
    inner: Arc<Mutex<Inner>>,
    shared: Arc<Shared>,
    handle: Option<JoinHandle<()>>,
    realtime: bool,
    dof: usize,
    alpha: f64,
}

/// Step the shield from its current time for `steps` steps (None: until stopped); real time
/// paces them.
fn run_steps(
    inner: &Mutex<Inner>,
    shared: &Shared,
    realtime: bool,
    steps: Option<u64>,
    alpha: f64,
) {
    let t0 = match inner.lock() {
        Ok(g) => g.last_t.map_or(g.start_t, |t| t + alpha),
        Err(_) => return,
    };
    let wall0 = Instant::now();
    let mut k: u64 = 0;
    while !shared.stop.load(Ordering::Relaxed) && steps.is_none_or(|n| k < n) {
        if realtime {
            let deadline = wall0 + Duration::from_secs_f64(k as f64 * alpha);
            let now = Instant::now();
            if deadline > now {
                std::thread::sleep(deadline - now);
            } else if now - deadline > Duration::from_secs_f64(alpha)
                && let Ok(mut o) = shared.out.lock()
            {
                o.overruns += 1;
            }
        }
        let t = t0 + k as f64 * alpha;
        let clock = Instant::now();
        let r = match inner.lock() {
            Ok(mut g) => g.step(t),
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
    fn check_error(&self) -> PyResult<()> {
        let o = self
            .shared
            .out
            .lock()
            .map_err(|_| err(Kind::State, "poisoned loop state"))?;
        if let Some(e) = &o.error {
            return Err(err(e.0, format!("the shield loop stopped: {}", e.1)));
        }
        Ok(())
    }
}

#[pymethods]
impl PyShieldLoop {
    #[new]
    #[pyo3(signature = (shield, realtime=true, history=10000))]
    fn new(shield: &Bound<'_, PyAny>, realtime: bool, history: usize) -> PyResult<Self> {
        let s = shield.cast::<PyShield>().map_err(|_| {
            type_err(format!(
                "shield: expected a pacs.Shield, got {}",
                show(shield)
            ))
        })?;
        let s = s.borrow();
        let inner = s.inner.clone();
        let (dof, alpha) = {
            let g = lock(&inner)?;
            if !g.started {
                return Err(err(
                    Kind::State,
                    "ShieldLoop: call shield.start(t, q) first",
                ));
            }
            if g.running {
                return Err(err(
                    Kind::State,
                    "ShieldLoop: another loop runs this shield",
                ));
            }
            (g.dof, g.shield.config().safety_step)
        };
        Ok(Self {
            inner,
            shared: Arc::new(Shared {
                stop: AtomicBool::new(false),
                out: Mutex::new(LoopOut {
                    capacity: history,
                    ..Default::default()
                }),
            }),
            handle: None,
            realtime,
            dof,
            alpha,
        })
    }

    /// Start stepping on the Rust thread (real time), or, with `realtime=False`, do nothing
    /// until `run_until`.
    fn start(&mut self) -> PyResult<()> {
        if self.handle.is_some() {
            return Err(err(Kind::State, "ShieldLoop.start: already running"));
        }
        lock(&self.inner)?.running = true;
        if self.realtime {
            self.shared.stop.store(false, Ordering::Relaxed);
            let (inner, shared, alpha) = (self.inner.clone(), self.shared.clone(), self.alpha);
            self.handle = Some(
                std::thread::Builder::new()
                    .name("pacs-shield-loop".into())
                    .spawn(move || run_steps(&inner, &shared, true, None, alpha))
                    .map_err(|e| err(Kind::State, format!("cannot start the loop thread: {e}")))?,
            );
        }
        Ok(())
    }

    /// Simulated time (`realtime=False`): step (in Rust, the GIL released) until the shield's time
    /// reaches `t` (s), then return (the GIL is released meanwhile).
    fn run_until(&mut self, py: Python<'_>, t: &Bound<'_, PyAny>) -> PyResult<()> {
        if self.realtime {
            return Err(err(
                Kind::State,
                "run_until: only for ShieldLoop(realtime=False)",
            ));
        }
        let t = finite(t, "t")?;
        let now = {
            let mut g = lock(&self.inner)?;
            g.running = true;
            g.last_t.map_or(g.start_t, |x| x + self.alpha)
        };
        if t < now {
            return Ok(());
        }
        let steps = ((t - now) / self.alpha).floor() as u64 + 1;
        let (inner, shared, alpha) = (self.inner.clone(), self.shared.clone(), self.alpha);
        py.detach(move || {
            let h =
                std::thread::spawn(move || run_steps(&inner, &shared, false, Some(steps), alpha));
            h.join().ok();
        });
        self.check_error()
    }

    /// Stop the thread (after its current step) and hand the shield back to direct `step`s.
    fn stop(&mut self, py: Python<'_>) -> PyResult<()> {
        self.shared.stop.store(true, Ordering::Relaxed);
        if let Some(h) = self.handle.take() {
            py.detach(|| h.join())
                .map_err(|_| err(Kind::State, "the loop thread panicked"))?;
        }
        lock(&self.inner)?.running = false;
        self.check_error()
    }

    /// `Shield.set_chunk` through the loop (`t` defaults to the loop's current time).
    #[pyo3(signature = (deltas, h=None, absolute=false, t=None))]
    fn set_chunk(
        &self,
        py: Python<'_>,
        deltas: &Bound<'_, PyAny>,
        h: Option<&Bound<'_, PyAny>>,
        absolute: bool,
        t: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<u64> {
        self.check_error()?;
        let t = match t {
            Some(t) if !t.is_none() => Some(finite(t, "t")?),
            _ => None,
        };
        let (rows, h, kind) = chunk_args(self.dof, deltas, h, absolute)?;
        let inner = &self.inner;
        py.detach(|| -> Result<u64, Fail> {
            let mut g = inner
                .lock()
                .map_err(|_| (Kind::State, "poisoned shield state".to_string()))?;
            let t = t.unwrap_or_else(|| g.now());
            g.set_chunk(t, rows, h, kind)
        })
        .map_err(raise)
    }

    /// `Shield.measure` through the loop.
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

    /// `Shield.measure_object` through the loop.
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

    /// The newest command (None before the first step).
    fn latest(&self) -> PyResult<Option<PyCommand>> {
        self.check_error()?;
        let o = self
            .shared
            .out
            .lock()
            .map_err(|_| err(Kind::State, "poisoned loop state"))?;
        Ok(o.latest.map(|(cmd, progress)| PyCommand { cmd, progress }))
    }

    /// The loop's current time (s): the time of the latest step.
    #[getter]
    fn time(&self) -> PyResult<f64> {
        Ok(lock(&self.inner)?.now())
    }

    /// `Shield.progress()`: which chunk runs and how many of its actions were executed.
    fn progress<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let g = lock(&self.inner)?;
        match g.shield.chunk_progress() {
            Some(p) => to_py(py, &p),
            None => Err(input("progress: the shield is not started")),
        }
    }

    /// The commands since the last call (at most `history`), drained: {"t": (N,) s,
    /// "q": (N, dof) rad, "dq": (N, dof) rad/s, "ddq": (N, dof) rad/s², "verified": (N,) bool}.
    fn commands<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, pyo3::types::PyDict>> {
        let cmds: Vec<Command> = {
            let mut o = self
                .shared
                .out
                .lock()
                .map_err(|_| err(Kind::State, "poisoned loop state"))?;
            o.history.drain(..).collect()
        };
        let n = self.dof;
        let rows = |f: &dyn Fn(&Command) -> &[f64]| -> Vec<Vec<f64>> {
            cmds.iter().map(|c| f(c)[..n].to_vec()).collect()
        };
        let d = pyo3::types::PyDict::new(py);
        let t: Vec<f64> = cmds.iter().map(|c| c.t).collect();
        d.set_item("t", PyArray1::from_vec(py, t))?;
        for (name, v) in [
            ("q", rows(&|c| &c.state.q)),
            ("dq", rows(&|c| &c.state.dq)),
            ("ddq", rows(&|c| &c.state.ddq)),
        ] {
            let a = if v.is_empty() {
                PyArray2::<f64>::zeros(py, [0, n], false)
            } else {
                PyArray2::from_vec2(py, &v).map_err(|e| input(e.to_string()))?
            };
            d.set_item(name, a)?;
        }
        let verified: Vec<bool> = cmds.iter().map(|c| c.diag.verified).collect();
        d.set_item("verified", PyArray1::from_vec(py, verified))?;
        Ok(d)
    }

    /// {"steps": int, "overruns": steps begun more than a safety step late, "max_step_us":
    /// the longest step (µs), "mean_step_us": the mean step (µs, the Rust step alone)}.
    fn stats<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, pyo3::types::PyDict>> {
        let o = self
            .shared
            .out
            .lock()
            .map_err(|_| err(Kind::State, "poisoned loop state"))?;
        let d = pyo3::types::PyDict::new(py);
        d.set_item("steps", o.steps)?;
        d.set_item("overruns", o.overruns)?;
        d.set_item("max_step_us", o.max_step_us)?;
        d.set_item(
            "mean_step_us",
            if o.steps > 0 {
                o.total_step_us / o.steps as f64
            } else {
                0.0
            },
        )?;
        Ok(d)
    }

    fn __enter__(mut slf: PyRefMut<'_, Self>) -> PyResult<PyRefMut<'_, Self>> {
        slf.start()?;
        Ok(slf)
    }

    #[pyo3(signature = (*_args))]
    fn __exit__(
        &mut self,
        py: Python<'_>,
        _args: &Bound<'_, pyo3::types::PyTuple>,
    ) -> PyResult<bool> {
        self.stop(py)?;
        Ok(false)
    }
}

impl Drop for PyShieldLoop {
    fn drop(&mut self) {
        self.shared.stop.store(true, Ordering::Relaxed);
        if let Some(h) = self.handle.take() {
            let _ = h.join();
        }
        if let Ok(mut g) = self.inner.lock() {
            g.running = false;
        }
    }
}
