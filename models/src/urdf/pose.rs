//! Poses: URDF origins as isometries, and roll-pitch-yaw of a rotation.

use crate::error::ModelError;
use crate::robot::PoseSpec;
use nalgebra::{Isometry3, Rotation3};

pub(super) fn urdf_pose_iso(
    p: &urdf_rs::Pose,
    field: impl Fn() -> String,
) -> Result<Isometry3<f64>, ModelError> {
    for (i, v) in p.xyz.iter().chain(p.rpy.iter()).enumerate() {
        if !v.is_finite() {
            let which = if i < 3 { "xyz" } else { "rpy" };
            return Err(ModelError::InvalidValue {
                field: format!("{}.{which}[{}]", field(), i % 3),
                value: *v,
                reason: "must be finite",
            });
        }
    }
    Ok(PoseSpec {
        xyz: *p.xyz,
        rpy: *p.rpy,
    }
    .to_isometry())
}

/// Roll-pitch-yaw (R = Rz(yaw)·Ry(pitch)·Rx(roll)) of a rotation, accurate also near pitch = ±π/2:
/// yaw and pitch from the first column, roll from what remains.
pub fn rpy_of(r: &Rotation3<f64>) -> [f64; 3] {
    let m = r.matrix();
    let yaw = m[(1, 0)].atan2(m[(0, 0)]);
    let pitch = (-m[(2, 0)]).atan2(m[(0, 0)].hypot(m[(1, 0)]));
    let zy = Rotation3::from_euler_angles(0.0, pitch, yaw);
    let rest = zy.inverse() * r; // ≈ Rx(roll)
    let roll = rest.matrix()[(2, 1)].atan2(rest.matrix()[(1, 1)]);
    [roll, pitch, yaw]
}

pub(super) fn iso_to_pose(iso: &Isometry3<f64>) -> PoseSpec {
    PoseSpec {
        xyz: iso.translation.vector.into(),
        rpy: rpy_of(&iso.rotation.to_rotation_matrix()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rpy_round_trip_including_gimbal_lock() {
        let mut seed = 0x1234_5678_9abc_def0_u64;
        let mut rnd = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let half_pi = std::f64::consts::FRAC_PI_2;
        for k in 0..2000 {
            let pitch = match k % 4 {
                0 => half_pi - 1e-9 * rnd().abs(),
                1 => -half_pi,
                2 => half_pi,
                _ => half_pi * rnd(),
            };
            let r = Rotation3::from_euler_angles(3.0 * rnd(), pitch, 3.0 * rnd());
            let back = PoseSpec {
                xyz: [0.0; 3],
                rpy: rpy_of(&r),
            }
            .to_isometry()
            .rotation
            .to_rotation_matrix();
            let err = (back.matrix() - r.matrix()).abs().max();
            assert!(err < 1e-14, "k={k} err={err}");
        }
    }
}
