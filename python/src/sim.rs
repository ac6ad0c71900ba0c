//! `pacs.Demo`: the simulation's built-in FR3 scenes (the paper's tasks) and their chunking
//! demonstration policy, for examples and tests of Python policy loops without a robot.

use crate::convert::{finite, flag, index, text, to_py, vector};
use crate::errors::{input, type_err};
use numpy::{PyArray1, PyArray2};
use pacs_sim::policy::ChunkPolicy;
use pacs_sim::task::{Scenario, TaskKind, constraint_spec, native_mode, scenario, tool_point};
use pyo3::prelude::*;

/// One of the simulation's FR3 tasks ("sorting", "handover", "feeding", "sphere", "crowded"):
/// its start configuration, models, the true motion of its person (`keypoints(t)`) and objects
/// (`object_state(i, t)`), and its chunking demonstration policy (`chunk(q)`: delta joint
/// actions, as a diffusion policy or SmolVLA emits them). Build the shield from `shield_args()`.
#[pyclass(name = "Demo", module = "pacs")]
pub struct PyDemo {
    sc: Scenario,
}

#[pymethods]
impl PyDemo {
    #[new]
    #[pyo3(signature = (task=None, seed=None, with_human=None))]
    fn new(
        task: Option<&Bound<'_, PyAny>>,
        seed: Option<&Bound<'_, PyAny>>,
        with_human: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let task = match task {
            Some(t) => text(t, "task")?,
            None => "sorting".to_string(),
        };
        let task = task.as_str();
        let seed = match seed {
            Some(s) => index(s, "seed")? as u64,
            None => 0,
        };
        let with_human = match with_human {
            Some(w) => flag(w, "with_human")?,
            None => true,
        };
        let kind: TaskKind = task.parse().map_err(|_| {
            input(format!(
                "task: unknown task `{task}` (sorting, handover, feeding, sphere, crowded)"
            ))
        })?;
        Ok(Self {
            sc: scenario(kind, seed, with_human),
        })
    }

    /// The task's name.
    #[getter]
    fn task(&self) -> &'static str {
        self.sc.task.name()
    }

    /// Start configuration (rad), at rest.
    #[getter]
    fn start<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.sc.start)
    }

    /// Time limit of the task (s).
    #[getter]
    fn max_time(&self) -> f64 {
        self.sc.max_time
    }

    /// Sub-goals of the tool point, in order: [{"name", "point" (m), "tolerance" (m)}].
    #[getter]
    fn goals<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let g: Vec<serde_json::Value> = self
            .sc
            .goals
            .iter()
            .map(
                |g| serde_json::json!({"name": g.name, "point": g.point, "tolerance": g.tolerance}),
            )
            .collect();
        to_py(py, &g)
    }

    /// Keyword arguments for `pacs.Shield` (and `pacs.LogWriter`) for this task: robot,
    /// humans (the model with the task's measurement uncertainty), constraints (the task's
    /// native SSM/PFL spec) and objects.
    fn shield_args<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let objects: Vec<serde_json::Value> = self
            .sc
            .objects
            .iter()
            .map(|o| serde_json::json!({"id": o.id, "object": o.spec, "contact": o.contact}))
            .collect();
        let v = serde_json::json!({
            "robot": "fr3",
            "humans": self.sc.human.spec(),
            "constraints": constraint_spec(self.sc.task, native_mode(self.sc.task)),
            "objects": objects,
        });
        to_py(py, &v)
    }

    /// The demonstration policy's next chunk for joint positions `q` (rad): `deltas` (H, 7)
    /// joint-position deltas (rad) and the number `h` of actions to execute.
    fn chunk<'py>(
        &mut self,
        py: Python<'py>,
        q: &Bound<'py, PyAny>,
    ) -> PyResult<(Bound<'py, PyArray2<f64>>, usize)> {
        let q = vector(q, "q", self.sc.start.len())?;
        let c = self.sc.policy.chunk(&q);
        let a = PyArray2::from_vec2(py, &c.actions).map_err(|e| input(e.to_string()))?;
        Ok((a, c.execute))
    }

    /// The person's true keypoints (m, shape (K, 3)) at time `t` (s).
    fn keypoints<'py>(
        &self,
        py: Python<'py>,
        t: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let t = finite(t, "t")?;
        let k: Vec<Vec<f64>> = self
            .sc
            .script
            .keypoints(t)
            .iter()
            .map(|p| p.to_vec())
            .collect();
        PyArray2::from_vec2(py, &k).map_err(|e| input(e.to_string()))
    }

    /// Object ids, in index order.
    #[getter]
    fn object_ids(&self) -> Vec<String> {
        self.sc.objects.iter().map(|o| o.id.clone()).collect()
    }

    /// Object `i`'s true position (m) and velocity (m/s) at `t` (s).
    fn object_state(
        &self,
        i: &Bound<'_, PyAny>,
        t: &Bound<'_, PyAny>,
    ) -> PyResult<([f64; 3], [f64; 3])> {
        let i = index(i, "i")?;
        let o = self.sc.objects.get(i).ok_or_else(|| {
            input(format!(
                "i: object {i} does not exist ({} objects)",
                self.sc.objects.len()
            ))
        })?;
        Ok(o.script.state(finite(t, "t")?))
    }

    /// The tool point (m, world frame) at joint positions `q` (rad).
    fn tool_point(&self, q: &Bound<'_, PyAny>) -> PyResult<[f64; 3]> {
        let q = vector(q, "q", self.sc.start.len())?;
        Ok(tool_point(&self.sc.robot, &q))
    }

    /// Distance (rad) from `q` to the nearest demonstrated configuration.
    fn deviation(&self, q: &Bound<'_, PyAny>) -> PyResult<f64> {
        let q = vector(q, "q", self.sc.start.len())?;
        Ok(self.sc.policy.deviation(&q))
    }
}

/// `count` teleoperation-like demonstrations of `task` (`pacs_sim::teleop`): pauses, changes of
/// pace, hesitations near the person, small detours within the task's tolerance, within the
/// robot's operated limits. Each is a dict of numpy arrays sampled at `fps` (Hz): `q` (T, 7)
/// rad, `action` (T, 7) rad (the joint-position delta to the next sample, zero at the end),
/// `stage` (T,) sub-goals reached, `person` (T, 3) m (keypoint centroid), `person_distance`
/// (T,) m (tool to nearest keypoint), `pace` (T,) (fraction of the nominal pace), `timestamp`
/// (T,) s; and `task`, `seed`, `fps`, `pauses`, `hesitations`, `detours`, `goals`.
#[pyfunction]
#[pyo3(signature = (task=None, count=None, seed=None, fps=None))]
pub fn teleop_demonstrations<'py>(
    py: Python<'py>,
    task: Option<&Bound<'py, PyAny>>,
    count: Option<&Bound<'py, PyAny>>,
    seed: Option<&Bound<'py, PyAny>>,
    fps: Option<&Bound<'py, PyAny>>,
) -> PyResult<Vec<Bound<'py, pyo3::types::PyDict>>> {
    use pacs_sim::teleop;
    use pyo3::types::PyDict;
    let task = task.map_or(Ok("sorting".to_string()), |t| text(t, "task"))?;
    let count = count.map_or(Ok(50), |c| index(c, "count"))?;
    if count == 0 {
        return Err(input("count: must be at least 1"));
    }
    let seed = seed.map_or(Ok(0), |s| index(s, "seed"))? as u64;
    let fps = fps.map_or(Ok(30.0), |f| finite(f, "fps"))?;
    let task = task.as_str();
    let kind: TaskKind = task.parse().map_err(|_| {
        input(format!(
            "task: unknown task `{task}` (sorting, handover, feeding, sphere, crowded)"
        ))
    })?;
    let demos = py
        .detach(|| teleop::teleop_demonstrations(kind, count, seed, fps))
        .map_err(|e| input(e.to_string()))?;
    let goals = pacs_sim::task::scenario(kind, seed, true).goals.len();
    let mut out = Vec::with_capacity(demos.len());
    for d in demos {
        let n = d.q.len();
        let action: Vec<Vec<f64>> = (0..n)
            .map(|k| match d.q.get(k + 1) {
                Some(next) => next.iter().zip(&d.q[k]).map(|(b, a)| b - a).collect(),
                None => vec![0.0; d.q[k].len()],
            })
            .collect();
        let person: Vec<Vec<f64>> = d.person.iter().map(|p| p.to_vec()).collect();
        let stage: Vec<i64> = d.stage.iter().map(|&s| s as i64).collect();
        let timestamp: Vec<f64> = (0..n).map(|k| k as f64 * d.dt).collect();
        let dict = PyDict::new(py);
        let arr2 = |v: &Vec<Vec<f64>>| PyArray2::from_vec2(py, v).map_err(|e| input(e.to_string()));
        dict.set_item("q", arr2(&d.q)?)?;
        dict.set_item("action", arr2(&action)?)?;
        dict.set_item("stage", PyArray1::from_slice(py, &stage))?;
        dict.set_item("person", arr2(&person)?)?;
        dict.set_item(
            "person_distance",
            PyArray1::from_slice(py, &d.person_distance),
        )?;
        dict.set_item("pace", PyArray1::from_slice(py, &d.pace))?;
        dict.set_item("timestamp", PyArray1::from_slice(py, &timestamp))?;
        dict.set_item("task", kind.name())?;
        dict.set_item("seed", d.seed)?;
        dict.set_item("fps", fps)?;
        dict.set_item("pauses", d.pauses)?;
        dict.set_item("hesitations", d.hesitations)?;
        dict.set_item("detours", d.detours)?;
        dict.set_item("goals", goals)?;
        out.push(dict);
    }
    Ok(out)
}

/// A recording `q` (T, 7) rad sampled at `fps` (Hz) replayed along its own path with the
/// shield's braking and resuming path-speed profiles (`pacs_sim::teleop::paced_replay`): brake
/// to rest at each of `pauses` ((path time s, hold s)), slow to the pace of each of `slows`
/// ((from s, to s, pace in (0, 1))), resume; within the FR3's operated limits. Returns `q`
/// (N, 7) rad, `source` (N,) (fractional sample index into the recording) and `pace` (N,).
/// The event of training replay `k` of a recording lasting `end_s` s, drawn with `seed`
/// (`pacs_sim::teleop::replay_event`: even `k` a pause with a hold in `hold` s, odd `k` a slow
/// passage at a pace in `pace`; default ranges `REPLAY_HOLD`, `REPLAY_PACE`), as the keyword
/// arguments of `paced_replay`: `{"pauses": [...], "slows": [...]}`.
#[pyfunction]
#[pyo3(signature = (end_s, k, seed, hold=None, pace=None))]
pub fn replay_event<'py>(
    py: Python<'py>,
    end_s: &Bound<'py, PyAny>,
    k: &Bound<'py, PyAny>,
    seed: &Bound<'py, PyAny>,
    hold: Option<(f64, f64)>,
    pace: Option<(f64, f64)>,
) -> PyResult<Bound<'py, pyo3::types::PyDict>> {
    use pacs_sim::teleop::{PaceEvent, REPLAY_HOLD, REPLAY_PACE};
    let end = finite(end_s, "end_s")?;
    if end <= 0.0 {
        return Err(input(format!("end_s: {end} is not a duration (s)")));
    }
    let k = index(k, "k")?;
    let seed = index(seed, "seed")? as u64;
    let hold = hold.unwrap_or(REPLAY_HOLD);
    let pace = pace.unwrap_or(REPLAY_PACE);
    if !(hold.0 > 0.0 && hold.0 <= hold.1 && hold.1.is_finite()) {
        return Err(input(format!(
            "hold: {hold:?} is not a range of holds (s) > 0"
        )));
    }
    if !(pace.0 > 0.0 && pace.0 <= pace.1 && pace.1 < 1.0) {
        return Err(input(format!(
            "pace: {pace:?} is not a range of paces in (0, 1)"
        )));
    }
    let mut rng = pacs_sim::humans::Rng::new(seed);
    let e = pacs_sim::teleop::replay_event(end, k, hold, pace, &mut rng);
    let d = pyo3::types::PyDict::new(py);
    let none2: Vec<(f64, f64)> = Vec::new();
    let none3: Vec<(f64, f64, f64)> = Vec::new();
    match e {
        PaceEvent::Pause { at, hold } => {
            d.set_item("pauses", vec![(at, hold)])?;
            d.set_item("slows", none3)?;
        }
        PaceEvent::Slow { from, to, pace } => {
            d.set_item("pauses", none2)?;
            d.set_item("slows", vec![(from, to, pace)])?;
        }
    }
    Ok(d)
}

/// A list of event tuples (`what`, e.g. "(at_s, hold_s) pairs") of the argument `name`; empty
/// when not given.
fn events<'py, T: pyo3::conversion::FromPyObjectOwned<'py>>(
    v: Option<&Bound<'py, PyAny>>,
    name: &str,
    what: &str,
) -> PyResult<Vec<T>> {
    match v {
        Some(p) => p.extract().map_err(|_| {
            type_err(format!(
                "{name}: expected a list of {what}, got {}",
                crate::convert::show(p)
            ))
        }),
        None => Ok(Vec::new()),
    }
}

#[pyfunction]
#[pyo3(signature = (q, fps=None, pauses=None, slows=None))]
pub fn paced_replay<'py>(
    py: Python<'py>,
    q: &Bound<'py, PyAny>,
    fps: Option<&Bound<'py, PyAny>>,
    pauses: Option<&Bound<'py, PyAny>>,
    slows: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, pyo3::types::PyDict>> {
    use pacs_sim::teleop::{PaceEvent, paced_replay};
    let fps = fps.map_or(Ok(30.0), |f| finite(f, "fps"))?;
    let pauses: Vec<(f64, f64)> = events(pauses, "pauses", "(at_s, hold_s) pairs")?;
    let slows: Vec<(f64, f64, f64)> = events(slows, "slows", "(from_s, to_s, pace) triples")?;
    if !(fps > 0.0 && fps.is_finite()) {
        return Err(input(format!("fps: {fps} is not a frame rate (Hz)")));
    }
    let rows: Vec<Vec<f64>> = q
        .call_method0("tolist")
        .unwrap_or_else(|_| q.clone())
        .extract()
        .map_err(|e| {
            input(format!(
                "q: expected a (T, 7) array of joint positions: {e}"
            ))
        })?;
    if let Some((i, r)) = rows
        .iter()
        .enumerate()
        .find(|(_, r)| r.len() != 7 || r.iter().any(|x| !x.is_finite()))
    {
        return Err(input(format!(
            "q[{i}]: expected 7 finite joint positions (rad), got {} values",
            r.len()
        )));
    }
    let mut events: Vec<PaceEvent> = pauses
        .iter()
        .map(|&(at, hold)| PaceEvent::Pause { at, hold })
        .collect();
    events.extend(
        slows
            .iter()
            .map(|&(from, to, pace)| PaceEvent::Slow { from, to, pace }),
    );
    let robot = pacs_models::fr3::fr3();
    let a_max = pacs_sim::task::demo_acceleration_limits(&robot);
    let v_max = robot.limits().v_max().to_vec();
    let r = paced_replay(&rows, 1.0 / fps, &events, &v_max, &a_max).map_err(|e| {
        let n = pauses.len();
        input(match e {
            pacs_sim::teleop::ReplayError::Event(i) if i < n => {
                format!("pauses[{i}]: times must be finite and ≥ 0, the hold > 0")
            }
            pacs_sim::teleop::ReplayError::Event(i) => {
                format!(
                    "slows[{}]: finite times ≥ 0 with from < to, a pace in (0, 1)",
                    i - n
                )
            }
            other => format!("q: {other}"),
        })
    })?;
    let d = pyo3::types::PyDict::new(py);
    d.set_item(
        "q",
        PyArray2::from_vec2(py, &r.q).map_err(|e| input(e.to_string()))?,
    )?;
    d.set_item("source", PyArray1::from_slice(py, &r.source))?;
    d.set_item("pace", PyArray1::from_slice(py, &r.pace))?;
    Ok(d)
}
