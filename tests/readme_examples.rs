//! The documented commands run verbatim from a fresh clone: every
//! `cargo run --release -- …` line of README.md's command blocks and every `pacs …` line of
//! docs/cli.md's `sh` blocks (`&&`-chains split) is run with the built binary, in order (later
//! lines may read what earlier ones wrote), from a scratch directory that sees the shipped
//! `examples/`; each must exit 0. Skipped, with the reason: the long runs (`demo`, `simulate`,
//! `bench`, covered by their own tests), lines naming the user's own files (`YOUR_…`) and shell
//! globs over `demo`'s output.

use std::path::Path;
use std::process::Command;

/// Run `commands` (argument strings, without the program) in order in a scratch directory
/// named after `what`; returns how many ran.
fn run_all(what: &str, commands: &[String]) -> usize {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = std::env::temp_dir().join(format!("pacs-{what}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // The scratch directory sees the shipped examples at the same relative path.
    #[cfg(unix)]
    std::os::unix::fs::symlink(root.join("examples"), dir.join("examples")).unwrap();
    let mut ran = 0;
    for cmd in commands {
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
            "{what}: `pacs {cmd}` exited {:?}: {}",
            out.status.code(),
            String::from_utf8_lossy(&out.stderr)
        );
        // README's claim about every command's output: JSON on stdout, except
        // `pacs audit` without `--json`, which prints one line per log.
        if what == "readme" {
            let stdout = String::from_utf8_lossy(&out.stdout);
            if args[0] == "audit" && !args.contains(&"--json") {
                assert_eq!(stdout.lines().count(), 1, "`pacs {cmd}`: {stdout}");
                assert!(
                    stdout.contains("violation episode(s)"),
                    "`pacs {cmd}`: {stdout}"
                );
            } else {
                assert!(
                    serde_json::from_str::<serde_json::Value>(&stdout).is_ok(),
                    "`pacs {cmd}` does not print JSON: {stdout}"
                );
            }
        }
        ran += 1;
    }
    std::fs::remove_dir_all(&dir).ok();
    ran
}

#[test]
fn readme_commands_run_verbatim() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let commands: Vec<String> = readme
        .lines()
        .filter_map(|l| l.trim().strip_prefix("cargo run --release -- "))
        .map(|rest| rest.split(" #").next().unwrap_or("").trim().to_string())
        .collect();
    let ran = run_all("readme", &commands);
    // reach ×3, fk, trajectory, shield, audit ×3, show ×4, capsules.
    assert!(ran >= 13, "only {ran} README commands found");
}

#[test]
fn cli_doc_commands_run_verbatim() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let doc = std::fs::read_to_string(root.join("docs/cli.md")).unwrap();
    let mut in_sh = false;
    let mut commands = Vec::new();
    for line in doc.lines() {
        let l = line.trim();
        if l.starts_with("```") {
            in_sh = l == "```sh";
            continue;
        }
        if in_sh && l.starts_with("pacs ") {
            for part in l.split(" && ") {
                let cmd = part.trim().strip_prefix("pacs ").expect("a pacs command");
                commands.push(cmd.to_string());
            }
        }
    }
    let ran = run_all("cli-doc", &commands);
    // fk, reach ×4, trajectory, show ×3, capsules + show, shield + audit, audit ×3.
    assert!(ran >= 16, "only {ran} docs/cli.md commands found");
}
