//! Train the kernel-regression policy of every task and print its cross-validation:
//! `cargo run --release -p pacs-sim --example learned_policy`.
use pacs_sim::task::{TaskKind, learned_policy};

fn main() {
    for task in TaskKind::ALL {
        let p = learned_policy(task);
        println!(
            "{}: kernel width {} (standard deviations)",
            task.name(),
            p.bandwidth()
        );
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
