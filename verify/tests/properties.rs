//! Property tests (10^4 cases each) over random chunks, start states, limit scales and failsafe starts.
#![allow(clippy::needless_range_loop)]

mod common;

use common::*;
use pacs_verify::problems::Rng;
use pacs_verify::*;
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

proptest! {
    #![proptest_config(ProptestConfig { cases: 10_000, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn random_chunks_pass_waypoints_within_limits(seed in any::<u64>()) {
        let (_, plan, start, wp, mut t) = random_problem(seed);
        let s = t.state_at(0.0);
        for i in 0..7 {
            prop_assert!((s.q[i] - start.q[i]).abs() <= 1e-12 && (s.dq[i] - start.dq[i]).abs() <= 1e-12 && (s.ddq[i] - start.ddq[i]).abs() <= 1e-12);
        }
        for (m, &tk) in t.waypoint_times().iter().enumerate() {
            for i in 0..7 {
                let (q, _, _) = left_limit(&t, i, tk);
                prop_assert!((q - wp.row(m + 1)[i]).abs() <= 1e-9);
            }
        }
        t.check(&plan).unwrap();
        assert_limits_at_samples(&t, &plan, 20);
    }

    #[test]
    fn random_failsafes_are_admissible_on_path_and_stop(seed in any::<u64>(), frac in 0.0f64..1.0) {
        let (hw, _, _, _, t) = random_problem(seed);
        let s0 = frac * t.duration();
        let f = Failsafe::new(&t, s0, &hw).unwrap();
        let n = 12;
        for k in 0..=n {
            let tau = f.stop_time() * k as f64 / n as f64;
            let (s, sd, _, _) = f.path_at(tau);
            let st = f.state_at(&t, tau);
            let on = t.state_at(s);
            prop_assert!((-1e-9..=1.0 + 1e-12).contains(&sd));
            for i in 0..7 {
                prop_assert!((st.q[i] - on.q[i]).abs() <= 1e-9);
                within(st.dq[i], hw.v[i], "dq");
                within(st.ddq[i], hw.a[i], "ddq");
                within(st.dddq[i], hw.j[i], "dddq");
            }
        }
        let end = f.state_at(&t, f.stop_time());
        for i in 0..7 {
            prop_assert!(end.dq[i].abs() < 1e-9 && end.ddq[i].abs() < 1e-9);
        }
    }
}
