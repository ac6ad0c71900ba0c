//! Quick quality/timing probe of the planner on the anchor set (development aid).
use pacs_models::RobotModel;
use pacs_motion::anchors::{anchor_set, lower_bound};
use pacs_motion::{JointState, Limits, OutOfLimits, PlanMethod, Planner, PlannerConfig, Waypoints};
use std::time::Instant;

fn main() {
    let robot = RobotModel::builtin("fr3").unwrap();
    let hw = Limits::from_joint_limits(robot.limits());
    let l = hw.with_uniform_acc_jerk(10.0, 400.0);
    let probs = anchor_set(robot.limits(), 200, 7);
    let iters: usize = std::env::args()
        .nth(1)
        .map(|s| s.parse().unwrap())
        .unwrap_or(12);
    let seg = std::env::args().nth(2).is_some();
    let mut pl = Planner::new(
        l,
        PlannerConfig {
            spline_iterations: iters,
            method: if seg {
                PlanMethod::Segments
            } else {
                PlanMethod::Spline
            },
            ..Default::default()
        },
    );
    let set: Vec<_> = probs
        .iter()
        .map(|p| {
            (
                JointState::at_rest(&p.q0),
                p.chunk
                    .waypoints(&p.q0, robot.limits(), OutOfLimits::Reject)
                    .unwrap(),
            )
        })
        .collect();
    let (ls, fb) = quality(&mut pl, &set, &l);
    moving_starts(&mut pl, &set, l, iters);
    let moving_us = replan_same_path(&mut pl, &set);
    planning_time(moving_us);
    replan_vs_segments(&mut pl, &set, l);
    timing(&mut pl, &set, (fb, iters, ls));
}

/// The problems: a start state and the chunk's waypoints.
type Problems = [(JointState, Waypoints)];

/// Fallbacks to the per-segment planner, and the sum of the log duration ratios over the lower
/// bound.
fn quality(pl: &mut Planner, set: &Problems, l: &Limits) -> (f64, usize) {
    let mut ls = 0.0;
    let mut fb = 0;
    for (s, wp) in set {
        let t = pl.plan(s, wp).unwrap();
        if pl.last_method() != PlanMethod::Spline {
            fb += 1;
        }
        ls += (t.duration() / lower_bound(wp, &l.v[..7])).ln();
    }
    (ls, fb)
}

/// Chunks planned from a moving state against the same waypoints planned from rest.
fn moving_starts(pl: &mut Planner, set: &Problems, l: Limits, iters: usize) {
    // Replanning from a moving state vs planning the same waypoints from
    // rest at the same configuration; the third case hands over at the last waypoint of a
    // chunk planned to end moving (continuous chunks).
    let mut moving = Planner::new(
        l,
        PlannerConfig {
            spline_iterations: iters,
            end: pacs_motion::EndCondition::Moving,
            ..Default::default()
        },
    );
    for (label, at_end) in [("33 ms", Some(0.033)), ("100 ms", Some(0.1)), ("end", None)] {
        let (mut lr, mut worst, mut n) = (0.0f64, 0.0f64, 0usize);
        for w in set.windows(2) {
            let pl_ = if at_end.is_none() {
                &mut moving
            } else {
                &mut *pl
            };
            let t = pl_.plan(&w[0].0, &w[0].1).unwrap();
            let ts = at_end.unwrap_or(t.duration() - 1e-3).min(t.duration());
            let s = t.state_at(ts);
            let Ok(wp) = shifted(&w[1].1, &s.q[..7]) else {
                continue;
            };
            let (Ok(a), Ok(b)) = (
                pl_.plan(&s, &wp),
                pl_.plan(&JointState::at_rest(&s.q[..7]), &wp),
            ) else {
                continue;
            };
            let r = a.duration() / b.duration();
            lr += r.ln();
            worst = worst.max(r);
            n += 1;
        }
        println!(
            "moving start at {label}: duration / from rest, geomean {:.3}, worst {:.3} ({n} cases)",
            (lr / n.max(1) as f64).exp(),
            worst
        );
    }
}

/// The same path replanned from a state 33 ms and 100 ms into it; returns the planning times
/// from the moving states (µs).
fn replan_same_path(pl: &mut Planner, set: &Problems) -> Vec<f64> {
    // The receding-horizon case: the next chunk continues the path the robot is on. Replan the
    // waypoints of the same chunk not yet passed from the state 33 ms / 100 ms into it, against
    // planning them from rest at that configuration, and against the original plan's remaining
    // time (no degradation: the replanned rest of the path takes no longer than the original).
    let mut moving_us = Vec::new();
    for dt in [0.033f64, 0.1] {
        let (mut lr, mut lo, mut worst, mut n) = (0.0f64, 0.0f64, 0.0f64, 0usize);
        let mut blends = 0usize;
        for (s0, wp) in set {
            let t = pl.plan(s0, wp).unwrap();
            if dt >= t.duration() {
                continue;
            }
            let s = t.state_at(dt);
            let times = t.waypoint_times();
            let mut rows = vec![s.q[..7].to_vec()];
            // times[k − 1]: when q̂_k is passed.
            for k in 1..=wp.segments() {
                if times[k - 1] > dt {
                    rows.push(wp.row(k).to_vec());
                }
            }
            let Ok(rest_wp) = pacs_motion::Waypoints::from_rows(&rows) else {
                continue;
            };
            let t0 = Instant::now();
            let a = pl.plan(&s, &rest_wp);
            moving_us.push(t0.elapsed().as_secs_f64() * 1e6);
            let (Ok(a), Ok(b)) = (a, pl.plan(&JointState::at_rest(&s.q[..7]), &rest_wp)) else {
                continue;
            };
            let r = a.duration() / b.duration();
            blends += (a.blended() > 0) as usize;
            lr += r.ln();
            lo += (a.duration() / (t.duration() - dt)).ln();
            worst = worst.max(r);
            n += 1;
        }
        println!(
            "same path, replanned {dt} s in: duration / from rest, geomean {:.3}, worst {:.3}; / the original's remaining time, geomean {:.3} ({n} cases, {blends} blends)",
            (lr / n.max(1) as f64).exp(),
            worst,
            (lo / n.max(1) as f64).exp()
        );
    }
    moving_us
}

/// The planning time from the moving states (µs): median, p99 and max.
fn planning_time(mut moving_us: Vec<f64>) {
    moving_us.sort_by(f64::total_cmp);
    println!(
        "same path, planning time from the moving states: median {:.1} us, p99 {:.1} us, max {:.1} us",
        moving_us[moving_us.len() / 2],
        moving_us[moving_us.len() * 99 / 100],
        moving_us[moving_us.len() - 1]
    );
}

/// The spline planner against the per-segment planner on replans from moving states.
fn replan_vs_segments(pl: &mut Planner, set: &Problems, l: Limits) {
    for dt in [0.033f64, 0.1] {
        let (mut fbm, mut lsm, mut lss) = (0, 0.0, 0.0);
        let mut seg = Planner::new(
            l,
            PlannerConfig {
                method: PlanMethod::Segments,
                ..Default::default()
            },
        );
        for w in set.windows(2) {
            let t = pl.plan(&w[0].0, &w[0].1).unwrap();
            let s = t.state_at(dt.min(t.duration()));
            let wp = shifted(&w[1].1, &s.q[..7]).unwrap();
            let t2 = pl.plan(&s, &wp).unwrap();
            if pl.last_method() != PlanMethod::Spline {
                fbm += 1;
            }
            let t3 = seg.plan(&s, &wp).unwrap();
            lsm += t2.duration().ln();
            lss += t3.duration().ln();
        }
        println!(
            "replan dt {dt}: fallbacks {fbm}/199, spline/segments duration geomean ratio {:.3}",
            ((lsm - lss) / 199.0).exp()
        );
    }
}

/// The planning time from rest over five passes of the set, with the quality figures
/// (`fb`, `iters`, `ls`).
fn timing(pl: &mut Planner, set: &Problems, (fb, iters, ls): (usize, usize, f64)) {
    let mut times = Vec::new();
    for _ in 0..5 {
        for (s, wp) in set {
            let t0 = Instant::now();
            let t = pl.plan(s, wp).unwrap();
            times.push(t0.elapsed().as_secs_f64() * 1e6);
            std::hint::black_box(t);
        }
    }
    times.sort_by(f64::total_cmp);
    println!(
        "fallbacks {fb} iters {iters}: ratio {:.3}  median {:.1} us p99 {:.1} us",
        (ls / set.len() as f64).exp(),
        times[times.len() / 2],
        times[times.len() * 99 / 100]
    );
}

/// The waypoints `wp` translated so that they start at `q` (the next chunk replanned from
/// wherever the previous one left the robot).
fn shifted(
    wp: &pacs_motion::Waypoints,
    q: &[f64],
) -> Result<pacs_motion::Waypoints, pacs_motion::TrajectoryError> {
    let rows: Vec<Vec<f64>> = (0..=wp.segments())
        .map(|k| {
            (0..q.len())
                .map(|i| q[i] + wp.row(k)[i] - wp.row(0)[i])
                .collect()
        })
        .collect();
    pacs_motion::Waypoints::from_rows(&rows)
}
