//! Failsafe construction timing probe (development aid): mean time per `Failsafe::new` over
//! batches, reported as the median batch.
use pacs_models::RobotModel;
use pacs_verify::failsafe::Failsafe;
use pacs_verify::problems::anchor_set;
use pacs_verify::{JointState, Limits, Method, OutOfLimits, Planner, PlannerConfig};
use std::time::Instant;

fn main() {
    let robot = RobotModel::builtin("fr3").unwrap();
    let hw = Limits::from_joint_limits(robot.limits());
    let l = hw.with_uniform_acc_jerk(10.0, 400.0);
    let seg = std::env::args().nth(1).as_deref() == Some("seg");
    let batches: usize = std::env::args()
        .nth(2)
        .map(|s| s.parse().unwrap())
        .unwrap_or(200);
    let mut pl = Planner::new(
        l,
        PlannerConfig {
            method: if seg {
                Method::Segments
            } else {
                Method::Spline
            },
            ..Default::default()
        },
    );
    let trajs: Vec<_> = anchor_set(robot.limits(), 200, 7)
        .iter()
        .map(|p| {
            let wp = p
                .chunk
                .waypoints(&p.q0, robot.limits(), OutOfLimits::Reject)
                .unwrap();
            pl.plan(&JointState::at_rest(&p.q0), &wp).unwrap()
        })
        .collect();
    let mut k = 0usize;
    let mut res = Vec::new();
    for _ in 0..batches {
        let t0 = Instant::now();
        let mut acc = 0.0;
        for _ in 0..1000 {
            let t = &trajs[k % trajs.len()];
            let s0 = t.duration() * ((k * 7919) % 1000) as f64 / 1000.0;
            k += 1;
            acc += Failsafe::new(t, s0, &hw).unwrap().stop_time();
        }
        std::hint::black_box(acc);
        res.push(t0.elapsed().as_secs_f64() * 1e3);
    }
    res.sort_by(f64::total_cmp);
    println!(
        "failsafe ({}): median {:.2} us per build, min {:.2}",
        if seg { "segments" } else { "spline" },
        res[res.len() / 2],
        res[0]
    );
}
