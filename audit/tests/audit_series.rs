//! The plots' nominal energy: each plot bucket shows the whole robot's nominal kinetic energy
//! ½q̇ᵀM(q)q̇ at the first sample checked in it, also after buckets merge (a log longer than
//! the plot's 1,024 buckets of the first width) and on both paths of the checker (the block
//! fast path while the person is far, span by span while close).

use pacs_audit::{AuditConfig, Auditor};
use pacs_log::LogModels;
use pacs_models::{ConstraintSpec, HumanModel, RobotModel};

use pacs_testkit::{sinusoidal_joints, standing_arms_forward as standing};

const Q: [f64; 7] = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785];

/// Sample `i` at 1 kHz: every joint on its own sinusoid, with its logged velocity.
fn sample(i: usize) -> (f64, [f64; 7], [f64; 7]) {
    let t = i as f64 * 1e-3;
    let (q, dq) = sinusoidal_joints(Q, 0.7, 0.13, t);
    (t, q, dq)
}

#[test]
fn each_bucket_shows_the_energy_at_its_first_sample() {
    let robot = RobotModel::builtin("fr3").unwrap();
    let models = LogModels {
        robot: robot.clone(),
        human: HumanModel::builtin("default").unwrap(),
        people: vec![("human".into(), HumanModel::builtin("default").unwrap())],
        constraints: ConstraintSpec::builtin("ssm").unwrap(),
        environment: vec![],
        objects: vec![],
    };
    let mut a = Auditor::new(models, AuditConfig::default()).unwrap();
    let n = 4500;
    for i in 0..n {
        let (t, q, dq) = sample(i);
        if i % 33 == 0 {
            // Far for the first half (blocks), within reach for the second (spans).
            let x = if i < n / 2 { 2.5 } else { 0.6 };
            a.push_human(t, t, &standing(x)).unwrap();
        }
        a.push_robot(t, &q, Some(&dq)).unwrap();
    }
    let r = a.finish("series", Default::default());
    assert!(
        r.series.len() > 256 && r.series[0].t_end - r.series[0].t > 3e-3,
        "the buckets merged ({} of width {})",
        r.series.len(),
        r.series[0].t_end - r.series[0].t
    );
    let energy = |i: usize| {
        let (_, q, dq) = sample(i);
        robot.kinetic_energy(&q, &dq)
    };
    let first_at = |t: f64| (0..n).find(|&i| sample(i).0 >= t).unwrap_or(n - 1);
    let mut checked = 0;
    for p in &r.series {
        if p.t >= sample(n - 1).0 {
            continue; // the last sample starts no span
        }
        let e = p
            .energy_nominal
            .unwrap_or_else(|| panic!("bucket at {} s has no nominal energy", p.t));
        // The first sample in the bucket (one within 1 ns of its start may round either way).
        let (i_a, i_b) = (first_at(p.t - 1e-9), first_at(p.t + 1e-9));
        assert!(
            e.to_bits() == energy(i_a).to_bits() || e.to_bits() == energy(i_b).to_bits(),
            "bucket at {} s: {e} J, the first sample's {} J",
            p.t,
            energy(i_a)
        );
        checked += 1;
    }
    assert!(checked > 256, "{checked} buckets checked");
}
