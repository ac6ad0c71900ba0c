//! [`RobotModel::new`]: a spec validated into a model (poses, axes, limits, names, parents,
//! capsules, inertials and the reach bound).

use super::{
    Inertial, InertialSpec, Joint, JointLimitSpec, JointLimits, Link, MAX_DOF, MAX_REACH,
    RobotModel, RobotSpec,
};
use crate::error::{ModelError, finite, non_negative, positive};
use crate::shape::Capsule;
use nalgebra::{Isometry3, Matrix3, Point3, Unit, Vector3};

impl RobotModel {
    /// Validate a spec: finite poses, unit-normalisable axes, admissible limits, unique names,
    /// known parents, PSD inertias, non-negative masses and radii.
    pub fn new(spec: RobotSpec) -> Result<Self, ModelError> {
        let base = spec.base.validate("base")?;
        let n = spec.joints.len();
        if n == 0 || n > MAX_DOF {
            return Err(ModelError::Invalid(format!(
                "joint count {n} not in 1..={MAX_DOF}"
            )));
        }
        let mut joints = Vec::with_capacity(n);
        for (i, j) in spec.joints.iter().enumerate() {
            if spec.joints[..i].iter().any(|o| o.name == j.name) {
                return Err(ModelError::DuplicateName {
                    kind: "joint",
                    name: j.name.clone(),
                });
            }
            let origin = j.origin.validate(&format!("joints[{i}].origin"))?;
            let axis = Vector3::from(j.axis);
            for (k, v) in j.axis.iter().enumerate() {
                finite(|| format!("joints[{i}].axis[{k}]"), *v)?;
            }
            let norm = axis.norm();
            // `norm` overflows to +inf for huge components; normalising would then give a degenerate axis.
            if !norm.is_finite() || norm <= 1e-9 {
                return Err(ModelError::InvalidValue {
                    field: format!("joints[{i}].axis"),
                    value: norm,
                    reason: "axis must have non-zero finite length",
                });
            }
            joints.push(Joint {
                name: j.name.clone(),
                origin,
                axis: Unit::new_normalize(axis),
            });
        }
        for (i, j) in spec.joints.iter().enumerate() {
            let l = &j.limits;
            finite(|| format!("joints[{i}].limits.q_min"), l.q_min)?;
            finite(|| format!("joints[{i}].limits.q_max"), l.q_max)?;
            if l.q_min > l.q_max {
                return Err(ModelError::InvalidValue {
                    field: format!("joints[{i}].limits.q_max"),
                    value: l.q_max,
                    reason: "must be >= q_min",
                });
            }
            positive(|| format!("joints[{i}].limits.v_max"), l.v_max)?;
            positive(|| format!("joints[{i}].limits.a_max"), l.a_max)?;
            positive(|| format!("joints[{i}].limits.j_max"), l.j_max)?;
        }
        let lim = |f: fn(&JointLimitSpec) -> f64| {
            spec.joints.iter().map(|j| f(&j.limits)).collect::<Vec<_>>()
        };
        let limits = JointLimits::new(
            lim(|l| l.q_min),
            lim(|l| l.q_max),
            lim(|l| l.v_max),
            lim(|l| l.a_max),
            lim(|l| l.j_max),
        )?;
        let mut links = Vec::with_capacity(spec.links.len());
        let mut link_origins = Vec::with_capacity(spec.links.len());
        for (li, l) in spec.links.iter().enumerate() {
            if spec.links[..li].iter().any(|o| o.name == l.name) {
                return Err(ModelError::DuplicateName {
                    kind: "link",
                    name: l.name.clone(),
                });
            }
            let frame = if l.parent == "base" {
                0
            } else {
                1 + spec
                    .joints
                    .iter()
                    .position(|j| j.name == l.parent)
                    .ok_or_else(|| ModelError::UnknownName {
                        kind: "joint",
                        name: l.parent.clone(),
                        field: format!("links[{li}].parent"),
                    })?
            };
            let origin = l.origin.validate(&format!("links[{li}].origin"))?;
            link_origins.push(origin);
            if l.frame && !l.capsules.is_empty() {
                return Err(ModelError::Invalid(format!(
                    "links[{li}] (`{}`): `frame: true` marks a link without capsules, but it has {}",
                    l.name,
                    l.capsules.len()
                )));
            }
            let mut capsules = Vec::with_capacity(l.capsules.len());
            for (ci, c) in l.capsules.iter().enumerate() {
                let cap = Capsule::try_from(*c)
                    .map_err(|e| prefix(e, &format!("links[{li}].capsules[{ci}].")))?;
                capsules.push(cap.transformed(&origin));
            }
            let inertial = match &l.inertial {
                None => None,
                Some(s) => Some(validate_inertial(
                    s,
                    &origin,
                    &format!("links[{li}].inertial"),
                )?),
            };
            links.push(Link {
                name: l.name.clone(),
                frame,
                capsules,
                inertial,
            });
        }
        check_reach(&base, &joints, &links, &link_origins)?;
        check_covered(&spec, &links)?;
        Ok(Self {
            spec,
            base,
            joints,
            links,
            limits,
        })
    }
}

/// Refuse moving links (carried by a joint) with mass but no capsules unless marked `frame`:
/// nothing could ever be found touching them, so every check would pass whatever they hit.
fn check_covered(spec: &RobotSpec, links: &[Link]) -> Result<(), ModelError> {
    let uncovered: Vec<(String, f64)> = links
        .iter()
        .zip(&spec.links)
        .filter(|(l, s)| l.frame != 0 && l.capsules.is_empty() && !s.frame)
        .filter_map(|(l, _)| {
            l.inertial
                .filter(|i| i.mass > 0.0)
                .map(|i| (l.name.clone(), i.mass))
        })
        .collect();
    if !uncovered.is_empty() {
        return Err(ModelError::UncoveredLinks {
            robot: spec.name.clone(),
            links: uncovered,
        });
    }
    // A `frame` mark states that the link has no body outside other links' capsules; its mass
    // must then at least sit inside one: the centre of mass within a capsule of another link on
    // the same joint (a necessary condition, so a massive link cannot be marked away).
    for (li, (l, s)) in links.iter().zip(&spec.links).enumerate() {
        let Some(i) = l.inertial.filter(|i| i.mass > 0.0) else {
            continue;
        };
        if !(s.frame && l.frame != 0) {
            continue;
        }
        let inside = links
            .iter()
            .enumerate()
            .filter(|(m, o)| *m != li && o.frame == l.frame)
            .flat_map(|(_, o)| o.capsules.iter())
            .any(|c| point_in_capsule(&i.com, c));
        if !inside {
            return Err(ModelError::Invalid(format!(
                "links[{li}] (`{}`): `frame: true` states that the link has no body outside other links' capsules, but its centre of mass ({:.4}, {:.4}, {:.4}) m ({} kg) lies outside every capsule of the other links on its joint: give it capsules (`pacs robot capsules` fits them to meshes) instead of the mark",
                l.name, i.com.x, i.com.y, i.com.z, i.mass
            )));
        }
    }
    Ok(())
}

/// Whether `p` lies in the capsule `c` (distance to its axis at most the radius, with a relative
/// allowance of 10⁻⁹ for rounding).
fn point_in_capsule(p: &nalgebra::Point3<f64>, c: &crate::Capsule) -> bool {
    let (a, b) = (c.p1(), c.p2());
    let ab = b - a;
    let l2 = ab.norm_squared();
    let t = if l2 > 0.0 {
        ((p - a).dot(&ab) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + ab * t)).norm() <= c.radius() * (1.0 + 1e-9) + 1e-12
}

/// Refuse a model that reaches farther than [`MAX_REACH`] from the world origin (see there),
/// naming the first offset (base, joint, link origin), capsule or centre of mass along the chain that does; the value is
/// the reach up to it. Every point of a link on frame k is within the sum of the base and joint
/// offsets up to k plus its distance from that frame's origin (rotations preserve lengths).
fn check_reach(
    base: &Isometry3<f64>,
    joints: &[Joint],
    links: &[Link],
    link_origins: &[Isometry3<f64>],
) -> Result<(), ModelError> {
    let check = |field: &dyn Fn() -> String, reach: f64| {
        if reach <= MAX_REACH {
            Ok(())
        } else {
            Err(ModelError::InvalidValue {
                field: field(),
                value: reach,
                reason: "the robot's reach from the world origin must be at most 1e6 m",
            })
        }
    };
    // Euclidean length without overflow in the squares (the value reported stays meaningful).
    let norm = |v: &Vector3<f64>| {
        let m = v.amax();
        if m > 0.0 { m * (v / m).norm() } else { 0.0 }
    };
    let mut cum = [0.0; MAX_DOF + 1];
    cum[0] = norm(&base.translation.vector);
    check(&|| "base.xyz".into(), cum[0])?;
    for (i, j) in joints.iter().enumerate() {
        cum[i + 1] = cum[i] + norm(&j.origin.translation.vector);
        check(&|| format!("joints[{i}].origin.xyz"), cum[i + 1])?;
    }
    for (li, (l, ls)) in links.iter().zip(link_origins).enumerate() {
        let origin = cum[l.frame] + norm(&ls.translation.vector);
        check(&|| format!("links[{li}].origin.xyz"), origin)?;
        for (ci, c) in l.capsules.iter().enumerate() {
            let far = norm(&c.p1().coords).max(norm(&c.p2().coords)) + c.radius();
            check(
                &|| format!("links[{li}].capsules[{ci}]"),
                cum[l.frame] + far,
            )?;
        }
        if let Some(i) = &l.inertial {
            check(
                &|| format!("links[{li}].inertial.com"),
                cum[l.frame] + norm(&i.com.coords),
            )?;
        }
    }
    Ok(())
}

fn prefix(e: ModelError, p: &str) -> ModelError {
    match e {
        ModelError::InvalidValue {
            field,
            value,
            reason,
        } => ModelError::InvalidValue {
            field: format!("{p}{field}"),
            value,
            reason,
        },
        other => other,
    }
}

fn validate_inertial(
    s: &InertialSpec,
    origin: &Isometry3<f64>,
    field: &str,
) -> Result<Inertial, ModelError> {
    non_negative(|| format!("{field}.mass"), s.mass)?;
    for (i, v) in s.com.iter().enumerate() {
        finite(|| format!("{field}.com[{i}]"), *v)?;
    }
    for (i, v) in s.inertia.iter().enumerate() {
        finite(|| format!("{field}.inertia[{i}]"), *v)?;
    }
    let [ixx, ixy, ixz, iyy, iyz, izz] = s.inertia;
    let m = Matrix3::new(ixx, ixy, ixz, ixy, iyy, iyz, ixz, iyz, izz);
    let eig = m.symmetric_eigenvalues();
    let scale = ixx.abs().max(iyy.abs()).max(izz.abs()).max(1e-300);
    if eig.iter().any(|&e| e < -1e-9 * scale) {
        return Err(ModelError::InvalidValue {
            field: format!("{field}.inertia"),
            value: eig.min(),
            reason: "inertia tensor must be positive semi-definite",
        });
    }
    let r = origin.rotation.to_rotation_matrix();
    Ok(Inertial {
        mass: s.mass,
        com: origin * Point3::from(s.com),
        inertia: r.matrix() * m * r.matrix().transpose(),
    })
}
