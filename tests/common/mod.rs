//! What the CLI tests share: running the `pacs` binary.

use std::process::{Command, Output};

/// The `pacs` binary under test.
pub fn pacs() -> Command {
    Command::new(env!("CARGO_BIN_EXE_pacs"))
}

/// Run `pacs ARGS`, which must succeed (its stderr is shown if not).
pub fn pacs_ok<I, S>(args: I) -> Output
where
    I: IntoIterator<Item = S>,
    S: AsRef<std::ffi::OsStr>,
{
    let out = pacs().args(args).output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}
