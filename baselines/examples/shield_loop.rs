//! Instruction-count harness for the shield step: `valgrind --tool=callgrind
//! target/release/examples/shield_loop sorting|handover N` runs the `pacs bench shield` scenario
//! (N steps) and prints its statistics; `sorting-continuous` runs the continuous-chunks scenario, `objects` the sorting scenario with
//! two dynamic objects, `sorting-offloop` continuous chunks planned on a `ChunkWorker`'s thread
//! (lead 3; the worker thread's instructions count too unless callgrind's `--toggle-collect`
//! restricts the count to the step).

use pacs_baselines::bench::{
    shield_objects_scenario, shield_scenario_offloop, shield_scenario_with,
};
use pacs_shield::ChunkMotion;
use pacs_shield::shield::FilterMode;

fn main() {
    let mut args = std::env::args().skip(1);
    let spec = args.next().unwrap_or_else(|| "handover".into());
    let steps: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(20_000);
    let (spec, motion) = match spec.strip_suffix("-continuous") {
        Some(base) => (base.to_string(), ChunkMotion::Continuous),
        None => (spec, ChunkMotion::Stop),
    };
    let s = if spec == "objects" {
        shield_objects_scenario(steps)
    } else if let Some(base) = spec.strip_suffix("-offloop") {
        shield_scenario_offloop(base, FilterMode::Pacs, 3, steps)
    } else {
        shield_scenario_with(&spec, FilterMode::Pacs, motion, steps)
    };
    println!(
        "{}: median {:.1} us, p90 {:.1} us, p99 {:.1} us, max {:.1} us, work max {:.1} us, verified {:.3}",
        s.scenario,
        s.median * 1e6,
        s.p90 * 1e6,
        s.p99 * 1e6,
        s.max * 1e6,
        s.work_max * 1e6,
        s.verified_fraction
    );
}
