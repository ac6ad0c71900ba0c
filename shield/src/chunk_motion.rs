//! How the shield moves from one chunk to the next: to rest at each chunk's end, or on through
//! it.

use crate::shield::ShieldConfig;
use pacs_motion::intended::PlanMethod;
use pacs_motion::trajectory::EndCondition;
use serde::{Deserialize, Serialize};

/// How chunk-following filters move from one chunk to the next.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ChunkMotion {
    /// Every chunk is planned (per segment) to come to rest at its last executed waypoint; the
    /// next chunk starts from wherever the robot is when it arrives.
    #[default]
    Stop,
    /// Chunks are planned with the time-optimised spline and pass their last waypoint moving
    /// toward the next chunk ([`EndCondition::Moving`], with a checked stopping tail in case no
    /// next chunk comes); a control loop hands the next chunk over when
    /// [`Shield::remaining`](crate::shield::Shield::remaining) drops to about one safety step.
    Continuous,
}

impl ChunkMotion {
    /// Apply to a shield configuration (chunk end and planner).
    pub fn apply(self, cfg: &mut ShieldConfig) {
        match self {
            ChunkMotion::Stop => {
                cfg.chunk_end = EndCondition::AtRest;
                cfg.plan_method = PlanMethod::Segments;
            }
            ChunkMotion::Continuous => {
                cfg.chunk_end = EndCondition::Moving;
                cfg.plan_method = PlanMethod::Spline;
            }
        }
    }
}
