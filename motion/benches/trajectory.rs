//! Criterion benches of the intended trajectory, the failsafe and the monitored trajectory on the
//! anchor problem set (FR3, H = 16, h = 8 / 6, a = 10 rad/s², j = 400 rad/s³), plus a printed
//! quality table (duration / lower bound, geometric mean) for the spline planner (default), the
//! per-segment planner and the single-action baseline.
#![allow(clippy::needless_range_loop)]

use criterion::{Criterion, criterion_group, criterion_main};
use pacs_models::RobotModel;
use pacs_motion::anchors::{anchor_set, lower_bound};
use pacs_motion::scaling::{PathState, admissible};
use pacs_motion::{JointState, Limits, OutOfLimits, PlanMethod, Planner, PlannerConfig};
use std::hint::black_box;

fn setup() -> (Limits, Limits, Vec<(JointState, pacs_motion::Waypoints)>) {
    let robot = RobotModel::builtin("fr3").expect("fr3");
    let hw = Limits::from_joint_limits(robot.limits());
    let plan = hw.with_uniform_acc_jerk(10.0, 400.0);
    let probs = anchor_set(robot.limits(), 200, 7);
    let set = probs
        .iter()
        .map(|p| {
            (
                JointState::at_rest(&p.q0),
                p.chunk
                    .waypoints(&p.q0, robot.limits(), OutOfLimits::Reject)
                    .expect("waypoints"),
            )
        })
        .collect();
    (hw, plan, set)
}

fn quality() {
    let (hw, plan, set) = setup();
    let configs: Vec<(String, PlannerConfig)> = [8usize, 12, 16, 24]
        .iter()
        .map(|&it| {
            (
                format!("spline iterations={it}"),
                PlannerConfig {
                    spline_iterations: it,
                    ..Default::default()
                },
            )
        })
        .chain([1usize, 3].iter().map(|&sw| {
            (
                format!("segments sweeps={sw}"),
                PlannerConfig {
                    method: PlanMethod::Segments,
                    sweeps: sw,
                    ..Default::default()
                },
            )
        }))
        .collect();
    let default = PlannerConfig::default();
    for (name, config) in configs {
        let mut planner = Planner::new(plan, config);
        let mut lsum = [0.0; 2];
        let mut lsum_sa = [0.0; 2];
        let mut count = [0usize; 2];
        let mut fallbacks = 0usize;
        let (mut fs_n, mut fs_none, mut fs_stops) = (0usize, 0usize, Vec::new());
        for (s, wp) in &set {
            let lb = lower_bound(wp, &plan.v[..plan.dof]);
            let t = planner.plan(s, wp).expect("plan");
            if planner.last_method() != config.method {
                fallbacks += 1;
            }
            let sa = planner.plan_single_action(s, wp).expect("single");
            let g = if wp.segments() == 8 { 0 } else { 1 };
            lsum[g] += (t.duration() / lb).ln();
            lsum_sa[g] += (sa.duration() / lb).ln();
            count[g] += 1;
            if config == default {
                for k in 0..20 {
                    let s0 = t.duration() * k as f64 / 20.0;
                    fs_n += 1;
                    match admissible(&t, &hw, PathState::intended(s0), 0.0, None) {
                        Some(b) => fs_stops.push(b.settle_time()),
                        None => fs_none += 1,
                    }
                }
            }
        }
        let all = ((lsum[0] + lsum[1]) / (count[0] + count[1]) as f64).exp();
        let all_sa = ((lsum_sa[0] + lsum_sa[1]) / (count[0] + count[1]) as f64).exp();
        println!(
            "quality {name}: duration/LB geomean chunk {all:.2} (h=8 {:.2}, h=6 {:.2}), {fallbacks} fallbacks; single-action {all_sa:.2} (h=8 {:.2}, h=6 {:.2})",
            (lsum[0] / count[0] as f64).exp(),
            (lsum[1] / count[1] as f64).exp(),
            (lsum_sa[0] / count[0] as f64).exp(),
            (lsum_sa[1] / count[1] as f64).exp(),
        );
        if fs_n > 0 {
            println!(
                "braking (the shield's, default planner, hardware limits a=10, j=5000): {fs_n} starts, {fs_none} without an admissible profile (no acceleration margin at that instant); median stop time {:.1} ms",
                1e3 * {
                    fs_stops.sort_by(f64::total_cmp);
                    fs_stops
                        .get(fs_stops.len() / 2)
                        .copied()
                        .unwrap_or(f64::NAN)
                }
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
    let mut segments = Planner::new(
        plan,
        PlannerConfig {
            method: PlanMethod::Segments,
            ..Default::default()
        },
    );
    c.bench_function("intended_trajectory_chunk_segments_3_sweeps", |b| {
        b.iter(|| {
            let (s, wp) = &set[k % set.len()];
            k += 1;
            black_box(segments.plan(s, wp).expect("plan"))
        })
    });
    // Replanning while moving: the next chunk arrives Δt = 33 ms or 100 ms into the previous one.
    let robot = RobotModel::builtin("fr3").expect("fr3");
    for dt in [0.033f64, 0.1] {
        let starts: Vec<_> = set
            .windows(2)
            .map(|w| {
                let t = planner.plan(&w[0].0, &w[0].1).expect("plan");
                let s = t.state_at(dt.min(t.duration()));
                let rows: Vec<Vec<f64>> = (0..=w[1].1.segments())
                    .map(|k| {
                        (0..7)
                            .map(|i| s.q[i] + w[1].1.row(k)[i] - w[1].1.row(0)[i])
                            .collect()
                    })
                    .collect();
                let wp = pacs_motion::Waypoints::from_rows(&rows).expect("rows");
                assert!((1..rows.len()).all(|k| robot.limits().contains(&rows[k])));
                (s, wp)
            })
            .collect();
        c.bench_function(&format!("replan_moving_dt_{}ms", (dt * 1e3).round()), |b| {
            b.iter(|| {
                let (s, wp) = &starts[k % starts.len()];
                k += 1;
                black_box(planner.plan(s, wp).expect("plan"))
            })
        });
    }
    c.bench_function("single_action_chunk", |b| {
        b.iter(|| {
            let (s, wp) = &set[k % set.len()];
            k += 1;
            black_box(planner.plan_single_action(s, wp).expect("plan"))
        })
    });
    let trajs: Vec<_> = set
        .iter()
        .map(|(s, wp)| planner.plan(s, wp).expect("plan"))
        .collect();
    c.bench_function("brake_profile", |b| {
        b.iter(|| {
            let t = &trajs[k % trajs.len()];
            let s0 = t.duration() * ((k * 7919) % 1000) as f64 / 1000.0;
            k += 1;
            black_box(
                admissible(t, &hw, PathState::intended(s0), 0.0, None).map(|p| p.settle_time()),
            )
        })
    });
    // Braking on per-segment trajectories (what the shield plans with).
    let seg_trajs: Vec<_> = set
        .iter()
        .map(|(s, wp)| segments.plan(s, wp).expect("plan"))
        .collect();
    c.bench_function("brake_profile_segments_trajectory", |b| {
        b.iter(|| {
            let t = &seg_trajs[k % seg_trajs.len()];
            let s0 = t.duration() * ((k * 7919) % 1000) as f64 / 1000.0;
            k += 1;
            black_box(
                admissible(t, &hw, PathState::intended(s0), 0.0, None).map(|p| p.settle_time()),
            )
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
