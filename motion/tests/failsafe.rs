//! `failsafe::brake_plan`: the earliest stop along the path from an intended instant.

mod common;

use common::*;
use pacs_motion::scaling::PathState;
use pacs_motion::*;

fn trajectory() -> Trajectory {
    let (_, plan) = limits();
    let mut pl = Planner::new(plan, PlannerConfig::default());
    let q0 = [0.0, -0.5, 0.0, -2.0, 0.0, 1.5, 0.8];
    let q1 = [0.3, -0.2, 0.1, -1.7, 0.1, 1.7, 0.6];
    let wp = Waypoints::from_rows(&[q0.to_vec(), q1.to_vec()]).unwrap();
    pl.plan(&JointState::at_rest(&q0), &wp).unwrap()
}

#[test]
fn brakes_within_the_limits_and_never_later_than_following_to_the_end() {
    let (hw, _) = limits();
    let traj = trajectory();
    assert_eq!(traj.end(), EndCondition::AtRest);
    let end = traj.duration();
    for k in 0..=20 {
        let tb = end * k as f64 / 20.0;
        let plan = brake_plan(&traj, &hw, tb).expect("a trajectory ending at rest has a failsafe");
        assert!(
            plan.delay >= 0.0 && plan.stop_after() <= end - tb + 1e-12,
            "t_b = {tb}"
        );
        if let Some(p) = plan.profile {
            // The profile starts on the intended timing at t_b + delay and settles at rest.
            let s0 = p.eval(0.0);
            let at = PathState::intended(tb + plan.delay);
            assert!((s0.s - at.s).abs() < 1e-9, "t_b = {tb}");
            assert!(p.settle_time() >= 0.0);
        }
    }
    // From the end, the robot is already at rest: nothing to follow.
    let last = brake_plan(&traj, &hw, end).unwrap();
    assert_eq!(last.stop_after(), 0.0);
}
