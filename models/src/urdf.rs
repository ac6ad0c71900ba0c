//! Loading robots from URDF plus a side file (TOML/JSON) with capsules and acceleration/jerk limits.
//!
//! The URDF gives the kinematic tree, position and velocity limits and inertials; the side file
//! ([`SideFile`]) picks the chain tip, gives what URDF lacks (acceleration and jerk limits,
//! collision capsules for mesh-only links, limits of continuous joints) and may override any limit,
//! capsule list or inertial. The format and every rule below are documented in `docs/models.md`.
//!
//! Rules:
//! - the chain runs from the URDF root link (the one link that is no joint's child) to the tip link
//!   (side file `tip`; default: the single leaf link, an error if there are several);
//! - revolute and continuous joints on that path become chain joints; fixed joints on it are merged
//!   (their child links become [`LinkSpec`]s carried by the last chain joint, or `"base"`);
//!   prismatic, floating, planar and spherical joints and `<mimic>` joints on it are rejected;
//! - joints off the path (gripper fingers, links beyond the tip) are frozen: fixed joints as they
//!   are, revolute/continuous/prismatic joints at `frozen_at` from the side file, default 0 clamped
//!   into their URDF position limits (so a Franka gripper is "closed"); their links keep their
//!   capsules and mass. Floating/planar/spherical joints off the path are rejected;
//! - capsules: a side-file `[links.NAME] capsules = [...]` list (link frame) replaces everything the
//!   URDF says about that link's collision geometry; otherwise URDF `<collision>` primitives are
//!   converted into capsules that contain them (sphere → ball; cylinder and URDF 1.2 capsule of
//!   length L, radius r → segment ±L/2 on the local z axis with radius r; box → segment along its
//!   longest edge with radius = half the diagonal of the other two edges); a link with a mesh
//!   collision and no side-file capsules is refused ([`ModelError::MeshCollision`]: a mesh cannot
//!   be bounded here, and dropping it would make SSM and PFL checks vacuous for that body);
//! - inertials: URDF `<inertial>` with its origin applied (centre of mass = origin xyz, inertia
//!   rotated into the link frame by the origin rpy); an all-zero `<inertial>` or none means
//!   massless; a side-file `inertial` (link frame) replaces the URDF one;
//! - limits: position and velocity from URDF `<limit>`, acceleration (min of URDF 1.2
//!   acceleration and deceleration) and jerk from URDF 1.2 if present; side-file values override:
//!   per-joint `[joints.NAME]` first, then the uniform `a_max` / `j_max`. A missing value is an error.

use crate::error::ModelError;
use crate::robot::{
    InertialSpec, JointLimitSpec, JointSpec, LinkSpec, PoseSpec, RobotModel, RobotSpec,
};
use crate::shape::CapsuleSpec;
use nalgebra::{
    Isometry3, Matrix3, Point3, Rotation3, Translation3, Unit, UnitQuaternion, Vector3,
};
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, HashMap};
use std::path::Path;
use urdf_rs::JointType;

/// Per-joint entries of a side file (`[joints.NAME]`); every field optional.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointOverride {
    /// Lower position limit (rad); required for continuous chain joints.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub q_min: Option<f64>,
    /// Upper position limit (rad); required for continuous chain joints.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub q_max: Option<f64>,
    /// Velocity limit (rad/s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub v_max: Option<f64>,
    /// Acceleration limit (rad/s²).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub a_max: Option<f64>,
    /// Jerk limit (rad/s³).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub j_max: Option<f64>,
    /// Only for joints off the chain: the position (rad or m) at which the joint is frozen.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frozen_at: Option<f64>,
}

/// Per-link entries of a side file (`[links.NAME]`).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinkOverride {
    /// Capsules in the URDF link frame; when present (even empty) they replace the URDF
    /// `<collision>` geometry of the link.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub capsules: Option<Vec<CapsuleSpec>>,
    /// Mass properties in the URDF link frame; when present they replace the URDF `<inertial>`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub inertial: Option<InertialSpec>,
}

/// What a URDF does not say (or says differently): tip link, acceleration/jerk limits, capsules.
/// Parse with [`SideFile::parse`] (JSON or TOML); unknown fields are errors.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SideFile {
    /// Robot name (default: the URDF `<robot name>`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Last link of the chain (default: the single leaf link of the URDF tree).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tip: Option<String>,
    /// Pose of the URDF root link in the world frame (default identity).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub base: Option<PoseSpec>,
    /// Acceleration limit (rad/s²) for every chain joint without a per-joint value.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub a_max: Option<f64>,
    /// Jerk limit (rad/s³) for every chain joint without a per-joint value.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub j_max: Option<f64>,
    /// Per-joint overrides by URDF joint name.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub joints: BTreeMap<String, JointOverride>,
    /// Per-link capsules / inertials by URDF link name.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub links: BTreeMap<String, LinkOverride>,
}

impl SideFile {
    /// Parse a side file from JSON (text starting with `{`) or TOML.
    pub fn parse(text: &str) -> Result<Self, ModelError> {
        crate::parse_json_or_toml(text)
    }
}

/// Load a robot from URDF text and a side file, and validate it with [`RobotModel::new`].
/// Validation errors name the spec field and, in brackets, the URDF joint or link.
pub fn load_urdf(urdf_text: &str, side: &SideFile) -> Result<RobotModel, ModelError> {
    let spec = urdf_to_spec(urdf_text, side)?;
    RobotModel::new(spec.clone()).map_err(|e| with_names(e, &spec))
}

/// Load a robot from a URDF file and an optional side file (JSON or TOML).
pub fn load_urdf_files(
    urdf_path: &Path,
    side_path: Option<&Path>,
) -> Result<RobotModel, ModelError> {
    let read = |p: &Path| {
        std::fs::read_to_string(p)
            .map_err(|e| ModelError::Invalid(format!("cannot read `{}`: {e}", p.display())))
    };
    let urdf = read(urdf_path)?;
    let side = match side_path {
        Some(p) => SideFile::parse(&read(p)?)?,
        None => SideFile::default(),
    };
    load_urdf(&urdf, &side)
}

/// Convert URDF text plus a side file into a (not yet validated) [`RobotSpec`].
pub fn urdf_to_spec(urdf_text: &str, side: &SideFile) -> Result<RobotSpec, ModelError> {
    let robot = urdf_rs::read_from_string(urdf_text).map_err(|e| ModelError::Parse {
        format: "URDF",
        message: e.to_string(),
    })?;
    Tree::new(&robot, side)?.to_spec(side)
}

struct Tree<'a> {
    robot: &'a urdf_rs::Robot,
    link_index: HashMap<&'a str, usize>,
    /// Joints whose parent is link i (URDF order).
    child_joints: Vec<Vec<usize>>,
    root: usize,
    /// Joints on the path root → tip.
    on_path: Vec<bool>,
}

impl<'a> Tree<'a> {
    fn new(robot: &'a urdf_rs::Robot, side: &SideFile) -> Result<Self, ModelError> {
        let mut link_index = HashMap::new();
        for (i, l) in robot.links.iter().enumerate() {
            if link_index.insert(l.name.as_str(), i).is_some() {
                return Err(ModelError::DuplicateName {
                    kind: "URDF link",
                    name: l.name.clone(),
                });
            }
        }
        if robot.links.is_empty() {
            return Err(ModelError::Invalid("URDF has no links".into()));
        }
        let mut joint_names = HashMap::new();
        let mut parent_joint: Vec<Option<usize>> = vec![None; robot.links.len()];
        let mut child_joints = vec![Vec::new(); robot.links.len()];
        for (ji, j) in robot.joints.iter().enumerate() {
            if joint_names.insert(j.name.as_str(), ji).is_some() {
                return Err(ModelError::DuplicateName {
                    kind: "URDF joint",
                    name: j.name.clone(),
                });
            }
            let find = |name: &str, what: &str| {
                link_index
                    .get(name)
                    .copied()
                    .ok_or_else(|| ModelError::UnknownName {
                        kind: "link",
                        name: name.into(),
                        field: format!("joint `{}` {what}", j.name),
                    })
            };
            let p = find(&j.parent.link, "parent")?;
            let c = find(&j.child.link, "child")?;
            if let Some(other) = parent_joint[c] {
                return Err(ModelError::Invalid(format!(
                    "URDF link `{}` is the child of two joints (`{}` and `{}`)",
                    j.child.link, robot.joints[other].name, j.name
                )));
            }
            parent_joint[c] = Some(ji);
            child_joints[p].push(ji);
        }
        let roots: Vec<usize> = (0..robot.links.len())
            .filter(|&i| parent_joint[i].is_none())
            .collect();
        if roots.len() != 1 {
            let names: Vec<&str> = roots
                .iter()
                .map(|&i| robot.links[i].name.as_str())
                .collect();
            return Err(ModelError::Invalid(format!(
                "URDF must have exactly one root link (a link that is no joint's child); found {names:?}"
            )));
        }
        let root = roots[0];
        // Every link must hang below the root (rules out detached cycles).
        let mut seen = vec![false; robot.links.len()];
        let mut stack = vec![root];
        while let Some(l) = stack.pop() {
            seen[l] = true;
            stack.extend(
                child_joints[l]
                    .iter()
                    .map(|&j| link_index[robot.joints[j].child.link.as_str()]),
            );
        }
        if let Some(i) = seen.iter().position(|s| !s) {
            return Err(ModelError::Invalid(format!(
                "URDF link `{}` is not connected to the root link `{}`",
                robot.links[i].name, robot.links[root].name
            )));
        }
        for name in side.joints.keys() {
            if !joint_names.contains_key(name.as_str()) {
                return Err(ModelError::UnknownName {
                    kind: "URDF joint",
                    name: name.clone(),
                    field: "joints".into(),
                });
            }
        }
        for name in side.links.keys() {
            if !link_index.contains_key(name.as_str()) {
                return Err(ModelError::UnknownName {
                    kind: "URDF link",
                    name: name.clone(),
                    field: "links".into(),
                });
            }
        }
        let tip = match &side.tip {
            Some(t) => *link_index
                .get(t.as_str())
                .ok_or_else(|| ModelError::UnknownName {
                    kind: "URDF link",
                    name: t.clone(),
                    field: "tip".into(),
                })?,
            None => {
                let leaves: Vec<usize> = (0..robot.links.len())
                    .filter(|&i| child_joints[i].is_empty())
                    .collect();
                if leaves.len() != 1 {
                    let names: Vec<&str> = leaves
                        .iter()
                        .map(|&i| robot.links[i].name.as_str())
                        .collect();
                    return Err(ModelError::Invalid(format!(
                        "URDF has {} leaf links {names:?}; name the chain's last link with `tip` in the side file",
                        leaves.len()
                    )));
                }
                leaves[0]
            }
        };
        let mut on_path = vec![false; robot.joints.len()];
        let mut l = tip;
        while let Some(j) = parent_joint[l] {
            on_path[j] = true;
            l = link_index[robot.joints[j].parent.link.as_str()];
        }
        Ok(Self {
            robot,
            link_index,
            child_joints,
            root,
            on_path,
        })
    }

    fn to_spec(&self, side: &SideFile) -> Result<RobotSpec, ModelError> {
        let robot = self.robot;
        let mut joints = Vec::new();
        let mut links = Vec::new();
        // (link, carrying frame name, pose of the link frame in the carrying frame; None = identity)
        let mut stack: Vec<(usize, String, Option<Isometry3<f64>>)> =
            vec![(self.root, "base".into(), None)];
        let mut mesh_links = Vec::new();
        while let Some((li, carrier, acc)) = stack.pop() {
            match self.link_spec(li, &carrier, acc, side) {
                Ok(l) => links.push(l),
                Err(ModelError::MeshCollision { links: l }) => mesh_links.extend(l),
                Err(e) => return Err(e),
            }
            // Push children in reverse so that they are visited in URDF order.
            for &ji in self.child_joints[li].iter().rev() {
                let j = &robot.joints[ji];
                let child = self.link_index[j.child.link.as_str()];
                let origin = urdf_pose_iso(&j.origin, || format!("joint `{}` origin", j.name))?;
                let to_joint = acc.map_or(origin, |a| a * origin);
                let ov = side.joints.get(&j.name).copied().unwrap_or_default();
                if self.on_path[ji] {
                    match j.joint_type {
                        JointType::Revolute | JointType::Continuous => {
                            if ov.frozen_at.is_some() {
                                return Err(ModelError::Invalid(format!(
                                    "side file `joints.{}.frozen_at`: joint is on the chain, only off-chain joints can be frozen",
                                    j.name
                                )));
                            }
                            if let Some(m) = &j.mimic {
                                return Err(ModelError::Invalid(format!(
                                    "URDF joint `{}` on the chain mimics `{}`; coupled (mimic) chain joints are not supported",
                                    j.name, m.joint
                                )));
                            }
                            let pose = match acc {
                                None => PoseSpec {
                                    xyz: *j.origin.xyz,
                                    rpy: *j.origin.rpy,
                                },
                                Some(_) => iso_to_pose(&to_joint),
                            };
                            joints.push(JointSpec {
                                name: j.name.clone(),
                                origin: pose,
                                axis: *j.axis.xyz,
                                limits: chain_limits(j, &ov, side)?,
                            });
                            stack.push((child, j.name.clone(), None));
                        }
                        JointType::Fixed => stack.push((child, carrier.clone(), Some(to_joint))),
                        ref t => {
                            return Err(ModelError::Invalid(format!(
                                "URDF joint `{}` of type {t:?} lies on the chain from `{}` to the tip; only revolute, \
                                 continuous and fixed joints are supported there",
                                j.name, robot.links[self.root].name
                            )));
                        }
                    }
                } else {
                    if ov.q_min.is_some()
                        || ov.q_max.is_some()
                        || ov.v_max.is_some()
                        || ov.a_max.is_some()
                        || ov.j_max.is_some()
                    {
                        return Err(ModelError::Invalid(format!(
                            "side file `joints.{}`: joint is not on the chain (it is frozen); only `frozen_at` applies",
                            j.name
                        )));
                    }
                    let motion = frozen_motion(j, ov.frozen_at)?;
                    stack.push((child, carrier.clone(), Some(to_joint * motion)));
                }
            }
        }
        if !mesh_links.is_empty() {
            return Err(ModelError::MeshCollision { links: mesh_links });
        }
        Ok(RobotSpec {
            name: side.name.clone().unwrap_or_else(|| robot.name.clone()),
            base: side.base.unwrap_or_default(),
            joints,
            links,
        })
    }

    fn link_spec(
        &self,
        li: usize,
        carrier: &str,
        acc: Option<Isometry3<f64>>,
        side: &SideFile,
    ) -> Result<LinkSpec, ModelError> {
        let link = &self.robot.links[li];
        let ov = side.links.get(&link.name);
        let capsules = match ov.and_then(|o| o.capsules.clone()) {
            Some(c) => c,
            None => {
                // A mesh cannot be bounded here: a link whose collision geometry includes one
                // needs side-file capsules, else SSM/PFL would silently ignore that body.
                if link
                    .collision
                    .iter()
                    .any(|c| matches!(c.geometry, urdf_rs::Geometry::Mesh { .. }))
                {
                    return Err(ModelError::MeshCollision {
                        links: vec![link.name.clone()],
                    });
                }
                collision_capsules(link)?
            }
        };
        let inertial = match ov.and_then(|o| o.inertial) {
            Some(i) => Some(i),
            None => urdf_inertial(link)?,
        };
        Ok(LinkSpec {
            name: link.name.clone(),
            parent: carrier.into(),
            origin: acc.map_or_else(PoseSpec::default, |a| iso_to_pose(&a)),
            capsules,
            inertial,
        })
    }
}

fn chain_limits(
    j: &urdf_rs::Joint,
    ov: &JointOverride,
    side: &SideFile,
) -> Result<JointLimitSpec, ModelError> {
    let l = &j.limit;
    // urdf-rs gives an all-zero limit when `<limit>` is absent (URDF < 1.2).
    let has_limit = !(l.lower == 0.0 && l.upper == 0.0 && l.velocity == 0.0 && l.effort == 0.0);
    let revolute = j.joint_type == JointType::Revolute;
    let missing = |what: &str, value: f64, reason: &'static str| ModelError::InvalidValue {
        field: format!("joint `{}` {what}", j.name),
        value,
        reason,
    };
    let urdf_pos = |v: f64| (revolute && has_limit && v.is_finite()).then_some(v);
    let q_min = ov.q_min.or(urdf_pos(l.lower)).ok_or_else(|| {
        missing(
            "q_min",
            l.lower,
            "no finite URDF lower limit (continuous joint or no <limit>); set q_min in the side file's [joints.NAME]",
        )
    })?;
    let q_max = ov.q_max.or(urdf_pos(l.upper)).ok_or_else(|| {
        missing(
            "q_max",
            l.upper,
            "no finite URDF upper limit (continuous joint or no <limit>); set q_max in the side file's [joints.NAME]",
        )
    })?;
    let urdf_pos_rate = |v: f64| (has_limit && v.is_finite() && v > 0.0).then_some(v);
    let v_max = ov.v_max.or(urdf_pos_rate(l.velocity)).ok_or_else(|| {
        missing(
            "v_max",
            l.velocity,
            "URDF velocity limit missing or not > 0; set v_max in the side file",
        )
    })?;
    let urdf_acc = urdf_pos_rate(l.acceleration.min(l.deceleration));
    let a_max = ov.a_max.or(side.a_max).or(urdf_acc).ok_or_else(|| {
        missing(
            "a_max",
            l.acceleration,
            "no acceleration limit; set a_max (uniform or per joint) in the side file",
        )
    })?;
    let j_max = ov
        .j_max
        .or(side.j_max)
        .or(urdf_pos_rate(l.jerk))
        .ok_or_else(|| {
            missing(
                "j_max",
                l.jerk,
                "no jerk limit; set j_max (uniform or per joint) in the side file",
            )
        })?;
    Ok(JointLimitSpec {
        q_min,
        q_max,
        v_max,
        a_max,
        j_max,
    })
}

/// Transform child-joint frame → frozen child frame of an off-chain joint.
fn frozen_motion(j: &urdf_rs::Joint, frozen_at: Option<f64>) -> Result<Isometry3<f64>, ModelError> {
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

fn urdf_pose_iso(
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

fn iso_to_pose(iso: &Isometry3<f64>) -> PoseSpec {
    PoseSpec {
        xyz: iso.translation.vector.into(),
        rpy: rpy_of(&iso.rotation.to_rotation_matrix()),
    }
}

fn collision_capsules(link: &urdf_rs::Link) -> Result<Vec<CapsuleSpec>, ModelError> {
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

fn urdf_inertial(link: &urdf_rs::Link) -> Result<Option<InertialSpec>, ModelError> {
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

/// Add the URDF joint/link name to a validation error's `joints[i]` / `links[i]` field.
fn with_names(e: ModelError, spec: &RobotSpec) -> ModelError {
    let rename = |field: String| -> String {
        for (prefix, names) in [
            (
                "joints[",
                spec.joints
                    .iter()
                    .map(|j| j.name.as_str())
                    .collect::<Vec<_>>(),
            ),
            (
                "links[",
                spec.links
                    .iter()
                    .map(|l| l.name.as_str())
                    .collect::<Vec<_>>(),
            ),
        ] {
            if let Some(rest) = field.strip_prefix(prefix)
                && let Some(end) = rest.find(']')
                && let Ok(i) = rest[..end].parse::<usize>()
                && let Some(name) = names.get(i)
            {
                return format!("{prefix}{i}]{{{name}}}{}", &rest[end + 1..]);
            }
        }
        field
    };
    match e {
        ModelError::InvalidValue {
            field,
            value,
            reason,
        } => ModelError::InvalidValue {
            field: rename(field),
            value,
            reason,
        },
        ModelError::UnknownName { kind, name, field } => ModelError::UnknownName {
            kind,
            name,
            field: rename(field),
        },
        ModelError::LengthMismatch {
            field,
            expected,
            found,
        } => ModelError::LengthMismatch {
            field: rename(field),
            expected,
            found,
        },
        other => other,
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

    #[test]
    fn error_fields_get_urdf_names() {
        let spec = crate::fr3::fr3().spec().clone();
        let e = ModelError::InvalidValue {
            field: "joints[2].limits.v_max".into(),
            value: -1.0,
            reason: "x",
        };
        match with_names(e, &spec) {
            ModelError::InvalidValue { field, .. } => {
                assert_eq!(field, "joints[2]{fr3_joint3}.limits.v_max")
            }
            other => panic!("{other:?}"),
        }
    }
}
