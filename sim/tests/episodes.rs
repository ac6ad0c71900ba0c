//! Short seeded episodes: scripted humans respect the model; PACS has no ground-truth violation
//! and succeeds; OFF violates where a person is in the way.

use pacs_models::{ConstraintSpec, HumanModel, default_human, fr3};
use pacs_sim::episode::{EpisodeConfig, Method, run};
use pacs_sim::humans::{Absent, Handover, HumanScript, WalkIn};
use pacs_sim::policy::Demonstration;

const Q_GOAL: [f64; 7] = [0.25, 0.15, 0.0, -1.95, 0.0, 2.1, 0.785];

fn human() -> HumanModel {
    default_human().with_uncertainty(0.01, 0.1, 0.03).unwrap()
}

fn tool(q: &[f64]) -> [f64; 3] {
    pacs_sim::task::tool_point(&fr3::fr3(), q)
}

fn scripts(demo: &Demonstration) -> Vec<Box<dyn HumanScript>> {
    let mid = tool(&demo.path()[20]);
    let goal = tool(&Q_GOAL);
    vec![
        Box::new(WalkIn {
            reach: [mid[0] + 0.05, mid[1], mid[2] + 0.05],
            times: [1.5, 1.5, 3.5],
        }),
        Box::new(Handover {
            offer: [goal[0] + 0.08, goal[1], goal[2] + 0.02],
            t_offer: 0.0,
        }),
        Box::new(Absent),
    ]
}

#[test]
fn scripted_humans_respect_the_model_speed_limits() {
    let h = human();
    let demo = Demonstration::linear(&fr3::Q_READY, &Q_GOAL, 40, 16, 8);
    for s in scripts(&demo) {
        let dt = 1e-3;
        let mut prev = s.keypoints(-0.1);
        for k in 0..10_000 {
            let t = -0.1 + (k + 1) as f64 * dt;
            let cur = s.keypoints(t);
            for (i, (a, b)) in prev.iter().zip(&cur).enumerate() {
                let v = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2))
                    .sqrt()
                    / dt;
                assert!(
                    v <= h.v_max()[i],
                    "{}: keypoint {i} moves at {v:.3} m/s at t = {t:.3}",
                    s.name()
                );
            }
            prev = cur;
        }
    }
}

#[test]
fn pacs_is_safe_and_succeeds_off_violates() {
    let robot = fr3::fr3();
    let h = human();
    let demo = Demonstration::linear(&fr3::Q_READY, &Q_GOAL, 40, 16, 8);
    let ss = scripts(&demo);
    let cfg = EpisodeConfig::default();
    let sorting = ConstraintSpec::builtin("sorting").unwrap();
    let handover = ConstraintSpec::builtin("handover").unwrap();
    let ep = |m: Method, spec: &ConstraintSpec, script: &dyn HumanScript| {
        run(m, &robot, &h, spec, script, &demo, &cfg, 0).unwrap()
    };
    for (spec, script) in [(&sorting, &ss[0]), (&handover, &ss[1]), (&sorting, &ss[2])] {
        let e = ep(Method::Pacs, spec, script.as_ref());
        assert_eq!(
            e.violation_fraction,
            0.0,
            "PACS {} / {}: violations",
            spec.name,
            script.name()
        );
        assert!(
            e.success,
            "PACS {} / {}: no success in {} s",
            spec.name,
            script.name(),
            cfg.max_time
        );
        assert!(
            e.max_deviation < 0.05,
            "PACS left the demonstrated path by {} rad",
            e.max_deviation
        );
    }
    let off = ep(Method::Off, &sorting, ss[0].as_ref());
    assert!(
        off.violation_fraction > 0.0,
        "OFF should violate SSM when a person reaches across the path"
    );
    // Without a human PACS is not slower than OFF (H4: no slowdown unless needed).
    let pacs_free = ep(Method::Pacs, &sorting, ss[2].as_ref());
    let off_free = ep(Method::Off, &sorting, ss[2].as_ref());
    assert!(
        pacs_free.duration <= off_free.duration + 0.01,
        "{} vs {}",
        pacs_free.duration,
        off_free.duration
    );
}
