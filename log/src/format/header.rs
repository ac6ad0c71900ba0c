//! The header: the first record of every log, its versions and their validation.

use super::{FORMAT, ModelRef, RobotRef, V1_PERSON, VERSION, dir_of};
use crate::error::HeaderError;
use pacs_models::object::{ObjectContact, ObjectSpec};
use pacs_models::shape::CapsuleSpec;
use pacs_models::{ConstraintSpec, HumanSpec};
use serde::{Deserialize, Serialize};

/// Most people a log (format v2) may declare: the audit checks each in a pass of its own, whose
/// memory (≈ 0.5 MB) and time add up per person.
pub const MAX_PEOPLE: usize = 32;

/// The first record of every log: models, constraints, static environment and free-form metadata.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Header {
    /// Always `"header"`.
    #[serde(rename = "type")]
    pub kind: String,
    /// Always [`FORMAT`].
    pub format: String,
    /// 1 or 2 ([`VERSIONS`](super::VERSIONS)).
    pub version: u32,
    /// Robot model (name, `{urdf, side}` relative to the log file, or spec).
    pub robot: RobotRef,
    /// Version 1: the one person's model (name or spec); absent in version 2.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub human: Option<ModelRef<HumanSpec>>,
    /// Version 2: the people, each with an id (what `human` records name) and a model.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub humans: Vec<PersonEntry>,
    /// Version 2: the writer promises an `end` event ([`END_EVENT`](super::END_EVENT)) as its
    /// last record, at the time of the last robot sample; a log that lacks it was cut short
    /// (`incomplete_log`).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub end_event: bool,
    /// Version 2: the writer promises a `start` event ([`START_EVENT`](super::START_EVENT)) at
    /// the time of its first robot sample (written just before it); a log that lacks it was cut
    /// at its beginning, and one whose first robot sample is later or earlier than it is not
    /// that run whole (`incomplete_log`). Only with `end_event`.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub start_event: bool,
    /// Task constraints (preset name or spec).
    pub constraints: ModelRef<ConstraintSpec>,
    /// Static environment shapes (capsules, m) a body part can be clamped against.
    #[serde(default)]
    pub environment: Vec<CapsuleSpec>,
    /// Dynamic objects: `object` records name them by `id` (omitted when empty).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub objects: Vec<ObjectEntry>,
    /// Free-form metadata (`task`, `policy`, `filter`, ... group the aggregate report).
    #[serde(default)]
    pub meta: serde_json::Map<String, serde_json::Value>,
}

impl Header {
    /// This header in place of `own`, the log's own (given with `pacs audit --header`, or a
    /// bag's `custom_data` header beside its parts' own records): it keeps the `start` and
    /// `end` events `own` promises, so a log cut short stays incomplete whatever header it is
    /// audited with. Test `audit_mcap.rs::a_given_header_keeps_the_logs_own_promises` (mutant
    /// `x114`).
    pub fn keep_promises_of(&mut self, own: &Header) {
        self.end_event |= own.end_event || own.start_event;
        self.start_event |= own.start_event;
    }

    /// Note in `meta.own_header_replaced` that this header, given by the caller, replaced the
    /// log's own (whose promises [`Self::keep_promises_of`] kept).
    pub fn mark_replacing(&mut self) {
        self.meta
            .insert("own_header_replaced".into(), serde_json::Value::Bool(true));
    }

    /// `meta` keys only the tools set after reading a log (the header given with `--header` and
    /// its hash, a replaced own header, a ROS recording's time base): a log's own values for them
    /// are dropped when it is read, so that no log can claim them for itself in a report.
    pub const TOOL_META: [&'static str; 5] = [
        "header_file",
        "header_file_sha256",
        "own_header_replaced",
        "mcap_time_base_s",
        "db3_time_base_s",
    ];

    /// A v1 header for the given models (one person, no end-event promise).
    pub fn new(
        robot: impl Into<RobotRef>,
        human: ModelRef<HumanSpec>,
        constraints: ModelRef<ConstraintSpec>,
    ) -> Self {
        Self {
            kind: "header".into(),
            format: FORMAT.into(),
            version: 1,
            robot: robot.into(),
            human: Some(human),
            humans: vec![],
            end_event: false,
            start_event: false,
            constraints,
            environment: vec![],
            objects: vec![],
            meta: Default::default(),
        }
    }

    /// A v2 header for the given people (`(id, model)`; ids unique), with the start- and
    /// end-event promises (what every pacs writer writes: [`Self::check`] validates it).
    pub fn with_people(
        robot: impl Into<RobotRef>,
        people: Vec<PersonEntry>,
        constraints: ModelRef<ConstraintSpec>,
    ) -> Self {
        Self {
            kind: "header".into(),
            format: FORMAT.into(),
            version: VERSION,
            robot: robot.into(),
            human: None,
            humans: people,
            end_event: true,
            start_event: true,
            constraints,
            environment: vec![],
            objects: vec![],
            meta: Default::default(),
        }
    }

    /// This header as version 2 with the start- and end-event promises: a v1 header's one
    /// person becomes person [`V1_PERSON`]. What pacs writers do with a header they are given.
    pub fn promising_end(mut self) -> Self {
        if let Some(h) = self.human.take() {
            self.humans = vec![PersonEntry {
                id: V1_PERSON.into(),
                human: h,
            }];
        }
        self.version = VERSION;
        self.end_event = true;
        self.start_event = true;
        self
    }

    /// The people of the log, `(id, model)` in header order: a v1 log's one person has id
    /// [`V1_PERSON`].
    pub fn people(&self) -> Vec<(&str, &ModelRef<HumanSpec>)> {
        match &self.human {
            Some(h) => vec![(V1_PERSON, h)],
            None => self
                .humans
                .iter()
                .map(|p| (p.id.as_str(), &p.human))
                .collect(),
        }
    }

    /// Check `type`, `format`, `version` and the fields of that version (v1: `human`; v2:
    /// `humans`, at least one, ids unique and non-empty); returns the problem otherwise.
    pub fn check(&self) -> Result<(), HeaderError> {
        if self.kind != "header" {
            return Err(HeaderError::NotHeader(self.kind.clone()));
        }
        if self.format != FORMAT {
            return Err(HeaderError::Format(self.format.clone()));
        }
        let fields = |m: &str| Err(HeaderError::Fields(m.to_string()));
        match self.version {
            1 => {
                if self.human.is_none() {
                    return fields(
                        "header.human: missing (a version 1 header names one human model)",
                    );
                }
                if !self.humans.is_empty() {
                    return fields(
                        "header.humans: version 1 has `human` (one person); several people need \"version\": 2",
                    );
                }
                if self.end_event {
                    return fields("header.end_event: a version 2 field (set \"version\": 2)");
                }
                if self.start_event {
                    return fields("header.start_event: a version 2 field (set \"version\": 2)");
                }
            }
            2 => {
                if self.human.is_some() {
                    return fields(
                        "header.human: a version 1 field; version 2 lists people in `humans`: [{\"id\": ..., \"human\": ...}]",
                    );
                }
                if self.humans.is_empty() {
                    return fields(
                        "header.humans: missing or empty (version 2 lists at least one person: [{\"id\": ..., \"human\": ...}])",
                    );
                }
                if self.start_event && !self.end_event {
                    return fields(
                        "header.start_event: only with \"end_event\": true (a writer that promises its start promises its end)",
                    );
                }
                if self.humans.len() > MAX_PEOPLE {
                    return Err(HeaderError::Fields(format!(
                        "header.humans: {} people, more than the {MAX_PEOPLE} a log may declare (the audit checks each person in a pass of its own)",
                        self.humans.len()
                    )));
                }
                for (i, p) in self.humans.iter().enumerate() {
                    if p.id.is_empty()
                        || p.id.trim() != p.id
                        || p.id.chars().any(|c| c.is_control() || ",/|`".contains(c))
                    {
                        return Err(HeaderError::Fields(format!(
                            "header.humans[{i}].id: {:?} is not a valid person id (non-empty, no surrounding spaces, no control characters, none of , / | ` — MCAP names a person's topic /humans/ID/keypoints, reports print it in tables)",
                            p.id
                        )));
                    }
                    if let Some(j) = self.humans[..i].iter().position(|q| q.id == p.id) {
                        return Err(HeaderError::Fields(format!(
                            "header.humans[{i}].id: {:?} is also the id of header.humans[{j}] (two people with one id)",
                            p.id
                        )));
                    }
                }
            }
            v => return Err(HeaderError::Version(v)),
        }
        Ok(())
    }

    /// The one header validation every reader goes through: a header as parsed (`parsed`; a
    /// parse error is [`HeaderError::Fields`]) is returned only if it passes [`Header::check`].
    pub fn validated(parsed: Result<Header, HeaderError>) -> Result<Header, HeaderError> {
        let mut header = parsed?;
        header.check()?;
        for k in Self::TOOL_META {
            header.meta.remove(k);
        }
        Ok(header)
    }

    /// A header from a parsed JSON value: it must have `"type": "header"`
    /// ([`HeaderError::MissingType`]), then [`Header::validated`].
    pub fn from_value(value: serde_json::Value) -> Result<Header, HeaderError> {
        if value.get("type").and_then(|t| t.as_str()) != Some("header") {
            return Err(HeaderError::MissingType);
        }
        Self::validated(Self::typed(value))
    }

    /// The header's fields from a JSON value; an error names the field where it can (a person,
    /// an object, `end_event`, `version`: serde's own message names the value only).
    fn typed(value: serde_json::Value) -> Result<Header, HeaderError> {
        serde_json::from_value::<Header>(value.clone())
            .map_err(|e| HeaderError::Fields(locate_error(&value).unwrap_or_else(|| e.to_string())))
    }

    /// A header parsed by a reader (`parsed`), [`Header::validated`]; errors name `file` and
    /// `loc`. A `{urdf, side}` robot's relative paths become relative to `file`'s directory.
    pub(crate) fn checked(
        file: &str,
        loc: crate::error::Location,
        parsed: Result<serde_json::Value, serde_json::Error>,
    ) -> Result<Header, crate::error::LogError> {
        use crate::error::LogError;
        let typed = match parsed {
            Ok(v) => Self::typed(v),
            Err(e) => Err(HeaderError::Fields(e.to_string())),
        };
        let mut header =
            Self::validated(typed).map_err(|p| LogError::input(file, loc, p.to_string()))?;
        header.robot.rebase(&dir_of(std::path::Path::new(file)));
        Ok(header)
    }
}

/// Where a header that does not deserialize goes wrong, as `header.FIELD: serde's message`: the
/// first person or object entry that does not read on its own, or `end_event` / `version` of the
/// wrong type. `None` where none of these is the cause (serde's message then stands alone).
fn locate_error(value: &serde_json::Value) -> Option<String> {
    let entries = |key: &str, read: &dyn Fn(&serde_json::Value) -> Option<String>| {
        value
            .get(key)?
            .as_array()?
            .iter()
            .enumerate()
            .find_map(|(i, v)| read(v).map(|e| format!("header.{key}[{i}]: {e}")))
    };
    // A person whose model does not read names `.human` (the entry's own fields read).
    let person = |v: &serde_json::Value| {
        let e = serde_json::from_value::<PersonEntry>(v.clone()).err()?;
        let model = v.get("human").and_then(|h| {
            serde_json::from_value::<ModelRef<HumanSpec>>(h.clone())
                .err()
                .map(|e| format!("human: {e}"))
        });
        Some(model.unwrap_or_else(|| e.to_string()))
    };
    let object = |v: &serde_json::Value| {
        serde_json::from_value::<ObjectEntry>(v.clone())
            .err()
            .map(|e| e.to_string())
    };
    for key in ["humans", "objects"] {
        if let Some(v) = value.get(key).filter(|v| !v.is_array() && !v.is_null()) {
            return Some(format!("header.{key}: expected a list, found {v}"));
        }
    }
    if let Some(e) = entries("humans", &person).or_else(|| entries("objects", &object)) {
        return Some(e);
    }
    for key in ["end_event", "start_event"] {
        if let Some(v) = value.get(key).filter(|v| !v.is_boolean()) {
            return Some(format!("header.{key}: expected true or false, found {v}"));
        }
    }
    match value.get("version") {
        Some(v) if v.as_u64().and_then(|n| u32::try_from(n).ok()).is_none() => Some(format!(
            "header.version: expected 1 or 2 (an integer), found {v}"
        )),
        _ => None,
    }
}

/// A dynamic object declared in the header: its id (what `object` records name), its model
/// (built-in name such as `"ball"`, or an inline spec) and the contact the task allows.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectEntry {
    /// Id used by the `object` records (unique in the header).
    pub id: String,
    /// The object model.
    pub object: ModelRef<ObjectSpec>,
    /// What contact the task allows (`"no_contact"`, `"ssm"`, `{"pfl": {"threshold": J}}`).
    pub contact: ObjectContact,
}

/// A person of a v2 header: the id its `human` records carry and its model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PersonEntry {
    /// Person id (unique in the header; `human` records name it in `id`).
    pub id: String,
    /// The person's human model (built-in name or inline spec).
    pub human: ModelRef<HumanSpec>,
}

/// Models that replace a header's (an audit config's `robot`, `human`, `constraints`).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ModelOverrides {
    /// Robot model.
    pub robot: Option<RobotRef>,
    /// Human model (of every person of the log).
    pub human: Option<ModelRef<HumanSpec>>,
    /// Task constraints.
    pub constraints: Option<ModelRef<ConstraintSpec>>,
}

impl Header {
    /// This header with the given models replaced.
    pub fn with_overrides(&self, o: &ModelOverrides) -> Header {
        let mut h = self.clone();
        if let Some(r) = &o.robot {
            h.robot = r.clone();
        }
        if let Some(x) = &o.human {
            if h.human.is_some() {
                h.human = Some(x.clone());
            }
            for p in &mut h.humans {
                p.human = x.clone();
            }
        }
        if let Some(c) = &o.constraints {
            h.constraints = c.clone();
        }
        h
    }
}
