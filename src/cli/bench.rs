//! `pacs bench shield`: step-time statistics of the shield and the CBF baseline on a fixed scenario.

use super::CliError;
use pacs_shield::bench::{StepStats, cbf_scenario, shield_objects_scenario, shield_scenario};
use pacs_shield::shield::FilterMode;
use serde_json::{Value, json};

fn us(s: &StepStats) -> Value {
    json!({
        "scenario": s.scenario, "steps": s.steps,
        "median_us": s.median * 1e6, "p90_us": s.p90 * 1e6, "p99_us": s.p99 * 1e6,
        "p99_9_us": s.p999 * 1e6, "max_us": s.max * 1e6, "steps_over_50_us": s.over_50us,
        "work_max_us": s.work_max * 1e6, "work_p99_9_us": s.work_p999 * 1e6,
        "work_steps_over_50_us": s.work_over_50us,
        "verified_fraction": s.verified_fraction,
        "set_chunk_median_us": s.chunk_median * 1e6, "set_chunk_p99_us": s.chunk_p99 * 1e6,
        "set_chunk_p99_9_us": s.chunk_p999 * 1e6,
        "set_chunk_max_us": s.chunk_max * 1e6, "set_chunk_over_100_us": s.chunk_over_100us,
        "planning_off_loop_median_us": s.plan_median * 1e6, "planning_off_loop_p99_us": s.plan_p99 * 1e6,
        "planning_off_loop_max_us": s.plan_max * 1e6, "offers": s.offers, "offers_taken": s.offers_taken,
        "slowest_steps": s.slowest.iter().map(|w| json!({
            "step": w.step, "us": w.time * 1e6, "steps_since_chunk": w.since_chunk,
            "verified": w.verified, "binding": serde_json::from_str::<Value>(&w.binding).unwrap_or(Value::Null),
        })).collect::<Vec<_>>(),
    })
}

/// Run `pacs bench shield --steps N`.
pub fn shield(steps: usize, progress: bool) -> Result<Value, CliError> {
    if steps == 0 {
        return Err(CliError::Input("--steps must be at least 1".into()));
    }
    let mut runs = Vec::new();
    for (label, spec) in [("PACS-SSM", "sorting"), ("PACS-PFL", "handover")] {
        if progress {
            eprintln!("pacs bench: {label}: {steps} steps ...");
        }
        runs.push(us(&shield_scenario(spec, FilterMode::Pacs, steps)));
    }
    if progress {
        eprintln!("pacs bench: PACS-SSM, continuous chunks: {steps} steps ...");
    }
    runs.push(us(&pacs_shield::bench::shield_scenario_with(
        "sorting",
        FilterMode::Pacs,
        pacs_shield::ChunkMotion::Continuous,
        steps,
    )));
    if progress {
        eprintln!(
            "pacs bench: PACS-SSM, continuous chunks planned off the loop: {steps} steps ..."
        );
    }
    // The loop's share of a chunk: `set_chunk_*` is the offer; planning runs off the loop.
    runs.push(us(&pacs_shield::bench::shield_scenario_offloop(
        "sorting",
        FilterMode::Pacs,
        3,
        steps,
    )));
    if progress {
        eprintln!("pacs bench: PACS-SSM with two objects: {steps} steps ...");
    }
    runs.push(us(&shield_objects_scenario(steps)));
    if progress {
        eprintln!("pacs bench: PACS-SSM with two objects, separation figure on: {steps} steps ...");
    }
    runs.push(us(&pacs_shield::bench::shield_objects_scenario_with(
        steps, true,
    )));
    let cbf_steps = steps.min(20_000);
    if progress {
        eprintln!("pacs bench: CBF: {cbf_steps} steps ...");
    }
    runs.push(us(&cbf_scenario(cbf_steps)));
    Ok(json!({
        "scenario": "FR3 moving back and forth (new chunk every 200 ms), default human walking between 1.5 m and 1.0 m, measured every 1 ms step; the objects run adds a ball rolling on the table 0.6 m ahead (no contact) and one resting to the side (SSM); the PACS runs compute the separation figure (a diagnostic, `config.separation_figure`) only where the name says so, as a real-time loop that does not log it would",
        "runs": runs,
    }))
}
