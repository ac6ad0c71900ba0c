//! Debug one rollout: `cargo run --release -p pacs-sim --example debug_rollout -- TASK METHOD SEED`.
use pacs_sim::eval::{Variant, run_rollout};
use pacs_sim::task::TaskKind;
fn main() {
    let a: Vec<String> = std::env::args().collect();
    let task: TaskKind = a[1].parse().unwrap();
    let v: Variant = a[2].parse().unwrap();
    let seed: u64 = a[3].parse().unwrap();
    let r = run_rollout(
        task,
        &v,
        seed,
        true,
        Some(std::path::Path::new("/tmp/dbg.jsonl")),
        10,
    )
    .unwrap();
    let e = &r.episode;
    println!(
        "success {} goals {} dur {:.2} dev {:.3} ood {} audit {:?}",
        e.success, e.goals_reached, e.duration, e.max_deviation, e.ood_chunks, e.truth_audit
    );
    let scn = pacs_sim::task::scenario(task, seed, true);
    for s in e.samples.iter().step_by(10) {
        let dev = scn.policy.deviation(&s.q);
        print!("dev {dev:.3} ");
        println!(
            "t {:6.2} sep {:7.3} E {:.5} ver {} viol {} tool {:?} v {:.3}",
            s.t,
            s.separation,
            s.energy,
            s.verified,
            s.violation,
            s.tool.map(|x| (x * 1000.0).round() / 1000.0),
            s.tool_speed
        );
    }
}
