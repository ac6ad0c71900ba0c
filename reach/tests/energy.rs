//! Soundness of the kinetic-energy bound: for any q, q̇ in the boxes, ½ q̇ᵀ M_k(q) q̇ (nominal,
//! from the model's mass properties) never exceeds the bound of sub-chain k.

use pacs_models::fr3::fr3;
use pacs_reach::JointBox;
use pacs_reach::robot::RobotReach;
use proptest::prelude::*;
use proptest::test_runner::{RngAlgorithm, TestRng};

/// A joint box from ordered finite bounds (test inputs).
fn jb(lo: &[f64], hi: &[f64]) -> JointBox {
    JointBox::new(lo, hi).expect("valid joint box")
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 10_000, ..ProptestConfig::default() })]

    #[test]
    fn energy_bound_covers_every_state_in_the_boxes(seed in any::<u64>()) {
        let mut rng = TestRng::from_seed(RngAlgorithm::ChaCha, &seed.to_le_bytes().repeat(4));
        let robot = fr3();
        let lim = robot.limits();
        let reach = RobotReach::new(&robot, 0.0);
        let wq = [0.0, 1e-3, 0.05, 0.5][rng.random_range(0..4)];
        let wv = [0.0, 1e-3, 0.1, 1.0][rng.random_range(0..4)];
        let mut ql = [0.0; 7];
        let mut qh = [0.0; 7];
        let mut vl = [0.0; 7];
        let mut vh = [0.0; 7];
        for i in 0..7 {
            ql[i] = rng.random_range(lim.q_min()[i]..=lim.q_max()[i]);
            qh[i] = ql[i] + rng.random_range(0.0..=wq);
            vl[i] = rng.random_range(-lim.v_max()[i]..=lim.v_max()[i]);
            vh[i] = vl[i] + rng.random_range(0.0..=wv);
        }
        let mut bound = [0.0; 8];
        reach.subchain_energy_bounds_into(&jb(&ql, &qh), &jb(&vl, &vh), &mut bound).unwrap();
        for k in 1..8 { prop_assert!(bound[k] >= bound[k - 1]); }
        for _ in 0..4 {
            let mut q = [0.0; 7];
            let mut dq = [0.0; 7];
            for i in 0..7 {
                q[i] = if rng.random_bool(0.3) { if rng.random_bool(0.5) { ql[i] } else { qh[i] } } else { rng.random_range(ql[i]..=qh[i]) };
                dq[i] = if rng.random_bool(0.3) { if rng.random_bool(0.5) { vl[i] } else { vh[i] } } else { rng.random_range(vl[i]..=vh[i]) };
            }
            let mut e = [0.0; 8];
            robot.subchain_energies_into(&q, &dq, &mut e);
            for k in 0..8 {
                // Nominal energies carry ~1e-15 relative float error; the bound must still cover them.
                prop_assert!(e[k] <= bound[k] * (1.0 + 1e-12) + 1e-15, "k={k}: {} > {}", e[k], bound[k]);
            }
        }
    }
}

#[test]
fn point_boxes_are_reasonably_tight() {
    // Ratio bound/nominal for point boxes: only the λ_max and triangle-inequality slack remain.
    let robot = fr3();
    let reach = RobotReach::new(&robot, 0.0);
    let q = pacs_models::fr3::Q_READY;
    let dq = [0.5, -0.4, 0.3, 0.6, -0.8, 0.9, 1.0];
    let b = reach.energy_bound(&jb(&q, &q), &jb(&dq, &dq)).unwrap();
    let e = robot.kinetic_energy(&q, &dq);
    assert!(b >= e, "{b} < {e}");
    assert!(b <= 1.5 * e, "bound {b} J is loose vs nominal {e} J");
}

#[test]
fn single_joint_hand_check() {
    // Only joint 7 moving: the bound covers the nominal and scales with ω².
    let robot = fr3();
    let reach = RobotReach::new(&robot, 0.0);
    let q = pacs_models::fr3::Q_READY;
    let mut dq = [0.0; 7];
    dq[6] = 1.0;
    let b1 = reach.energy_bound(&jb(&q, &q), &jb(&dq, &dq)).unwrap();
    dq[6] = 2.0;
    let b2 = reach.energy_bound(&jb(&q, &q), &jb(&dq, &dq)).unwrap();
    assert!((b2 / b1 - 4.0).abs() < 1e-9);
    let zero = [0.0; 7];
    assert!(reach.energy_bound(&jb(&q, &q), &jb(&zero, &zero)).unwrap() < 1e-300);
}
