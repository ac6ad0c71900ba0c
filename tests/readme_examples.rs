//! The README's command examples run verbatim from a fresh clone (issue 17, item 6): every
//! `cargo run --release -- …` line of its command blocks is run with the built binary, in order
//! (later lines may read what earlier ones wrote), from a scratch directory that sees the
//! shipped `examples/`; each must exit 0. Skipped, with the reason: the long runs (`demo`,
//! `simulate`, `bench`, covered by their own tests), lines naming the user's own files
//! (`YOUR_…`) and shell globs over `demo`'s output.

use std::path::Path;
use std::process::Command;

#[test]
fn readme_commands_run_verbatim() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let dir = std::env::temp_dir().join(format!("pacs-readme-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // The scratch directory sees the shipped examples at the same relative path.
    #[cfg(unix)]
    std::os::unix::fs::symlink(root.join("examples"), dir.join("examples")).unwrap();
    let mut ran = 0;
    for line in readme.lines() {
        let Some(rest) = line.trim().strip_prefix("cargo run --release -- ") else {
            continue;
        };
        let cmd = rest.split(" #").next().unwrap_or("").trim();
        let args: Vec<&str> = cmd.split_whitespace().collect();
        let long = matches!(args.first(), Some(&("demo" | "simulate" | "bench")));
        if long || cmd.contains("YOUR_") || cmd.contains('*') {
            continue;
        }
        let out = Command::new(env!("CARGO_BIN_EXE_pacs"))
            .args(&args)
            .current_dir(&dir)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "`pacs {cmd}` exited {:?}: {}",
            out.status.code(),
            String::from_utf8_lossy(&out.stderr)
        );
        ran += 1;
    }
    // reach ×3, fk, trajectory, shield, audit ×2, show ×4, capsules.
    assert!(ran >= 13, "only {ran} README commands found");
    std::fs::remove_dir_all(&dir).ok();
}

/// Every command of docs/cli.md's `sh` blocks (lines starting with `pacs `, `&&`-chains split)
/// runs verbatim, in order, from a scratch directory that sees the shipped `examples/`; each
/// exits 0. Skipped: the long runs (`demo`, `simulate`, `bench`, covered by their own tests).
#[test]
fn cli_doc_commands_run_verbatim() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let doc = std::fs::read_to_string(root.join("docs/cli.md")).unwrap();
    let dir = std::env::temp_dir().join(format!("pacs-cli-doc-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    #[cfg(unix)]
    std::os::unix::fs::symlink(root.join("examples"), dir.join("examples")).unwrap();
    let (mut in_sh, mut ran) = (false, 0);
    for line in doc.lines() {
        let l = line.trim();
        if l.starts_with("```") {
            in_sh = l == "```sh";
            continue;
        }
        if !in_sh || !l.starts_with("pacs ") {
            continue;
        }
        for part in l.split(" && ") {
            let cmd = part.trim().strip_prefix("pacs ").expect("a pacs command");
            let args: Vec<&str> = cmd.split_whitespace().collect();
            if matches!(args.first(), Some(&("demo" | "simulate" | "bench"))) {
                continue;
            }
            let out = Command::new(env!("CARGO_BIN_EXE_pacs"))
                .args(&args)
                .current_dir(&dir)
                .output()
                .unwrap();
            assert!(
                out.status.success(),
                "docs/cli.md: `pacs {cmd}` exited {:?}: {}",
                out.status.code(),
                String::from_utf8_lossy(&out.stderr)
            );
            ran += 1;
        }
    }
    // fk, reach ×4, trajectory, show ×3, capsules + show, shield + audit, audit ×3.
    assert!(ran >= 16, "only {ran} docs/cli.md commands found");
    std::fs::remove_dir_all(&dir).ok();
}
