//! URDF links: collision primitives converted into containing capsules, and inertials in the
//! link frame.

use super::pose::urdf_pose_iso;
use crate::error::ModelError;
use crate::robot::InertialSpec;
use crate::shape::CapsuleSpec;
use nalgebra::{Matrix3, Point3, Vector3};

/// The capsules containing a URDF link's primitive collision geometry (sphere, cylinder, capsule, box)
/// in the link frame; mesh collisions are skipped (fitted by `pacs-mesh`, reviewed in a side file).
pub fn collision_capsules(link: &urdf_rs::Link) -> Result<Vec<CapsuleSpec>, ModelError> {
    let mut out = Vec::new();
    for (ci, c) in link.collision.iter().enumerate() {
        let field = || format!("link `{}` collision[{ci}]", link.name);
        let t = urdf_pose_iso(&c.origin, || format!("{} origin", field()))?;
        let seg = |half: Vector3<f64>, radius: f64| -> Result<CapsuleSpec, ModelError> {
            if !(radius.is_finite() && radius >= 0.0 && half.iter().all(|v| v.is_finite())) {
                return Err(ModelError::InvalidValue {
                    field: field(),
                    value: radius,
                    reason: "collision geometry dimensions must be finite and >= 0",
                });
            }
            let p1 = t * Point3::from(-half);
            let p2 = t * Point3::from(half);
            Ok(CapsuleSpec {
                p1: p1.coords.into(),
                p2: p2.coords.into(),
                radius,
            })
        };
        match &c.geometry {
            urdf_rs::Geometry::Sphere { radius } => out.push(seg(Vector3::zeros(), *radius)?),
            urdf_rs::Geometry::Cylinder { radius, length }
            | urdf_rs::Geometry::Capsule { radius, length } => {
                out.push(seg(Vector3::new(0.0, 0.0, length / 2.0), *radius)?)
            }
            urdf_rs::Geometry::Box { size } => {
                let s = *size;
                if !s.iter().all(|v| v.is_finite() && *v >= 0.0) {
                    return Err(ModelError::InvalidValue {
                        field: format!("{}.box.size", field()),
                        value: s.iter().copied().fold(f64::NAN, f64::min),
                        reason: "box size must be finite and >= 0",
                    });
                }
                // Longest edge k: segment ±s_k/2 along it; radius = half-diagonal of the other two.
                let k = (0..3).fold(0, |best, i| if s[i] > s[best] { i } else { best });
                let (a, b) = ((k + 1) % 3, (k + 2) % 3);
                let mut half = Vector3::zeros();
                half[k] = s[k] / 2.0;
                out.push(seg(half, 0.5 * s[a].hypot(s[b]))?);
            }
            urdf_rs::Geometry::Mesh { .. } => {}
        }
    }
    Ok(out)
}

pub(super) fn urdf_inertial(link: &urdf_rs::Link) -> Result<Option<InertialSpec>, ModelError> {
    let i = &link.inertial;
    let t = &i.inertia;
    let vals = [t.ixx, t.ixy, t.ixz, t.iyy, t.iyz, t.izz];
    if i.mass.value == 0.0 && vals.iter().all(|v| *v == 0.0) {
        return Ok(None);
    }
    let iso = urdf_pose_iso(&i.origin, || {
        format!("link `{}` inertial origin", link.name)
    })?;
    let m = Matrix3::new(
        t.ixx, t.ixy, t.ixz, t.ixy, t.iyy, t.iyz, t.ixz, t.iyz, t.izz,
    );
    let inertia = if i.origin.rpy.iter().all(|v| *v == 0.0) {
        vals
    } else {
        let r = iso.rotation.to_rotation_matrix();
        let ml = r.matrix() * m * r.matrix().transpose();
        [
            ml[(0, 0)],
            ml[(0, 1)],
            ml[(0, 2)],
            ml[(1, 1)],
            ml[(1, 2)],
            ml[(2, 2)],
        ]
    };
    Ok(Some(InertialSpec {
        mass: i.mass.value,
        com: *i.origin.xyz,
        inertia,
    }))
}
