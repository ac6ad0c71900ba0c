//! Shield settings as a user writes them (a scene file's `config`, the Python `config=` dict):
//! every field optional, names and units as in [`ShieldConfig`], unknown fields refused. The one
//! place where user text becomes a [`ShieldConfig`] (the CLI's `pacs shield` and the Python
//! package both call [`ShieldSettings::config`]).

use crate::chunk_motion::ChunkMotion;
use crate::shield::{FilterMode, ShieldConfig};
use pacs_motion::chunk::OutOfLimits;
use pacs_reach::human::HumanReachModel;
use serde::{Deserialize, Serialize};
use thiserror::Error;

/// Shield settings a user may override (the rest keep [`ShieldConfig::default`]). Choices are
/// typed: an unknown name is refused when the settings are read, with the field's path and the
/// names allowed.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShieldSettings {
    /// `"pacs"`, `"off"` or `"single-action"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mode: Option<FilterMode>,
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
    pub human_model: Option<HumanReachModel>,
    /// Waypoints outside the joint limits: `"reject"` the chunk or `"project"` them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub out_of_limits: Option<OutOfLimits>,
    /// `"stop"` (every chunk ends at rest; default) or `"continuous"` (chunks pass their last
    /// executed waypoint moving; see [`ChunkMotion`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub chunk_motion: Option<ChunkMotion>,
    /// Compute each step's separation figure (default `true`; a diagnostic costing 1.5–2 µs per
    /// step, see [`ShieldConfig::separation_figure`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub separation_figure: Option<bool>,
}

/// A setting that is not finite.
#[derive(Debug, Clone, PartialEq, Error)]
#[error("config.{field}: value {value} is not finite")]
pub struct SettingError {
    /// The field (`safety_step`, …).
    pub field: &'static str,
    /// Its value.
    pub value: f64,
}

fn finite(field: &'static str, value: f64) -> Result<f64, SettingError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(SettingError { field, value })
    }
}

impl ShieldSettings {
    /// The shield configuration: the defaults with these overrides. Errors name the field
    /// (`config.safety_step`, …) and the value; ranges are checked again by
    /// [`crate::shield::Shield::new`].
    pub fn config(&self) -> Result<ShieldConfig, SettingError> {
        let mut cfg = ShieldConfig::default();
        if let Some(m) = self.mode {
            cfg.mode = m;
        }
        if let Some(m) = self.human_model {
            cfg.human_model = m;
        }
        if let Some(m) = self.out_of_limits {
            cfg.out_of_limits = m;
        }
        if let Some(m) = self.chunk_motion {
            m.apply(&mut cfg);
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
            safety_step: Some(f64::NAN),
            ..Default::default()
        }
        .config()
        .unwrap_err()
        .to_string();
        assert!(e.contains("config.safety_step") && e.contains("NaN"), "{e}");
        // Unknown names are refused when read, naming the value and the choices.
        for (text, bad, choices) in [
            (r#"{"mode": "fast"}"#, "fast", "single-action"),
            (r#"{"chunk_motion": "smooth"}"#, "smooth", "continuous"),
            (r#"{"human_model": "x"}"#, "`x`", "combined"),
            (r#"{"out_of_limits": "clip"}"#, "clip", "project"),
            (r#"{"speed": 1}"#, "speed", "mode"),
        ] {
            let e = serde_json::from_str::<ShieldSettings>(text)
                .unwrap_err()
                .to_string();
            assert!(e.contains(bad) && e.contains(choices), "{text}: {e}");
        }
    }

    #[test]
    fn settings_are_written_as_read() {
        let text = r#"{"mode":"single-action","human_model":"vel","out_of_limits":"project","chunk_motion":"continuous"}"#;
        let s: ShieldSettings = serde_json::from_str(text).unwrap();
        assert_eq!(serde_json::to_string(&s).unwrap(), text);
    }
}
