//! # pacs-models
//!
//! The models every other pacs crate reasons about:
//! - [`robot`]: serial-chain robots (joints, limits, link capsules, inertials), validated once at load;
//!   [`fr3`] is the built-in Franka FR3; [`urdf`] loads other robots from URDF plus a capsule file;
//! - [`kinematics`]: forward kinematics, point Jacobians, mass matrix, sub-chain kinetic energies;
//! - [`human`]: keypoint human models with speed/acceleration bounds, measurement errors and delay;
//! - [`constraints`]: ISO/TS 15066 task specs (SSM or PFL per body region) and the paper's presets.
//!
//! Units everywhere: metres, radians, seconds, kilograms, joules.

pub mod constraints;
pub mod error;
pub mod fr3;
pub mod human;
pub mod json_path;
pub mod kinematics;
pub mod object;
pub mod robot;
pub mod shape;
pub mod urdf;

pub use constraints::{Constraint, ConstraintSpec, TaskConstraints};
pub use error::ModelError;
pub use human::{HumanModel, HumanSpec, default_human};
pub use json_path::{describe_json_error, json_path_at};
pub use object::{ObjectModel, ObjectSpec};
pub use robot::{JointLimits, MAX_DOF, MAX_REACH, RobotModel, RobotSpec};
pub use shape::Capsule;

/// Load a model-like value from a string that is either JSON (starts with `{`) or TOML.
pub fn parse_json_or_toml<T: serde::de::DeserializeOwned>(text: &str) -> Result<T, ModelError> {
    if text.trim_start().starts_with('{') {
        error::parse_json(text)
    } else {
        error::parse_toml(text)
    }
}
