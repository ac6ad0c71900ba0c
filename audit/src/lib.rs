//! The offline audit of logged runs against SSM and PFL: every span between logged robot samples
//! judged by the one ISO/TS 15066 rule ([`pacs_verify::iso15066`]).
//!
//! - [`check`]: the span checker ([`check::Auditor`]);
//! - [`config`]: its settings ([`config::AuditConfig`]);
//! - [`enclosure`]: sound joint boxes over a span and the consistency of the samples;
//! - [`verdict`]: verdicts, violation intervals, metrics;
//! - [`series`]: the bounded plot series;
//! - [`claims`]: the checks, the tests backing them, and the assumptions, in one list.
//!
//! The log format and its readers live in `pacs-log`. Entry points: [`audit_file`] and
//! [`audit_reader`]. Semantics: `docs/audit.md`.

pub mod check;
pub mod claims;
pub mod config;
pub mod enclosure;
pub mod error;
pub mod people;
pub mod series;
pub mod verdict;

pub use check::{AuditConfig, Auditor};
pub use error::AuditError;
/// Log-form detection, implemented in `pacs-log` (re-exported beside [`open_log`]).
pub use pacs_log::{is_db3, is_mcap};
pub use verdict::{
    Completeness, ConstraintKind, Evidence, InconclusiveReason, Metrics, PersonModel, RunResult,
    Verdict, Violation,
};

use pacs_log::{
    EqualTimeGroup, Header, Location, LogError, LogModels, MAX_EQUAL_TIME, Record, RecordReader,
    TooManyAtOneTime,
};
use std::path::Path;

/// Load an audit config from TOML text; errors name the file and the problem.
pub fn parse_config(file: &str, text: &str) -> Result<AuditConfig, LogError> {
    let mut cfg: AuditConfig = toml::from_str(text)
        .map_err(|e| LogError::input(file, Location::File, format!("invalid config: {e}")))?;
    // A {urdf, side} robot's relative paths are relative to the config file.
    if let Some(r) = &mut cfg.robot {
        r.rebase(&pacs_log::dir_of(std::path::Path::new(file)));
    }
    cfg.validate()
        .map_err(|p| LogError::input(file, Location::File, format!("invalid config: {p}")))?;
    Ok(cfg)
}

/// The checker of one log: one person (v1, or v2 with one person), or several
/// ([`people::PeopleAuditor`]).
enum Checker {
    One {
        auditor: Box<Auditor>,
        /// A v2 log's person id (human records may name it), `None` for v1.
        id: Option<String>,
    },
    Many(people::PeopleAuditor),
}

impl Checker {
    fn new(header: &Header, models: LogModels, cfg: &AuditConfig) -> Result<Self, AuditError> {
        if models.people.len() > 1 {
            return Ok(Checker::Many(people::PeopleAuditor::new(&models, cfg)?));
        }
        let id = (header.version >= 2).then(|| models.people[0].0.clone());
        let auditor = match &id {
            Some(id) => Auditor::for_person(models, cfg.clone(), id, false)?,
            None => Auditor::new(models, cfg.clone())?,
        };
        Ok(Checker::One {
            auditor: Box::new(auditor),
            id,
        })
    }

    fn apply(&mut self, rec: Record<'_>) -> Result<(), AuditError> {
        match (self, rec) {
            (Checker::Many(p), Record::Robot { t, q, dq, ddq }) => {
                p.push_robot_with_acc(t, q, dq, ddq)
            }
            (Checker::One { auditor, .. }, Record::Robot { t, q, dq, ddq }) => {
                auditor.push_robot_with_acc(t, q, dq, ddq)
            }
            (
                Checker::Many(p),
                Record::Human {
                    t,
                    t_meas,
                    person,
                    positions,
                },
            ) => p.push_human(person, t, t_meas, positions),
            (
                Checker::One { auditor, id },
                Record::Human {
                    t,
                    t_meas,
                    person,
                    positions,
                },
            ) => {
                if let Some(p) = person
                    && id.as_deref() != Some(p)
                {
                    return Err(AuditError::UnknownPerson {
                        id: p.to_string(),
                        declared: id.clone().unwrap_or_else(|| "none (v1)".into()),
                    });
                }
                auditor.push_human(t, t_meas, positions)
            }
            (Checker::Many(p), Record::Event { name, .. }) => {
                p.push_event(name);
                Ok(())
            }
            (Checker::One { auditor, .. }, Record::Event { name, .. }) => {
                auditor.push_event(name);
                Ok(())
            }
            (_, Record::Shield { .. }) => Ok(()),
            (
                Checker::Many(p),
                Record::Object {
                    t,
                    t_meas,
                    id,
                    position,
                    velocity,
                },
            ) => p.push_object(t, t_meas, id, position, velocity),
            (
                Checker::One { auditor, .. },
                Record::Object {
                    t,
                    t_meas,
                    id,
                    position,
                    velocity,
                },
            ) => auditor.push_object(t, t_meas, id, position, velocity),
        }
    }

    fn finish(self, log: &str, meta: serde_json::Map<String, serde_json::Value>) -> RunResult {
        match self {
            Checker::One { auditor, .. } => auditor.finish(log, meta),
            Checker::Many(p) => p.finish(log, meta),
        }
    }
}

/// Audit every record of `reader` with `cfg`. Never returns `pass` unless every span between the
/// first and last robot sample was checked, for every person of the log, and (where the header
/// promises an `end` event) the log reaches its end. Errors name the file and line/offset.
pub fn audit_reader(
    reader: &mut dyn RecordReader,
    cfg: &AuditConfig,
) -> Result<RunResult, LogError> {
    let file = reader.file().to_string();
    let header = reader.header().with_overrides(&cfg.overrides());
    let header_loc = reader.header_location();
    let header_file = reader.header_file().to_string();
    let models = LogModels::from_header(&header)
        .map_err(|p| LogError::input(&header_file, header_loc, p.to_string()))?;
    let mut checker = Checker::new(&header, models, cfg)
        .map_err(|p| LogError::input(&header_file, header_loc, p.to_string()))?;
    let mut last_t = f64::NEG_INFINITY;
    // The `end` and `start` events' times, once seen; and the first and last robot samples'.
    let mut end: Option<f64> = None;
    let mut start: Option<f64> = None;
    let mut robot_span: Option<(f64, f64)> = None;
    // The earliest shield diagnostics record's time: the writer logs one after each robot
    // sample, so one before the promised start shows samples cut out before it.
    let mut first_shield: Option<f64> = None;
    // Records of one time stamp are applied in the canonical order (`order`): human
    // measurements, robot samples, events, then file order.
    let mut group = EqualTimeGroup::default();
    // A reader that already hands equal times over in the canonical order is applied record by
    // record (no copy), with the group's cap on records sharing one time stamp kept.
    let direct = reader.in_canonical_order();
    let mut at_this_time = 0usize;
    let mut apply = |rec: Record<'_>| -> Result<(), AuditError> {
        if let Some(e) = end {
            let kind = match rec {
                Record::Robot { .. } => "a robot",
                Record::Human { .. } => "a human",
                Record::Object { .. } => "an object",
                Record::Event { .. } => "an event",
                // Diagnostics may follow (at the end's time, they sort after events).
                Record::Shield { .. } => return Ok(()),
            };
            return Err(AuditError::AfterEnd {
                kind,
                t: rec.t(),
                end: e,
            });
        }
        match rec {
            Record::Robot { t, .. } => robot_span = Some((robot_span.map_or(t, |s| s.0), t)),
            Record::Shield { t } => first_shield = Some(first_shield.map_or(t, |f| f.min(t))),
            Record::Event { t, name } if header.end_event && name == pacs_log::END_EVENT => {
                end = Some(t)
            }
            Record::Event { t, name } if header.start_event && name == pacs_log::START_EVENT => {
                if let Some(first) = start {
                    return Err(AuditError::SecondStart { t, first });
                }
                start = Some(t)
            }
            _ => {}
        }
        checker.apply(rec)
    };
    loop {
        let rec = reader.next_record()?;
        let Some(rec) = rec else { break };
        let t = rec.t();
        if !t.is_finite() {
            let p = format!("t: value {t} is not finite");
            return Err(LogError::input(reader.file(), reader.location(), p));
        }
        if t < last_t {
            let p = format!("time goes backwards: t = {t} s after t = {last_t} s");
            return Err(LogError::input(reader.file(), reader.location(), p));
        }
        if direct {
            at_this_time = if t == last_t { at_this_time + 1 } else { 1 };
            last_t = t;
            if at_this_time > MAX_EQUAL_TIME {
                let p = TooManyAtOneTime { t }.to_string();
                return Err(LogError::input(reader.file(), reader.location(), p));
            }
            if let Err(p) = apply(rec) {
                return Err(LogError::input(
                    reader.file(),
                    reader.location(),
                    p.to_string(),
                ));
            }
            continue;
        }
        if group.time().is_some_and(|tg| tg != t) {
            group
                .drain(&mut apply)
                .map_err(|(loc, p)| LogError::input(&file, loc, p.to_string()))?;
        }
        last_t = t;
        group
            .push(&rec, Location::File)
            .map_err(|p| LogError::input(reader.file(), reader.location(), p.to_string()))?;
        group.locate_last(reader.location());
    }
    group
        .drain(&mut apply)
        .map_err(|(loc, p)| LogError::input(&file, loc, p.to_string()))?;
    let mut result = checker.finish(&file, header.meta.clone());
    if header.end_event {
        let start = header.start_event.then_some(start);
        complete_or_not(&mut result, start, end, robot_span, first_shield);
    }
    Ok(result)
}

/// Whether a log whose writer promised an `end` event (and, `start` not `None`, a `start`
/// event) is complete: the end event is there and the robot samples reach it (last sample ≥
/// end), and where a start is promised, it is there and the samples begin at it (first sample
/// = start: a log cut at its beginning keeps its header but not the samples after the start;
/// samples before the start are not the run's), and no shield diagnostics record is stamped
/// before the start (the shield logs one after each sample: one before the start belongs to
/// samples cut out, the start moved later with them).
/// Otherwise the result gains an `incomplete_log` span for each missing stretch — from the
/// start (or the first sample, when the start is missing) to the first sample, and from the
/// last sample to the end (or to the last sample, when the end is missing) — and can no longer
/// pass. Without a start promise a complete log is [`Completeness::EndOnly`]: a cut at its
/// beginning cannot be told.
///
/// [`Completeness::EndOnly`]: verdict::Completeness::EndOnly
fn complete_or_not(
    result: &mut RunResult,
    start: Option<Option<f64>>,
    end: Option<f64>,
    robot_span: Option<(f64, f64)>,
    first_shield: Option<f64>,
) {
    use verdict::{Completeness, InconclusiveSpan};
    let (first, last) = robot_span.map_or((0.0, 0.0), |(a, b)| (a, b));
    let mut missing: Vec<(f64, f64)> = Vec::new();
    // The writer stamps its start as its first robot sample: a later first sample means the
    // log's beginning was cut, an earlier one samples before the run's start (a log glued
    // from two).
    if let Some(start) = start
        && !matches!((start, robot_span), (Some(s), Some(_)) if first == s)
    {
        // (Without robot samples: at the start event, or at 0.)
        let s = start.unwrap_or(first);
        let first = if robot_span.is_some() { first } else { s };
        missing.push((s.min(first), s.max(first)));
    }
    // The shield logs its diagnostics after each robot sample: one stamped before the start
    // belongs to samples cut out (the start moved later with them).
    if let (Some(Some(s)), Some(f)) = (start, first_shield)
        && f < s
    {
        missing.push((f, s));
    }
    if !matches!((end, robot_span), (Some(e), Some(_)) if last >= e) {
        missing.push((last, end.unwrap_or(last).max(last)));
    }
    result.evidence.completeness = match (missing.is_empty(), start.is_some()) {
        (false, _) => Completeness::Incomplete,
        (true, true) => Completeness::Complete,
        (true, false) => Completeness::EndOnly,
    };
    for (t_start, t_end) in missing {
        result.inconclusive.push(InconclusiveSpan {
            t_start,
            t_end,
            reason: InconclusiveReason::IncompleteLog,
            spans: 0,
            person: None,
            object: None,
        });
    }
    result.refresh_verdict();
}

/// Audit one log file: MCAP if it starts with the MCAP magic or its name ends in `.mcap`, a ROS 2
/// sqlite3 bag if it is a directory with `metadata.yaml`, starts with the SQLite magic or its name
/// ends in `.db3`, CSV form if the name ends in `.csv`, JSON Lines otherwise. The path as given names the log in
/// messages and in the result.
pub fn audit_file(path: &Path, cfg: &AuditConfig) -> Result<RunResult, LogError> {
    audit_file_with_header(path, cfg, None)
}

/// [`audit_file`] with a pacs header given separately (`pacs audit --header`), which only MCAP
/// logs and sqlite3 bags accept: for them it replaces the `pacs` metadata record (the bag's
/// `custom_data` header); for other logs it is an error.
pub fn audit_file_with_header(
    path: &Path,
    cfg: &AuditConfig,
    header: Option<&Header>,
) -> Result<RunResult, LogError> {
    // A fresh auditor for each reading (`read_file`).
    let mut result = read_file(path, cfg, header, |reader| audit_reader(reader, cfg))?;
    // The run is the log as given (a bag directory, not the part read last).
    result.log = path.display().to_string();
    Ok(result)
}

/// Read the log at `path` with `read` as the audit reads it: with `cfg`'s reader settings, a
/// sqlite3 bag in the table's own order, through its time index where it refuses that order
/// (`read` then runs again from the start: [`pacs_log::read_log`]). What [`audit_file_with_header`]
/// audits and `pacs bench audit` times.
pub fn read_file<T>(
    path: &Path,
    cfg: &AuditConfig,
    header: Option<&Header>,
    read: impl FnMut(&mut dyn RecordReader) -> Result<T, LogError>,
) -> Result<T, LogError> {
    pacs_log::read_log(path, &cfg.mcap, &cfg.overrides(), header, read, |e| {
        matches!(e, LogError::RowsNotInTimeOrder { .. })
    })
}

/// Open a log for reading by its form with the audit's reader settings: [`pacs_log::open_log`]
/// with `cfg`'s MCAP settings and model overrides (see [`audit_file`]); a separate header only
/// for MCAP logs and bags (`--header`; an error for other logs).
pub fn open_log(
    path: &Path,
    cfg: &AuditConfig,
    header: Option<&Header>,
) -> Result<Box<dyn RecordReader>, LogError> {
    pacs_log::open_log(path, &cfg.mcap, &cfg.overrides(), header)
}
