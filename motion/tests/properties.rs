//! Property tests over random chunks, start states, limit scales and failsafe starts: 2 × 10^4 cases
//! with the default (spline) planner plus 4000 spline-vs-segments cases (moving starts and ends).
#![allow(clippy::needless_range_loop)]

mod common;

use common::*;
use pacs_motion::anchors::Rng;
use pacs_motion::intended::{BLEND_TOLERANCE, BLEND_WAYPOINTS};
use pacs_motion::*;
use proptest::prelude::*;

fn random_problem(seed: u64) -> (Limits, Limits, JointState, Waypoints, Trajectory) {
    let (hw, plan0) = limits();
    let mut rng = Rng::new(seed);
    let scale = rng.uniform(0.2, 1.0);
    let plan = plan0.scaled(scale).unwrap();
    let h = 1 + (rng.next_u64() % 8) as usize;
    let step = rng.uniform(0.001, 0.08);
    let q0: Vec<f64> = (0..7)
        .map(|i| rng.uniform(plan.q_min[i] + 0.5, plan.q_max[i] - 0.5))
        .collect();
    // Start state: at rest, or a moving state taken from a previous plan (replanning).
    let mut pl = Planner::new(
        plan,
        PlannerConfig {
            sweeps: 2,
            ..Default::default()
        },
    );
    let start = if rng.uniform(0.0, 1.0) < 0.5 {
        JointState::at_rest(&q0)
    } else {
        let q1: Vec<f64> = q0.iter().map(|x| x + rng.uniform(-0.1, 0.1)).collect();
        let pre = pl
            .plan(
                &JointState::at_rest(&q0),
                &Waypoints::from_rows(&[q0.clone(), q1]).unwrap(),
            )
            .unwrap();
        pre.state_at(rng.uniform(0.0, pre.duration()))
    };
    let mut rows = vec![start.q[..7].to_vec()];
    for _ in 0..h {
        let last = rows.last().unwrap().clone();
        rows.push(
            last.iter()
                .enumerate()
                .map(|(i, x)| (x + step * rng.normal()).clamp(plan.q_min[i], plan.q_max[i]))
                .collect(),
        );
    }
    let wp = Waypoints::from_rows(&rows).unwrap();
    let t = pl.plan(&start, &wp).unwrap();
    (hw, plan, start, wp, t)
}

/// Every waypoint is passed exactly (1e-9 rad, from the left at its time), except the leading
/// ones a blend from a moving start leaves out ([`Trajectory::blended`], at most
/// `BLEND_WAYPOINTS`): those are passed, in order, within `BLEND_TOLERANCE` (joint-space distance).
fn assert_waypoints_passed(
    t: &Trajectory,
    start: &JointState,
    wp: &Waypoints,
) -> Result<(), TestCaseError> {
    let moving = (0..7).any(|i| start.dq[i] != 0.0 || start.ddq[i] != 0.0);
    prop_assert!(t.blended() <= BLEND_WAYPOINTS);
    prop_assert!(
        moving || t.blended() == 0,
        "a start at rest is never blended"
    );
    let mut prev = 0.0;
    for (m, &tk) in t.waypoint_times().iter().enumerate() {
        prop_assert!(tk >= prev, "waypoint times out of order");
        prev = tk;
        if m < t.blended() {
            let q = t.state_at(tk).q;
            let d = (0..7)
                .map(|i| (q[i] - wp.row(m + 1)[i]).powi(2))
                .sum::<f64>()
                .sqrt();
            prop_assert!(
                d <= BLEND_TOLERANCE,
                "blended waypoint {} passed {d} rad away",
                m + 1
            );
        } else {
            for i in 0..7 {
                let (q, _, _) = left_limit(t, i, tk);
                prop_assert!((q - wp.row(m + 1)[i]).abs() <= 1e-9);
            }
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 10_000, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn random_chunks_pass_waypoints_within_limits(seed in any::<u64>()) {
        let (_, plan, start, wp, mut t) = random_problem(seed);
        let s = t.state_at(0.0);
        for i in 0..7 {
            prop_assert!((s.q[i] - start.q[i]).abs() <= 1e-12 && (s.dq[i] - start.dq[i]).abs() <= 1e-12 && (s.ddq[i] - start.ddq[i]).abs() <= 1e-12);
        }
        prop_assert_eq!(t.waypoint_times().len(), wp.segments());
        assert_waypoints_passed(&t, &start, &wp)?;
        t.check(&plan).unwrap();
        assert_limits_at_samples(&t, &plan, 20);
    }

    /// The shield's braking (`scaling::admissible`, ṡ from the intended timing to 0) from random
    /// points of random trajectories: on the path, within the robot's limits, at rest at the end.
    #[test]
    fn random_brakes_are_admissible_on_path_and_stop(seed in any::<u64>(), frac in 0.0f64..1.0) {
        use pacs_motion::scaling::{PathState, admissible};
        let (hw, _, _, _, t) = random_problem(seed);
        let s0 = frac * t.duration();
        let f = admissible(&t, &hw, PathState::intended(s0), 0.0, None);
        prop_assume!(f.is_some());
        let f = f.unwrap();
        let n = 12;
        let mut s_prev = s0;
        for k in 0..=n {
            let tau = f.settle_time() * k as f64 / n as f64;
            let p = f.eval(tau);
            let st = p.joint_state(&t);
            let on = t.state_at(p.s);
            prop_assert!((-1e-9..=1.0 + 1e-12).contains(&p.sd));
            prop_assert!(p.s >= s_prev - 1e-12, "the path only moves forward");
            s_prev = p.s;
            for i in 0..7 {
                prop_assert!((st.q[i] - on.q[i]).abs() <= 1e-9);
                within(st.dq[i], hw.v[i], "dq");
                within(st.ddq[i], hw.a[i], "ddq");
            }
        }
        let end = f.eval(f.settle_time()).joint_state(&t);
        for i in 0..7 {
            prop_assert!(end.dq[i].abs() < 1e-9 && end.ddq[i].abs() < 1e-9);
        }
    }
}

/// A random chunk planned from a random (at rest or moving) start with the given end condition
/// by both methods; the moving start comes from a previous spline plan.
fn random_spline_case(
    seed: u64,
    end: EndCondition,
) -> (Limits, JointState, Waypoints, Planner, Planner) {
    let (_, plan0) = limits();
    let mut rng = Rng::new(seed ^ 0x5eed_5eed);
    let plan = plan0.scaled(rng.uniform(0.2, 1.0)).unwrap();
    let h = 2 + (rng.next_u64() % 10) as usize;
    let step = rng.uniform(0.001, 0.06);
    let q0: Vec<f64> = (0..7)
        .map(|i| rng.uniform(plan.q_min[i] + 0.5, plan.q_max[i] - 0.5))
        .collect();
    let cfg = |method| PlannerConfig {
        end,
        method,
        ..Default::default()
    };
    let mut spline = Planner::new(
        plan,
        PlannerConfig {
            end: EndCondition::AtRest,
            ..cfg(PlanMethod::Spline)
        },
    );
    let start = if rng.uniform(0.0, 1.0) < 0.3 {
        JointState::at_rest(&q0)
    } else {
        let mut rows = vec![q0.clone()];
        for _ in 0..4 {
            let last = rows.last().unwrap().clone();
            rows.push(last.iter().map(|x| x + step * rng.normal()).collect());
        }
        let pre = spline
            .plan(
                &JointState::at_rest(&q0),
                &Waypoints::from_rows(&rows).unwrap(),
            )
            .unwrap();
        pre.state_at(rng.uniform(0.0, pre.duration()))
    };
    // Correlated deltas (as policies produce) or independent ones.
    let mut d: Vec<f64> = (0..7).map(|_| rng.normal()).collect();
    let rho = if rng.uniform(0.0, 1.0) < 0.5 {
        0.8
    } else {
        0.0
    };
    let mut rows = vec![start.q[..7].to_vec()];
    for _ in 0..h {
        let last = rows.last().unwrap().clone();
        for x in d.iter_mut() {
            *x = rho * *x + (1.0 - rho) * rng.normal();
        }
        rows.push(
            last.iter()
                .enumerate()
                .map(|(i, x)| (x + step * d[i]).clamp(plan.q_min[i], plan.q_max[i]))
                .collect(),
        );
    }
    spline.set_config(cfg(PlanMethod::Spline));
    let segments = Planner::new(plan, cfg(PlanMethod::Segments));
    (
        plan,
        start,
        Waypoints::from_rows(&rows).unwrap(),
        spline,
        segments,
    )
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 4_000, failure_persistence: None, ..ProptestConfig::default() })]

    /// The spline planner (with its fallback) plans wherever the per-segment planner does, passes
    /// every waypoint within 1e-9 rad, starts in the given state, ends as configured and passes
    /// the exact limit check.
    #[test]
    fn spline_plans_start_exactly_pass_waypoints_and_never_fail_where_segments_succeed(
        seed in any::<u64>(), moving_end in any::<bool>()
    ) {
        let end = if moving_end { EndCondition::Moving } else { EndCondition::AtRest };
        let (plan, start, wp, mut spline, mut segments) = random_spline_case(seed, end);
        let seg = segments.plan(&start, &wp);
        let sp = spline.plan(&start, &wp);
        if seg.is_ok() {
            prop_assert!(sp.is_ok(), "spline failed where segments succeeded: {:?}", sp.err());
        }
        let Ok(mut t) = sp else { return Ok(()) };
        let s = t.state_at(0.0);
        for i in 0..7 {
            prop_assert!((s.q[i] - start.q[i]).abs() <= 1e-12);
            prop_assert!((s.dq[i] - start.dq[i]).abs() <= 1e-12);
            prop_assert!((s.ddq[i] - start.ddq[i]).abs() <= 1e-12);
        }
        prop_assert_eq!(t.waypoint_times().len(), wp.segments());
        assert_waypoints_passed(&t, &start, &wp)?;
        for (m, &tk) in t.waypoint_times().iter().enumerate().skip(t.blended()) {
            for i in 0..7 {
                prop_assert!((t.state_at(tk).q[i] - wp.row(m + 1)[i]).abs() <= 1e-9);
            }
        }
        let after = t.state_at(t.duration());
        let h = wp.segments();
        for i in 0..7 {
            let moving = t.end() == EndCondition::Moving;
            let v_end = if moving && spline.last_method() == PlanMethod::Spline {
                // The last planned segment: from q̂_{h−1}, or from the start where a blend left
                // out every waypoint before q̂_h.
                let (q_prev, t_prev) = if h > 1 && t.blended() < h - 1 {
                    (wp.row(h - 1)[i], t.waypoint_times()[h - 2])
                } else {
                    (wp.row(0)[i], 0.0)
                };
                (wp.row(h)[i] - q_prev) / (t.duration() - t_prev)
            } else if moving {
                after.dq[i]
            } else {
                0.0
            };
            prop_assert!((after.dq[i] - v_end).abs() <= 1e-9 * (1.0 + v_end.abs()));
            prop_assert!(after.ddq[i] == 0.0);
        }
        // A Moving trajectory stops on its own tail; either way it is at rest from rest_time on.
        let rest = t.state_at(t.rest_time());
        let later = t.state_at(t.rest_time() + 1.0);
        prop_assert!(t.rest_time() >= t.duration());
        prop_assert!(t.end() == EndCondition::Moving || t.rest_time() == t.duration());
        for i in 0..7 {
            prop_assert!(rest.dq[i] == 0.0 && rest.ddq[i] == 0.0 && later.dq[i] == 0.0);
            prop_assert!(rest.q[i] == later.q[i]);
        }
        t.check(&plan).unwrap();
        assert_limits_at_samples(&t, &plan, 10);
    }
}

/// `Trajectory::joint_deriv_abs` (the path-speed limits' windows) bounds |q̇|, |q̈| sampled at
/// 40 instants of random windows and |q⃛| of every piece the window touches, and is never looser
/// than `joint_derivs`' derivative ranges (it evaluates a subset of the same points with the same
/// pads). 2000 random plans (moving and resting starts) × 7 joints × 3 windows.
#[test]
fn derivative_bounds_enclose_samples_and_match_joint_derivs() {
    let mut rng = Rng::new(0xd5e1);
    for seed in 0..2000u64 {
        let (_, _, _, _, t) = random_problem(seed);
        for _ in 0..3 {
            let ta = rng.uniform(-0.01, t.duration());
            let tb = ta.max(0.0) + rng.uniform(0.0, 0.3);
            for i in 0..7 {
                let [v, a, j] = t.joint_deriv_abs(i, ta, tb);
                let full = t.joint_derivs(i, ta, tb);
                assert!(v <= full.r[1].abs_max() && a <= full.r[2].abs_max());
                assert_eq!(j, full.r[3].abs_max());
                let (lo, hi) = (ta.max(0.0), tb.max(ta.max(0.0)));
                for k in 0..=40 {
                    let s = lo + (hi - lo) * k as f64 / 40.0;
                    let (_, sv, sa) = t.joint_at(i, s);
                    assert!(
                        sv.abs() <= v && sa.abs() <= a,
                        "joint {i} at {s}: {sv} {sa} vs {v} {a}"
                    );
                }
                for p in t.pieces(i) {
                    if p.t <= hi {
                        // Pieces starting inside the window (and the one containing its start).
                        let inside = p.t >= lo;
                        assert!(!inside || p.j.abs() <= j);
                    }
                }
            }
        }
    }
}
