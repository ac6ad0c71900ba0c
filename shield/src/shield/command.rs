//! What a step returns: the [`Command`] for the low-level controller, its [`Diagnostics`], the
//! [`Binding`] that decided it, and the [`BindingNames`] its indices stand for.

use pacs_motion::trajectory::JointState;
use serde::Serialize;

/// What decided a step.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum Binding {
    /// Nothing bound: the intended step was verified.
    None,
    /// No valid human (or object) measurement yet.
    NoMeasurement,
    /// A person's latest measurement contradicts the ones the shield trusts (some keypoint moved
    /// farther than the human model allows between their stamps): one of them is wrong, and no
    /// step verifies until one newer than it agrees with the trusted ones.
    ContradictedMeasurement {
        /// Human index (0: the first human, not written to logs).
        #[serde(skip_serializing_if = "is_first")]
        human: usize,
    },
    /// A dynamic object's latest measurement contradicts the ones the shield trusts (positions,
    /// velocities or a velocity's direction beyond the object model): no step verifies until a
    /// newer one agrees with them.
    ContradictedObject {
        /// Object index (order of [`Shield::add_object`](super::Shield::add_object)).
        object: usize,
    },
    /// No admissible path-speed profile (limits leave no margin).
    NoProfile,
    /// SSM: contact possible while moving.
    Ssm {
        /// Human index (0: the first human, not written to logs).
        #[serde(skip_serializing_if = "is_first")]
        human: usize,
        /// Robot link index.
        link: usize,
        /// Body part index.
        body_part: usize,
        /// Occupancy interval index.
        interval: usize,
    },
    /// A dynamic object's contact constraint may be violated.
    Object {
        /// Object index (order of [`Shield::add_object`](super::Shield::add_object)).
        object: usize,
        /// Robot link index.
        link: usize,
        /// Occupancy interval index (0 also for the coarse whole-trajectory check).
        interval: usize,
    },
    /// CBF baseline: barrier constraints were active this step.
    Barrier {
        /// Number of active barrier rows.
        active: usize,
    },
    /// PFL: energy bound above the threshold where contact is possible.
    Pfl {
        /// Human index (0: the first human, not written to logs).
        #[serde(skip_serializing_if = "is_first")]
        human: usize,
        /// Robot link index.
        link: usize,
        /// Body part index.
        body_part: usize,
        /// Energy upper bound (J).
        energy: f64,
        /// Threshold (J).
        threshold: f64,
        /// Constrained (clamping) contact.
        constrained: bool,
    },
}

fn is_first(i: &usize) -> bool {
    *i == 0
}

/// Per-step diagnostics.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Diagnostics {
    /// The intended step was verified and executed. (In OFF mode every candidate is executed;
    /// this says whether its monitored trajectory verified, so an executed step may be
    /// unverified.)
    pub verified: bool,
    /// The robot follows a failsafe (braking) this step.
    pub on_failsafe: bool,
    /// What decided the step.
    pub binding: Binding,
    /// Lower bound of the separation between robot and human occupancies over the first checked
    /// interval that contains the step (the whole monitored trajectory, or the part before its
    /// last occupancy interval, or `[0, α_s]`: each a lower bound for the coming step; m; +∞
    /// without a human in the robot's workspace ball, and where it was not computed:
    /// [`ShieldConfig::separation_figure`](super::ShieldConfig::separation_figure) off, a human inside the workspace ball and no
    /// contact possible).
    pub min_separation: f64,
    /// Largest energy bound where contact was possible (J; 0 if none).
    pub contact_energy: f64,
    /// Threshold belonging to `contact_energy` (J).
    pub contact_threshold: f64,
    /// Path speed ṡ after the step (1 = intended timing, 0 = stopped).
    pub path_speed: f64,
    /// Time (s) at which the monitored trajectory reaches standstill.
    pub stop_time: f64,
}

impl Diagnostics {
    /// The diagnostics a step at time `t` starts from: nothing verified or bound yet, no
    /// separation figure (+∞), no contact, standing at `t`.
    pub fn unbound(t: f64) -> Self {
        Self {
            verified: false,
            on_failsafe: false,
            binding: Binding::None,
            min_separation: f64::INFINITY,
            contact_energy: 0.0,
            contact_threshold: 0.0,
            path_speed: 0.0,
            stop_time: t,
        }
    }
}

/// The command for the low-level controller at time `t`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Command {
    /// Time the command is for (s).
    pub t: f64,
    /// Joint state (entries beyond dof are 0).
    pub state: JointState,
    /// Number of joints carrying targets in `state` (the robot's).
    pub dof: usize,
    /// Diagnostics.
    pub diag: Diagnostics,
}

impl Command {
    /// Commanded joint positions (rad), one per joint of the robot.
    pub fn q(&self) -> &[f64] {
        &self.state.q[..self.dof]
    }

    /// Commanded joint velocities (rad/s), one per joint of the robot.
    pub fn dq(&self) -> &[f64] {
        &self.state.dq[..self.dof]
    }

    /// Commanded joint accelerations (rad/s²), one per joint of the robot.
    pub fn ddq(&self) -> &[f64] {
        &self.state.ddq[..self.dof]
    }
}

/// What a [`Binding`]'s indices stand for ([`Shield::binding_names`](super::Shield::binding_names)): one implementation for
/// every output that names them (`pacs shield`'s commands, the Python `Command.binding`).
#[derive(Debug, Clone, Default)]
pub struct BindingNames {
    /// Robot link names, by link index.
    pub links: Vec<String>,
    /// Per human (by index): its id, if known, and its body-part names.
    pub people: Vec<(Option<String>, Vec<String>)>,
    /// Object ids, by index (empty: unknown).
    pub objects: Vec<String>,
}

impl BindingNames {
    /// The binding as a JSON object: its fields (indices, energies in J) and beside each index
    /// the name it stands for — `link_name`, `person` (where the id is known), `body_part_name`,
    /// `object_id` (where the ids are known).
    pub fn describe(&self, b: &Binding) -> serde_json::Value {
        let mut v = serde_json::to_value(b).unwrap_or(serde_json::Value::Null);
        let Some(m) = v.as_object_mut() else {
            return v;
        };
        let (link, part, object) = match *b {
            Binding::Ssm {
                human,
                link,
                body_part,
                ..
            }
            | Binding::Pfl {
                human,
                link,
                body_part,
                ..
            } => (Some(link), Some((human, body_part)), None),
            Binding::Object { link, object, .. } => (Some(link), None, Some(object)),
            Binding::ContradictedObject { object } => (None, None, Some(object)),
            _ => (None, None, None),
        };
        if let Some(l) = link.and_then(|l| self.links.get(l)) {
            m.insert("link_name".into(), l.clone().into());
        }
        if let Some((h, p)) = part
            && let Some((id, parts)) = self.people.get(h)
        {
            if let Some(id) = id {
                m.insert("person".into(), id.clone().into());
            }
            if let Some(bp) = parts.get(p) {
                m.insert("body_part_name".into(), bp.clone().into());
            }
        }
        if let Some(id) = object.and_then(|o| self.objects.get(o)) {
            m.insert("object_id".into(), id.clone().into());
        }
        if let Binding::ContradictedMeasurement { human } = *b
            && let Some((Some(id), _)) = self.people.get(human)
        {
            m.insert("person".into(), id.clone().into());
        }
        v
    }
}
