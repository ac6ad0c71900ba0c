//! The online filters behind one interface: PACS, OFF, single-action and CBF are kinds of one
//! [`SafetyFilter`], chosen by [`FilterKind`] — not a flag spread over several types.

use crate::cbf::{CbfConfig, CbfFilter};
use pacs_models::object::ObjectContact;
use pacs_models::object::ObjectModel;
use pacs_models::{ConstraintSpec, HumanModel, RobotModel};
use pacs_motion::Chunk;
use pacs_reach::human::HumanMeasurement;
use pacs_reach::object::ObjectMeasurement;
use pacs_shield::ChunkMotion;
use pacs_shield::session::MeasurementSink;
use pacs_shield::shield::{Command, FilterMode, Shield, ShieldConfig, ShieldError};
use serde::{Deserialize, Serialize};

/// What every online filter offers: start at rest, take chunks and measurements (of every person
/// and object, through [`MeasurementSink`]), one command per safety step.
pub trait SafetyFilter: MeasurementSink {
    /// Start at rest at `q` (rad) at time `t` (s).
    fn start(&mut self, t: f64, q: &[f64]) -> Result<(), ShieldError>;
    /// Hand a new action chunk to the filter at time `t` (s); a chunk that cannot be planned is
    /// an error and is ignored (the robot keeps its motion).
    fn set_chunk(&mut self, t: f64, chunk: &Chunk) -> Result<(), ShieldError>;
    /// One safety step at `t` (s) with the latest measurement, if any: the command for the next
    /// step ([`ShieldError::NotStarted`] before `start`).
    fn step(
        &mut self,
        t: f64,
        measurement: Option<&HumanMeasurement>,
    ) -> Result<Command, ShieldError>;
    /// Add a dynamic object with the contact its task allows; returns its id.
    fn add_object(
        &mut self,
        model: ObjectModel,
        contact: ObjectContact,
    ) -> Result<usize, ShieldError>;
    /// Add another person with the task's constraints; returns its index (the first person,
    /// given at construction and measured through [`Self::step`], is 0).
    fn add_human(
        &mut self,
        human: HumanModel,
        constraints: &ConstraintSpec,
    ) -> Result<usize, ShieldError>;
    /// Intended time (s) left until the current chunk's last waypoint, if the filter follows a
    /// time-parameterised chunk ([`Shield::remaining`]); `None` otherwise.
    fn remaining(&self) -> Option<f64> {
        None
    }
}

impl SafetyFilter for Shield {
    fn start(&mut self, t: f64, q: &[f64]) -> Result<(), ShieldError> {
        Shield::start(self, t, q)
    }
    fn set_chunk(&mut self, _t: f64, chunk: &Chunk) -> Result<(), ShieldError> {
        Shield::set_chunk(self, chunk)
    }
    fn step(
        &mut self,
        t: f64,
        measurement: Option<&HumanMeasurement>,
    ) -> Result<Command, ShieldError> {
        Shield::step(self, t, measurement)
    }
    fn add_object(
        &mut self,
        model: ObjectModel,
        contact: ObjectContact,
    ) -> Result<usize, ShieldError> {
        Shield::add_object(self, model, contact)
    }
    fn add_human(
        &mut self,
        human: HumanModel,
        constraints: &ConstraintSpec,
    ) -> Result<usize, ShieldError> {
        Shield::add_human(self, human, constraints)
    }
    fn remaining(&self) -> Option<f64> {
        Shield::remaining(self)
    }
}

impl SafetyFilter for CbfFilter {
    fn start(&mut self, t: f64, q: &[f64]) -> Result<(), ShieldError> {
        CbfFilter::start(self, t, q)
    }
    fn set_chunk(&mut self, t: f64, chunk: &Chunk) -> Result<(), ShieldError> {
        CbfFilter::set_chunk(self, t, chunk)
    }
    fn step(
        &mut self,
        t: f64,
        measurement: Option<&HumanMeasurement>,
    ) -> Result<Command, ShieldError> {
        CbfFilter::step(self, t, measurement)
    }
    fn add_object(
        &mut self,
        model: ObjectModel,
        contact: ObjectContact,
    ) -> Result<usize, ShieldError> {
        contact
            .validated()
            .map_err(|error| ShieldError::ObjectContact {
                index: self.object_count(),
                error,
            })?;
        Ok(CbfFilter::add_object(self, model))
    }
    fn add_human(
        &mut self,
        human: HumanModel,
        _constraints: &ConstraintSpec,
    ) -> Result<usize, ShieldError> {
        Ok(CbfFilter::add_human(self, human))
    }
}

impl MeasurementSink for CbfFilter {
    fn measure_human(&mut self, id: usize, m: &HumanMeasurement) -> Result<(), ShieldError> {
        // The first person's measurement reaches the CBF through its step (the newest of the
        // step); the inbox hands every one to the sink as well, for the shield's own checks.
        if id == 0 {
            return Ok(());
        }
        CbfFilter::measure_human(self, id, m)
    }
    fn measure_object(&mut self, id: usize, m: &ObjectMeasurement) -> Result<(), ShieldError> {
        CbfFilter::measure_object(self, id, m)
    }
}

/// The kinds of online filter.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FilterKind {
    /// PACS: verify every step, brake along the path when needed.
    Pacs,
    /// OFF: follow the intended trajectory, never brake.
    Off,
    /// PACS planning each action as its own stop-at-target motion (the single-action baseline).
    SingleAction,
    /// The control-barrier-function baseline.
    Cbf,
    /// No filter, each action sent as a target on its own: OFF with every chunk planned to end
    /// at rest (a chunk of one action is one time-optimal jerk-limited move to that target, cut
    /// short by the next target).
    Direct,
}

impl FilterKind {
    /// Build the filter for a robot, a human with a task constraint spec, with default settings.
    pub fn build(
        self,
        robot: &RobotModel,
        human: &HumanModel,
        spec: &ConstraintSpec,
    ) -> Result<Box<dyn SafetyFilter + Send>, ShieldError> {
        self.build_with(robot, human, spec, ChunkMotion::default())
    }

    /// [`Self::build`] with the given chunk motion for the chunk-following kinds (PACS, OFF,
    /// single-action; single actions always stop, the direct baseline always stops at its one
    /// target, the CBF has no chunk trajectory).
    pub fn build_with(
        self,
        robot: &RobotModel,
        human: &HumanModel,
        spec: &ConstraintSpec,
        motion: ChunkMotion,
    ) -> Result<Box<dyn SafetyFilter + Send>, ShieldError> {
        Ok(match self {
            FilterKind::Cbf => Box::new(CbfFilter::new(
                robot.clone(),
                Some(human.clone()),
                CbfConfig::default(),
            )?),
            kind => {
                let mut cfg = ShieldConfig {
                    mode: match kind {
                        FilterKind::Off | FilterKind::Direct => FilterMode::Off,
                        FilterKind::SingleAction => FilterMode::SingleAction,
                        _ => FilterMode::Pacs,
                    },
                    ..ShieldConfig::default()
                };
                match kind {
                    FilterKind::Direct | FilterKind::SingleAction => {
                        ChunkMotion::Stop.apply(&mut cfg)
                    }
                    _ => motion.apply(&mut cfg),
                }
                Box::new(Shield::new(
                    robot.clone(),
                    Some((human.clone(), spec)),
                    vec![],
                    cfg,
                )?)
            }
        })
    }
}
