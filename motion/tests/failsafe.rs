//! Failsafe and monitored trajectory: path consistency, limits, standstill, sound bounds.
#![allow(clippy::needless_range_loop)]

mod common;

use common::*;
use pacs_motion::anchors::anchor_set;
use pacs_motion::failsafe::FailsafeKind;
use pacs_motion::*;

fn trajectories(n: usize, seed: u64, plan: Limits) -> Vec<Trajectory> {
    let robot = fr3();
    let mut pl = Planner::new(plan, PlannerConfig::default());
    anchor_set(robot.limits(), n, seed)
        .iter()
        .map(|p| {
            pl.plan(
                &JointState::at_rest(&p.q0),
                &p.chunk
                    .waypoints(&p.q0, robot.limits(), OutOfLimits::Reject)
                    .unwrap(),
            )
            .unwrap()
        })
        .collect()
}

/// Check one failsafe: starts in the intended state, stays on the path (s monotone, each
/// configuration equals the intended configuration at s within 1e-9, velocity = q′·ṡ by finite
/// differences), within `lim` at dense samples, at rest at its stop time.
pub fn check_failsafe(t: &Trajectory, f: &Failsafe, lim: &Limits) {
    let n = t.dof();
    let s0 = f.s0();
    let a = f.state_at(t, 0.0);
    let b = t.state_at(s0);
    for i in 0..n {
        assert!(
            (a.q[i] - b.q[i]).abs() < 1e-12
                && (a.dq[i] - b.dq[i]).abs() < 1e-12
                && (a.ddq[i] - b.ddq[i]).abs() < 1e-12
        );
    }
    let m = 300;
    let mut s_prev = s0;
    let mut sd_prev = 1.0 + 1e-12;
    for k in 0..=m {
        let tau = f.stop_time() * k as f64 / m as f64;
        let (s, sd, _, _) = f.path_at(tau);
        assert!(
            s >= s_prev - 1e-12 && sd <= sd_prev + 1e-12 && sd >= -1e-9,
            "s {s} sd {sd} at {tau}"
        );
        s_prev = s;
        sd_prev = sd;
        let st = f.state_at(t, tau);
        let on_path = t.state_at(s);
        for i in 0..n {
            assert!((st.q[i] - on_path.q[i]).abs() <= 1e-9, "off path");
            within(st.dq[i], lim.v[i], "failsafe dq");
            within(st.ddq[i], lim.a[i], "failsafe ddq");
            within(st.dddq[i], lim.j[i], "failsafe dddq");
        }
        // Chain rule cross-check by central differences of the configuration.
        if tau > 2e-6 && tau < f.stop_time() - 2e-6 {
            let h = 1e-6;
            let qp = f.state_at(t, tau + h);
            let qm = f.state_at(t, tau - h);
            for i in 0..n {
                let fd = (qp.q[i] - qm.q[i]) / (2.0 * h);
                assert!(
                    (fd - st.dq[i]).abs() < 1e-4 * (1.0 + st.dq[i].abs()),
                    "dq {} vs fd {fd}",
                    st.dq[i]
                );
            }
        }
    }
    let end = f.state_at(t, f.stop_time());
    let later = f.state_at(t, f.stop_time() + 1.0);
    for i in 0..n {
        assert!(
            end.dq[i].abs() < 1e-9 && end.ddq[i].abs() < 1e-9,
            "not at rest: {} {}",
            end.dq[i],
            end.ddq[i]
        );
        assert_eq!(later.dq[i], 0.0);
        assert!((later.q[i] - end.q[i]).abs() < 1e-12);
        let r = f.q_range(t, i);
        assert!(r.lo <= b.q[i] && b.q[i] <= r.hi && r.lo <= end.q[i] && end.q[i] <= r.hi);
        assert!((end.q[i] - b.q[i]).abs() <= f.distance_bound(t, i));
    }
}

#[test]
fn failsafes_from_many_states_are_path_consistent_and_within_hardware_limits() {
    let (hw, plan) = limits();
    let mut kinds = [0usize; 3];
    for t in trajectories(20, 31, plan) {
        for k in 0..=25 {
            let s0 = t.duration() * k as f64 / 25.0;
            let f = Failsafe::new(&t, s0, &hw).unwrap();
            check_failsafe(&t, &f, &hw);
            assert!(
                f.stop_time() <= t.duration() - s0 + 1e-12,
                "never slower than following to the end"
            );
            kinds[match (f.kind(), f.delay() > 0.0) {
                (FailsafeKind::FollowToEnd, _) => 0,
                (_, true) => 1,
                _ => 2,
            }] += 1;
        }
    }
    assert!(kinds[2] > 0, "some failsafes brake immediately: {kinds:?}");
}

#[test]
fn with_margin_the_failsafe_brakes_immediately_and_stops_fast() {
    // Planning at half the hardware limits leaves margin: braking starts at once.
    let (hw, plan) = limits();
    let slow = plan.scaled(0.5).unwrap();
    let mut immediate = 0;
    let mut total = 0;
    for t in trajectories(10, 41, slow) {
        for k in 0..10 {
            let s0 = t.duration() * k as f64 / 10.0;
            let f = Failsafe::new(&t, s0, &hw).unwrap();
            check_failsafe(&t, &f, &hw);
            total += 1;
            if f.kind() == FailsafeKind::Brake && f.delay() == 0.0 {
                immediate += 1;
                assert!(f.stop_time() < 0.5 * (t.duration() - s0) + 0.05);
            }
        }
    }
    assert!(immediate * 10 >= total * 9, "{immediate}/{total} immediate");
}

#[test]
fn a_moving_end_trajectory_gets_a_braking_failsafe_before_its_end() {
    let robot = fr3();
    let (hw, plan) = limits();
    let slow = plan.scaled(0.5).unwrap();
    let mut pl = Planner::new(
        slow,
        PlannerConfig {
            end: EndCondition::Moving,
            ..Default::default()
        },
    );
    let p = &anchor_set(robot.limits(), 1, 4)[0];
    let t = pl
        .plan(
            &JointState::at_rest(&p.q0),
            &p.chunk
                .waypoints(&p.q0, robot.limits(), OutOfLimits::Reject)
                .unwrap(),
        )
        .unwrap();
    let f = Failsafe::new(&t, 0.2 * t.duration(), &hw).unwrap();
    assert_eq!(f.kind(), FailsafeKind::Brake);
    assert!(f.s_stop() <= t.duration());
    check_failsafe(&t, &f, &hw);
    assert!(matches!(
        Failsafe::new(&t, t.duration() + 1.0, &hw),
        Err(FailsafeError::StartOutsideTrajectory { .. })
    ));
    assert!(matches!(
        Failsafe::new(&t, f64::NAN, &hw),
        Err(FailsafeError::StartOutsideTrajectory { .. })
    ));
}

#[test]
fn monitored_bounds_enclose_dense_samples_and_end_at_rest() {
    let (hw, plan) = limits();
    for t in trajectories(8, 51, plan) {
        for k in 0..8 {
            let t0 = t.duration() * k as f64 / 8.0;
            let m = Monitored::new(&t, t0, 0.001, &hw).unwrap();
            assert!(m.stop_time() >= m.switch_time());
            let s = m.state_at(m.stop_time());
            for i in 0..7 {
                assert!(s.dq[i].abs() < 1e-9);
            }
            let iv: Vec<_> = m.intervals(0.004).collect();
            assert!(
                (iv[0].0 - t0).abs() < 1e-15
                    && (iv.last().unwrap().1 - m.stop_time()).abs() < 1e-15
            );
            for w in iv.windows(2) {
                assert_eq!(w[0].1, w[1].0);
            }
            for (ta, tb) in iv {
                let b = m.bounds(ta, tb);
                for j in 0..=20 {
                    let st = m.state_at(ta + (tb - ta) * j as f64 / 20.0);
                    for i in 0..7 {
                        assert!(b.q[i].lo <= st.q[i] && st.q[i] <= b.q[i].hi, "q bound");
                        assert!(
                            b.dq[i].lo <= st.dq[i] && st.dq[i] <= b.dq[i].hi,
                            "dq bound {:?} {}",
                            b.dq[i],
                            st.dq[i]
                        );
                        assert!(
                            b.ddq[i].lo <= st.ddq[i] && st.ddq[i] <= b.ddq[i].hi,
                            "ddq bound {:?} {}",
                            b.ddq[i],
                            st.ddq[i]
                        );
                    }
                }
            }
        }
    }
}
