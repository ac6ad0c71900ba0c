//! Fuzz the JSON Lines reader and the audit behind it: any input must give a result or a typed
//! error, never a panic; and a `pass` only for input that parsed completely. Every line the
//! reader's fast scanner takes must read as serde_json reads it (`fast_path_agrees`), and the
//! reader must give the same records, lines and errors whatever the size of its input's buffer
//! (lines read in place or copied out).
#![no_main]

use libfuzzer_sys::fuzz_target;
use pacs_audit::{AuditConfig, Verdict, audit_reader};
use pacs_log::RecordReader;
use pacs_log::jsonl::JsonlReader;

/// Every record's `Debug` text with its line, then the error (at most 10,000 entries).
fn records(data: &[u8], capacity: usize) -> Vec<String> {
    let mut out = Vec::new();
    match JsonlReader::new("fuzz.jsonl", std::io::BufReader::with_capacity(capacity, data)) {
        Err(e) => out.push(format!("header error: {e}")),
        Ok(mut r) => {
            while out.len() < 10_000 {
                match r.next_record() {
                    Ok(Some(rec)) => {
                        let rec = format!("{rec:?}");
                        out.push(format!("{rec} at {:?}", r.location()));
                    }
                    Ok(None) => break,
                    Err(e) => {
                        out.push(format!("error: {e}"));
                        break;
                    }
                }
            }
        }
    }
    out
}

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        for line in text.split_inclusive('\n') {
            assert!(pacs_log::jsonl::fast_path_agrees(line), "{line:?}");
        }
    }
    assert_eq!(records(data, 1 << 16), records(data, 1 + data.len() % 37));
    let Ok(mut r) = JsonlReader::new("fuzz.jsonl", std::io::Cursor::new(data)) else {
        return;
    };
    if let Ok(run) = audit_reader(&mut r, &AuditConfig::default()) {
        if run.verdict == Verdict::Pass {
            assert!(run.metrics.samples >= 2);
            assert!(run.inconclusive.is_empty());
            // Evidence: a pass covers time and never comes from a log cut short.
            assert!(run.evidence.t_end > run.evidence.t_start);
            assert_ne!(run.evidence.completeness, pacs_audit::Completeness::Incomplete);
        }
    }
});
