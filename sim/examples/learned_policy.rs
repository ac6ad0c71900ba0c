//! Train the learned policies of every task (`pacs simulate --policy kernel`, `kernel-paced`
//! and `kernel-shield-paced`) and print their cross-validation:
//! `cargo run --release -p pacs-sim --example learned_policy`.
use pacs_sim::task::{Replays, TaskKind, learned_policy};

fn main() {
    for task in TaskKind::ALL {
        for (replays, name) in [
            (Replays::None, "kernel"),
            (Replays::Constant, "kernel-paced"),
            (Replays::Shield, "kernel-shield-paced"),
        ] {
            let start = std::time::Instant::now();
            let p = learned_policy(task, replays);
            println!(
                "{} ({name}): kernel width {} standard deviations, trained in {:.2} s",
                task.name(),
                p.bandwidth(),
                start.elapsed().as_secs_f64()
            );
            let s = p.feature_scales();
            let n = s.len() / 2;
            let fmt = |v: &[f64]| {
                v.iter()
                    .map(|x| format!("{x:.4}"))
                    .collect::<Vec<_>>()
                    .join(" ")
            };
            println!("  spread of the joint angles (rad):   {}", fmt(&s[..n]));
            println!("  spread of the motion per Δt (rad):  {}", fmt(&s[n..]));
            for (b, e) in p.cross_validation() {
                let mark = if b == p.bandwidth() {
                    "  <- chosen"
                } else {
                    ""
                };
                println!(
                    "  width {b:>5}: held-out RMS error {:.5} rad{mark}",
                    e.sqrt()
                );
            }
        }
    }
}
