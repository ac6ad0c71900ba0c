//! Serial-chain robot models: joints, limits, link capsules and inertials, and the built-in FR3.

use crate::error::{ModelError, finite, non_negative, positive};
use crate::shape::{Capsule, CapsuleSpec};
use nalgebra::{Isometry3, Matrix3, Point3, Translation3, Unit, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

/// Largest number of joints a model may have (fixed-size buffers in hot paths use this).
pub const MAX_DOF: usize = 16;

/// Largest reach (m) of a robot model from the world origin: the base offset, the joint offsets
/// along the chain and the farthest capsule point (radius included) or centre of mass. Finite
/// but astronomical offsets (a unit mistake, `1e300`) would overflow forward kinematics,
/// distances and energies into `inf`/NaN; such a model is refused instead.
pub const MAX_REACH: f64 = 1.0e6;

/// A rigid pose as URDF writes it: translation `xyz` (m) then roll-pitch-yaw `rpy` (rad, fixed axes X, Y, Z).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct PoseSpec {
    /// Translation (m).
    #[serde(default)]
    pub xyz: [f64; 3],
    /// Roll, pitch, yaw (rad): R = Rz(yaw)·Ry(pitch)·Rx(roll).
    #[serde(default)]
    pub rpy: [f64; 3],
}

impl PoseSpec {
    fn validate(&self, field: &str) -> Result<Isometry3<f64>, ModelError> {
        for (i, v) in self.xyz.iter().enumerate() {
            finite(|| format!("{field}.xyz[{i}]"), *v)?;
        }
        for (i, v) in self.rpy.iter().enumerate() {
            finite(|| format!("{field}.rpy[{i}]"), *v)?;
        }
        Ok(self.to_isometry())
    }

    /// The pose as an isometry (parent ← child).
    pub fn to_isometry(&self) -> Isometry3<f64> {
        let [x, y, z] = self.xyz;
        let [r, p, yaw] = self.rpy;
        Isometry3::from_parts(
            Translation3::new(x, y, z),
            UnitQuaternion::from_euler_angles(r, p, yaw),
        )
    }
}

/// Per-joint kinematic limits as written in a model file (rad, rad/s, rad/s², rad/s³).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointLimitSpec {
    /// Lower position limit (rad).
    pub q_min: f64,
    /// Upper position limit (rad).
    pub q_max: f64,
    /// Velocity limit (rad/s), symmetric.
    pub v_max: f64,
    /// Acceleration limit (rad/s²), symmetric.
    pub a_max: f64,
    /// Jerk limit (rad/s³), symmetric.
    pub j_max: f64,
}

/// One revolute joint of the chain as written in a model file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointSpec {
    /// Unique joint name.
    pub name: String,
    /// Pose of this joint's frame in the previous joint's frame (or the base frame) at q = 0.
    #[serde(default)]
    pub origin: PoseSpec,
    /// Rotation axis in the joint frame (normalised at load; default +z).
    #[serde(default = "default_axis")]
    pub axis: [f64; 3],
    /// Kinematic limits of this joint.
    pub limits: JointLimitSpec,
}

fn default_axis() -> [f64; 3] {
    [0.0, 0.0, 1.0]
}

/// Mass properties of a link: mass (kg), centre of mass (m) and inertia about the centre of mass
/// (kg·m², URDF order `[ixx, ixy, ixz, iyy, iyz, izz]`), both in the link frame.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InertialSpec {
    /// Mass (kg).
    pub mass: f64,
    /// Centre of mass in the link frame (m).
    pub com: [f64; 3],
    /// Inertia tensor about the centre of mass, link-frame axes (kg·m²).
    pub inertia: [f64; 6],
}

/// A rigid link as written in a model file: fixed to the frame of `parent` (`"base"` or a joint name).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinkSpec {
    /// Unique link name.
    pub name: String,
    /// `"base"` or the name of the joint whose frame carries this link.
    pub parent: String,
    /// Pose of the link frame in the parent frame (default identity).
    #[serde(default)]
    pub origin: PoseSpec,
    /// Collision capsules in the link frame.
    #[serde(default)]
    pub capsules: Vec<CapsuleSpec>,
    /// Mass properties (absent: massless).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub inertial: Option<InertialSpec>,
}

/// A robot as written in a model file (JSON or TOML); [`RobotModel::new`] validates it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotSpec {
    /// Robot name.
    pub name: String,
    /// Pose of the robot base in the world frame (default identity).
    #[serde(default)]
    pub base: PoseSpec,
    /// Revolute joints from base to tip.
    pub joints: Vec<JointSpec>,
    /// Links with their capsules and inertials.
    pub links: Vec<LinkSpec>,
}

/// Joint limits as arrays over the joints; checked once at load (`q_min <= q_max`, all finite,
/// velocity, acceleration and jerk limits `> 0`).
#[derive(Debug, Clone, PartialEq)]
pub struct JointLimits {
    q_min: Vec<f64>,
    q_max: Vec<f64>,
    v_max: Vec<f64>,
    a_max: Vec<f64>,
    j_max: Vec<f64>,
}

impl JointLimits {
    /// Build from arrays, validating every entry (names the index and value on error).
    pub fn new(
        q_min: Vec<f64>,
        q_max: Vec<f64>,
        v_max: Vec<f64>,
        a_max: Vec<f64>,
        j_max: Vec<f64>,
    ) -> Result<Self, ModelError> {
        let n = q_min.len();
        if n == 0 || n > MAX_DOF {
            return Err(ModelError::Invalid(format!(
                "joint count {n} not in 1..={MAX_DOF}"
            )));
        }
        for (name, v) in [
            ("q_max", &q_max),
            ("v_max", &v_max),
            ("a_max", &a_max),
            ("j_max", &j_max),
        ] {
            if v.len() != n {
                return Err(ModelError::LengthMismatch {
                    field: format!("limits.{name}"),
                    expected: n,
                    found: v.len(),
                });
            }
        }
        for i in 0..n {
            finite(|| format!("limits.q_min[{i}]"), q_min[i])?;
            finite(|| format!("limits.q_max[{i}]"), q_max[i])?;
            if q_min[i] > q_max[i] {
                return Err(ModelError::InvalidValue {
                    field: format!("limits.q_max[{i}]"),
                    value: q_max[i],
                    reason: "must be >= q_min",
                });
            }
            positive(|| format!("limits.v_max[{i}]"), v_max[i])?;
            positive(|| format!("limits.a_max[{i}]"), a_max[i])?;
            positive(|| format!("limits.j_max[{i}]"), j_max[i])?;
        }
        Ok(Self {
            q_min,
            q_max,
            v_max,
            a_max,
            j_max,
        })
    }

    /// Number of joints.
    #[inline]
    pub fn dof(&self) -> usize {
        self.q_min.len()
    }
    /// Lower position limits (rad).
    #[inline]
    pub fn q_min(&self) -> &[f64] {
        &self.q_min
    }
    /// Upper position limits (rad).
    #[inline]
    pub fn q_max(&self) -> &[f64] {
        &self.q_max
    }
    /// Velocity limits (rad/s).
    #[inline]
    pub fn v_max(&self) -> &[f64] {
        &self.v_max
    }
    /// Acceleration limits (rad/s²).
    #[inline]
    pub fn a_max(&self) -> &[f64] {
        &self.a_max
    }
    /// Jerk limits (rad/s³).
    #[inline]
    pub fn j_max(&self) -> &[f64] {
        &self.j_max
    }

    /// Velocity, acceleration and jerk limits multiplied by the given factors in (0, 1];
    /// position limits unchanged.
    pub fn scaled(&self, v: f64, a: f64, j: f64) -> Result<Self, ModelError> {
        for (name, f) in [("v", v), ("a", a), ("j", j)] {
            if !(f > 0.0 && f <= 1.0) {
                return Err(ModelError::InvalidValue {
                    field: format!("limit_scale.{name}"),
                    value: f,
                    reason: "must be in (0, 1]",
                });
            }
        }
        Ok(Self {
            q_min: self.q_min.clone(),
            q_max: self.q_max.clone(),
            v_max: self.v_max.iter().map(|x| x * v).collect(),
            a_max: self.a_max.iter().map(|x| x * a).collect(),
            j_max: self.j_max.iter().map(|x| x * j).collect(),
        })
    }

    /// Replace acceleration and jerk limits by uniform values (e.g. the paper's 10 rad/s², 400 rad/s³),
    /// never above the current ones.
    pub fn with_uniform_acc_jerk(&self, a: f64, j: f64) -> Result<Self, ModelError> {
        positive(|| "a_max".into(), a)?;
        positive(|| "j_max".into(), j)?;
        let mut out = self.clone();
        out.a_max.iter_mut().for_each(|x| *x = x.min(a));
        out.j_max.iter_mut().for_each(|x| *x = x.min(j));
        Ok(out)
    }

    /// True iff every `q[i]` lies within `[q_min[i], q_max[i]]`.
    pub fn contains(&self, q: &[f64]) -> bool {
        q.len() == self.dof()
            && q.iter()
                .zip(self.q_min.iter().zip(&self.q_max))
                .all(|(x, (lo, hi))| *lo <= *x && *x <= *hi)
    }
}

/// Validated mass properties, expressed in the frame of the joint that carries the link.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Inertial {
    /// Mass (kg), `>= 0`.
    pub mass: f64,
    /// Centre of mass in the carrying joint frame (m).
    pub com: Point3<f64>,
    /// Inertia about the centre of mass, carrying-joint-frame axes (kg·m², symmetric PSD).
    pub inertia: Matrix3<f64>,
}

/// A validated revolute joint.
#[derive(Debug, Clone, PartialEq)]
pub struct Joint {
    /// Joint name.
    pub name: String,
    /// Pose of the joint frame in the previous frame at q = 0.
    pub origin: Isometry3<f64>,
    /// Unit rotation axis in the joint frame.
    pub axis: Unit<Vector3<f64>>,
}

/// A validated link: capsules and inertial already expressed in the carrying frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Link {
    /// Link name.
    pub name: String,
    /// Carrying frame: 0 = base, i = frame after joint i (1-based).
    pub frame: usize,
    /// Collision capsules in the carrying frame.
    pub capsules: Vec<Capsule>,
    /// Mass properties in the carrying frame (None: massless).
    pub inertial: Option<Inertial>,
}

/// A validated serial-chain robot. Frames are numbered 0 (base) to n (after the last joint).
#[derive(Debug, Clone, PartialEq)]
pub struct RobotModel {
    spec: RobotSpec,
    base: Isometry3<f64>,
    joints: Vec<Joint>,
    links: Vec<Link>,
    limits: JointLimits,
}

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
        Ok(Self {
            spec,
            base,
            joints,
            links,
            limits,
        })
    }

    /// Parse a JSON robot spec and validate it.
    pub fn from_json(text: &str) -> Result<Self, ModelError> {
        Self::new(crate::error::parse_json(text)?)
    }

    /// Parse a TOML robot spec and validate it.
    pub fn from_toml(text: &str) -> Result<Self, ModelError> {
        Self::new(crate::error::parse_toml(text)?)
    }

    /// A built-in robot by name (`"fr3"`).
    pub fn builtin(name: &str) -> Result<Self, ModelError> {
        match name {
            "fr3" | "FR3" => Ok(crate::fr3::fr3()),
            other => Err(ModelError::UnknownName {
                kind: "robot",
                name: other.into(),
                field: "robot".into(),
            }),
        }
    }

    /// The spec this model was built from (what `pacs robot show` prints).
    pub fn spec(&self) -> &RobotSpec {
        &self.spec
    }
    /// Robot name.
    pub fn name(&self) -> &str {
        &self.spec.name
    }
    /// Number of joints.
    #[inline]
    pub fn dof(&self) -> usize {
        self.joints.len()
    }
    /// Base pose in the world frame.
    #[inline]
    pub fn base(&self) -> &Isometry3<f64> {
        &self.base
    }
    /// Joints from base to tip.
    #[inline]
    pub fn joints(&self) -> &[Joint] {
        &self.joints
    }
    /// Links (any order; each names its carrying frame).
    #[inline]
    pub fn links(&self) -> &[Link] {
        &self.links
    }
    /// Joint limits.
    #[inline]
    pub fn limits(&self) -> &JointLimits {
        &self.limits
    }
    /// Index of the link with this name.
    pub fn link_index(&self, name: &str) -> Option<usize> {
        self.links.iter().position(|l| l.name == name)
    }
    /// Total number of link capsules.
    pub fn capsule_count(&self) -> usize {
        self.links.iter().map(|l| l.capsules.len()).sum()
    }
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
