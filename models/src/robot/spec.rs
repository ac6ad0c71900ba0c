//! Robots as written in a model file (JSON or TOML; also what the URDF loader produces): poses,
//! joints with their limits, links with capsules and inertials. Not yet validated.

use crate::error::{ModelError, finite};
use crate::shape::CapsuleSpec;
use nalgebra::{Isometry3, Translation3, UnitQuaternion};
use serde::{Deserialize, Serialize};

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
    pub(super) fn validate(&self, field: &str) -> Result<Isometry3<f64>, ModelError> {
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
    /// `true`: the link has no capsules on purpose — a coordinate frame, or a body that lies
    /// inside other links' capsules (the FR3's closed fingers inside the hand's). Its mass still
    /// counts for the PFL energy bound, but no contact with it is ever checked. Without this
    /// mark a moving link with mass and no capsules is refused ([`ModelError::UncoveredLinks`]);
    /// with it, capsules must be empty.
    ///
    /// [`ModelError::UncoveredLinks`]: crate::ModelError::UncoveredLinks
    #[serde(default, skip_serializing_if = "is_false")]
    pub frame: bool,
}

fn is_false(b: &bool) -> bool {
    !*b
}

/// A robot as written in a model file (JSON or TOML); [`RobotModel::new`] validates it.
///
/// [`RobotModel::new`]: super::RobotModel::new
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
    /// Values the user gave rather than the robot description (the URDF loader lists what came
    /// from the side file: limits the URDF lacks or that override it, capsules, `frame` marks,
    /// inertials, frozen joints, the base pose); reports list them under the assumptions.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub user_values: Vec<String>,
}
