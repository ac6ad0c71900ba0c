//! The side file: what a URDF does not say (or says differently), per robot, joint and link.

use crate::error::ModelError;
use crate::robot::{InertialSpec, PoseSpec};
use crate::shape::CapsuleSpec;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

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
    /// `true`: the link has no body of its own to collide with (a frame, or a body inside other
    /// links' capsules); it gets no capsules, and a moving link with mass is then accepted
    /// without them. Refused together with capsules or on a link with URDF collision geometry.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frame: Option<bool>,
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
