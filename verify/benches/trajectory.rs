//! Criterion benches of the intended trajectory, the failsafe and the monitored trajectory on the
//! anchor problem set (FR3, H = 16, h = 8 / 6, a = 10 rad/s², j = 400 rad/s³), plus a printed
//! quality table (duration / lower bound, geometric mean) for the chunk planner and the
//! single-action baseline.

use criterion::{Criterion, criterion_group, criterion_main};
use pacs_models::RobotModel;
use pacs_verify::problems::{anchor_set, lower_bound};
use pacs_verify::{JointState, Limits, Monitored, OutOfLimits, Planner, PlannerConfig};
use std::hint::black_box;

fn setup() -> (Limits, Limits, Vec<(JointState, pacs_verify::Waypoints)>) {
    let robot = RobotModel::builtin("fr3").expect("fr3");
    let hw = Limits::from_joint_limits(robot.limits());
    let plan = hw.with_uniform_acc_jerk(10.0, 400.0);
    let probs = anchor_set(robot.limits(), 200, 7);
    let set = probs
        .iter()
        .map(|p| (JointState::at_rest(&p.q0), p.chunk.waypoints(&p.q0, robot.limits(), OutOfLimits::Reject).expect("waypoints")))
        .collect();
    (hw, plan, set)
}

fn quality() {
    let (hw, plan, set) = setup();
    let gains: Vec<f64> = std::env::var("GAINS").ok().map(|g| g.split(',').map(|x| x.parse().unwrap()).collect()).unwrap_or(vec![1.0]);
    for &velocity_gain in &gains {
    for sweeps in [0usize, 2, 3, 4, 6] {
        let acceleration_gain: f64 = std::env::var("AGAIN").ok().map(|g| g.parse().unwrap()).unwrap_or(1.0);
        let mut planner = Planner::new(plan, PlannerConfig { sweeps, velocity_gain, acceleration_gain, ..Default::default() });
        let mut lsum = 0.0;
        let mut lsum_sa = 0.0;
        let mut fs_delay = 0usize;
        let mut fs_follow = 0usize;
        let mut fs_n = 0usize;
        for (s, wp) in &set {
            let lb = lower_bound(wp, &plan.v[..plan.dof]);
            let t = planner.plan(s, wp).expect("plan");
            let sa = planner.plan_single_action(s, wp).expect("single");
            lsum += (t.duration() / lb).ln();
            lsum_sa += (sa.duration() / lb).ln();
            for k in 0..20 {
                let t0 = t.duration() * k as f64 / 20.0;
                let m = Monitored::new(&t, t0, 0.001, &hw).expect("monitored");
                fs_n += 1;
                match m.failsafe().kind() {
                    pacs_verify::failsafe::FailsafeKind::FollowToEnd => fs_follow += 1,
                    _ if m.failsafe().delay() > 0.0 => fs_delay += 1,
                    _ => {}
                }
            }
        }
        let n = set.len() as f64;
        println!(
            "quality gain={velocity_gain} sweeps={sweeps}: chunk duration/LB geomean {:.3}, single-action {:.3}; failsafes: {fs_n} built, {fs_delay} delayed, {fs_follow} follow-to-end",
            (lsum / n).exp(),
            (lsum_sa / n).exp()
        );
    }
    }
}

fn benches(c: &mut Criterion) {
    quality();
    let (hw, plan, set) = setup();
    let mut planner = Planner::new(plan, PlannerConfig::default());
    let mut k = 0usize;
    c.bench_function("intended_trajectory_chunk", |b| {
        b.iter(|| {
            let (s, wp) = &set[k % set.len()];
            k += 1;
            black_box(planner.plan(s, wp).expect("plan"))
        })
    });
    c.bench_function("single_action_chunk", |b| {
        b.iter(|| {
            let (s, wp) = &set[k % set.len()];
            k += 1;
            black_box(planner.plan_single_action(s, wp).expect("plan"))
        })
    });
    let trajs: Vec<_> = set.iter().map(|(s, wp)| planner.plan(s, wp).expect("plan")).collect();
    c.bench_function("monitored_failsafe_build", |b| {
        b.iter(|| {
            let t = &trajs[k % trajs.len()];
            let t0 = t.duration() * ((k * 7919) % 1000) as f64 / 1000.0;
            k += 1;
            black_box(Monitored::new(t, t0, 0.001, &hw).expect("fs").stop_time())
        })
    });
    c.bench_function("state_at", |b| {
        b.iter(|| {
            let t = &trajs[k % trajs.len()];
            k += 1;
            black_box(t.state_at(t.duration() * 0.37))
        })
    });
    c.bench_function("bounds_10ms", |b| {
        b.iter(|| {
            let t = &trajs[k % trajs.len()];
            k += 1;
            let a = t.duration() * 0.37;
            black_box(t.bounds(a, a + 0.01))
        })
    });
}

criterion_group!(name = g; config = Criterion::default().sample_size(50).warm_up_time(std::time::Duration::from_millis(500)).measurement_time(std::time::Duration::from_secs(2)); targets = benches);
criterion_main!(g);
