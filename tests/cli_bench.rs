//! `pacs bench shield` and `pacs bench cbf`: every scenario reports the step's
//! and `set_chunk`'s median, p99, p99.9 and maximum, the counts over 50 µs / 100 µs and the
//! work-time figures, as finite numbers in order (median ≤ p99 ≤ p99.9 ≤ max), on a short run;
//! by default the chunks are planned on the planning thread, whose figures are reported too.

use serde_json::Value;
mod common;

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

fn bench(args: &[&str]) -> Vec<Value> {
    let out = common::pacs_ok(args);
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    v["runs"].as_array().unwrap().clone()
}

/// The figures every run reports, finite and in order.
fn check_run(run: &Value) {
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
    let v = num(run, "verified_fraction");
    assert!(v <= 1.0);
}

#[test]
fn bench_shield_reports_tails_of_steps_and_set_chunk() {
    let runs = bench(&["bench", "shield", "--steps", "600"]);
    assert_eq!(runs.len(), 5, "five shield scenarios");
    let mut reruns = 0;
    for run in &runs {
        check_run(run);
        // The shield's scenarios time their work.
        assert!(num(run, "work_max_us") > 0.0, "{}", run["scenario"]);
        num(run, "work_steps_over_50_us");
        assert!(num(run, "work_p99_9_us") <= num(run, "work_max_us"));
        // Each floor probe spins at least as long as its step's work, so its quantiles bound
        // the work's from above.
        let (fp, fm) = (num(run, "floor_p99_9_us"), num(run, "floor_max_us"));
        assert!(fp <= fm, "{}", run["scenario"]);
        assert!(fp >= num(run, "work_p99_9_us"), "{}", run["scenario"]);
        assert!(fm >= num(run, "work_max_us"), "{}", run["scenario"]);
        assert!(num(run, "floor_steps_over_50_us") >= num(run, "work_steps_over_50_us"));
        // The slowest steps' neighbourhood medians cannot exceed them (at most 7 steps of the
        // run are slower than any of them).
        let slowest = run["slowest_steps"].as_array().unwrap();
        for w in slowest {
            assert!(num(w, "around_median_us") <= num(w, "us"), "{w}");
        }
        // Every one of the slowest steps is re-run at the end of the run from its kept copy.
        for w in slowest {
            assert!(num(w, "rerun_us") > 0.0, "{w}");
        }
        reruns += slowest.len();
        // Chunks go through the planning thread: 3 chunks in 600 steps, each planned there
        // (the planning figures are the thread's) and offered back by a poll.
        assert!(
            run["scenario"]
                .as_str()
                .unwrap()
                .contains("planning thread, lead 3"),
            "{}",
            run["scenario"]
        );
        assert_eq!(num(run, "chunks"), 3.0, "{}", run["scenario"]);
        let plan =
            ["planning_median_us", "planning_p99_us", "planning_max_us"].map(|k| num(run, k));
        assert!(
            plan[0] <= plan[1] && plan[1] <= plan[2],
            "{}: planning {plan:?}",
            run["scenario"]
        );
        assert!(
            plan[0] > 0.0,
            "{}: nothing planned on the thread",
            run["scenario"]
        );
        assert!(num(run, "offer_median_us") <= num(run, "offer_max_us"));
        assert!(num(run, "chunks_followed") <= 3.0);
        num(run, "replans");
    }
    assert_eq!(
        reruns,
        5 * 8,
        "eight slowest steps per scenario, each re-run"
    );
}

#[test]
fn bench_shield_in_loop_and_cbf_report_the_same_figures() {
    let runs = bench(&["bench", "shield", "--steps", "300", "--in-loop"]);
    assert_eq!(runs.len(), 5);
    for run in &runs {
        check_run(run);
        assert!(
            run["scenario"]
                .as_str()
                .unwrap()
                .contains("planned in the loop"),
            "{}",
            run["scenario"]
        );
        // No planning thread: its figures are absent, not 0.
        for k in ["planning_max_us", "offer_max_us", "chunks", "replans"] {
            assert!(run.get(k).is_none(), "{k} in {run}");
        }
        assert!(num(run, "work_max_us") > 0.0, "{}", run["scenario"]);
    }
    let runs = bench(&["bench", "cbf", "--steps", "300"]);
    assert_eq!(runs.len(), 1);
    check_run(&runs[0]);
    // The CBF run times neither its work apart nor the machine's floor, and plans nothing on a
    // thread: those fields are absent (they read as measured when printed as 0.0).
    for k in [
        "work_max_us",
        "work_p99_9_us",
        "work_steps_over_50_us",
        "floor_max_us",
        "floor_p99_9_us",
        "floor_steps_over_50_us",
        "planning_median_us",
        "offer_median_us",
        "chunks",
    ] {
        assert!(runs[0].get(k).is_none(), "{k} in {}", runs[0]);
    }
}

#[test]
fn bench_shield_refuses_zero_steps_and_lead() {
    for args in [
        &["bench", "shield", "--steps", "0"][..],
        &["bench", "shield", "--steps", "10", "--lead", "0"][..],
        &["bench", "cbf", "--steps", "0"][..],
    ] {
        let out = common::pacs().args(args).output().unwrap();
        assert!(!out.status.success(), "{args:?} was accepted");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("must be at least 1"), "{args:?}: {err}");
    }
}

/// Lines of the files at `logs` for which `keep` holds.
fn count_lines(logs: &[&str], keep: impl Fn(&str) -> bool) -> u64 {
    logs.iter()
        .map(|p| {
            std::fs::read_to_string(p)
                .unwrap()
                .lines()
                .filter(|l| keep(l))
                .count() as u64
        })
        .sum()
}

/// The stage names of a `pacs bench audit` report, in order.
fn stage_names(v: &Value) -> Vec<&str> {
    v["stages"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["stage"].as_str().unwrap())
        .collect()
}

/// `pacs bench audit`: the robot samples counted by reading are the logs' robot lines, every
/// stage reports its fastest ≤ median ≤ slowest run with throughputs that match the counts, the
/// checks' share is the audit's median less the read's, the JSON syntax stage appears for JSON
/// Lines logs only and checks every line that is not blank, and the verdicts are those of `pacs
/// audit` (the clean example passes, the close one fails).
#[test]
fn bench_audit_times_reading_syntax_and_the_whole_audit() {
    let logs = [
        "examples/logs/clean_sorting.jsonl",
        "examples/logs/close_sorting.jsonl",
    ];
    let robot_lines = count_lines(&logs, |l| l.contains(r#""type": "robot""#));
    let bytes: u64 = logs
        .iter()
        .map(|p| std::fs::metadata(p).unwrap().len())
        .sum();
    let out = common::pacs_ok(["bench", "audit", "--runs", "3", logs[0], logs[1]]);
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["robot_samples"].as_u64(), Some(robot_lines), "{v}");
    assert_eq!(v["bytes"].as_u64(), Some(bytes), "{v}");
    assert_eq!(v["runs"].as_u64(), Some(3));
    assert_eq!(v["verdicts"]["pass"].as_u64(), Some(1), "{v}");
    assert_eq!(v["verdicts"]["fail"].as_u64(), Some(1), "{v}");
    assert_eq!(stage_names(&v), ["read", "json_syntax", "audit"]);
    let rel = |a: f64, b: f64| ((a - b) / b).abs() < 1e-9;
    let mut medians = Vec::new();
    for s in v["stages"].as_array().unwrap() {
        let [lo, mid, hi] = ["ms_min", "ms_median", "ms_max"].map(|k| s[k].as_f64().unwrap());
        assert!(0.0 < lo && lo <= mid && mid <= hi, "{s}");
        let per_s = s["robot_samples_per_s_median"].as_f64().unwrap();
        let mb_s = s["mb_per_s_median"].as_f64().unwrap();
        assert!(rel(per_s, robot_lines as f64 / (mid / 1e3)), "{s}");
        assert!(rel(mb_s, bytes as f64 / (mid / 1e3) / 1e6), "{s}");
        medians.push(mid);
    }
    let checks = (medians[2] - medians[0]).max(0.0);
    let reported = v["checker_ms_median"].as_f64().unwrap();
    assert!((reported - checks).abs() <= 1e-9 * medians[2], "{v}");
    // The syntax stage checked every line that is not blank, of both logs.
    let lines = count_lines(&logs, |l| !l.trim().is_empty());
    assert_eq!(v["json_lines"].as_u64(), Some(lines), "{v}");
    // An MCAP log: no JSON syntax stage, and it says why.
    let out = common::pacs_ok([
        "bench",
        "audit",
        "--runs",
        "1",
        "--header",
        "examples/logs/clean_sorting_header.json",
        "examples/logs/clean_sorting.mcap",
    ]);
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(stage_names(&v), ["read", "audit"]);
    assert!(
        v["json_syntax"].as_str().unwrap().contains("not every log"),
        "{v}"
    );
    assert_eq!(v["robot_samples"].as_u64(), Some(1001), "{v}");
}

#[test]
fn bench_audit_refuses_zero_runs_and_names_a_missing_log() {
    let out = common::pacs()
        .args([
            "bench",
            "audit",
            "--runs",
            "0",
            "examples/logs/clean_sorting.jsonl",
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(3));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--runs must be at least 1"));
    let out = common::pacs()
        .args(["bench", "audit", "no/such/log.jsonl"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(3));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no/such/log.jsonl"));
}
