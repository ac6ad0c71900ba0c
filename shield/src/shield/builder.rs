//! [`ShieldBuilder`]: a shield from its robot, people, objects, environment and configuration.

use super::{EnvShape, Shield, ShieldConfig, ShieldError};
use pacs_models::object::{ObjectContact, ObjectModel};
use pacs_models::{ConstraintSpec, HumanModel, RobotModel};

/// Builds a [`Shield`]: every person the same way ([`Self::person`], in index order: the
/// first is person 0), every dynamic object ([`Self::object`]), the static environment
/// (clamping surfaces) and the configuration, in any order; [`Self::build`] checks them all.
///
/// ```
/// use pacs_models::{ConstraintSpec, RobotModel, default_human, fr3};
/// use pacs_shield::shield::{Shield, ShieldConfig};
///
/// let sorting = ConstraintSpec::builtin("sorting")?; // SSM for every body part
/// let mut shield = Shield::builder(RobotModel::builtin("fr3")?)
///     .person(default_human(), &sorting) // the operator: person 0
///     .person(default_human(), &sorting) // a passer-by: person 1
///     .config(ShieldConfig::default())
///     .build()?;
/// shield.start(0.0, &fr3::Q_READY)?;
/// assert_eq!(shield.human_count(), 2);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone)]
pub struct ShieldBuilder {
    robot: RobotModel,
    people: Vec<(HumanModel, ConstraintSpec)>,
    objects: Vec<(ObjectModel, ObjectContact)>,
    environment: Vec<EnvShape>,
    config: ShieldConfig,
}

impl Shield {
    /// A builder for a shield of `robot` (no people, objects or environment yet; the default
    /// configuration).
    pub fn builder(robot: RobotModel) -> ShieldBuilder {
        ShieldBuilder {
            robot,
            people: Vec::new(),
            objects: Vec::new(),
            environment: Vec::new(),
            config: ShieldConfig::default(),
        }
    }
}

impl ShieldBuilder {
    /// The shield's configuration (default: [`ShieldConfig::default`]).
    pub fn config(mut self, config: ShieldConfig) -> Self {
        self.config = config;
        self
    }

    /// Add a person with the task's constraints; people are numbered in the order added
    /// (0, 1, …: the index of [`Shield::measure_human`] and of the bindings).
    pub fn person(mut self, human: HumanModel, constraints: &ConstraintSpec) -> Self {
        self.people.push((human, constraints.clone()));
        self
    }

    /// Add several people with the task's constraints, in order.
    pub fn people(
        mut self,
        people: impl IntoIterator<Item = HumanModel>,
        constraints: &ConstraintSpec,
    ) -> Self {
        self.people
            .extend(people.into_iter().map(|h| (h, constraints.clone())));
        self
    }

    /// Add a dynamic object with the contact its task allows; objects are numbered in the
    /// order added (the index of [`Shield::measure_object`]).
    pub fn object(mut self, model: ObjectModel, contact: ObjectContact) -> Self {
        self.objects.push((model, contact));
        self
    }

    /// Add static environment shapes (surfaces a person may be clamped against).
    pub fn environment(mut self, shapes: impl IntoIterator<Item = EnvShape>) -> Self {
        self.environment.extend(shapes);
        self
    }

    /// The shield (not started). Errors: those of [`Shield::new`] (the configuration, the robot,
    /// person 0), [`Shield::add_human`] and [`Shield::add_object`], for the first one refused.
    pub fn build(self) -> Result<Shield, ShieldError> {
        let mut people = self.people.into_iter();
        let first = people.next();
        let mut shield = Shield::new(
            self.robot,
            first.as_ref().map(|(h, c)| (h.clone(), c)),
            self.environment,
            self.config,
        )?;
        for (human, constraints) in people {
            shield.add_human(human, &constraints)?;
        }
        for (model, contact) in self.objects {
            shield.add_object(model, contact)?;
        }
        Ok(shield)
    }
}
