//! Shield settings as a user writes them (a scene file's `config`, the Python `config=` dict):
//! every field optional, names and units as in [`ShieldConfig`], unknown fields refused. The one
//! place where user text becomes a [`ShieldConfig`] (the CLI's `pacs shield` and the Python
//! package both call [`ShieldSettings::config`]).

use crate::chunk_motion::ChunkMotion;
use crate::shield::{FilterMode, ShieldConfig, ShieldError};
use pacs_motion::chunk::OutOfLimits;
use serde::{Deserialize, Serialize};

/// Shield settings a user may override (the rest keep [`ShieldConfig::default`]).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShieldSettings {
    /// `"pacs"`, `"off"` or `"single-action"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mode: Option<String>,
    /// Safety step α_s (s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub safety_step: Option<f64>,
    /// Cartesian tracking error of the low-level controller (m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tracking_error: Option<f64>,
    /// Joint velocity tracking error of the low-level controller (rad/s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub velocity_tracking_error: Option<f64>,
    /// SSM rest speed (rad/s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rest_speed: Option<f64>,
    /// Human reachability model: `"combined"`, `"pos"`, `"vel"` or `"acc"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub human_model: Option<String>,
    /// Waypoints outside the joint limits: `"reject"` the chunk or `"project"` them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub out_of_limits: Option<String>,
    /// `"stop"` (every chunk ends at rest; default) or `"continuous"` (chunks pass their last
    /// executed waypoint moving; see [`ChunkMotion`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub chunk_motion: Option<String>,
    /// Compute each step's separation figure (default `true`; a diagnostic costing 1.5–2 µs per
    /// step, see [`ShieldConfig::separation_figure`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub separation_figure: Option<bool>,
}

fn invalid(msg: String) -> ShieldError {
    ShieldError::Invalid(msg)
}

fn finite(field: &str, v: f64) -> Result<f64, ShieldError> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(invalid(format!("config.{field}: value {v} is not finite")))
    }
}

impl ShieldSettings {
    /// The shield configuration: the defaults with these overrides. Errors name the field
    /// (`config.mode`, …) and the value; ranges are checked again by [`crate::shield::Shield::new`].
    pub fn config(&self) -> Result<ShieldConfig, ShieldError> {
        let mut cfg = ShieldConfig::default();
        if let Some(m) = &self.mode {
            cfg.mode = match m.as_str() {
                "pacs" => FilterMode::Pacs,
                "off" => FilterMode::Off,
                "single-action" => FilterMode::SingleAction,
                o => {
                    return Err(invalid(format!(
                        "config.mode: unknown mode `{o}` (pacs, off, single-action)"
                    )));
                }
            };
        }
        if let Some(m) = &self.human_model {
            cfg.human_model = m
                .parse()
                .map_err(|e| invalid(format!("config.human_model: {e}")))?;
        }
        if let Some(m) = &self.out_of_limits {
            cfg.out_of_limits = match m.as_str() {
                "reject" => OutOfLimits::Reject,
                "project" => OutOfLimits::Project,
                o => {
                    return Err(invalid(format!(
                        "config.out_of_limits: unknown choice `{o}` (reject, project)"
                    )));
                }
            };
        }
        if let Some(m) = &self.chunk_motion {
            let motion = match m.as_str() {
                "stop" => ChunkMotion::Stop,
                "continuous" => ChunkMotion::Continuous,
                o => {
                    return Err(invalid(format!(
                        "config.chunk_motion: unknown choice `{o}` (stop, continuous)"
                    )));
                }
            };
            motion.apply(&mut cfg);
        }
        if let Some(v) = self.safety_step {
            cfg.safety_step = finite("safety_step", v)?;
        }
        if let Some(v) = self.tracking_error {
            cfg.tracking_error = finite("tracking_error", v)?;
        }
        if let Some(v) = self.velocity_tracking_error {
            cfg.velocity_tracking_error = finite("velocity_tracking_error", v)?;
        }
        if let Some(v) = self.rest_speed {
            cfg.rest_speed = finite("rest_speed", v)?;
        }
        if let Some(v) = self.separation_figure {
            cfg.separation_figure = v;
        }
        Ok(cfg)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pacs_motion::trajectory::EndCondition;

    #[test]
    fn defaults_and_overrides() {
        assert_eq!(
            ShieldSettings::default().config().unwrap(),
            ShieldConfig::default()
        );
        let s: ShieldSettings = serde_json::from_str(
            r#"{"mode": "off", "safety_step": 0.002, "chunk_motion": "continuous", "rest_speed": 0.01,
                "separation_figure": false}"#,
        )
        .unwrap();
        let c = s.config().unwrap();
        assert!(ShieldConfig::default().separation_figure && !c.separation_figure);
        assert_eq!(c.mode, FilterMode::Off);
        assert_eq!(c.safety_step, 0.002);
        assert_eq!(c.rest_speed, 0.01);
        assert_eq!(c.chunk_end, EndCondition::Moving);
    }

    #[test]
    fn errors_name_the_field_and_value() {
        let e = ShieldSettings {
            mode: Some("fast".into()),
            ..Default::default()
        }
        .config()
        .unwrap_err()
        .to_string();
        assert!(e.contains("config.mode") && e.contains("fast"), "{e}");
        let e = ShieldSettings {
            safety_step: Some(f64::NAN),
            ..Default::default()
        }
        .config()
        .unwrap_err()
        .to_string();
        assert!(e.contains("config.safety_step") && e.contains("NaN"), "{e}");
        let e = ShieldSettings {
            chunk_motion: Some("smooth".into()),
            ..Default::default()
        }
        .config()
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("config.chunk_motion") && e.contains("smooth"),
            "{e}"
        );
        let bad: Result<ShieldSettings, _> = serde_json::from_str(r#"{"speed": 1}"#);
        assert!(bad.unwrap_err().to_string().contains("speed"));
    }
}
