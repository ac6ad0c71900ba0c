//! `pacs bench audit LOG...`: where the audit's time goes on your own logs, on one thread —
//! reading the records alone, the whole audit, and (for JSON Lines) a JSON syntax check of the
//! same lines by serde_json as a reference for what one JSON pass over the bytes costs.

use super::CliError;
use pacs_audit::{AuditConfig, Verdict};
use pacs_log::{Header, LogError, Record};
use serde_json::{Value, json};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// One stage's times over the runs (s), in run order.
struct Stage {
    name: &'static str,
    what: &'static str,
    times: Vec<f64>,
}

/// Run `pacs bench audit --runs N LOG...` (see `pacs bench audit --help`).
pub fn audit(
    logs: &[PathBuf],
    header: Option<&Path>,
    runs: usize,
    progress: bool,
) -> Result<Value, CliError> {
    if runs == 0 {
        return Err(CliError::Input("--runs must be at least 1".into()));
    }
    if logs.is_empty() {
        return Err(CliError::Input("give at least one log".into()));
    }
    let cfg = AuditConfig::default();
    let header = header
        .map(|p| {
            pacs_log::mcap::load_header_file(p)
                .map_err(|e| CliError::Input(format!("--header {}: {e}", p.display())))
        })
        .transpose()?;
    let header = header.as_ref();
    let mut bytes = 0u64;
    for p in logs {
        bytes += log_bytes(p)?;
    }
    // JSON Lines logs only (by extension, as `pacs audit` tells the forms apart).
    let jsonl = logs
        .iter()
        .all(|p| p.extension().is_some_and(|e| e == "jsonl"));
    let mut read = Stage {
        name: "read",
        what: "every record read and checked for form by the audit's reader; nothing checked against the rule",
        times: Vec::with_capacity(runs),
    };
    let mut syntax = Stage {
        name: "json_syntax",
        what: "serde_json's syntax check of every line (IgnoredAny: numbers' grammar checked, none converted, no record built): a reference, not pacs's work",
        times: Vec::with_capacity(runs),
    };
    let mut whole = Stage {
        name: "audit",
        what: "the whole audit of each log, as `pacs audit` on one thread",
        times: Vec::with_capacity(runs),
    };
    let mut samples = 0u64;
    let mut verdicts = [0u64; 3];
    for run in 0..runs {
        if progress {
            eprintln!("pacs bench audit: run {} of {runs} ...", run + 1);
        }
        let t = Instant::now();
        let mut n = 0u64;
        for p in logs {
            n += read_all(p, &cfg, header).map_err(|e| CliError::Input(e.to_string()))?;
        }
        read.times.push(t.elapsed().as_secs_f64());
        samples = n;
        if jsonl {
            let t = Instant::now();
            for p in logs {
                json_syntax(p)?;
            }
            syntax.times.push(t.elapsed().as_secs_f64());
        }
        let t = Instant::now();
        verdicts = [0; 3];
        for p in logs {
            let r = pacs_audit::audit_file_with_header(p, &cfg, header)
                .map_err(|e| CliError::Input(e.to_string()))?;
            verdicts[match r.verdict {
                Verdict::Pass => 0,
                Verdict::Fail => 1,
                Verdict::Inconclusive => 2,
            }] += 1;
        }
        whole.times.push(t.elapsed().as_secs_f64());
    }
    let stages: Vec<&Stage> = [&read, &syntax, &whole]
        .into_iter()
        .filter(|s| !s.times.is_empty())
        .collect();
    let figures: Vec<Value> = stages
        .iter()
        .map(|s| {
            let (min, median, max) = spread(&s.times);
            json!({
                "stage": s.name,
                "what": s.what,
                "ms_min": min * 1e3,
                "ms_median": median * 1e3,
                "ms_max": max * 1e3,
                "robot_samples_per_s_median": samples as f64 / median,
                "mb_per_s_median": bytes as f64 / median / 1e6,
            })
        })
        .collect();
    let (_, read_median, _) = spread(&read.times);
    let (_, audit_median, _) = spread(&whole.times);
    let mut out = json!({
        "logs": logs.len(),
        "bytes": bytes,
        "robot_samples": samples,
        "runs": runs,
        "threads": 1,
        "stages": figures,
        "checker_ms_median": ((audit_median - read_median) * 1e3).max(0.0),
        "verdicts": {"pass": verdicts[0], "fail": verdicts[1], "inconclusive": verdicts[2]},
    });
    if !jsonl {
        out["json_syntax"] = json!("not measured: not every log is JSON Lines (.jsonl)");
    }
    Ok(out)
}

/// Smallest, median (the upper of the two middle ones) and largest of `times`.
fn spread(times: &[f64]) -> (f64, f64, f64) {
    let mut t = times.to_vec();
    t.sort_by(f64::total_cmp);
    (t[0], t[t.len() / 2], t[t.len() - 1])
}

/// The log's size in bytes (a bag directory: its files').
fn log_bytes(p: &Path) -> Result<u64, CliError> {
    let meta = |p: &Path| {
        std::fs::metadata(p).map_err(|e| CliError::Input(format!("{}: {e}", p.display())))
    };
    if !p.is_dir() {
        return Ok(meta(p)?.len());
    }
    let mut n = 0;
    for entry in
        std::fs::read_dir(p).map_err(|e| CliError::Input(format!("{}: {e}", p.display())))?
    {
        let entry = entry.map_err(|e| CliError::Input(format!("{}: {e}", p.display())))?;
        if entry.path().is_file() {
            n += meta(&entry.path())?.len();
        }
    }
    Ok(n)
}

/// Read every record of the log as the audit's reader gives them; the number of robot samples.
fn read_all(p: &Path, cfg: &AuditConfig, header: Option<&Header>) -> Result<u64, LogError> {
    pacs_log::read_log(
        p,
        &cfg.mcap,
        &cfg.overrides(),
        header,
        |reader| {
            let mut n = 0;
            while let Some(r) = reader.next_record()? {
                n += u64::from(matches!(r, Record::Robot { .. }));
            }
            Ok(n)
        },
        |e| matches!(e, LogError::RowsNotInTimeOrder { .. }),
    )
}

/// Check every non-empty line of a JSON Lines file with serde_json, converting nothing. The
/// file is read as the audit's reader reads it (a 64 KiB buffer; each line copied into one
/// reused buffer), so that neither stage pays for holding a whole file in memory.
fn json_syntax(p: &Path) -> Result<(), CliError> {
    use std::io::BufRead;
    let fail = |what: String| CliError::Input(format!("{}: {what}", p.display()));
    let file = std::fs::File::open(p).map_err(|e| fail(e.to_string()))?;
    let mut input = std::io::BufReader::with_capacity(1 << 16, file);
    let mut line = Vec::new();
    let mut number = 0u64;
    loop {
        line.clear();
        if input
            .read_until(b'\n', &mut line)
            .map_err(|e| fail(e.to_string()))?
            == 0
        {
            return Ok(());
        }
        number += 1;
        if line.iter().all(u8::is_ascii_whitespace) {
            continue;
        }
        serde_json::from_slice::<serde::de::IgnoredAny>(&line)
            .map_err(|e| fail(format!("line {number}: {e}")))?;
    }
}
