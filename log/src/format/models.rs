//! The models a log's header refers to, loaded and validated.

use super::{Header, ModelRef};
use crate::error::HeaderError;
use pacs_models::object::{ObjectContact, ObjectModel};
use pacs_models::{Capsule, ConstraintSpec, HumanModel, RobotModel};

/// The models a log refers to, validated.
#[derive(Debug, Clone)]
pub struct LogModels {
    /// Robot model.
    pub robot: RobotModel,
    /// The first person's human model (a v1 log's one person).
    pub human: HumanModel,
    /// Every person: id and model, in header order (the first is `human`).
    pub people: Vec<(String, HumanModel)>,
    /// Constraint spec (resolved against every person's model by the checker).
    pub constraints: ConstraintSpec,
    /// Static environment capsules (m).
    pub environment: Vec<Capsule>,
    /// Dynamic objects: id, validated model and allowed contact.
    pub objects: Vec<(String, ObjectModel, ObjectContact)>,
}

impl LogModels {
    /// Load and validate the header's models; the error names the header field.
    pub fn from_header(h: &Header) -> Result<Self, HeaderError> {
        let model = |field: &str| {
            let field = field.to_string();
            move |source| HeaderError::Model { field, source }
        };
        let robot = h.robot.load().map_err(model("header.robot"))?;
        let constraints = match &h.constraints {
            ModelRef::Name(n) => ConstraintSpec::builtin(n),
            ModelRef::Spec(s) => Ok((**s).clone()),
        }
        .map_err(model("header.constraints"))?;
        let mut people = Vec::new();
        for (i, (id, r)) in h.people().into_iter().enumerate() {
            let field = if h.human.is_some() {
                "header.human".to_string()
            } else {
                format!("header.humans[{i}].human")
            };
            let human = match r {
                ModelRef::Name(n) => HumanModel::builtin(n),
                ModelRef::Spec(s) => HumanModel::new((**s).clone()),
            }
            .map_err(model(&field))?;
            constraints
                .resolve(&human)
                .map_err(model("header.constraints"))?
                .check_robot(&robot)
                .map_err(model("header.robot"))?;
            people.push((id.to_string(), human));
        }
        let Some(human) = people.first().map(|(_, m)| m.clone()) else {
            return Err(HeaderError::Fields(
                "header.humans: missing or empty".into(),
            ));
        };
        let mut environment = Vec::with_capacity(h.environment.len());
        for (i, c) in h.environment.iter().enumerate() {
            environment
                .push(Capsule::try_from(*c).map_err(model(&format!("header.environment[{i}]")))?);
        }
        let mut objects: Vec<(String, ObjectModel, ObjectContact)> =
            Vec::with_capacity(h.objects.len());
        for (i, o) in h.objects.iter().enumerate() {
            let field = format!("header.objects[{i}]");
            if objects.iter().any(|(id, _, _)| *id == o.id) {
                return Err(HeaderError::Model {
                    field: format!("{field}.id"),
                    source: pacs_models::ModelError::DuplicateName {
                        kind: "object id",
                        name: o.id.clone(),
                    },
                });
            }
            // Violations, bindings and reports name a person or an object by its id alone.
            if let Some(j) = h.humans.iter().position(|p| p.id == o.id) {
                return Err(HeaderError::Fields(format!(
                    "{field}.id: {:?} is also the id of a person (header.humans[{j}]): violations and reports name people and objects by id, so each needs its own",
                    o.id
                )));
            }
            let spec = match &o.object {
                ModelRef::Name(n) => pacs_models::object::builtin_object(n).ok_or_else(|| {
                    pacs_models::ModelError::UnknownName {
                        kind: "built-in object",
                        name: n.clone(),
                        field: "object".into(),
                    }
                }),
                ModelRef::Spec(s) => Ok((**s).clone()),
            }
            .map_err(model(&format!("{field}.object")))?;
            let m = ObjectModel::new(&spec).map_err(model(&format!("{field}.object")))?;
            let c = o
                .contact
                .validated()
                .map_err(model(&format!("{field}.contact")))?;
            objects.push((o.id.clone(), m, c));
        }
        Ok(Self {
            robot,
            human,
            people,
            constraints,
            environment,
            objects,
        })
    }
}
