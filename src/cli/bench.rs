//! `pacs bench shield` and `pacs bench cbf`: step-time statistics of the shield and of the CBF
//! baseline on a fixed scenario.

use super::CliError;
use pacs_baselines::bench::{
    ChunkDelivery, StepStats, cbf_scenario, shield_objects_scenario_with, shield_scenario_delivered,
};
use pacs_shield::ChunkMotion;
use pacs_shield::shield::FilterMode;
use serde_json::{Value, json};

/// A run's statistics (µs). Figures a run did not measure are absent, never 0: `work_*` (the
/// step's own work, without the wait for the clock) only where the run timed it, `floor_*` (the
/// machine's timing floor) only where it probed it, `planning_*`/`offer_*`/`chunks*`/`replans`
/// only where chunks went through the planning thread, `set_chunk_*` only where chunks were
/// set in the loop. A timed maximum is never exactly 0, which is how an unmeasured one shows.
fn us(s: &StepStats) -> Value {
    let mut v = json!({
        "scenario": s.scenario, "steps": s.steps,
        "median_us": s.median * 1e6, "p90_us": s.p90 * 1e6, "p99_us": s.p99 * 1e6,
        "p99_9_us": s.p999 * 1e6, "max_us": s.max * 1e6, "steps_over_50_us": s.over_50us,
        "verified_fraction": s.verified_fraction,
    });
    let mut add = |measured: bool, fields: Value| {
        if let (true, Some(f)) = (measured, fields.as_object()) {
            for (k, x) in f {
                v[k] = x.clone();
            }
        }
    };
    add(
        s.work_max > 0.0,
        json!({"work_max_us": s.work_max * 1e6, "work_p99_9_us": s.work_p999 * 1e6,
               "work_steps_over_50_us": s.work_over_50us}),
    );
    add(
        s.floor_max > 0.0,
        json!({"floor_p99_9_us": s.floor_p999 * 1e6, "floor_max_us": s.floor_max * 1e6,
               "floor_steps_over_50_us": s.floor_over_50us}),
    );
    add(
        s.chunk_max > 0.0,
        json!({"set_chunk_median_us": s.chunk_median * 1e6, "set_chunk_p99_us": s.chunk_p99 * 1e6,
               "set_chunk_p99_9_us": s.chunk_p999 * 1e6, "set_chunk_max_us": s.chunk_max * 1e6,
               "set_chunk_over_100_us": s.chunk_over_100us}),
    );
    add(
        s.offers > 0 || s.plan_max > 0.0,
        json!({"planning_median_us": s.plan_median * 1e6, "planning_p99_us": s.plan_p99 * 1e6,
               "planning_max_us": s.plan_max * 1e6, "offer_median_us": s.offer_median * 1e6,
               "offer_max_us": s.offer_max * 1e6, "chunks": s.offers,
               "chunks_followed": s.offers_taken, "replans": s.replans}),
    );
    v["slowest_steps"] = json!(
        s.slowest
            .iter()
            .map(|w| {
                let mut v = json!({
                    "step": w.step, "us": w.time * 1e6, "around_median_us": w.around * 1e6,
                    "steps_since_chunk": w.since_chunk, "verified": w.verified,
                    "binding": serde_json::from_str::<Value>(&w.binding).unwrap_or(Value::Null),
                });
                // Where the run kept a copy of the shield before the step (not CBF).
                if let Some(r) = w.rerun {
                    v["rerun_us"] = json!(r * 1e6);
                }
                v
            })
            .collect::<Vec<_>>()
    );
    v
}

/// What the bench's scenario is (printed with the runs).
const SCENARIO: &str = "FR3 moving back and forth (new chunk every 200 ms; `pacs bench shield` plans it on the planning thread unless the run's name says `planned in the loop`), default human walking between 1.5 m and 1.0 m, measured every 1 ms step; the objects runs add a ball rolling on the table 0.6 m ahead (no contact) and one resting to the side (SSM); the PACS runs compute the separation figure (a diagnostic, `config.separation_figure`) only where the name says so, as a real-time loop that does not log it would";

fn check_steps(steps: usize) -> Result<(), CliError> {
    if steps == 0 {
        return Err(CliError::Input("--steps must be at least 1".into()));
    }
    Ok(())
}

/// Run `pacs bench shield --steps N` with the chunks delivered as `delivery` says.
pub fn shield(steps: usize, delivery: ChunkDelivery, progress: bool) -> Result<Value, CliError> {
    check_steps(steps)?;
    if let ChunkDelivery::Worker { lead: 0 } = delivery {
        return Err(CliError::Input(
            "--lead must be at least 1 safety step (the planning thread's deadline)".into(),
        ));
    }
    let mut runs = Vec::new();
    let say = |what: &str| {
        if progress {
            eprintln!("pacs bench: {what}: {steps} steps ...");
        }
    };
    for (label, spec) in [("PACS-SSM", "sorting"), ("PACS-PFL", "handover")] {
        say(label);
        runs.push(us(&shield_scenario_delivered(
            spec,
            FilterMode::Pacs,
            ChunkMotion::Stop,
            delivery,
            steps,
        )));
    }
    say("PACS-SSM, continuous chunks");
    runs.push(us(&shield_scenario_delivered(
        "sorting",
        FilterMode::Pacs,
        ChunkMotion::Continuous,
        delivery,
        steps,
    )));
    say("PACS-SSM with two objects");
    runs.push(us(&shield_objects_scenario_with(steps, false, delivery)));
    say("PACS-SSM with two objects, separation figure on");
    runs.push(us(&shield_objects_scenario_with(steps, true, delivery)));
    Ok(json!({ "scenario": SCENARIO, "runs": runs }))
}

/// Run `pacs bench cbf --steps N`: the CBF baseline on the same scenario.
pub fn cbf(steps: usize) -> Result<Value, CliError> {
    check_steps(steps)?;
    Ok(json!({ "scenario": SCENARIO, "runs": [us(&cbf_scenario(steps))] }))
}
