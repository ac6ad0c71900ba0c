//! `pacs bench shield` (issue 15 item 1): every scenario reports the step's and `set_chunk`'s
//! median, p99, p99.9 and maximum, the counts over 50 µs / 100 µs and the work-time figures, as
//! finite numbers in order (median ≤ p99 ≤ p99.9 ≤ max), on a short run.

use serde_json::Value;
use std::process::Command;

fn num(run: &Value, key: &str) -> f64 {
    let x = run[key]
        .as_f64()
        .unwrap_or_else(|| panic!("{}: {key} is not a number: {}", run["scenario"], run[key]));
    assert!(
        x.is_finite() && x >= 0.0,
        "{}: {key} = {x}",
        run["scenario"]
    );
    x
}

/// The four figures `keys` of `run` (median, p99, p99.9, max: µs) are finite and in order;
/// returns the last.
fn ordered(run: &Value, keys: [&str; 4]) -> f64 {
    let v = keys.map(|k| num(run, k));
    assert!(
        v.windows(2).all(|w| w[0] <= w[1]),
        "{keys:?} = {v:?} in {run}"
    );
    v[3]
}

#[test]
fn bench_shield_reports_tails_of_steps_and_set_chunk() {
    let out = Command::new(env!("CARGO_BIN_EXE_pacs"))
        .args(["bench", "shield", "--steps", "600"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    let runs = v["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 7, "six shield scenarios and the CBF baseline");
    for run in runs {
        let steps = num(run, "steps");
        assert!(steps > 0.0);
        ordered(run, ["median_us", "p99_us", "p99_9_us", "max_us"]);
        assert!(num(run, "steps_over_50_us") <= steps);
        let cmax = ordered(
            run,
            [
                "set_chunk_median_us",
                "set_chunk_p99_us",
                "set_chunk_p99_9_us",
                "set_chunk_max_us",
            ],
        );
        assert!(cmax > 0.0, "{}: no chunk was timed", run["scenario"]);
        num(run, "set_chunk_over_100_us");
        num(run, "work_p99_9_us");
        num(run, "work_max_us");
        num(run, "work_steps_over_50_us");
        let v = num(run, "verified_fraction");
        assert!(v <= 1.0);
    }
    // The shield's scenarios time their work (the CBF baseline does not).
    for run in &runs[..6] {
        assert!(num(run, "work_max_us") > 0.0, "{}", run["scenario"]);
        assert!(num(run, "work_p99_9_us") <= num(run, "work_max_us"));
    }
}
