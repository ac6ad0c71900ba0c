//! `pacs demo`: the built-in handover scenario with PACS (PFL) and with the filter OFF, scored
//! against the ground-truth human motion.

use super::CliError;
use pacs_audit::AuditConfig;
use pacs_models::{ConstraintSpec, default_human, fr3};
use pacs_reports::{InputFile, ReportInput};
use pacs_sim::episode::{Episode, EpisodeConfig, Method, run_logged};
use pacs_sim::humans::{Handover, HumanScript, WalkIn};
use pacs_sim::policy::Demonstration;
use serde_json::{Value, json};
use std::path::Path;

/// Goal configuration of the built-in demonstration (rad): the tool moves forward and down to the
/// handover point.
pub const Q_GOAL: [f64; 7] = [0.25, 0.15, 0.0, -1.95, 0.0, 2.1, 0.785];

fn summary(e: &Episode) -> Value {
    json!({
        "method": e.method, "task": e.task, "human": e.human,
        "success": e.success, "safe_success": e.safe_success,
        "safety_violation_fraction": e.violation_fraction,
        "duration_s": e.duration, "min_separation_m": e.min_separation,
        "max_path_deviation_rad": e.max_deviation, "verified_fraction": e.verified_fraction,
    })
}

/// Run `pacs demo`: simulate, log, audit the logs, write the certification report to `out`.
pub fn run_demo(progress: bool, out: &Path) -> Result<Value, CliError> {
    std::fs::create_dir_all(out)
        .map_err(|e| CliError::Output(format!("cannot create {}: {e}", out.display())))?;
    let robot = fr3::fr3();
    let human = default_human()
        .with_uncertainty(0.01, 0.1, 0.03)
        .map_err(|e| CliError::Internal(e.to_string()))?;
    let demo = Demonstration::linear(&fr3::Q_READY, &Q_GOAL, 40, 16, 8);
    let tool = |q: &[f64]| pacs_sim::task::tool_point(&robot, q);
    let mid = tool(&demo.path()[20]);
    let goal = tool(&Q_GOAL);
    let sorting: Box<dyn HumanScript> = Box::new(WalkIn {
        reach: [mid[0] + 0.05, mid[1], mid[2] + 0.05],
        times: [1.5, 1.5, 3.5],
    });
    let handover: Box<dyn HumanScript> = Box::new(Handover {
        offer: [goal[0] + 0.08, goal[1], goal[2] + 0.02],
        t_offer: 0.0,
    });
    let cfg = EpisodeConfig::default();
    let audit_cfg = AuditConfig::default();
    let (mut runs, mut logs, mut audits) = (Vec::new(), Vec::new(), Vec::new());
    for (task, script) in [("sorting", &sorting), ("handover", &handover)] {
        let spec = ConstraintSpec::builtin(task).map_err(|e| CliError::Internal(e.to_string()))?;
        for method in [Method::Pacs, Method::Off] {
            if progress {
                eprintln!("pacs demo: {task} with {method:?} ...");
            }
            let path = out.join(format!("{task}-{}.jsonl", method_name(method)));
            let file = std::fs::File::create(&path)
                .map_err(|e| CliError::Output(format!("cannot write {}: {e}", path.display())))?;
            let mut w = std::io::BufWriter::new(file);
            let e = run_logged(
                method,
                &robot,
                &human,
                &spec,
                script.as_ref(),
                &demo,
                &cfg,
                0,
                Some(&mut w),
            )
            .map_err(|e| CliError::Internal(e.to_string()))?;
            drop(w);
            let audited = pacs_audit::audit_file(&path, &audit_cfg)
                .map_err(|e| CliError::Internal(format!("audit of {}: {e}", path.display())))?;
            let mut v = summary(&e);
            v["log"] = json!(path.display().to_string());
            v["audit_verdict"] = serde_json::to_value(audited.verdict).unwrap_or_default();
            // The same definition with the audit as evidence (what the report shows).
            v["audit_safe_success"] = json!(pacs_audit::verdict::safe_success(
                e.success,
                audited.verdict == pacs_audit::Verdict::Pass
            ));
            v["audit_violation_fraction"] = json!(audited.metrics.violation_fraction);
            runs.push(v);
            logs.push(path);
            audits.push(audited);
        }
    }
    let hashed: Result<Vec<InputFile>, _> = logs.iter().map(|p| InputFile::hash(p)).collect();
    let input = ReportInput {
        runs: &audits,
        logs: hashed.map_err(|e| CliError::Internal(e.to_string()))?,
        config: None,
        settings: serde_json::to_value(&audit_cfg).unwrap_or_default(),
        generated: pacs_reports::utc_now(),
        skipped: Vec::new(),
    };
    pacs_reports::write_reports(out, &input).map_err(|e| CliError::Internal(e.to_string()))?;
    eprint!("{}", screen_summary(&runs, out));
    Ok(json!({
        "scenario": "FR3 follows a demonstration with a nearest-neighbour chunk policy (H=16, h=8, Δt=33 ms). Sorting (SSM): a person walks up and reaches across the robot's path. Handover (PFL, hand 0.265 J free / 0.014 J clamped): a person offers a block at the goal. Camera 100 Hz, 30 ms delay, 1 cm noise; metrics against the true human motion; each run is logged, audited offline (audit_verdict) and reported (report).",
        "runs": runs,
        "report": out.join("report.html").display().to_string(),
    }))
}

fn method_name(m: Method) -> &'static str {
    match m {
        Method::Off => "off",
        Method::Pacs => "pacs",
        Method::SingleAction => "single-action",
        Method::Cbf => "cbf",
        Method::Direct => "direct",
    }
}

/// One sentence per run, read off its row (so the words never contradict the numbers): how
/// many of its steps violate the task's constraint against the true human motion.
pub fn row_sentences(runs: &[Value]) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    for r in runs {
        let task = r["task"].as_str().unwrap_or("?");
        let method = r["method"].as_str().unwrap_or("?").to_uppercase();
        let constraint = if task == "handover" { "PFL" } else { "SSM" };
        let frac = r["safety_violation_fraction"].as_f64().unwrap_or(f64::NAN);
        let _ = if frac > 0.0 {
            writeln!(
                s,
                "  {task}, {method}: {:.1} % of its steps violate {constraint} against the true human motion.",
                100.0 * frac
            )
        } else if frac == 0.0 {
            writeln!(
                s,
                "  {task}, {method}: no step violates {constraint} against the true human motion{}{}.",
                if method == "PACS" {
                    " (it brakes along the demonstrated path)"
                } else {
                    " in this run"
                },
                if r["audit_verdict"] == "fail" {
                    "; the audit, judging the log with the camera's errors and delay, finds possible violations (fail)"
                } else {
                    ""
                }
            )
        } else {
            writeln!(s, "  {task}, {method}: violations not measured.")
        };
    }
    s
}

/// The one-screen, human-readable summary printed on stderr (stdout carries the JSON).
fn screen_summary(runs: &[Value], out: &Path) -> String {
    use std::fmt::Write as _;
    let mut s = String::from(
        "\npacs demo: FR3 + nearest-neighbour chunk policy (H = 16, h = 8, Δt = 33 ms); camera 100 Hz, 30 ms delay, 1 cm noise\n\n  task      filter  success  steps violating (true human)  audit verdict  duration  min. separation\n",
    );
    for r in runs {
        let _ = writeln!(
            s,
            "  {:<9} {:<7} {:<8} {:<29} {:<14} {:>6.2} s  {:>7.3} m",
            r["task"].as_str().unwrap_or("?"),
            r["method"].as_str().unwrap_or("?"),
            if r["success"] == true { "yes" } else { "no" },
            format!(
                "{:.1} %",
                100.0 * r["safety_violation_fraction"].as_f64().unwrap_or(f64::NAN)
            ),
            r["audit_verdict"].as_str().unwrap_or("?"),
            r["duration_s"].as_f64().unwrap_or(f64::NAN),
            r["min_separation_m"].as_f64().unwrap_or(f64::NAN),
        );
    }
    s.push('\n');
    s.push_str(&row_sentences(runs));
    let _ = writeln!(
        s,
        "\n  Negative separation = contact: allowed for SSM only while the robot is at rest, for PFL only\n  below the body part's energy threshold. The audit judges each log alone (measurement errors\n  and delay included), so it may flag what the true motion did not do, never the reverse.\n  Certification report: {}  (logs: {}/*.jsonl; JSON summary on stdout)\n",
        out.join("report.html").display(),
        out.display()
    );
    s
}
