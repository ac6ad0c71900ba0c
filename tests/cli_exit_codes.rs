//! Every exit code `pacs` documents (docs/cli.md, docs/audit.md) is what it returns: 0 success
//! (audit: pass), 1 audit fail, 2 audit inconclusive, 3 invalid input, 74 an output that cannot
//! be written (the message names the path); never a panic.

use std::process::{Command, Output};

fn pacs(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pacs"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("run pacs")
}

fn code(o: &Output) -> i32 {
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("panicked"), "{err}");
    o.status.code().expect("exit code")
}

/// A path no one can create: below a character device.
const UNWRITABLE: &str = "/dev/null/pacs-out";

#[test]
fn audit_exit_codes() {
    assert_eq!(
        code(&pacs(&["audit", "examples/logs/clean_sorting.jsonl"])),
        0
    );
    assert_eq!(
        code(&pacs(&["audit", "examples/logs/close_sorting.jsonl"])),
        1
    );
    assert_eq!(code(&pacs(&["audit", "no/such/log.jsonl"])), 3);
    let o = pacs(&[
        "audit",
        "examples/logs/clean_sorting.jsonl",
        "--out",
        UNWRITABLE,
    ]);
    assert_eq!(code(&o), 74);
    assert!(String::from_utf8_lossy(&o.stderr).contains("/dev/null/pacs-out"));
}

#[test]
fn audit_inconclusive_is_2() {
    // A log whose robot samples are 1 s apart (beyond max_gap): nothing can be checked.
    let dir = std::env::temp_dir().join(format!("pacs-exit-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let log = dir.join("gap.jsonl");
    let kp = "[[2.6,0,1],[2.6,0.1,1],[2.6,0.2,1],[2.6,0.3,1],[2.6,0.4,1],[2.6,0.5,1],[2.6,0.6,1],[2.6,0.7,1],[2.6,0.8,1]]";
    let q = "[0.3,-0.5,0.2,-2.0,0.1,1.8,0.6]";
    let text = format!(
        "{{\"type\":\"header\",\"format\":\"pacs-log\",\"version\":1,\"robot\":\"fr3\",\"human\":\"default\",\"constraints\":\"ssm\"}}\n\
         {{\"type\":\"human\",\"t\":0.0,\"positions\":{kp}}}\n\
         {{\"type\":\"robot\",\"t\":0.0,\"q\":{q}}}\n\
         {{\"type\":\"robot\",\"t\":1.0,\"q\":{q}}}\n"
    );
    std::fs::write(&log, text).unwrap();
    assert_eq!(code(&pacs(&["audit", log.to_str().unwrap()])), 2);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn commands_that_write_exit_74_when_they_cannot() {
    for args in [
        vec!["shield", "--out", UNWRITABLE],
        vec!["demo", "--out", UNWRITABLE],
        vec![
            "simulate",
            "--task",
            "sorting",
            "--method",
            "off",
            "--rollouts",
            "1",
            "--out",
            UNWRITABLE,
        ],
    ] {
        let o = pacs(&args);
        assert_eq!(
            code(&o),
            74,
            "{args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert!(
            String::from_utf8_lossy(&o.stderr).contains(UNWRITABLE),
            "{args:?}: the message names the path"
        );
    }
}

#[test]
fn invalid_input_is_3() {
    assert_eq!(code(&pacs(&["fk", "--input", "no/such/file.json"])), 3);
    assert_eq!(code(&pacs(&["shield", "--input", "no/such/scene.json"])), 3);
    assert_eq!(code(&pacs(&["robot", "show", "ur99"])), 3);
    assert_eq!(code(&pacs(&["simulate", "--task", "juggling"])), 3);
}
