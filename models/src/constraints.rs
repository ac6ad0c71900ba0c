//! ISO/TS 15066 task constraints: SSM or PFL per body region, with energy thresholds per contact type.

use crate::error::{ModelError, non_negative};
use crate::human::HumanModel;
use serde::{Deserialize, Serialize};

/// What must hold when the robot may touch a body part.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase", deny_unknown_fields)]
pub enum Constraint {
    /// Speed and separation monitoring: no contact possible unless the robot is at rest.
    Ssm,
    /// Power and force limiting: contact allowed while the robot's kinetic energy (J) is at most the
    /// threshold for the contact type.
    Pfl {
        /// Threshold for free (unconstrained) contact (J).
        unconstrained: f64,
        /// Threshold for clamping (constrained) contact (J).
        constrained: f64,
    },
}

impl Constraint {
    /// Energy threshold (J) for the contact type; 0 for SSM.
    #[inline]
    pub fn threshold(&self, constrained: bool) -> f64 {
        match *self {
            Constraint::Ssm => 0.0,
            Constraint::Pfl {
                unconstrained,
                constrained: c,
            } => {
                if constrained {
                    c
                } else {
                    unconstrained
                }
            }
        }
    }
}

/// A body region: a named set of body parts sharing one constraint.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RegionSpec {
    /// Region name (e.g. "hand").
    pub name: String,
    /// Body parts of the human model in this region.
    pub body_parts: Vec<String>,
    /// The constraint for contacts with this region.
    pub constraint: Constraint,
}

/// The JSON/TOML form of a task constraint spec.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConstraintSpec {
    /// Task name.
    pub name: String,
    /// Constraint for body parts not in any region.
    pub default: Constraint,
    /// Regions with their own constraint (a body part may be in at most one region).
    #[serde(default)]
    pub regions: Vec<RegionSpec>,
}

impl ConstraintSpec {
    /// A built-in preset by name: `ssm`, `sorting`, `handover`, `feeding` (see [`Self::preset`]).
    pub fn builtin(name: &str) -> Result<Self, ModelError> {
        Self::preset(name).ok_or_else(|| ModelError::UnknownName {
            kind: "constraint preset",
            name: name.into(),
            field: "constraints".into(),
        })
    }

    /// Presets for the paper's tasks (thresholds in J), body parts named as in the default human:
    /// - `ssm` / `sorting`: SSM for every body part (paper: Sorting, hand, 0 J);
    /// - `handover`: PFL hands 0.265 J unconstrained / 0.014 J constrained; other parts PFL with
    ///   SaRA's "link" thresholds (upper arm 1.5, lower arm 1.3, torso 1.6, head 0.11 J
    ///   unconstrained, 0.01 J constrained);
    /// - `feeding`: PFL head 0.001 J (both contact types); other parts as in `handover`'s defaults
    ///   with hands at SaRA's link value 0.49 J / 0.01 J.
    pub fn preset(name: &str) -> Option<Self> {
        let pfl = |u: f64, c: f64| Constraint::Pfl {
            unconstrained: u,
            constrained: c,
        };
        let region = |name: &str, parts: &[&str], constraint| RegionSpec {
            name: name.into(),
            body_parts: parts.iter().map(|s| s.to_string()).collect(),
            constraint,
        };
        let arms = |hand: Constraint| {
            vec![
                region("upper_arm", &["lUpperArm", "rUpperArm"], pfl(1.5, 0.01)),
                region("lower_arm", &["lLowerArm", "rLowerArm"], pfl(1.3, 0.01)),
                region("hand", &["lHand", "rHand"], hand),
                region("torso", &["torso"], pfl(1.6, 0.01)),
            ]
        };
        match name {
            "ssm" | "sorting" => Some(Self {
                name: name.into(),
                default: Constraint::Ssm,
                regions: vec![],
            }),
            "handover" => {
                let mut regions = arms(pfl(0.265, 0.014));
                regions.push(region("head", &["head"], pfl(0.11, 0.01)));
                Some(Self {
                    name: name.into(),
                    default: Constraint::Ssm,
                    regions,
                })
            }
            "feeding" => {
                let mut regions = arms(pfl(0.49, 0.01));
                regions.push(region("head", &["head"], pfl(0.001, 0.001)));
                Some(Self {
                    name: name.into(),
                    default: Constraint::Ssm,
                    regions,
                })
            }
            _ => None,
        }
    }

    /// Resolve against a human model: one constraint per body part, in the model's order.
    /// Unknown body-part names, parts in two regions, or negative/non-finite thresholds are errors.
    pub fn resolve(&self, human: &HumanModel) -> Result<TaskConstraints, ModelError> {
        let check = |c: &Constraint, field: String| -> Result<(), ModelError> {
            if let Constraint::Pfl {
                unconstrained,
                constrained,
            } = c
            {
                non_negative(|| format!("{field}.unconstrained"), *unconstrained)?;
                non_negative(|| format!("{field}.constrained"), *constrained)?;
            }
            Ok(())
        };
        check(&self.default, "default".into())?;
        let n = human.body_parts().len();
        let mut per_part = vec![self.default; n];
        let mut assigned = vec![false; n];
        for (ri, r) in self.regions.iter().enumerate() {
            check(&r.constraint, format!("regions[{ri}].constraint"))?;
            for (pi, p) in r.body_parts.iter().enumerate() {
                let idx = human
                    .body_part_index(p)
                    .ok_or_else(|| ModelError::UnknownName {
                        kind: "body part",
                        name: p.clone(),
                        field: format!("regions[{ri}].body_parts[{pi}]"),
                    })?;
                if assigned[idx] {
                    return Err(ModelError::DuplicateName {
                        kind: "body part in regions",
                        name: p.clone(),
                    });
                }
                assigned[idx] = true;
                per_part[idx] = r.constraint;
            }
        }
        Ok(TaskConstraints {
            name: self.name.clone(),
            per_part,
        })
    }
}

/// Constraints resolved per body part of one human model.
#[derive(Debug, Clone, PartialEq)]
pub struct TaskConstraints {
    /// Task name.
    pub name: String,
    /// Constraint per body part (human model order).
    pub per_part: Vec<Constraint>,
}

impl TaskConstraints {
    /// Refuse a robot that would make this task's PFL checks vacuous: with any PFL body part,
    /// every moving link (frame ≥ 1) that has collision capsules must have a positive mass and a
    /// non-zero inertia tensor, else its kinetic energy would be ignored. Links without capsules
    /// and without mass are frames (flanges, TCPs), not bodies, and are accepted — unless no
    /// moving link has any mass, when every moving link is refused. SSM-only tasks accept any
    /// robot.
    pub fn check_robot(&self, robot: &crate::RobotModel) -> Result<(), ModelError> {
        if self.is_ssm_only() {
            return Ok(());
        }
        // No moving mass at all: every moving link is refused (the energy would always be 0).
        let moving_mass: f64 = robot
            .links()
            .iter()
            .filter(|l| l.frame >= 1)
            .filter_map(|l| l.inertial.as_ref().map(|i| i.mass))
            .sum();
        let massless_robot = moving_mass.is_nan() || moving_mass <= 0.0;
        let links: Vec<String> = robot
            .links()
            .iter()
            .filter(|l| l.frame >= 1 && (massless_robot || !l.capsules.is_empty()))
            .filter(|l| {
                l.inertial.as_ref().is_none_or(|i| {
                    i.mass.is_nan()
                        || i.mass <= 0.0
                        || i.inertia.trace().is_nan()
                        || i.inertia.trace() <= 0.0
                })
            })
            .map(|l| l.name.clone())
            .collect();
        if links.is_empty() {
            Ok(())
        } else {
            Err(ModelError::MasslessLinks {
                task: self.name.clone(),
                robot: robot.name().to_string(),
                links,
            })
        }
    }

    /// True if every body part is SSM.
    pub fn is_ssm_only(&self) -> bool {
        self.per_part.iter().all(|c| matches!(c, Constraint::Ssm))
    }
}
