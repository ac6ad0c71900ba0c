//! Fuzz the MCAP reader (and its CDR decoder) and the audit behind it: any input must give a
//! result or a typed error, never a panic, an abort or a huge allocation; and a `pass` only for
//! input that was read completely.
#![no_main]

use libfuzzer_sys::fuzz_target;
use pacs_audit::{AuditConfig, Verdict, audit_reader};
use pacs_log::mcap::McapReader;

fuzz_target!(|data: &[u8]| {
    let cfg = AuditConfig::default();
    let Ok(mut r) = McapReader::new(
        "fuzz.mcap",
        std::io::Cursor::new(data),
        &cfg.mcap,
        &cfg.overrides(),
        None,
    ) else {
        return;
    };
    if let Ok(run) = audit_reader(&mut r, &cfg) {
        if run.verdict == Verdict::Pass {
            assert!(run.metrics.samples >= 2);
            assert!(run.inconclusive.is_empty());
            // Evidence: a pass covers time and never comes from a log cut short.
            assert!(run.evidence.t_end > run.evidence.t_start);
            assert_ne!(run.evidence.completeness, pacs_audit::Completeness::Incomplete);
        }
    }
});
