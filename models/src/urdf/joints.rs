//! URDF joints: the limits of a chain joint (URDF, then side-file overrides) and the fixed motion
//! of a frozen off-chain joint.

use super::{JointOverride, SideFile};
use crate::error::ModelError;
use crate::robot::JointLimitSpec;
use nalgebra::{Isometry3, Translation3, Unit, UnitQuaternion, Vector3};
use urdf_rs::JointType;

/// The limits a chain joint gets from the side file and the URDF, in the order
/// `[q_min, q_max, v_max, a_max, j_max]`; `None` where neither gives one (see [`chain_limits`]).
pub(super) fn limit_values(
    j: &urdf_rs::Joint,
    ov: &JointOverride,
    side: &SideFile,
) -> [Option<f64>; 5] {
    let l = &j.limit;
    // urdf-rs gives an all-zero limit when `<limit>` is absent (URDF < 1.2).
    let has_limit = !(l.lower == 0.0 && l.upper == 0.0 && l.velocity == 0.0 && l.effort == 0.0);
    let revolute = j.joint_type == JointType::Revolute;
    let urdf_pos = |v: f64| (revolute && has_limit && v.is_finite()).then_some(v);
    let urdf_pos_rate = |v: f64| (has_limit && v.is_finite() && v > 0.0).then_some(v);
    [
        ov.q_min.or(urdf_pos(l.lower)),
        ov.q_max.or(urdf_pos(l.upper)),
        ov.v_max.or(urdf_pos_rate(l.velocity)),
        ov.a_max
            .or(side.a_max)
            .or(urdf_pos_rate(l.acceleration.min(l.deceleration))),
        ov.j_max.or(side.j_max).or(urdf_pos_rate(l.jerk)),
    ]
}

/// Why a chain joint has no value for limit `k` of [`limit_values`] (the URDF value shown).
pub(super) const MISSING_LIMIT: [(&str, &str); 5] = [
    (
        "q_min",
        "no finite URDF lower limit (continuous joint or no <limit>); set q_min in the side file's [joints.NAME]",
    ),
    (
        "q_max",
        "no finite URDF upper limit (continuous joint or no <limit>); set q_max in the side file's [joints.NAME]",
    ),
    (
        "v_max",
        "URDF velocity limit missing or not > 0; set v_max in the side file",
    ),
    (
        "a_max",
        "no acceleration limit; set a_max (uniform or per joint) in the side file",
    ),
    (
        "j_max",
        "no jerk limit; set j_max (uniform or per joint) in the side file",
    ),
];

pub(super) fn chain_limits(
    j: &urdf_rs::Joint,
    ov: &JointOverride,
    side: &SideFile,
) -> Result<JointLimitSpec, ModelError> {
    let l = &j.limit;
    let urdf = [l.lower, l.upper, l.velocity, l.acceleration, l.jerk];
    let v = limit_values(j, ov, side);
    let mut out = [0.0; 5];
    for k in 0..5 {
        out[k] = v[k].ok_or_else(|| ModelError::InvalidValue {
            field: format!("joint `{}` {}", j.name, MISSING_LIMIT[k].0),
            value: urdf[k],
            reason: MISSING_LIMIT[k].1,
        })?;
    }
    let [q_min, q_max, v_max, a_max, j_max] = out;
    Ok(JointLimitSpec {
        q_min,
        q_max,
        v_max,
        a_max,
        j_max,
    })
}

/// Transform child-joint frame → frozen child frame of an off-chain joint.
pub(super) fn frozen_motion(
    j: &urdf_rs::Joint,
    frozen_at: Option<f64>,
) -> Result<Isometry3<f64>, ModelError> {
    let l = &j.limit;
    let has_limit = !(l.lower == 0.0 && l.upper == 0.0 && l.velocity == 0.0 && l.effort == 0.0);
    let default = || {
        let mut x = 0.0_f64;
        if has_limit && j.joint_type != JointType::Continuous {
            if l.lower.is_finite() {
                x = x.max(l.lower);
            }
            if l.upper.is_finite() {
                x = x.min(l.upper);
            }
        }
        x
    };
    let x = frozen_at.unwrap_or_else(default);
    if !x.is_finite() {
        return Err(ModelError::InvalidValue {
            field: format!("joints.{}.frozen_at", j.name),
            value: x,
            reason: "must be finite",
        });
    }
    let axis = || {
        let a = Vector3::from(*j.axis.xyz);
        let n = a.norm();
        if n.is_finite() && n > 1e-9 {
            Ok(Unit::new_normalize(a))
        } else {
            Err(ModelError::InvalidValue {
                field: format!("joint `{}` axis", j.name),
                value: n,
                reason: "axis must have non-zero finite length",
            })
        }
    };
    match j.joint_type {
        JointType::Fixed => Ok(Isometry3::identity()),
        JointType::Revolute | JointType::Continuous => Ok(Isometry3::from_parts(
            Translation3::identity(),
            UnitQuaternion::from_axis_angle(&axis()?, x),
        )),
        JointType::Prismatic => Ok(Isometry3::from_parts(
            Translation3::from(axis()?.into_inner() * x),
            UnitQuaternion::identity(),
        )),
        ref t => Err(ModelError::Invalid(format!(
            "URDF joint `{}` of type {t:?} is not supported (only revolute, continuous, prismatic and fixed)",
            j.name
        ))),
    }
}
