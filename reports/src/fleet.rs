//! The fleet report: many audited logs of many robots, grouped per robot, scene and day, with
//! verdict counts, audited and violation time, and the worst runs; and the listing of an
//! archive's log files. One implementation for `pacs audit DIR --out` (report.json `fleet`, the
//! HTML and Markdown fleet table) and Python's `pacs.fleet.audit` (locally or on Dask).
//!
//! Where each key comes from (docs/fleet.md):
//! - **robot**: the header's `meta.robot_id`, else `meta.robot`, else the robot model's name;
//! - **scene**: `meta.task`, else `meta.scene`, else `-`;
//! - **day** (UTC date, `YYYY-MM-DD`): `meta.date` (a date as written), else `meta.start_time`
//!   (Unix seconds, or an RFC 3339 time with `Z` or an offset), else `meta.mcap_time_base_s` or
//!   `meta.db3_time_base_s` (a ROS bag's first message time) when it is a wall clock (after
//!   2000-01-01; a simulated clock starts near 0), else the log
//!   file's modification time. A stated date that cannot be read is not replaced by a guess: its
//!   day is `invalid` and `day_source` says why.
//!
//! A run's **violation time** is the length of the union of its violation intervals (intervals of
//! different body part / link pairs overlap in time and count once).

use pacs_audit::{RunResult, Verdict};
use pacs_log::db3::{METADATA_FILE as BAG_METADATA, is_bag_dir};
use serde::Serialize;
use serde_json::Value;
use std::path::{Path, PathBuf};

/// File name endings of the logs an archive directory expands to (`pacs audit DIR`).
pub const LOG_EXTENSIONS: [&str; 4] = pacs_log::db3::LOG_EXTENSIONS;

/// Worst runs listed per group.
pub const WORST_PER_GROUP: usize = 3;
/// Worst runs listed for the whole fleet.
pub const WORST_OVERALL: usize = 10;

/// `meta.mcap_time_base_s` and `meta.db3_time_base_s` are taken as a wall clock from this time on
/// (2000-01-01T00:00:00Z).
const WALL_CLOCK_FROM: f64 = 946_684_800.0;

/// The logs of `paths`: a file stays as given; a directory becomes its log files
/// ([`LOG_EXTENSIONS`]) and ROS 2 bag directories (with `metadata.yaml`), in it and its
/// subdirectories (symbolic links to directories are not followed; every entry with a log's
/// name counts, also one that cannot be read), sorted by path; a bag directory given itself is
/// one log. Errors name the path: one that cannot be read, a directory without logs, or a log
/// given twice (paths that name the same file).
pub fn expand_logs(paths: &[PathBuf]) -> Result<Vec<PathBuf>, ExpandError> {
    list_logs(paths).map(|l| l.logs)
}

/// The logs [`list_logs`] found, and the entries under the given directories it passed over.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Listing {
    /// The logs, as [`expand_logs`] gives them.
    pub logs: Vec<PathBuf>,
    /// Entries under a given directory that are not logs (another name, a symbolic link to a
    /// directory, which is not followed), sorted: not audited, and said so (the CLI's note on
    /// stderr, `skipped` in report.json), so that a report never leaves one out without a word.
    pub skipped: Vec<PathBuf>,
}

/// [`expand_logs`], with the entries under the given directories that it passed over. Test
/// `reports/tests/fleet.rs::a_directory_expands_to_its_sorted_log_files`.
pub fn list_logs(paths: &[PathBuf]) -> Result<Listing, ExpandError> {
    let mut out = Vec::new();
    let mut skipped = Vec::new();
    for p in paths {
        let meta = std::fs::metadata(p).map_err(|error| ExpandError::Read {
            path: p.clone(),
            error,
        })?;
        if !meta.is_dir() || is_bag_dir(p) {
            out.push(p.clone());
            continue;
        }
        let mut found = Vec::new();
        collect_logs(p, &mut found, &mut skipped)?;
        if found.is_empty() {
            return Err(ExpandError::NoLogs(p.clone()));
        }
        found.sort();
        out.extend(found);
    }
    // A FIFO, socket or device with a log's name would block the reading of the archive for ever
    // (opening a FIFO waits for a writer): refused here, before anything opens it.
    for p in &out {
        if let Ok(m) = std::fs::metadata(p)
            && !m.is_file()
            && !m.is_dir()
        {
            return Err(ExpandError::NotAFile(p.clone()));
        }
    }
    // A log named twice (a directory and a file in it, or one path twice) would count twice in
    // the fleet's runs, verdict counts and violation time: refused.
    refuse_twice(&out)?;
    skipped.sort();
    Ok(Listing { logs: out, skipped })
}

/// Refuse a log named twice among `logs` (one file by two paths, hard links included: the file
/// decides, its device and inode on Unix; a bag directory is also each of its parts, so the
/// directory and its own `.db3` are one log): it would count twice in a report's runs, verdict
/// counts and violation time. Used by [`expand_logs`] and by Python's `pacs.audit`.
pub fn refuse_twice(logs: &[PathBuf]) -> Result<(), ExpandError> {
    let mut seen: std::collections::HashMap<FileKey, usize> = std::collections::HashMap::new();
    for (i, p) in logs.iter().enumerate() {
        for key in log_keys(p) {
            match seen.get(&key) {
                Some(&first) if first != i => {
                    return Err(ExpandError::Twice {
                        first: logs[first].clone(),
                        second: p.clone(),
                    });
                }
                Some(_) => {}
                None => {
                    seen.insert(key, i);
                }
            }
        }
    }
    Ok(())
}

/// The files a log is made of: the file itself, or for a bag directory the directory and every
/// file in it but its `metadata.yaml` (its parts: the bag reader refuses a data file the metadata
/// does not list). So a bag directory and its own `.db3` given together, or two bag directories
/// whose parts are hard links of one file, are one log given twice.
fn log_keys(p: &Path) -> Vec<FileKey> {
    let mut keys = vec![file_key(p)];
    if p.is_dir()
        && let Ok(entries) = std::fs::read_dir(p)
    {
        for e in entries.flatten() {
            let path = e.path();
            if e.file_name() != BAG_METADATA && path.is_file() {
                keys.push(file_key(&path));
            }
        }
    }
    keys
}

/// What makes two paths one log: the file itself (device and inode on Unix: hard links too),
/// else the canonical path, else the path as given.
#[derive(Debug, PartialEq, Eq, Hash)]
enum FileKey {
    Inode(u64, u64),
    Path(PathBuf),
}

fn file_key(p: &Path) -> FileKey {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if let Ok(m) = std::fs::metadata(p) {
            return FileKey::Inode(m.dev(), m.ino());
        }
    }
    FileKey::Path(std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf()))
}

/// Why [`expand_logs`] could not list the logs; each names the path.
#[derive(Debug, thiserror::Error)]
pub enum ExpandError {
    /// A path (or a directory entry's type) that cannot be read.
    #[error("{}: cannot read: {error}", path.display())]
    Read {
        path: PathBuf,
        error: std::io::Error,
    },
    /// A directory that cannot be listed.
    #[error("{}: cannot list: {error}", path.display())]
    List {
        path: PathBuf,
        error: std::io::Error,
    },
    /// A directory (with its subdirectories) without a log.
    #[error(
        "{}: a directory without log files (*.{} or ROS 2 bag directories)",
        .0.display(),
        LOG_EXTENSIONS.join(", *.")
    )]
    NoLogs(PathBuf),
    /// Not a regular file or directory (a FIFO, socket or device).
    #[error(
        "{}: not a regular file (a FIFO, socket or device): a log is a file or a bag directory",
        .0.display()
    )]
    NotAFile(PathBuf),
    /// One log given twice (by paths that name the same file, or a bag directory and one of its
    /// parts).
    #[error(
        "{}: the same log as {} (given twice, it would count twice in the fleet report)",
        second.display(),
        first.display()
    )]
    Twice { first: PathBuf, second: PathBuf },
}

fn collect_logs(
    dir: &Path,
    out: &mut Vec<PathBuf>,
    skipped: &mut Vec<PathBuf>,
) -> Result<(), ExpandError> {
    let list = |error| ExpandError::List {
        path: dir.to_path_buf(),
        error,
    };
    for entry in std::fs::read_dir(dir).map_err(list)? {
        let entry = entry.map_err(list)?;
        let path = entry.path();
        let kind = entry.file_type().map_err(|error| ExpandError::Read {
            path: path.clone(),
            error,
        })?;
        if kind.is_dir() && is_bag_dir(&path) {
            // A bag directory is one log (its .db3 files are its parts).
            out.push(path);
        } else if kind.is_dir() {
            collect_logs(&path, out, skipped)?;
        } else if is_log_name(&path) {
            // Every entry with a log's name counts, also one that cannot be read (a dangling
            // link, a FIFO, a link to a directory): its audit then fails with the path named,
            // never leaves the archive without a word.
            out.push(path);
        } else {
            skipped.push(path);
        }
    }
    Ok(())
}

fn is_log_name(p: &Path) -> bool {
    pacs_log::db3::has_log_name(p)
}

/// A file's modification time in whole Unix seconds (rounded down), None if unknown or before
/// 1970.
pub fn modified(path: &Path) -> Option<u64> {
    let t = std::fs::metadata(path).ok()?.modified().ok()?;
    Some(t.duration_since(std::time::UNIX_EPOCH).ok()?.as_secs())
}

/// Where a run sits in the fleet, and its figures.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FleetRun {
    /// The log, as given.
    pub log: String,
    /// Robot (see the module docs).
    pub robot: String,
    /// Scene.
    pub scene: String,
    /// UTC date `YYYY-MM-DD` (or `invalid` / `unknown`).
    pub day: String,
    /// Where the day comes from: `meta.date`, `meta.start_time`, `meta.mcap_time_base_s`,
    /// `meta.db3_time_base_s`, `file_mtime`, or why it could not be read.
    pub day_source: String,
    /// The audit's verdict.
    pub verdict: Verdict,
    /// Audited time: first to last robot sample (s).
    pub duration_s: f64,
    /// Of it, the time not checked (s): the union of the inconclusive spans
    /// (`metrics.inconclusive_duration`). No violation found there means nothing.
    pub not_checked_s: f64,
    /// Length of the union of the violation intervals (s).
    pub violation_time_s: f64,
    /// Violating robot samples / robot samples.
    pub violation_fraction: f64,
}

/// A run among the worst: most violation time, then the highest violation fraction.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct WorstRun {
    /// The log.
    pub log: String,
    /// Robot.
    pub robot: String,
    /// Scene.
    pub scene: String,
    /// Day.
    pub day: String,
    /// Verdict.
    pub verdict: Verdict,
    /// Violation time (s).
    pub violation_time_s: f64,
    /// Violation fraction.
    pub violation_fraction: f64,
}

/// Verdict counts and times of a set of runs.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Counts {
    /// Logs.
    pub runs: usize,
    /// Logs that pass.
    pub pass: usize,
    /// Logs that fail.
    pub fail: usize,
    /// Logs that are inconclusive.
    pub inconclusive: usize,
    /// Audited time (s), summed in log order.
    pub duration_s: f64,
    /// Of it, time not checked (s), summed in log order.
    pub not_checked_s: f64,
    /// Violation time (s), summed in log order.
    pub violation_time_s: f64,
}

impl Counts {
    fn add(&mut self, r: &FleetRun) {
        self.runs += 1;
        match r.verdict {
            Verdict::Pass => self.pass += 1,
            Verdict::Fail => self.fail += 1,
            Verdict::Inconclusive => self.inconclusive += 1,
        }
        self.duration_s += r.duration_s;
        self.not_checked_s += r.not_checked_s;
        self.violation_time_s += r.violation_time_s;
    }
}

/// One (robot, scene, day) group.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Group {
    /// Robot.
    pub robot: String,
    /// Scene.
    pub scene: String,
    /// Day.
    pub day: String,
    /// Its counts.
    #[serde(flatten)]
    pub counts: Counts,
    /// Its worst runs (at most [`WORST_PER_GROUP`], only runs with violations).
    pub worst: Vec<WorstRun>,
}

/// The fleet report (report.json `fleet`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Fleet {
    /// All runs together.
    pub total: Counts,
    /// Groups sorted by (robot, scene, day).
    pub groups: Vec<Group>,
    /// The fleet's worst runs (at most [`WORST_OVERALL`], only runs with violations).
    pub worst: Vec<WorstRun>,
    /// Every run's place and figures, in log order.
    pub runs: Vec<FleetRun>,
}

fn meta_text(meta: &serde_json::Map<String, Value>, key: &str) -> Option<String> {
    match meta.get(key)? {
        Value::String(s) if !s.is_empty() => Some(s.clone()),
        Value::String(_) | Value::Null => None,
        other => Some(other.to_string()),
    }
}

/// Days since 1970-01-01 of a proleptic Gregorian date (Hinnant's `days_from_civil`), None if
/// the date does not exist.
fn days_from_civil(y: i64, m: i64, d: i64) -> Option<i64> {
    let leap = (y % 4 == 0 && y % 100 != 0) || y % 400 == 0;
    let month_days = [
        31,
        if leap { 29 } else { 28 },
        31,
        30,
        31,
        30,
        31,
        31,
        30,
        31,
        30,
        31,
    ];
    if !(1..=12).contains(&m) || d < 1 || d > month_days[(m - 1) as usize] {
        return None;
    }
    let y = if m <= 2 { y - 1 } else { y };
    let era = y.div_euclid(400);
    let yoe = y - era * 400;
    let mp = (m + 9) % 12;
    let doy = (153 * mp + 2) / 5 + d - 1;
    let doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    Some(era * 146_097 + doe - 719_468)
}

/// `n` ASCII digits at `s[at..]` as a number.
fn digits(s: &[u8], at: usize, n: usize) -> Option<i64> {
    let part = s.get(at..at + n)?;
    part.iter().try_fold(0i64, |acc, &c| {
        c.is_ascii_digit().then(|| acc * 10 + i64::from(c - b'0'))
    })
}

/// `YYYY-MM-DD` at the start of `s`: (year, month, day, days since 1970-01-01).
fn civil_date(s: &[u8]) -> Option<(i64, i64, i64, i64)> {
    if s.get(4) != Some(&b'-') || s.get(7) != Some(&b'-') {
        return None;
    }
    let (y, m, d) = (digits(s, 0, 4)?, digits(s, 5, 2)?, digits(s, 8, 2)?);
    Some((y, m, d, days_from_civil(y, m, d)?))
}

/// The UTC date of Unix seconds.
fn day_of_unix(secs: f64) -> Option<String> {
    if !(0.0..=253_402_300_799.0).contains(&secs) {
        return None; // before 1970 or after 9999-12-31
    }
    Some(crate::utc(secs.floor() as u64)[..10].to_string())
}

/// The UTC date of an RFC 3339 time: `YYYY-MM-DDTHH:MM:SS[.frac](Z|±HH:MM)` (`t`/`z` and a space
/// for `T` accepted).
fn day_of_rfc3339(s: &str) -> Option<String> {
    let b = s.as_bytes();
    let (_, _, _, days) = civil_date(b)?;
    if !matches!(b.get(10), Some(b'T' | b't' | b' ')) || b.get(13) != Some(&b':') {
        return None;
    }
    let (hh, mm) = (digits(b, 11, 2)?, digits(b, 14, 2)?);
    if b.get(16) != Some(&b':') {
        return None;
    }
    let ss = digits(b, 17, 2)?;
    if hh > 23 || mm > 59 || ss > 60 {
        return None;
    }
    let mut i = 19;
    if b.get(i) == Some(&b'.') {
        i += 1;
        let start = i;
        while b.get(i).is_some_and(u8::is_ascii_digit) {
            i += 1;
        }
        if i == start {
            return None;
        }
    }
    let offset_min = match b.get(i)? {
        b'Z' | b'z' if i + 1 == b.len() => 0,
        &sign @ (b'+' | b'-') if i + 6 == b.len() && b[i + 3] == b':' => {
            let (oh, om) = (digits(b, i + 1, 2)?, digits(b, i + 4, 2)?);
            if oh > 23 || om > 59 {
                return None;
            }
            let o = oh * 60 + om;
            if sign == b'+' { o } else { -o }
        }
        _ => return None,
    };
    let secs = days * 86_400 + hh * 3600 + mm * 60 + ss.min(59) - offset_min * 60;
    day_of_unix(secs as f64)
}

/// The day of a run and where it comes from (module docs), with the log file's modification
/// time (Unix seconds) as the last resort.
pub fn day(run: &RunResult, mtime: Option<u64>) -> (String, String) {
    let invalid = |key: &str, v: &Value, what: &str| {
        (
            "invalid".to_string(),
            format!("meta.{key} is not {what}: {v}"),
        )
    };
    if let Some(v) = run.meta.get("date").filter(|v| !v.is_null()) {
        let ok = v
            .as_str()
            .filter(|s| s.len() == 10)
            .and_then(|s| civil_date(s.as_bytes()).map(|_| s.to_string()));
        return match ok {
            Some(d) => (d, "meta.date".into()),
            None => invalid("date", v, "a date YYYY-MM-DD"),
        };
    }
    if let Some(v) = run.meta.get("start_time").filter(|v| !v.is_null()) {
        let d = match v {
            Value::Number(n) => n.as_f64().and_then(day_of_unix),
            Value::String(s) => day_of_rfc3339(s),
            _ => None,
        };
        return match d {
            Some(d) => (d, "meta.start_time".into()),
            None => invalid(
                "start_time",
                v,
                "Unix seconds or an RFC 3339 time (2026-11-28T09:30:00Z)",
            ),
        };
    }
    // A ROS recording's first message time: MCAP's, or a sqlite3 bag's (one reader sets one).
    for key in ["mcap_time_base_s", "db3_time_base_s"] {
        if let Some(b) = run
            .meta
            .get(key)
            .and_then(Value::as_f64)
            .filter(|&b| b >= WALL_CLOCK_FROM)
            && let Some(d) = day_of_unix(b)
        {
            return (d, format!("meta.{key}"));
        }
    }
    match mtime.and_then(|s| day_of_unix(s as f64)) {
        Some(d) => (d, "file_mtime".into()),
        None => ("unknown".into(), "no date in meta, no file mtime".into()),
    }
}

/// Length of the union of a run's violation intervals (s), summed in start order.
pub fn violation_time(run: &RunResult) -> f64 {
    let mut iv: Vec<(f64, f64)> = run
        .violations
        .iter()
        .map(|v| (v.t_start, v.t_end.max(v.t_start)))
        .collect();
    iv.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let mut total = 0.0;
    let mut open: Option<(f64, f64)> = None;
    for (s, e) in iv {
        open = match open {
            Some((os, oe)) if s <= oe => Some((os, oe.max(e))),
            Some((os, oe)) => {
                total += oe - os;
                Some((s, e))
            }
            None => Some((s, e)),
        };
    }
    if let Some((os, oe)) = open {
        total += oe - os;
    }
    total
}

/// A run's place in the fleet and its figures; `mtime` is its log file's modification time.
pub fn place(run: &RunResult, mtime: Option<u64>) -> FleetRun {
    let (day, day_source) = day(run, mtime);
    FleetRun {
        log: run.log.clone(),
        robot: meta_text(&run.meta, "robot_id")
            .or_else(|| meta_text(&run.meta, "robot"))
            .unwrap_or_else(|| run.models.robot.clone()),
        scene: meta_text(&run.meta, "task")
            .or_else(|| meta_text(&run.meta, "scene"))
            .unwrap_or_else(|| "-".into()),
        day,
        day_source,
        verdict: run.verdict,
        duration_s: run.metrics.duration,
        not_checked_s: run.metrics.inconclusive_duration,
        violation_time_s: violation_time(run),
        violation_fraction: run.metrics.violation_fraction,
    }
}

/// The worst of `runs`: those with violations, by violation time, then fraction (both
/// descending), then log name and position; at most `n`.
fn worst<'a>(runs: impl Iterator<Item = (usize, &'a FleetRun)>, n: usize) -> Vec<WorstRun> {
    let mut bad: Vec<(usize, &FleetRun)> = runs
        .filter(|(_, r)| r.violation_time_s > 0.0 || r.violation_fraction > 0.0)
        .collect();
    bad.sort_by(|(ia, a), (ib, b)| {
        b.violation_time_s
            .total_cmp(&a.violation_time_s)
            .then(b.violation_fraction.total_cmp(&a.violation_fraction))
            .then_with(|| a.log.cmp(&b.log))
            .then(ia.cmp(ib))
    });
    bad.into_iter()
        .take(n)
        .map(|(_, r)| WorstRun {
            log: r.log.clone(),
            robot: r.robot.clone(),
            scene: r.scene.clone(),
            day: r.day.clone(),
            verdict: r.verdict,
            violation_time_s: r.violation_time_s,
            violation_fraction: r.violation_fraction,
        })
        .collect()
}

/// The fleet report of `runs` (in log order) whose log files were last modified at `mtimes`
/// (Unix seconds; same length as `runs`, None where unknown).
pub fn fleet(runs: &[RunResult], mtimes: &[Option<u64>]) -> Fleet {
    let placed: Vec<FleetRun> = runs
        .iter()
        .enumerate()
        .map(|(i, r)| place(r, mtimes.get(i).copied().flatten()))
        .collect();
    // Members of each (robot, scene, day), in log order; keys sorted.
    let mut members: std::collections::BTreeMap<(&str, &str, &str), Vec<usize>> =
        std::collections::BTreeMap::new();
    for (i, r) in placed.iter().enumerate() {
        members
            .entry((r.robot.as_str(), r.scene.as_str(), r.day.as_str()))
            .or_default()
            .push(i);
    }
    let groups = members
        .into_iter()
        .map(|(k, idx)| {
            let mut counts = Counts::default();
            idx.iter().for_each(|&i| counts.add(&placed[i]));
            Group {
                robot: k.0.to_string(),
                scene: k.1.to_string(),
                day: k.2.to_string(),
                counts,
                worst: worst(idx.iter().map(|&i| (i, &placed[i])), WORST_PER_GROUP),
            }
        })
        .collect();
    let mut total = Counts::default();
    placed.iter().for_each(|r| total.add(r));
    Fleet {
        total,
        groups,
        worst: worst(placed.iter().enumerate(), WORST_OVERALL),
        runs: placed,
    }
}

/// The fleet report of a report's input: the logs' modification times read now.
pub fn of_input(input: &crate::ReportInput) -> Fleet {
    let mtimes: Vec<Option<u64>> = input
        .logs
        .iter()
        .map(|f| modified(Path::new(&f.path)))
        .collect();
    fleet(input.runs, &mtimes)
}

/// The fleet table's column heads (HTML and Markdown).
pub const COLUMNS: [&str; 11] = [
    "robot",
    "scene",
    "day (UTC)",
    "logs",
    "pass",
    "fail",
    "inconclusive",
    "audited (s)",
    "not checked (s)",
    "violation time (s)",
    "worst runs (violation time s)",
];

/// A group as table cells ([`COLUMNS`]), text unescaped.
pub fn cells(g: &Group) -> [String; 11] {
    let worst = if g.worst.is_empty() {
        "-".to_string()
    } else {
        g.worst
            .iter()
            .map(|w| format!("{} ({:.3})", w.log, w.violation_time_s))
            .collect::<Vec<_>>()
            .join("; ")
    };
    [
        g.robot.clone(),
        g.scene.clone(),
        g.day.clone(),
        g.counts.runs.to_string(),
        g.counts.pass.to_string(),
        g.counts.fail.to_string(),
        g.counts.inconclusive.to_string(),
        format!("{:.3}", g.counts.duration_s),
        format!("{:.3}", g.counts.not_checked_s),
        format!("{:.3}", g.counts.violation_time_s),
        worst,
    ]
}

/// Where the days came from, e.g. `meta.date: 3, file_mtime: 2` (sources in first-seen order).
pub fn day_sources(f: &Fleet) -> String {
    let mut seen: Vec<(&str, usize)> = Vec::new();
    for r in &f.runs {
        match seen.iter_mut().find(|(s, _)| *s == r.day_source) {
            Some((_, n)) => *n += 1,
            None => seen.push((&r.day_source, 1)),
        }
    }
    seen.iter()
        .map(|(s, n)| format!("{s}: {n}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The fleet section of report.md.
pub fn markdown(f: &Fleet) -> String {
    let mut s = format!(
        "\n## Fleet (per robot, scene and day)\n\n| {} |\n|{}\n",
        COLUMNS.join(" | "),
        "---|".repeat(COLUMNS.len())
    );
    for g in &f.groups {
        let c = cells(g).map(|c| crate::markdown::md_cell(&c));
        s.push_str(&format!("| {} |\n", c.join(" | ")));
    }
    s.push_str(&format!(
        "\nAll {} logs: {} pass, {} fail, {} inconclusive; {:.3} s audited, of which {:.3} s not checked (inconclusive: no violation found there means nothing), {:.3} s in violation. Days from {}. Violation time: the length of the union of a log's violation intervals.\n",
        f.total.runs,
        f.total.pass,
        f.total.fail,
        f.total.inconclusive,
        f.total.duration_s,
        f.total.not_checked_s,
        f.total.violation_time_s,
        day_sources(f)
    ));
    s
}

/// The fleet section of report.html; `esc` escapes text for HTML.
pub fn html(f: &Fleet, esc: impl Fn(&str) -> String) -> String {
    let mut s = String::from("<h2>Fleet (per robot, scene and day)</h2><table><tr>");
    for (i, c) in COLUMNS.iter().enumerate() {
        let class = if (3..10).contains(&i) {
            " class=\"num\""
        } else {
            ""
        };
        s.push_str(&format!("<th{class}>{}</th>", esc(c)));
    }
    s.push_str("</tr>");
    for g in &f.groups {
        s.push_str("<tr>");
        for (i, c) in cells(g).iter().enumerate() {
            let class = if (3..10).contains(&i) {
                " class=\"num\""
            } else {
                ""
            };
            s.push_str(&format!("<td{class}>{}</td>", esc(c)));
        }
        s.push_str("</tr>");
    }
    s.push_str(&format!(
        "</table><p class=\"note\">All {} logs: {} pass, {} fail, {} inconclusive; {:.3} s audited, of which {:.3} s not checked (inconclusive: no violation found there means nothing), {:.3} s in violation. Days from {}. Violation time: the length of the union of a log's violation intervals.</p>",
        f.total.runs,
        f.total.pass,
        f.total.fail,
        f.total.inconclusive,
        f.total.duration_s,
        f.total.not_checked_s,
        f.total.violation_time_s,
        esc(&day_sources(f))
    ));
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn civil_days_match_known_dates() {
        assert_eq!(days_from_civil(1970, 1, 1), Some(0));
        assert_eq!(days_from_civil(2000, 3, 1), Some(11_017));
        assert_eq!(days_from_civil(2026, 11, 28), Some(20_785));
        assert_eq!(days_from_civil(2024, 2, 29), Some(19_782));
        assert_eq!(days_from_civil(2023, 2, 29), None);
        assert_eq!(days_from_civil(2026, 13, 1), None);
        assert_eq!(days_from_civil(2026, 4, 31), None);
    }

    #[test]
    fn rfc3339_times_give_their_utc_date() {
        assert_eq!(
            day_of_rfc3339("2026-11-28T09:30:00Z").as_deref(),
            Some("2026-11-28")
        );
        // 23:30 at UTC-05:00 is 04:30 the next day in UTC.
        assert_eq!(
            day_of_rfc3339("2026-11-28T23:30:00.125-05:00").as_deref(),
            Some("2026-11-29")
        );
        // 00:30 at UTC+02:00 is the day before in UTC.
        assert_eq!(
            day_of_rfc3339("2026-01-01 00:30:00+02:00").as_deref(),
            Some("2025-12-31")
        );
        for bad in [
            "2026-11-28",
            "2026-11-28T09:30Z",
            "2026-11-28T25:00:00Z",
            "2026-02-30T00:00:00Z",
            "2026-11-28T09:30:00",
            "2026-11-28T09:30:00.Z",
            "2026-11-28T09:30:00+0100",
        ] {
            assert_eq!(day_of_rfc3339(bad), None, "{bad}");
        }
    }

    #[test]
    fn unix_seconds_give_their_utc_date() {
        assert_eq!(day_of_unix(0.0).as_deref(), Some("1970-01-01"));
        assert_eq!(day_of_unix(1_795_824_000.0).as_deref(), Some("2026-11-28"));
        assert_eq!(day_of_unix(1_795_910_399.9).as_deref(), Some("2026-11-28"));
        assert_eq!(day_of_unix(-1.0), None);
        assert_eq!(day_of_unix(f64::NAN), None);
    }
}
