//! Serial-chain robot models: joints, limits, link capsules and inertials, and the built-in FR3.

mod limits;
mod spec;
mod validation;

pub use limits::JointLimits;
pub use spec::{InertialSpec, JointLimitSpec, JointSpec, LinkSpec, PoseSpec, RobotSpec};

use crate::error::ModelError;
use crate::shape::Capsule;
use nalgebra::{Isometry3, Matrix3, Point3, Unit, Vector3};

/// Largest number of joints a model may have (fixed-size buffers in hot paths use this).
pub const MAX_DOF: usize = 16;

/// Largest reach (m) of a robot model from the world origin: the base offset, the joint offsets
/// along the chain and the farthest capsule point (radius included) or centre of mass. Finite
/// but astronomical offsets (a unit mistake, `1e300`) would overflow forward kinematics,
/// distances and energies into `inf`/NaN; such a model is refused instead.
pub const MAX_REACH: f64 = 1.0e6;

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
