//! `pacs.audit`, `pacs.Run`, `pacs.LogWriter`, `pacs.report`: the offline audit of logged runs
//! against SSM and PFL from Python — the same code as `pacs audit`.

use crate::convert::{
    Given, finite, from_py, optional_vec3, path, points, show, text, to_py, vec3, vector,
};
use crate::errors::{Kind, err, input, type_err};
use crate::models::scene;
use pacs_audit::{AuditConfig, RunResult};
use pacs_log::{Header, LogWriter};
use pacs_reports::{InputFile, ReportInput};
use pyo3::prelude::*;
use pyo3::types::PyString;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::PathBuf;

/// The audit settings from `config`: None (defaults), a dict (the TOML file's fields), or a
/// path to a TOML file. Returns the settings and the config file (hashed in reports).
fn audit_config(config: Option<&Bound<'_, PyAny>>) -> PyResult<(AuditConfig, Option<PathBuf>)> {
    let Some(c) = config.filter(|c| !c.is_none()) else {
        return Ok((AuditConfig::default(), None));
    };
    if c.cast::<pyo3::types::PyDict>().is_ok() {
        let cfg: AuditConfig = from_py(c, "config")?;
        cfg.validate().map_err(|e| input(format!("config: {e}")))?;
        return Ok((cfg, None));
    }
    let p: PathBuf = c.extract().map_err(|_| {
        type_err(format!(
            "config: expected None, a dict or a path to a TOML file, got {}",
            show(c)
        ))
    })?;
    let text = std::fs::read_to_string(&p)
        .map_err(|e| input(format!("config: cannot read {}: {e}", p.display())))?;
    let cfg = pacs_audit::parse_config(&p.display().to_string(), &text)
        .map_err(|e| input(e.to_string()))?;
    Ok((cfg, Some(p)))
}

fn verdict_str(v: pacs_audit::Verdict) -> &'static str {
    match v {
        pacs_audit::Verdict::Pass => "pass",
        pacs_audit::Verdict::Fail => "fail",
        pacs_audit::Verdict::Inconclusive => "inconclusive",
    }
}

/// The audit result of one log: verdict, violations, unchecked spans and metrics.
#[pyclass(name = "Run", module = "pacs", frozen)]
pub struct PyRun {
    pub(crate) run: RunResult,
    pub(crate) path: PathBuf,
    /// The log's SHA-256 and size when it was audited (a report refuses a log changed since).
    pub(crate) hashed: InputFile,
    /// The log's modification time (Unix seconds) when it was audited: the fleet report's day
    /// when the header states none (`pacs_reports::fleet::day`).
    pub(crate) modified: Option<u64>,
    pub(crate) config: AuditConfig,
    pub(crate) config_path: Option<PathBuf>,
}

#[pymethods]
impl PyRun {
    /// The log file as given.
    #[getter]
    fn log(&self) -> String {
        self.run.log.clone()
    }
    /// "pass", "fail" or "inconclusive".
    #[getter]
    fn verdict(&self) -> &'static str {
        verdict_str(self.run.verdict)
    }
    /// verdict == "pass": every span was checked and no violation is possible.
    #[getter]
    fn passed(&self) -> bool {
        self.run.verdict == pacs_audit::Verdict::Pass
    }
    /// Violation intervals (list of dicts: t_start, t_end (s), constraint, link, body part,
    /// separation bound (m), energy bound and threshold (J), certain), by start time.
    #[getter]
    fn violations<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, &self.run.violations)
    }
    /// Spans that could not be checked (list of dicts with the reason), by start time.
    #[getter]
    fn inconclusive<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, &self.run.inconclusive)
    }
    /// Metrics (dict): samples, duration (s), violation_fraction, min_separation (m), ...
    #[getter]
    fn metrics<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, &self.run.metrics)
    }
    /// The models the run was audited with (names and the limits the checks used).
    #[getter]
    fn models<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, &self.run.models)
    }
    /// The header's `meta` object.
    #[getter]
    fn meta<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, &self.run.meta)
    }
    /// The log's people (ids in header order; empty for a v1 log).
    #[getter]
    fn people<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, &self.run.people)
    }
    /// The audited time span and whether the log is the whole run (dict: `t_start`, `t_end`
    /// (s), `completeness`).
    #[getter]
    fn evidence<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, &self.run.evidence)
    }
    /// Violation episodes (list of dicts): the violation intervals of one person (or object),
    /// link and constraint less than 0.1 s apart merged (`who`, `body_parts`, `link`,
    /// `constraint`, `t_start`, `t_end`, `violating_s` (s), `intervals`, `worst_separation_m`
    /// (m), `worst_energy_j`, `threshold_j` (J; 0 for SSM), `clamped`, `certain`), by start
    /// time, as in report.json and `pacs audit --json`.
    #[getter]
    fn episodes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_py(py, &pacs_reports::episodes::episodes(&self.run.violations))
    }
    /// Everything above as one dict, `episodes` included: what `pacs audit --json` prints per
    /// run.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        #[derive(serde::Serialize)]
        struct WithEpisodes<'a> {
            #[serde(flatten)]
            run: &'a RunResult,
            episodes: Vec<pacs_reports::episodes::Episode>,
        }
        to_py(
            py,
            &WithEpisodes {
                run: &self.run,
                episodes: pacs_reports::episodes::episodes(&self.run.violations),
            },
        )
    }
    /// Pickling (Dask, multiprocessing): the whole run — results, plot series, model
    /// parameters, the audited bytes' SHA-256, the settings — rebuilt by
    /// `pacs.fleet._run_from_state` (same pacs version only).
    fn __reduce__<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, pyo3::types::PyBytes>,))> {
        crate::fleet::reduce_run(py, self)
    }
    fn __repr__(&self) -> String {
        format!(
            "Run(log={:?}, verdict={:?}, violations={}, inconclusive={})",
            self.run.log,
            verdict_str(self.run.verdict),
            self.run.violations.len(),
            self.run.inconclusive.len()
        )
    }
}

/// The separate pacs header of `pacs.audit(..., header=)`: None, a dict (the header object) or a
/// JSON/TOML file (as `pacs audit --header`).
fn audit_header(h: Option<&Bound<'_, PyAny>>) -> PyResult<Option<Header>> {
    let Some(h) = h.filter(|h| !h.is_none()) else {
        return Ok(None);
    };
    if h.cast::<pyo3::types::PyDict>().is_ok() {
        let v: serde_json::Value = from_py(h, "header")?;
        return pacs_log::mcap::header_from_value(v)
            .map(Some)
            .map_err(|e| input(format!("header: {e}")));
    }
    let p: PathBuf = h.extract().map_err(|_| {
        type_err(format!(
            "header: expected None, a dict or a path to a JSON/TOML header file, got {}",
            show(h)
        ))
    })?;
    pacs_log::mcap::load_header_file(&p)
        .map(Some)
        .map_err(|e| input(format!("header: {e}")))
}

/// Audit logged runs (log formats v1 and v2: JSON Lines, CSV for *.csv, ROS 2 MCAP, ROS 2 sqlite3 bags:
/// *.db3 or a bag directory with metadata.yaml, the header in custom_data `pacs_header`) against
/// the SSM and PFL constraints their headers name, with the one ISO/TS 15066 rule the shield uses.
/// `header`: for MCAP logs and ROS 2 bags only, the pacs header (a dict, or a JSON/TOML file)
/// instead of the logs' own (`pacs audit --header`; e.g. for ROS 2 Humble bags, which carry none).
/// `paths`: one path or a list; `config`: None, a dict of audit settings (max_gap,
/// max_human_age, rest_speed, human_model, tracking_error, limit_slack, robot/human/constraints
/// overrides; see docs/audit.md) or a TOML file. A run passes only if every span between its
/// first and last robot sample was checked. Invalid logs raise `pacs.InputError` naming the
/// file, line and field. Releases the GIL.
#[pyfunction]
#[pyo3(signature = (paths, config=None, header=None))]
pub fn audit(
    py: Python<'_>,
    paths: &Bound<'_, PyAny>,
    config: Option<&Bound<'_, PyAny>>,
    header: Option<&Bound<'_, PyAny>>,
) -> PyResult<Vec<PyRun>> {
    let list: Vec<PathBuf> = if paths.is_instance_of::<PyString>() {
        vec![paths.extract()?]
    } else if let Ok(p) = paths.extract::<PathBuf>() {
        vec![p]
    } else {
        paths.extract().map_err(|_| {
            type_err(format!(
                "paths: expected a path or a list of paths, got {}",
                show(paths)
            ))
        })?
    };
    if list.is_empty() {
        return Err(input("paths: no log given"));
    }
    pacs_reports::fleet::refuse_twice(&list).map_err(|e| input(format!("paths: {e}")))?;
    let (cfg, cfg_path) = audit_config(config)?;
    let header = audit_header(header)?;
    let mut out = Vec::with_capacity(list.len());
    for p in list {
        // Hashed before and after the audit: the verdict belongs to exactly these bytes.
        let hash = |p: &PathBuf| {
            py.detach(|| InputFile::hash(p))
                .map_err(|e| input(format!("paths: {e}")))
        };
        let before = hash(&p)?;
        let modified = pacs_reports::fleet::modified(&p);
        let r = py.detach(|| pacs_audit::audit_file_with_header(&p, &cfg, header.as_ref()));
        let run = r.map_err(|e| match e {
            pacs_log::LogError::Io { .. } => input(format!("{e}")),
            _ => input(e.to_string()),
        })?;
        let after = hash(&p)?;
        if after.sha256 != before.sha256 {
            return Err(input(format!(
                "paths: {} changed while it was audited (sha256 {} before, {} after); audit it again",
                p.display(),
                before.sha256,
                after.sha256
            )));
        }
        out.push(PyRun {
            run,
            hashed: before,
            modified,
            path: p,
            config: cfg.clone(),
            config_path: cfg_path.clone(),
        });
    }
    Ok(out)
}

/// Write the certification report of audited runs into `out_dir` (created): report.json
/// (inputs with SHA-256, settings, assumptions, checks and the tests/harnesses backing them,
/// verdicts, violations, metrics), report.md and report.html (with plots). The runs must come
/// from one `audit` call (one set of settings). Returns the overall verdict.
#[pyfunction]
pub fn report(runs: &Bound<'_, PyAny>, out_dir: &Bound<'_, PyAny>) -> PyResult<&'static str> {
    let out_dir = path(out_dir, "out_dir")?;
    let runs: Vec<PyRef<'_, PyRun>> = runs.extract().map_err(|_| {
        type_err(format!(
            "runs: expected a list of pacs.Run (from pacs.audit), got {}",
            show(runs)
        ))
    })?;
    let Some(first) = runs.first() else {
        return Err(input("runs: no run given"));
    };
    if runs.iter().any(|r| r.config != first.config) {
        return Err(input(
            "runs: audited with different settings; report each audit call separately",
        ));
    }
    // One log given twice would count twice in the fleet report (as `pacs.audit` refuses).
    for (i, r) in runs.iter().enumerate() {
        let key = std::fs::canonicalize(&r.path).unwrap_or_else(|_| r.path.clone());
        if let Some(first) = runs[..i]
            .iter()
            .find(|o| std::fs::canonicalize(&o.path).unwrap_or_else(|_| o.path.clone()) == key)
        {
            return Err(input(format!(
                "runs: {} is the same log as {} (given twice, it would count twice in the fleet report)",
                r.path.display(),
                first.path.display()
            )));
        }
    }
    // The report binds each verdict to the bytes that were audited: a log changed since its
    // audit is refused (audit it again).
    let mut logs = Vec::with_capacity(runs.len());
    for r in &runs {
        let now = InputFile::hash(&r.path).map_err(|e| input(format!("runs: {e}")))?;
        if now.sha256 != r.hashed.sha256 {
            return Err(input(format!(
                "runs: {} changed since it was audited (sha256 {} then, {} now): audit it again before reporting",
                r.path.display(),
                r.hashed.sha256,
                now.sha256
            )));
        }
        logs.push(r.hashed.clone());
    }
    if let Some((a, b)) = pacs_reports::same_bytes(&logs) {
        return Err(input(format!(
            "runs: {}",
            pacs_reports::same_bytes_message(a, b)
        )));
    }
    let config = match &first.config_path {
        Some(p) => Some(InputFile::hash(p).map_err(|e| input(format!("config: {e}")))?),
        None => None,
    };
    let results: Vec<RunResult> = runs.iter().map(|r| r.run.clone()).collect();
    let input_doc = ReportInput {
        runs: &results,
        logs,
        config,
        settings: serde_json::to_value(&first.config).unwrap_or_default(),
        generated: pacs_reports::utc_now(),
        skipped: Vec::new(),
    };
    pacs_reports::write_reports(&out_dir, &input_doc)
        .map_err(|e| err(Kind::Output, format!("out_dir: {e}")))?;
    Ok(verdict_str(pacs_reports::overall(&results)))
}

/// Write a run as a pacs log (format v2, JSON Lines; several people, each with an id) from a
/// Python loop, for `pacs.audit`.
/// The models are named as for `Shield` (URDF robots are written as their converted spec).
/// Records must come in time order: `robot(t, q, dq=None, ddq=None)` (rad, rad/s, rad/s²; the
/// audit bounds motion between samples by the robot's limits, tighter with dq/ddq),
/// `human(t, t_meas, positions)` (m, shape (K, 3)), `object(t, t_meas, id, position,
/// velocity=None)`, `event(t, name)` ("success" / "failure" set the task outcome). Use as a
/// context manager or call `close()`.
#[pyclass(name = "LogWriter", module = "pacs")]
pub struct PyLogWriter {
    w: Option<LogWriter<BufWriter<File>>>,
    path: PathBuf,
    dof: usize,
    /// Person ids and keypoint counts, in header order.
    people: Vec<(String, usize)>,
    object_ids: Vec<String>,
}

impl PyLogWriter {
    fn writer(&mut self) -> PyResult<&mut LogWriter<BufWriter<File>>> {
        self.w
            .as_mut()
            .ok_or_else(|| err(Kind::State, "LogWriter: already closed"))
    }
    fn werr(&self, e: pacs_log::WriteError) -> PyErr {
        match e {
            pacs_log::WriteError::Io(e) => {
                err(Kind::Output, format!("{}: {e}", self.path.display()))
            }
            e => input(format!("{}: {e}", self.path.display())),
        }
    }
}

#[pymethods]
impl PyLogWriter {
    #[new]
    #[pyo3(signature = (path, robot=None, human=Given::Missing, constraints=None, objects=None, environment=None, side=None, meta=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        path: &Bound<'_, PyAny>,
        robot: Option<&Bound<'_, PyAny>>,
        human: Given<'_>,
        constraints: Option<&Bound<'_, PyAny>>,
        objects: Option<&Bound<'_, PyAny>>,
        environment: Option<&Bound<'_, PyAny>>,
        side: Option<&Bound<'_, PyAny>>,
        meta: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let s = scene(py, robot, side, human, constraints, objects, environment)?;
        let path = crate::convert::path(path, "path")?;
        if s.humans.is_empty() {
            return Err(input(
                "human: a log names at least one human model (the audit checks the robot against their measurements); got None",
            ));
        }
        // Version 2 with the end-event promise: `close()` writes the `end` event, so a log that
        // was never closed audits `incomplete_log`.
        let mut header: Header = s.header.promising_end();
        header.meta.insert("filter".into(), "python".into());
        if let Some(m) = meta.filter(|m| !m.is_none()) {
            let extra: serde_json::Map<String, serde_json::Value> = from_py(m, "meta")?;
            header.meta.extend(extra);
        }
        let f = File::create(&path).map_err(|e| {
            err(
                Kind::Output,
                format!("path: cannot create {}: {e}", path.display()),
            )
        })?;
        let mut w = LogWriter::new(BufWriter::new(f));
        let mut me = Self {
            w: None,
            path,
            dof: s.models.robot.dof(),
            people: s
                .models
                .people
                .iter()
                .map(|(id, m)| (id.clone(), m.keypoint_count()))
                .collect(),
            object_ids: s
                .models
                .objects
                .iter()
                .map(|(id, _, _)| id.clone())
                .collect(),
        };
        w.write_header(&header).map_err(|e| me.werr(e))?;
        me.w = Some(w);
        Ok(me)
    }

    /// A robot sample at `t` (s): positions `q` (rad), optional velocities `dq` (rad/s) and
    /// accelerations `ddq` (rad/s², only with `dq`).
    #[pyo3(signature = (t, q, dq=None, ddq=None))]
    fn robot(
        &mut self,
        t: &Bound<'_, PyAny>,
        q: &Bound<'_, PyAny>,
        dq: Option<&Bound<'_, PyAny>>,
        ddq: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<()> {
        let t = finite(t, "t")?;
        let n = self.dof;
        let q = vector(q, "q", n)?;
        let opt = |v: Option<&Bound<'_, PyAny>>, name: &str| -> PyResult<Option<Vec<f64>>> {
            match v {
                Some(v) if !v.is_none() => Ok(Some(vector(v, name, n)?)),
                _ => Ok(None),
            }
        };
        let dq = opt(dq, "dq")?;
        let ddq = opt(ddq, "ddq")?;
        if dq.is_none() && ddq.is_some() {
            return Err(input("ddq: accelerations need velocities (dq)"));
        }
        let r = self
            .writer()?
            .write_robot_with_acc(t, &q, dq.as_deref(), ddq.as_deref());
        r.map_err(|e| self.werr(e))
    }

    /// A human measurement logged at `t`, taken at `t_meas` (s): keypoints (m, shape (K, 3)) of
    /// person `person` (an index or id of the writer's humans; may be left out only when the
    /// writer has one person).
    #[pyo3(signature = (t, t_meas, positions, person=None))]
    fn human(
        &mut self,
        t: &Bound<'_, PyAny>,
        t_meas: &Bound<'_, PyAny>,
        positions: &Bound<'_, PyAny>,
        person: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<()> {
        let ids = || {
            self.people
                .iter()
                .map(|(p, _)| p.as_str())
                .collect::<Vec<_>>()
        };
        let k = match person {
            // Several people: whose measurement this is must be said (a default would give
            // one person's measurements to another).
            None if self.people.len() > 1 => {
                return Err(input(format!(
                    "person: required with several people (give an id or index of {:?})",
                    ids()
                )));
            }
            None => 0,
            Some(p) if p.is_none() && self.people.len() > 1 => {
                return Err(input(format!(
                    "person: required with several people (give an id or index of {:?})",
                    ids()
                )));
            }
            Some(p) if p.is_none() => 0,
            Some(p) if p.is_instance_of::<pyo3::types::PyBool>() => {
                return Err(type_err(format!(
                    "person: expected an id (str) or an index (int ≥ 0), got {}",
                    show(p)
                )));
            }
            Some(p)
                if p.is_instance_of::<pyo3::types::PyInt>() && p.extract::<usize>().is_err() =>
            {
                return Err(input(format!(
                    "person: expected an id (str) or an index (int ≥ 0), got {}",
                    show(p)
                )));
            }
            Some(p) => {
                if let Ok(i) = p.extract::<usize>() {
                    if i >= self.people.len() {
                        return Err(input(format!(
                            "person: index {i} is out of range ({} people)",
                            self.people.len()
                        )));
                    }
                    i
                } else {
                    let id = text(p, "person")?;
                    self.people
                        .iter()
                        .position(|(p, _)| *p == id)
                        .ok_or_else(|| {
                            input(format!(
                                "person: no person `{id}` in the header (humans: {:?})",
                                self.people
                                    .iter()
                                    .map(|(p, _)| p.as_str())
                                    .collect::<Vec<_>>()
                            ))
                        })?
                }
            }
        };
        let (id, keypoints) = self.people[k].clone();
        let t = finite(t, "t")?;
        let tm = finite(t_meas, "t_meas")?;
        if tm > t {
            return Err(input(format!(
                "t_meas: {tm} s is after the log time t = {t} s"
            )));
        }
        let p = points(positions, "positions", Some(keypoints))?;
        let r = self.writer()?.write_person(t, tm, Some(&id), &p);
        r.map_err(|e| self.werr(e))
    }

    /// A measurement of the header's object `id` logged at `t`, taken at `t_meas` (s):
    /// position (m), velocity (m/s) if measured.
    #[pyo3(signature = (t, t_meas, id, position, velocity=None))]
    fn object(
        &mut self,
        t: &Bound<'_, PyAny>,
        t_meas: &Bound<'_, PyAny>,
        id: &Bound<'_, PyAny>,
        position: &Bound<'_, PyAny>,
        velocity: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<()> {
        let id = text(id, "id")?;
        if !self.object_ids.contains(&id) {
            return Err(input(format!(
                "id: no object `{id}` in the header (objects: {:?})",
                self.object_ids
            )));
        }
        let t = finite(t, "t")?;
        let tm = finite(t_meas, "t_meas")?;
        let p = vec3(position, "position")?;
        let v = optional_vec3(velocity, "velocity")?;
        let r = self.writer()?.write_object(t, tm, &id, p, v);
        r.map_err(|e| self.werr(e))
    }

    /// A named event at `t` (s): "success" / "failure" record the task outcome.
    fn event(&mut self, t: &Bound<'_, PyAny>, name: &Bound<'_, PyAny>) -> PyResult<()> {
        let t = finite(t, "t")?;
        let name = text(name, "name")?;
        if name == pacs_log::END_EVENT {
            return Err(input(
                "name: the `end` event is written by close() (the header promises it last)",
            ));
        }
        let r = self.writer()?.write_event(t, &name);
        r.map_err(|e| self.werr(e))
    }

    /// Write the promised `end` event (at the last record's time), flush and close the file
    /// (idempotent). Log the run's last robot sample last: a measurement or event stamped after
    /// it leaves the stretch up to `end` without robot samples, and the audit then reads the
    /// log as `incomplete_log`.
    fn close(&mut self) -> PyResult<()> {
        if let Some(mut w) = self.w.take() {
            let path = self.path.display().to_string();
            // The promised `end` event, at the last record's time.
            let last = w.last_time();
            let t_end = if last.is_finite() { last } else { 0.0 };
            w.write_event(t_end, pacs_log::END_EVENT)
                .map_err(|e| self.werr(e))?;
            let mut out = w.finish().map_err(|e| self.werr(e))?;
            out.flush()
                .map_err(|e| err(Kind::Output, format!("{path}: {e}")))?;
        }
        Ok(())
    }

    /// The log's path.
    #[getter]
    fn path(&self) -> PathBuf {
        self.path.clone()
    }

    fn __enter__(slf: Py<Self>) -> Py<Self> {
        slf
    }

    /// Leaving a `with` block closes the log; leaving it by an exception does not write the
    /// `end` event: the run was cut short, and the audit reads the log as `incomplete_log` (never
    /// `pass`), as it would a writer that was never closed.
    #[pyo3(signature = (*args))]
    fn __exit__(&mut self, args: &Bound<'_, pyo3::types::PyTuple>) -> PyResult<bool> {
        let raised = args.get_item(0).is_ok_and(|e| !e.is_none());
        if raised {
            self.abandon()?;
        } else {
            self.close()?;
        }
        Ok(false)
    }
}

impl PyLogWriter {
    /// Flush and close the file without the `end` event (a run cut short by an exception).
    fn abandon(&mut self) -> PyResult<()> {
        if let Some(w) = self.w.take() {
            let path = self.path.display().to_string();
            let mut out = w.finish().map_err(|e| self.werr(e))?;
            out.flush()
                .map_err(|e| err(Kind::Output, format!("{path}: {e}")))?;
        }
        Ok(())
    }
}
