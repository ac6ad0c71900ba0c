//! (g) The energy bound is at least ½ q̇ᵀ M(q) q̇ for any q, q̇ in the given boxes (every sub-chain).

use super::robot::joint_box;
use crate::{Source, harness};
use nalgebra::DVector;
use pacs_models::fr3::fr3;
use pacs_reach::JointBox;
use pacs_reach::robot::RobotReach;

/// Relative tolerance for the nominal (round-to-nearest) energy of the comparison: the nominal
/// value carries a relative rounding error ≪ 1e-9; the bound is rigorous for the exact value.
const NOMINAL_REL: f64 = 1e-9;

fn energy<S: Source>(s: &mut S) {
    let model = fr3();
    let n = model.dof();
    let reach = RobotReach::new(&model, 0.0);
    let (qlo, qhi, q) = joint_box(s, &model, 0.3);
    let (mut vlo, mut vhi, mut dq) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    for i in 0..n {
        let vm = model.limits().v_max()[i];
        let a = s.f64_in(-vm, vm);
        let b = s.f64_in(-vm, vm);
        vlo[i] = a.min(b);
        vhi[i] = a.max(b);
        dq[i] = s.f64_in(vlo[i], vhi[i]);
    }
    let mut bound = vec![0.0; n + 1];
    reach
        .subchain_energy_bounds_into(
            &JointBox::new(&qlo, &qhi).expect("valid box"),
            &JointBox::new(&vlo, &vhi).expect("valid box"),
            &mut bound,
        )
        .expect("valid boxes");
    let mut nominal = vec![0.0; n + 1];
    model.subchain_energies_into(&q, &dq, &mut nominal);
    for k in 0..=n {
        assert!(
            bound[k] >= nominal[k] * (1.0 - NOMINAL_REL),
            "sub-chain {k}: bound {} < energy {} at q={q:?} dq={dq:?}",
            bound[k],
            nominal[k]
        );
    }
    // The whole chain against the mass-matrix form ½ q̇ᵀ M(q) q̇ (independent computation).
    let m = model.mass_matrix(&q);
    let v = DVector::from_column_slice(&dq);
    let e = 0.5 * v.dot(&(&m * &v));
    assert!(
        bound[n] >= e * (1.0 - NOMINAL_REL),
        "bound {} < ½ q̇ᵀM q̇ = {e}",
        bound[n]
    );
}
harness!(
    g1_energy_bound_dominates,
    twin_only,
    cases = crate::DEFAULT_CASES,
    energy
);
