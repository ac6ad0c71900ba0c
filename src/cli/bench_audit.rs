//! `pacs bench audit LOG...`: where the audit's time goes on your own logs — reading the records
//! alone, the whole audit, and (for JSON Lines) a JSON syntax check of the same lines by
//! serde_json as a reference for what one JSON pass over the bytes costs.

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

/// Run `pacs bench audit --runs N [--header FILE] LOG...` (see `pacs bench audit --help`).
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
    let input = |e: LogError| CliError::Input(e.to_string());
    let mut bytes = 0u64;
    let mut jsonl = true;
    for p in logs {
        bytes += log_bytes(p)?;
        // As the audit tells the forms apart (`pacs_log::open_log`).
        jsonl &= pacs_log::is_jsonl(p).map_err(input)?;
    }
    let mut read = Stage {
        name: "read",
        what: "every record read by the audit's reader (its form checked, the numbers the audit uses converted); nothing checked against the rule",
        times: Vec::with_capacity(runs),
    };
    let mut syntax = Stage {
        name: "json_syntax",
        what: "serde_json's syntax check of every line (IgnoredAny: numbers' grammar checked, none converted, no record built): a reference, not pacs's work",
        times: Vec::with_capacity(runs),
    };
    let mut whole = Stage {
        name: "audit",
        what: "the whole audit of each log, as `pacs audit` does it on one thread",
        times: Vec::with_capacity(runs),
    };
    let mut samples = 0u64;
    let mut json_lines = 0u64;
    let mut verdicts = [0u64; 3];
    // The syntax stage's line buffer, kept across files and runs.
    let mut buf = Vec::new();
    for run in 0..runs {
        if progress {
            eprintln!("pacs bench audit: run {} of {runs} ...", run + 1);
        }
        let t = Instant::now();
        let mut n = 0u64;
        for p in logs {
            n += read_all(p, &cfg, header).map_err(input)?;
        }
        read.times.push(t.elapsed().as_secs_f64());
        samples = n;
        if jsonl {
            let t = Instant::now();
            let mut lines = 0u64;
            for p in logs {
                lines += json_syntax(p, &mut buf)?;
            }
            syntax.times.push(t.elapsed().as_secs_f64());
            json_lines = lines;
        }
        let t = Instant::now();
        verdicts = [0; 3];
        for p in logs {
            let r = pacs_audit::audit_file_with_header(p, &cfg, header).map_err(input)?;
            verdicts[match r.verdict {
                Verdict::Pass => 0,
                Verdict::Fail => 1,
                Verdict::Inconclusive => 2,
            }] += 1;
        }
        whole.times.push(t.elapsed().as_secs_f64());
    }
    let figures: Vec<Value> = [&read, &syntax, &whole]
        .into_iter()
        .filter(|s| !s.times.is_empty())
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
        "stages": figures,
        "checker_ms_median": ((audit_median - read_median) * 1e3).max(0.0),
        "verdicts": {"pass": verdicts[0], "fail": verdicts[1], "inconclusive": verdicts[2]},
    });
    if jsonl {
        out["json_lines"] = json!(json_lines);
    } else {
        out["json_syntax"] = json!("not measured: not every log is JSON Lines");
    }
    Ok(out)
}

/// Smallest, median (for an even count the upper of the two middle ones) and largest of
/// `times` (not empty).
fn spread(times: &[f64]) -> (f64, f64, f64) {
    let mut t = times.to_vec();
    t.sort_by(f64::total_cmp);
    (t[0], t[t.len() / 2], t[t.len() - 1])
}

/// The log's size in bytes (a bag directory: its files').
fn log_bytes(p: &Path) -> Result<u64, CliError> {
    let fail = |e: std::io::Error| CliError::Input(format!("{}: {e}", p.display()));
    if !p.is_dir() {
        return Ok(std::fs::metadata(p).map_err(fail)?.len());
    }
    let mut n = 0;
    for entry in std::fs::read_dir(p).map_err(fail)? {
        let meta = entry.and_then(|e| e.metadata()).map_err(fail)?;
        if meta.is_file() {
            n += meta.len();
        }
    }
    Ok(n)
}

/// Read every record of the log as the audit's reader gives them; the number of robot samples.
fn read_all(p: &Path, cfg: &AuditConfig, header: Option<&Header>) -> Result<u64, LogError> {
    pacs_audit::read_file(p, cfg, header, |reader| {
        let mut n = 0;
        while let Some(r) = reader.next_record()? {
            n += u64::from(matches!(r, Record::Robot { .. }));
        }
        Ok(n)
    })
}

/// Check every line of a JSON Lines file with serde_json, converting nothing; the number of
/// lines checked. Blank lines (only whitespace) are skipped, as the audit's reader skips them.
/// The file is read through a 64 KiB buffer, as the reader reads it, each line copied into
/// `line` (reused) and checked there while it is in the cache (faster than reading a whole file
/// into memory first: docs/performance-audit.md, "A floor").
fn json_syntax(p: &Path, line: &mut Vec<u8>) -> Result<u64, CliError> {
    use std::io::BufRead;
    let fail = |what: String| CliError::Input(format!("{}: {what}", p.display()));
    let file = std::fs::File::open(p).map_err(|e| fail(e.to_string()))?;
    let mut input = std::io::BufReader::with_capacity(1 << 16, file);
    let (mut number, mut checked) = (0u64, 0u64);
    loop {
        line.clear();
        if input
            .read_until(b'\n', line)
            .map_err(|e| fail(e.to_string()))?
            == 0
        {
            return Ok(checked);
        }
        number += 1;
        if std::str::from_utf8(line).is_ok_and(|s| s.trim().is_empty()) {
            continue;
        }
        serde_json::from_slice::<serde::de::IgnoredAny>(line).map_err(|e| {
            let msg = e.to_string().replace(" at line 1 column ", " at column ");
            fail(format!("line {number}: {msg}"))
        })?;
        checked += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Lines with CRLF ends are checked; lines of only whitespace (Unicode's, as the reader's
    /// `trim`: a vertical tab, a no-break space) are skipped; a bad line is named by its number.
    #[test]
    fn the_syntax_stage_checks_what_the_reader_reads() {
        let dir = std::env::temp_dir().join(format!("pacs-bench-audit-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let good = dir.join("good.jsonl");
        std::fs::write(
            &good,
            "{\"a\": [1, 2.5e-3]}\r\n\r\n \u{b}\n\u{a0}\n{\"b\": {\"c\": \"d\"}}\n{}",
        )
        .unwrap();
        let mut buf = Vec::new();
        assert_eq!(json_syntax(&good, &mut buf).unwrap(), 3);
        let bad = dir.join("bad.jsonl");
        std::fs::write(&bad, "{\"a\": 1}\n\n{\"a\": 1,}\n").unwrap();
        let err = json_syntax(&bad, &mut buf).unwrap_err();
        let msg = err.message();
        assert!(
            msg.contains("bad.jsonl: line 3: ") && msg.contains("at column"),
            "{msg}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn the_median_of_an_even_count_is_the_upper_middle() {
        assert_eq!(spread(&[4.0, 1.0, 3.0, 2.0]), (1.0, 3.0, 4.0));
        assert_eq!(spread(&[2.0]), (2.0, 2.0, 2.0));
    }
}
