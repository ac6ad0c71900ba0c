//! Fuzz the CSV reader and the audit behind it: a result or a typed error, never a panic; `pass`
//! only with at least two robot samples and no inconclusive span.
#![no_main]

use libfuzzer_sys::fuzz_target;
use pacs_audit::{AuditConfig, Verdict, audit_reader};
use pacs_log::csv::CsvReader;

fuzz_target!(|data: &[u8]| {
    let Ok(mut r) = CsvReader::new("fuzz.csv", std::io::Cursor::new(data)) else {
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
