//! What `pacs.fleet` (python/python/pacs/fleet.py) runs in Rust: the archive's log listing and
//! the fleet report (`pacs_reports::fleet`, the one implementation `pacs audit DIR --out` uses),
//! a `Run`'s state for pickling (so that runs audited on Dask workers come back whole: results,
//! plot series, model parameters, the audited bytes' hash, the settings), and the simulation's
//! rollouts in parts (a range of seeds each) with their merge into the summary.

use crate::audit::PyRun;
use crate::convert::{show, to_py};
use crate::errors::{Kind, err, input, type_err};
use pacs_audit::verdict::SeriesPoint;
use pacs_audit::{AuditConfig, RunResult};
use pacs_reports::InputFile;
use pacs_sim::eval::{self, EvalConfig, METHOD_NAMES, Rollout, Variant};
use pacs_sim::task::TaskKind;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyString};
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// Version of [`RunState`]'s layout; a state of another layout or pacs version is refused.
const STATE_LAYOUT: u32 = 1;

/// Everything a `Run` holds, as pickled (CBOR: floats, NaN and infinities round-trip exactly).
#[derive(Serialize, Deserialize)]
struct RunState {
    layout: u32,
    pacs: String,
    run: RunResult,
    /// `RunResult::series` and `ModelNames::specs` are not serialized with the run (they are
    /// not part of `pacs audit --json`): carried beside it, the series by columns (a third of
    /// the bytes of one map per point, and faster to decode on the client).
    series: SeriesColumns,
    specs: serde_json::Value,
    path: PathBuf,
    hashed_path: String,
    sha256: String,
    bytes: u64,
    modified: Option<u64>,
    config: AuditConfig,
    config_path: Option<PathBuf>,
}

/// A plot series by columns.
#[derive(Serialize, Deserialize, Default)]
struct SeriesColumns {
    t: Vec<f64>,
    t_end: Vec<f64>,
    min_separation: Vec<Option<f64>>,
    /// The coarse far-range separation bound (m) of each bucket.
    #[serde(default)]
    far_separation: Vec<Option<f64>>,
    energy_nominal: Vec<Option<f64>>,
    energy_bound: Vec<Option<f64>>,
    threshold: Vec<Option<f64>>,
    /// Bit 0: violation, bit 1: inconclusive, bit 2: at rest.
    flags: Vec<u8>,
}

impl SeriesColumns {
    fn of(points: &[SeriesPoint]) -> Self {
        let col = |f: fn(&SeriesPoint) -> Option<f64>| points.iter().map(f).collect();
        Self {
            t: points.iter().map(|p| p.t).collect(),
            t_end: points.iter().map(|p| p.t_end).collect(),
            min_separation: col(|p| p.min_separation),
            far_separation: col(|p| p.far_separation),
            energy_nominal: col(|p| p.energy_nominal),
            energy_bound: col(|p| p.energy_bound),
            threshold: col(|p| p.threshold),
            flags: points
                .iter()
                .map(|p| {
                    u8::from(p.violation) | u8::from(p.inconclusive) << 1 | u8::from(p.at_rest) << 2
                })
                .collect(),
        }
    }

    fn points(&self) -> PyResult<Vec<SeriesPoint>> {
        let n = self.t.len();
        let lens = [
            self.t_end.len(),
            self.min_separation.len(),
            self.far_separation.len(),
            self.energy_nominal.len(),
            self.energy_bound.len(),
            self.threshold.len(),
            self.flags.len(),
        ];
        if lens.iter().any(|&l| l != n) {
            return Err(input("state: the plot series' columns differ in length"));
        }
        Ok((0..n)
            .map(|i| SeriesPoint {
                t: self.t[i],
                t_end: self.t_end[i],
                min_separation: self.min_separation[i],
                far_separation: self.far_separation[i],
                energy_nominal: self.energy_nominal[i],
                energy_bound: self.energy_bound[i],
                threshold: self.threshold[i],
                violation: self.flags[i] & 1 != 0,
                inconclusive: self.flags[i] & 2 != 0,
                at_rest: self.flags[i] & 4 != 0,
            })
            .collect())
    }
}

fn cbor<T: Serialize>(v: &T, what: &str) -> PyResult<Vec<u8>> {
    let mut out = Vec::new();
    ciborium::into_writer(v, &mut out)
        .map_err(|e| err(Kind::Output, format!("{what}: cannot encode: {e}")))?;
    Ok(out)
}

/// `Run.__reduce__`: rebuilt by `pacs.fleet._run_from_state(state)` (a Python function, so that
/// pickle finds it by its module and name), which calls [`_run_from_state`].
pub fn reduce_run<'py>(
    py: Python<'py>,
    r: &PyRun,
) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, PyBytes>,))> {
    let state = RunState {
        layout: STATE_LAYOUT,
        pacs: env!("CARGO_PKG_VERSION").into(),
        run: RunResult {
            series: Vec::new(),
            ..r.run.clone()
        },
        series: SeriesColumns::of(&r.run.series),
        specs: r.run.models.specs.clone(),
        path: r.path.clone(),
        hashed_path: r.hashed.path.clone(),
        sha256: r.hashed.sha256.clone(),
        bytes: r.hashed.bytes,
        modified: r.modified,
        config: r.config.clone(),
        config_path: r.config_path.clone(),
    };
    let bytes = cbor(&state, "Run")?;
    let f = py.import("pacs.fleet")?.getattr("_run_from_state")?;
    Ok((f, (PyBytes::new(py, &bytes),)))
}

/// A `Run` from its pickled state (`Run.__reduce__`).
#[pyfunction]
pub fn _run_from_state(state: &Bound<'_, PyAny>) -> PyResult<PyRun> {
    let b = state.cast::<PyBytes>().map_err(|_| {
        type_err(format!(
            "state: expected the bytes of Run.__reduce__, got {}",
            show(state)
        ))
    })?;
    let s: RunState = ciborium::from_reader(b.as_bytes())
        .map_err(|e| input(format!("state: not a pacs Run state: {e}")))?;
    if s.layout != STATE_LAYOUT || s.pacs != env!("CARGO_PKG_VERSION") {
        return Err(input(format!(
            "state: a Run pickled by pacs {} (layout {}); this is pacs {} (layout {STATE_LAYOUT}): use one pacs version on the client and the workers",
            s.pacs,
            s.layout,
            env!("CARGO_PKG_VERSION")
        )));
    }
    let mut run = s.run;
    run.series = s.series.points()?;
    run.models.specs = s.specs;
    Ok(PyRun {
        run,
        path: s.path,
        hashed: InputFile {
            path: s.hashed_path,
            sha256: s.sha256,
            bytes: s.bytes,
        },
        modified: s.modified,
        config: s.config,
        config_path: s.config_path,
    })
}

/// Paths from one path or a list of them (argument `name`).
fn path_list(paths: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<PathBuf>> {
    let bad = || {
        type_err(format!(
            "{name}: expected a path or a list of paths, got {}",
            show(paths)
        ))
    };
    if paths.is_instance_of::<PyString>() {
        return Ok(vec![paths.extract().map_err(|_| bad())?]);
    }
    if let Ok(p) = paths.extract::<PathBuf>() {
        return Ok(vec![p]);
    }
    paths.extract().map_err(|_| bad())
}

/// Whether a log of an archive takes the header given to `pacs.fleet.audit` (MCAP logs and ROS 2
/// bags: [`pacs_log::takes_header`]); JSON Lines and CSV keep their own. A path that cannot be
/// read takes it (its audit names the problem).
#[pyfunction]
pub fn _takes_header(path: PathBuf) -> bool {
    pacs_log::takes_header(&path).unwrap_or(true)
}

/// The log files of `paths` (files as given, directories expanded to their sorted log files),
/// as `pacs audit` takes them.
#[pyfunction]
pub fn _fleet_logs(paths: &Bound<'_, PyAny>) -> PyResult<Vec<String>> {
    let list = path_list(paths, "paths")?;
    if list.is_empty() {
        return Err(input("paths: no log given"));
    }
    let logs = pacs_reports::fleet::expand_logs(&list).map_err(|e| input(format!("paths: {e}")))?;
    logs.into_iter()
        .map(|p| {
            p.into_os_string().into_string().map_err(|p| {
                input(format!(
                    "paths: {} is not valid UTF-8",
                    PathBuf::from(p).display()
                ))
            })
        })
        .collect()
}

/// The fleet report of audited runs (report.json's `fleet`), with each log's modification
/// time as read when it was audited.
#[pyfunction]
pub fn _fleet_report<'py>(
    py: Python<'py>,
    runs: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyAny>> {
    let runs: Vec<PyRef<'_, PyRun>> = runs.extract().map_err(|_| {
        type_err(format!(
            "runs: expected a list of pacs.Run (from pacs.audit), got {}",
            show(runs)
        ))
    })?;
    let results: Vec<RunResult> = runs.iter().map(|r| r.run.clone()).collect();
    let mtimes: Vec<Option<u64>> = runs.iter().map(|r| r.modified).collect();
    to_py(py, &pacs_reports::fleet::fleet(&results, &mtimes))
}

/// A simulation as `pacs.simulate` describes it, checked.
struct SimPlan {
    tasks: Vec<TaskKind>,
    variants: Vec<Variant>,
    with_human: bool,
}

fn sim_plan(
    tasks: &[String],
    methods: &[String],
    with_human: bool,
    chunk_motion: &str,
    policy: &str,
) -> PyResult<SimPlan> {
    let all_tasks: Vec<&str> = TaskKind::ALL.iter().map(|t| t.name()).collect();
    let names = |given: &[String], all: &[&str], what: &str| -> PyResult<Vec<String>> {
        if given.is_empty() {
            return Err(input(format!("{what}: no name given")));
        }
        Ok(if given.len() == 1 && given[0] == "all" {
            all.iter().map(|s| s.to_string()).collect()
        } else {
            given.to_vec()
        })
    };
    let tasks = names(tasks, &all_tasks, "task")?
        .iter()
        .map(|t| t.parse().map_err(|e| input(format!("task: {e}"))))
        .collect::<PyResult<Vec<TaskKind>>>()?;
    let motion = match chunk_motion {
        "continuous" => pacs_shield::ChunkMotion::Continuous,
        "stop" => pacs_shield::ChunkMotion::Stop,
        o => {
            return Err(input(format!(
                "chunk_motion: unknown `{o}` (continuous, stop)"
            )));
        }
    };
    let policy: eval::PolicyKind = policy.parse().map_err(|e| input(format!("policy: {e}")))?;
    let variants = names(methods, &METHOD_NAMES, "method")?
        .iter()
        .map(|m| {
            let mut v: Variant = m.parse().map_err(|e| input(format!("method: {e}")))?;
            v.motion = motion;
            v.policy = policy;
            Ok(v)
        })
        .collect::<PyResult<Vec<Variant>>>()?;
    Ok(SimPlan {
        tasks,
        variants,
        with_human,
    })
}

/// Check a simulation's names before any rollout runs (`pacs.simulate` calls it on the client).
#[pyfunction]
#[pyo3(signature = (tasks, methods, with_human, chunk_motion, policy))]
pub fn _simulate_check(
    tasks: Vec<String>,
    methods: Vec<String>,
    with_human: bool,
    chunk_motion: &str,
    policy: &str,
) -> PyResult<()> {
    sim_plan(&tasks, &methods, with_human, chunk_motion, policy).map(|_| ())
}

/// The rollouts of seeds `seed .. seed + rollouts` for every task and method (the simulation's
/// evaluation, `pacs_sim::eval::evaluate`, on `threads` threads), encoded for `_simulate_merge`.
/// Releases the GIL.
#[pyfunction]
#[pyo3(signature = (tasks, methods, seed, rollouts, with_human, chunk_motion, policy, log_dir=None, threads=None, time_limit=None))]
#[allow(clippy::too_many_arguments)]
pub fn _simulate_rollouts<'py>(
    py: Python<'py>,
    tasks: Vec<String>,
    methods: Vec<String>,
    seed: u64,
    rollouts: usize,
    with_human: bool,
    chunk_motion: &str,
    policy: &str,
    log_dir: Option<PathBuf>,
    threads: Option<usize>,
    time_limit: Option<f64>,
) -> PyResult<Bound<'py, PyBytes>> {
    let plan = sim_plan(&tasks, &methods, with_human, chunk_motion, policy)?;
    if threads == Some(0) {
        return Err(input("threads: must be at least 1"));
    }
    let time_limit = checked_time_limit(time_limit)?;
    let cfg = EvalConfig {
        tasks: plan.tasks,
        variants: plan.variants,
        rollouts,
        seed,
        with_human: plan.with_human,
        log_dir,
        record_every: 0,
        time_limit,
    };
    let done = py.detach(|| {
        let mut b = rayon::ThreadPoolBuilder::new();
        if let Some(n) = threads {
            b = b.num_threads(n);
        }
        let pool = b
            .build()
            .map_err(|e| err(Kind::State, format!("thread pool: {e}")))?;
        pool.install(|| eval::evaluate(&cfg, &|_| {}))
            .map_err(|e| match e {
                eval::EvalError::Io { .. } => err(Kind::Output, e.to_string()),
                other => input(other.to_string()),
            })
    })?;
    Ok(PyBytes::new(py, &cbor(&done, "rollouts")?))
}

/// The summary of rollouts computed in parts (each from `_simulate_rollouts`): every rollout in
/// the evaluation's order, then the evaluation's summary rows — what one evaluation of all the
/// seeds gives. Returns `{"rows": [...], "rollouts": [...]}`.
#[pyfunction]
pub fn _simulate_merge<'py>(py: Python<'py>, parts: Vec<Vec<u8>>) -> PyResult<Bound<'py, PyAny>> {
    let mut decoded = Vec::with_capacity(parts.len());
    for (i, p) in parts.iter().enumerate() {
        let r: Vec<Rollout> = ciborium::from_reader(p.as_slice())
            .map_err(|e| input(format!("parts[{i}]: not encoded rollouts: {e}")))?;
        decoded.push(r);
    }
    let rollouts = eval::merge(decoded);
    let rows = eval::summarize(&rollouts);
    to_py(py, &serde_json::json!({"rows": rows, "rollouts": rollouts}))
}

/// A Python policy object as the simulation's [`TaskPolicy`]: `policy.act(obs)` returns the
/// chunk of joint-position deltas (H, 7) (rad); `obs` is a dict of `task`, `seed` (the
/// rollout's), `t` (s), `q`, `q_before`
/// (rad, now and one policy step earlier), `stage`, `person`, `person_before` ((K, 3) m) and
/// `tool`, `tool_before` (m). `policy.n_action_steps` (or `h`) is the executed actions per chunk
/// (default 8). The deviation is measured against the task's built-in demonstrations. A Python
/// error inside `act` ends the rollout's chunks (a zero chunk: the robot holds) and is raised
/// after the rollout.
struct PyTaskPolicy<'a> {
    obj: &'a Py<PyAny>,
    demos: pacs_sim::policy::DemoSet,
    robot: pacs_models::RobotModel,
    execute: usize,
    ood: usize,
    error: Option<PyErr>,
    task: &'static str,
    /// The rollout's seed (set before each rollout by whoever runs them).
    seed: std::sync::Arc<std::sync::atomic::AtomicU64>,
}

impl<'a> PyTaskPolicy<'a> {
    /// The policy object `obj` for `task`'s rollouts (the demonstrations its deviation is
    /// measured against are the task's built-in ones), starting with `seed`.
    fn new(obj: &'a Py<PyAny>, task: TaskKind, seed: u64, execute: usize) -> Self {
        let scn = pacs_sim::task::scenario(task, seed, true);
        Self {
            obj,
            demos: scn.policy,
            robot: scn.robot,
            execute,
            ood: 0,
            error: None,
            task: task.name(),
            seed: std::sync::Arc::new(seed.into()),
        }
    }

    fn call(&self, obs: &pacs_sim::policy::Observation) -> PyResult<Vec<Vec<f64>>> {
        use numpy::{PyArray1, PyArray2};
        Python::attach(|py| {
            let d = pyo3::types::PyDict::new(py);
            let pts = |p: &[[f64; 3]]| -> PyResult<Bound<'_, PyAny>> {
                let v: Vec<Vec<f64>> = p.iter().map(|x| x.to_vec()).collect();
                if v.is_empty() {
                    Ok(numpy::PyArray2::<f64>::zeros(py, [0, 3], false).into_any())
                } else {
                    Ok(PyArray2::from_vec2(py, &v)
                        .map_err(|e| input(e.to_string()))?
                        .into_any())
                }
            };
            d.set_item("task", self.task)?;
            d.set_item("seed", self.seed.load(std::sync::atomic::Ordering::Relaxed))?;
            d.set_item("t", obs.t)?;
            d.set_item("q", PyArray1::from_slice(py, obs.q))?;
            d.set_item("q_before", PyArray1::from_slice(py, obs.q_before))?;
            d.set_item("stage", obs.stage)?;
            d.set_item("person", pts(obs.person)?)?;
            d.set_item("person_before", pts(obs.person_before)?)?;
            let tool = pacs_sim::task::tool_point(&self.robot, obs.q);
            let tool_before = pacs_sim::task::tool_point(&self.robot, obs.q_before);
            d.set_item("tool", tool.to_vec())?;
            d.set_item("tool_before", tool_before.to_vec())?;
            let out = self.obj.bind(py).call_method1("act", (d,))?;
            let a: Vec<Vec<f64>> = out
                .call_method0("tolist")
                .unwrap_or(out)
                .extract()
                .map_err(|e| input(format!("policy.act: expected an (H, 7) array: {e}")))?;
            let n = obs.q.len();
            if a.is_empty()
                || a.iter()
                    .any(|r| r.len() != n || r.iter().any(|x| !x.is_finite()))
            {
                return Err(input(format!(
                    "policy.act: expected a non-empty (H, {n}) array of finite deltas (rad)"
                )));
            }
            Ok(a)
        })
    }
}

impl pacs_sim::policy::TaskPolicy for PyTaskPolicy<'_> {
    fn act(&mut self, obs: &pacs_sim::policy::Observation) -> pacs_motion::chunk::Chunk {
        use pacs_motion::chunk::{ActionKind, Chunk};
        let hold = |n: usize| Chunk {
            kind: ActionKind::Delta,
            actions: vec![vec![0.0; n]],
            execute: 1,
            gripper: None,
        };
        if self.error.is_some() {
            return hold(obs.q.len());
        }
        if self.demos.deviation(obs.q) > pacs_sim::policy::OOD_RADIUS {
            self.ood += 1;
        }
        match self.call(obs) {
            Ok(actions) => {
                let execute = self.execute.min(actions.len()).max(1);
                Chunk {
                    kind: ActionKind::Delta,
                    actions,
                    execute,
                    gripper: None,
                }
            }
            Err(e) => {
                self.error = Some(e);
                hold(obs.q.len())
            }
        }
    }
    fn deviation(&self, q: &[f64]) -> f64 {
        self.demos.deviation(q)
    }
    fn ood_chunks(&self) -> usize {
        self.ood
    }
    fn name(&self) -> &'static str {
        "external"
    }
    fn execute(&self) -> usize {
        self.execute
    }
}

/// A policy object's executed actions per chunk: its `n_action_steps` (or `h`), default 8.
fn policy_execute(b: &Bound<'_, PyAny>) -> PyResult<usize> {
    let execute = ["n_action_steps", "h"]
        .iter()
        .find_map(|k| b.getattr(*k).ok().and_then(|v| v.extract::<usize>().ok()))
        .unwrap_or(8);
    if execute == 0 {
        return Err(input("policy.n_action_steps: must be at least 1"));
    }
    Ok(execute)
}

/// `time_limit` (s) as the simulation accepts it, or an `InputError` naming the argument.
fn checked_time_limit(time_limit: Option<f64>) -> PyResult<Option<f64>> {
    time_limit
        .map(|t| eval::check_time_limit(t).map_err(|e| input(format!("time_limit: {e}"))))
        .transpose()
}

/// Rollouts of a Python policy object (see [`PyTaskPolicy`]) for every task × method × seed,
/// one after another on this thread (`policy.reset()`, if present, before each); encoded as
/// `_simulate_rollouts` encodes them (merge with `_simulate_merge`). `progress(done, total)`
/// after each rollout, if given.
#[pyfunction]
#[pyo3(signature = (policy, tasks, methods, seeds, with_human, chunk_motion, log_dir=None, progress=None, time_limit=None))]
#[allow(clippy::too_many_arguments)]
pub fn _simulate_external<'py>(
    py: Python<'py>,
    policy: Py<PyAny>,
    tasks: Vec<String>,
    methods: Vec<String>,
    seeds: Vec<u64>,
    with_human: bool,
    chunk_motion: &str,
    log_dir: Option<PathBuf>,
    progress: Option<Py<PyAny>>,
    time_limit: Option<f64>,
) -> PyResult<Bound<'py, PyBytes>> {
    let plan = sim_plan(&tasks, &methods, with_human, chunk_motion, "nearest")?;
    let time_limit = checked_time_limit(time_limit)?;
    let total = plan.tasks.len() * plan.variants.len() * seeds.len();
    let b = policy.bind(py);
    if !b.hasattr("act")? {
        return Err(type_err(
            "policy: needs act(obs) -> (H, 7) joint-position deltas (rad)",
        ));
    }
    let execute = policy_execute(b)?;
    if let Some(d) = &log_dir {
        std::fs::create_dir_all(d)
            .map_err(|e| err(Kind::Output, format!("{}: {e}", d.display())))?;
    }
    let mut out = Vec::new();
    for &task in &plan.tasks {
        for v in &plan.variants {
            for &seed in &seeds {
                if b.hasattr("reset")? {
                    b.call_method0("reset")?;
                }
                let log = log_dir
                    .as_ref()
                    .map(|d| d.join(format!("{}-{}-{seed:04}.jsonl", task.name(), v.label)));
                let mut p = PyTaskPolicy::new(&policy, task, seed, execute);
                let r = py.detach(|| {
                    eval::run_rollout_in(
                        task,
                        v,
                        seed,
                        eval::Scene::of(plan.with_human).with_time_limit(time_limit),
                        log.as_deref(),
                        0,
                        Some(&mut p),
                    )
                });
                if let Some(e) = p.error.take() {
                    return Err(e);
                }
                out.push(r.map_err(|e| match e {
                    eval::EvalError::Io { .. } => err(Kind::Output, e.to_string()),
                    other => input(other.to_string()),
                })?);
                if let Some(f) = &progress {
                    f.bind(py).call1((out.len(), total))?;
                }
            }
        }
    }
    Ok(PyBytes::new(py, &cbor(&out, "rollouts")?))
}

/// The tolerance tool (`pacs_sim::tolerance`): interrupted rollouts of a policy (a built-in
/// name or a policy object, as `_simulate_external` runs it) against their undisturbed twins.
/// Returns `{"runs": [...], "rows": [...]}` (`pacs_sim::tolerance::rows`).
#[pyfunction]
#[pyo3(signature = (policy, task, method, seeds, at, holds, progress=None))]
#[allow(clippy::too_many_arguments)]
pub fn _tolerance<'py>(
    py: Python<'py>,
    policy: Py<PyAny>,
    task: &str,
    method: &str,
    seeds: Vec<u64>,
    at: Vec<f64>,
    holds: Vec<f64>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    // `progress(done, total)` after each rollout (Python errors in it are ignored).
    let mut tell = |done: usize, total: usize| {
        if let Some(f) = &progress {
            Python::attach(|py| {
                let _ = f.bind(py).call1((done, total));
            });
        }
    };
    let name: Option<String> = policy.bind(py).extract().ok();
    let plan = sim_plan(
        &[task.to_string()],
        &[method.to_string()],
        true,
        "continuous",
        name.as_deref().unwrap_or("nearest"),
    )?;
    let (kind, v) = (plan.tasks[0], &plan.variants[0]);
    if !matches!(v.method, pacs_sim::episode::Method::Pacs) {
        return Err(input(format!(
            "method: `{method}` does not brake along the path; the tolerance tool runs PACS \
             (pacs, pacs-ssm, pacs-pfl)"
        )));
    }
    if let Some((i, f)) = at
        .iter()
        .enumerate()
        .find(|(_, f)| !(0.0..=1.0).contains(*f))
    {
        return Err(input(format!(
            "at[{i}]: {f} is not a fraction of the rollout in [0, 1]"
        )));
    }
    if let Some((i, h)) = holds
        .iter()
        .enumerate()
        .find(|(_, h)| !(**h > 0.0 && h.is_finite()))
    {
        return Err(input(format!("holds[{i}]: {h} is not a positive time (s)")));
    }
    let grid = pacs_sim::tolerance::Interruptions {
        seeds: &seeds,
        at: &at,
        holds: &holds,
    };
    let err_of = |e: eval::EvalError| match e {
        eval::EvalError::Io { .. } => err(Kind::Output, e.to_string()),
        other => input(other.to_string()),
    };
    let runs = if name.is_some() {
        py.detach(|| pacs_sim::tolerance::tolerance(kind, v, &grid, None, &mut |_| {}, &mut tell))
            .map_err(err_of)?
    } else {
        let b = policy.bind(py);
        if !b.hasattr("act")? {
            return Err(type_err(
                "policy: a built-in policy's name or an object with act(obs)",
            ));
        }
        let execute = policy_execute(b)?;
        let mut p = PyTaskPolicy::new(&policy, kind, seeds.first().copied().unwrap_or(0), execute);
        let seed_now = p.seed.clone();
        let has_reset = b.hasattr("reset")?;
        let mut reset_error: Option<PyErr> = None;
        let r = py.detach(|| {
            let obj = &policy;
            let mut reset = |seed: u64| {
                seed_now.store(seed, std::sync::atomic::Ordering::Relaxed);
                if has_reset
                    && let Err(e) =
                        Python::attach(|py| obj.bind(py).call_method0("reset").map(|_| ()))
                {
                    reset_error.get_or_insert(e);
                }
            };
            pacs_sim::tolerance::tolerance(kind, v, &grid, Some(&mut p), &mut reset, &mut tell)
        });
        if let Some(e) = reset_error.or(p.error.take()) {
            return Err(e);
        }
        r.map_err(err_of)?
    };
    let rows = pacs_sim::tolerance::rows(&runs, &holds);
    to_py(py, &serde_json::json!({"runs": runs, "rows": rows}))
}
