//! Fuzz the ROS 2 sqlite3 bag reader (SQLite through rusqlite, the shared CDR conversion) and the
//! audit behind it: any bytes as a `.db3` file must give a result or a typed error, never a panic,
//! an abort or a hang; and a `pass` only for input that was read completely. SQLite opens files
//! by path, so each input is written to a file of this process first.
#![no_main]

use libfuzzer_sys::fuzz_target;
use pacs_audit::{AuditConfig, Verdict, audit_reader};
use pacs_log::db3::Db3Reader;

fuzz_target!(|data: &[u8]| {
    let path = std::env::temp_dir().join(format!("pacs-fuzz-{}.db3", std::process::id()));
    if std::fs::write(&path, data).is_err() {
        return;
    }
    let cfg = AuditConfig::default();
    // The header is given (a bag's own is in its metadata), so that inputs reach the messages.
    let header = pacs_log::mcap::parse_header_json(
        r#"{"type":"header","format":"pacs-log","version":1,"robot":"fr3","human":"default","constraints":"ssm"}"#,
    )
    .expect("a valid header");
    let Ok(mut r) = Db3Reader::open(&path, &cfg.mcap, &cfg.overrides(), Some(header)) else {
        return;
    };
    if let Ok(run) = audit_reader(&mut r, &cfg) {
        if run.verdict == Verdict::Pass {
            assert!(run.metrics.samples >= 2);
            assert!(run.inconclusive.is_empty());
        }
    }
});
