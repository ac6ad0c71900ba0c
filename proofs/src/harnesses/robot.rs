//! (d) The robot's link enlargement bound is at least the true excursion: for a joint box where
//! one joint (or two consecutive joints) varies, every link capsule at every configuration of the
//! box lies in the reported occupancy capsule.

use crate::{Source, harness};
use pacs_models::fr3::fr3;
use pacs_models::{Capsule, RobotModel};
use pacs_reach::JointBox;
use pacs_reach::geometry::segment_distance_upper_bound;
use pacs_reach::robot::RobotReach;
use pacs_reach::rounding::add_up;

/// A joint box of `model`: all joints fixed except `j` (and `j + 1` if `two`), which vary over
/// `[c − δ, c + δ]` within the limits; and a configuration in it.
pub(crate) fn joint_box<S: Source>(
    s: &mut S,
    model: &RobotModel,
    max_width: f64,
) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let n = model.dof();
    let j = s.index(n);
    let two = s.bool() && j + 1 < n;
    let (mut lo, mut hi, mut q) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    for i in 0..n {
        let (qmin, qmax) = (model.limits().q_min()[i], model.limits().q_max()[i]);
        let c = s.f64_in(qmin, qmax);
        if i == j || (two && i == j + 1) {
            let d = s.f64_in(0.0, max_width);
            lo[i] = (c - d).max(qmin);
            hi[i] = (c + d).min(qmax);
        } else {
            lo[i] = c;
            hi[i] = c;
        }
        q[i] = s.f64_in(lo[i], hi[i]);
    }
    (lo, hi, q)
}

fn link_enlargement<S: Source>(s: &mut S) {
    let model = fr3();
    let reach = RobotReach::new(&model, 0.0);
    let (lo, hi, q) = joint_box(s, &model, 0.5);
    let mut occ = vec![
        Capsule::new_unchecked(Default::default(), Default::default(), 0.0);
        reach.capsule_count()
    ];
    let qb = JointBox::new(&lo, &hi).expect("valid box");
    reach.occupancy_into(&qb, &mut occ).expect("valid box");
    let nominal = model.capsules_world(&q);
    assert_eq!(nominal.len(), occ.len());
    for (i, ((_, c), o)) in nominal.iter().zip(&occ).enumerate() {
        // The nominal capsule is inside `o` iff both axis endpoints are within o.r − c.r of o's
        // axis (distance to a segment is convex). Nominal FK rounding (≤ 1e-14 m) is covered by
        // the occupancy's MODEL_PAD; the tracking error is 0 here.
        for e in [c.p1(), c.p2()] {
            let d = segment_distance_upper_bound(&e, &e, &o.p1(), &o.p2());
            assert!(
                add_up(d, c.radius()) <= o.radius(),
                "capsule {i}: endpoint {e:?} at q={q:?} is {d} from the axis of {o:?} (box {lo:?}..{hi:?})"
            );
        }
    }
}
harness!(
    d1_robot_link_enlargement,
    twin_only,
    cases = crate::DEFAULT_CASES,
    link_enlargement
);
