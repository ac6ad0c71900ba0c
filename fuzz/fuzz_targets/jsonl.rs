//! Fuzz the JSON Lines reader and the audit behind it: any input must give a result or a typed
//! error, never a panic; and a `pass` only for input that parsed completely. Every line the
//! reader's fast scanner takes must read as serde_json reads it (`fast_path_agrees`).
#![no_main]

use libfuzzer_sys::fuzz_target;
use pacs_audit::{AuditConfig, Verdict, audit_reader};
use pacs_log::jsonl::JsonlReader;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        for line in text.split_inclusive('\n') {
            assert!(pacs_log::jsonl::fast_path_agrees(line), "{line:?}");
        }
    }
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
