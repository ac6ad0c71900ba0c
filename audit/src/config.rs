//! The audit's settings (`--config task.toml`).

use crate::error::AuditError;
use pacs_reach::human::HumanReachModel;
use serde::{Deserialize, Serialize};

/// The largest `limit_slack` the audit accepts (relative). The limit and consistency tests let
/// samples through that miss them by up to the slack, and the span boxes do not cover what such
/// samples leave unexplained: a large slack would judge a logger's `dq = 0` beside moving
/// positions consistent, and the robot at rest (at 1000, a joint at 0.5 rad/s next to a person
/// passed). At 1e-6 the tests accept at most a millionth beyond the limits and the velocity
/// reach band, far below any figure the rule compares with.
pub const MAX_LIMIT_SLACK: f64 = 1e-6;

/// Audit settings (`--config task.toml`); every field has a documented default.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct AuditConfig {
    /// A span between robot samples longer than this (s; beyond the stamps' rounding, 4ε of the
    /// larger stamp, ε = 2⁻⁵²) is inconclusive. Default 0.1 s.
    pub max_gap: f64,
    /// A span is inconclusive once the human measurement in use is older than this (s) at its
    /// end. Default 1.0 s.
    pub max_human_age: f64,
    /// The robot is at rest on a span if every joint speed is provably ≤ this (rad/s). Default
    /// 0.02 rad/s.
    pub rest_speed: f64,
    /// Human reachability model: `combined` (default), `vel`, `pos` (`acc` needs velocities,
    /// which logs do not carry).
    pub human_model: HumanReachModel,
    /// Extra radius (m) added to every robot capsule (tracking/calibration error). Default 0.
    pub tracking_error: f64,
    /// Relative slack on `|q_{i+1} − q_i| ≤ v_max·Δt` before samples count as exceeding the
    /// velocity limits. Default 1e-9, at most [`MAX_LIMIT_SLACK`].
    pub limit_slack: f64,
    /// Override the header's robot (absent from the report's `settings`: the header's) (name, `{urdf, side}` relative to the config file, or spec).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub robot: Option<pacs_log::RobotRef>,
    /// Override the header's human model.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub human: Option<pacs_log::ModelRef<pacs_models::HumanSpec>>,
    /// Override the header's constraints.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub constraints: Option<pacs_log::ModelRef<pacs_models::ConstraintSpec>>,
    /// MCAP reading settings (topics, reorder window): the `[mcap]` table.
    pub mcap: pacs_log::mcap::McapConfig,
}

impl Default for AuditConfig {
    fn default() -> Self {
        Self {
            max_gap: 0.1,
            max_human_age: 1.0,
            rest_speed: 0.02,
            human_model: HumanReachModel::Combined,
            tracking_error: 0.0,
            limit_slack: 1e-9,
            robot: None,
            human: None,
            constraints: None,
            mcap: Default::default(),
        }
    }
}

impl AuditConfig {
    /// The models this config puts in place of a log header's.
    pub fn overrides(&self) -> pacs_log::ModelOverrides {
        pacs_log::ModelOverrides {
            robot: self.robot.clone(),
            human: self.human.clone(),
            constraints: self.constraints.clone(),
        }
    }

    /// Check every value; the error names the field and value.
    pub fn validate(&self) -> Result<(), AuditError> {
        for (f, v) in [
            ("max_gap", self.max_gap),
            ("max_human_age", self.max_human_age),
            ("rest_speed", self.rest_speed),
            ("tracking_error", self.tracking_error),
            ("limit_slack", self.limit_slack),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(AuditError::Setting { field: f, value: v });
            }
        }
        if self.limit_slack > MAX_LIMIT_SLACK {
            return Err(AuditError::LimitSlack(self.limit_slack));
        }
        // The one rule's bound: a larger rest speed would let SSM pass a moving robot.
        pacs_verify::iso15066::check_rest_speed(self.rest_speed).map_err(AuditError::Rule)?;
        if self.human_model == HumanReachModel::Acc {
            return Err(AuditError::AccModel);
        }
        self.mcap.validate().map_err(AuditError::Mcap)
    }
}
