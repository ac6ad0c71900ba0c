//! Instruction-count harness: `valgrind --tool=callgrind target/release/examples/occupancy_loop N`
//! runs the `fr3_occupancy_1_joint_box` workload N times (default 10 000); with `ENERGY` set,
//! each occupancy is followed by the sub-chain energy bounds over the same box.

use nalgebra::Point3;
use pacs_models::{Capsule, fr3};
use pacs_reach::JointBox;
use pacs_reach::robot::{ReachScratch, RobotReach};
use std::hint::black_box;

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(10_000);
    let reach = RobotReach::new(&fr3::fr3(), 0.005);
    let q = fr3::Q_READY;
    let lo: Vec<f64> = q.iter().map(|x| x - 0.002).collect();
    let hi: Vec<f64> = q.iter().map(|x| x + 0.002).collect();
    let qb = JointBox::new(&lo, &hi).expect("valid box");
    let mut out = vec![
        Capsule::new_unchecked(Point3::origin(), Point3::origin(), 0.0);
        reach.capsule_count()
    ];
    let mut scratch = ReachScratch::default();
    if std::env::var_os("ENERGY").is_some() {
        // The shield's PFL pattern: occupancy, then the energy bound over the same box.
        let vb = JointBox::new(&[-0.3; 7], &[0.5; 7]).expect("valid box");
        let mut e = [0.0; 8];
        for _ in 0..n {
            reach
                .occupancy_with(&mut scratch, black_box(&qb), &mut out)
                .unwrap();
            reach
                .subchain_energy_bounds_with(&mut scratch, &qb, &vb, &mut e)
                .unwrap();
        }
        black_box(&e);
        return;
    }
    for _ in 0..n {
        reach
            .occupancy_with(&mut scratch, black_box(&qb), &mut out)
            .unwrap();
    }
    black_box(&out);
    if std::env::var_os("PRINT").is_some() {
        println!("{:?}", out[11]);
    }
}
