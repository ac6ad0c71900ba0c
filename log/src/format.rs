//! Log format v2 (and v1, still read; see `docs/log-format.md`): the header, the record view shared
//! by all readers, and the JSON Lines writer the shield uses.

use crate::error::HeaderError;
use pacs_models::object::{ObjectContact, ObjectModel, ObjectSpec};
use pacs_models::shape::CapsuleSpec;
use pacs_models::{Capsule, ConstraintSpec, HumanModel, HumanSpec, RobotModel, RobotSpec};
use serde::{Deserialize, Serialize};
use std::io::Write;

/// The value of the header's `format` field.
pub const FORMAT: &str = "pacs-log";
/// The format version pacs writes: 2 (several people, each with an id; the end-event promise).
pub const VERSION: u32 = 2;
/// The versions read: 1 (one person, `human`) and 2 (`humans`).
pub const VERSIONS: [u32; 2] = [1, 2];
/// The person id of a v1 log's one person (v1 human records carry no id).
pub const V1_PERSON: &str = "human";
/// The name of the event a writer that promises it (`end_event: true`) logs last, at the end
/// time of the run.
pub const END_EVENT: &str = "end";

/// A model given by built-in name or as an inline spec (the JSON forms the model loaders accept).
/// Read by its shape — a string is a name, a table/object a spec — so a faulty inline spec
/// reports its own error (the missing or unknown field), not "did not match any variant".
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum ModelRef<T> {
    /// Built-in name (`"fr3"`, `"default"`, `"ssm"`, ...).
    Name(String),
    /// Inline spec.
    Spec(Box<T>),
}

impl<'de, T: Deserialize<'de>> Deserialize<'de> for ModelRef<T> {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Shape<T>(std::marker::PhantomData<T>);
        impl<'de, T: Deserialize<'de>> serde::de::Visitor<'de> for Shape<T> {
            type Value = ModelRef<T>;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("a built-in model name (a string) or an inline spec (an object)")
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<Self::Value, E> {
                Ok(ModelRef::Name(v.to_string()))
            }
            fn visit_string<E: serde::de::Error>(self, v: String) -> Result<Self::Value, E> {
                Ok(ModelRef::Name(v))
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                map: A,
            ) -> Result<Self::Value, A::Error> {
                T::deserialize(serde::de::value::MapAccessDeserializer::new(map))
                    .map(|t| ModelRef::Spec(Box::new(t)))
            }
        }
        d.deserialize_any(Shape(std::marker::PhantomData))
    }
}

/// A robot given by built-in name (`"fr3"`), as a URDF with its side file (`{"urdf":
/// "arm.urdf", "side": "arm.toml"}`), or as an inline spec (what `pacs robot show` prints) —
/// in log headers, audit configs and CLI inputs alike. Read by its shape (a string; an object
/// with `urdf`; any other object), so a faulty inline spec reports its own missing or unknown
/// field. Relative URDF and side-file paths mean relative to the file that names them: readers
/// call [`RobotRef::rebase`] with that file's directory.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum RobotRef {
    /// Built-in name.
    Name(String),
    /// A URDF file and its side file (JSON or TOML; capsules, acceleration/jerk limits).
    Urdf {
        /// URDF path.
        urdf: std::path::PathBuf,
        /// Side-file path.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        side: Option<std::path::PathBuf>,
    },
    /// Inline spec.
    Spec(Box<RobotSpec>),
}

impl<'de> Deserialize<'de> for RobotRef {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::Error;
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct UrdfRef {
            urdf: std::path::PathBuf,
            #[serde(default)]
            side: Option<std::path::PathBuf>,
        }
        let v = serde_json::Value::deserialize(d)?;
        match &v {
            serde_json::Value::String(n) => Ok(RobotRef::Name(n.clone())),
            serde_json::Value::Object(m) if m.contains_key("urdf") => {
                let u: UrdfRef = serde_json::from_value(v)
                    .map_err(|e| D::Error::custom(format!("robot {{urdf, side}}: {e}")))?;
                Ok(RobotRef::Urdf {
                    urdf: u.urdf,
                    side: u.side,
                })
            }
            serde_json::Value::Object(_) => serde_json::from_value(v)
                .map(|s| RobotRef::Spec(Box::new(s)))
                .map_err(|e| D::Error::custom(format!("inline robot spec: {e}"))),
            other => Err(D::Error::custom(format!(
                "expected a built-in model name (a string), {{\"urdf\": ..., \"side\": ...}} or an inline spec (an object), found {other}"
            ))),
        }
    }
}

impl From<ModelRef<RobotSpec>> for RobotRef {
    fn from(m: ModelRef<RobotSpec>) -> Self {
        match m {
            ModelRef::Name(n) => RobotRef::Name(n),
            ModelRef::Spec(s) => RobotRef::Spec(s),
        }
    }
}

impl RobotRef {
    /// Make relative URDF and side-file paths relative to `dir` (the directory of the file that
    /// names them); absolute paths, names and inline specs are unchanged.
    pub fn rebase(&mut self, dir: &std::path::Path) {
        if let RobotRef::Urdf { urdf, side } = self {
            if urdf.is_relative() {
                *urdf = dir.join(&*urdf);
            }
            if let Some(s) = side
                && s.is_relative()
            {
                *s = dir.join(&*s);
            }
        }
    }

    /// The validated model (a URDF is converted with its side file).
    pub fn load(&self) -> Result<RobotModel, pacs_models::ModelError> {
        match self {
            RobotRef::Name(n) => RobotModel::builtin(n),
            RobotRef::Urdf { urdf, side } => {
                pacs_models::urdf::load_urdf_files(urdf, side.as_deref()).map_err(|e| {
                    pacs_models::ModelError::Invalid(format!("URDF {}: {e}", urdf.display()))
                })
            }
            RobotRef::Spec(s) => RobotModel::new((**s).clone()),
        }
    }
}

/// The directory of the file at `path` (`.` for a bare file name): where the relative paths it
/// names start.
pub fn dir_of(path: &std::path::Path) -> std::path::PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => std::path::PathBuf::from("."),
    }
}

/// The first record of every log: models, constraints, static environment and free-form metadata.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Header {
    /// Always `"header"`.
    #[serde(rename = "type")]
    pub kind: String,
    /// Always [`FORMAT`].
    pub format: String,
    /// 1 or 2 ([`VERSIONS`]).
    pub version: u32,
    /// Robot model (name, `{urdf, side}` relative to the log file, or spec).
    pub robot: RobotRef,
    /// Version 1: the one person's model (name or spec); absent in version 2.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub human: Option<ModelRef<HumanSpec>>,
    /// Version 2: the people, each with an id (what `human` records name) and a model.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub humans: Vec<PersonEntry>,
    /// Version 2: the writer promises an `end` event ([`END_EVENT`]) as its last record, at the
    /// time of the last robot sample; a log that lacks it was cut short (`incomplete_log`).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub end_event: bool,
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
            constraints,
            environment: vec![],
            objects: vec![],
            meta: Default::default(),
        }
    }

    /// A v2 header for the given people (`(id, model)`; ids unique), with the end-event
    /// promise (what every pacs writer writes: [`Self::check`] validates it).
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
            constraints,
            environment: vec![],
            objects: vec![],
            meta: Default::default(),
        }
    }

    /// This header as version 2 with the end-event promise: a v1 header's one person becomes
    /// person [`V1_PERSON`]. What pacs writers do with a header they are given.
    pub fn promising_end(mut self) -> Self {
        if let Some(h) = self.human.take() {
            self.humans = vec![PersonEntry {
                id: V1_PERSON.into(),
                human: h,
            }];
        }
        self.version = VERSION;
        self.end_event = true;
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
                for (i, p) in self.humans.iter().enumerate() {
                    if p.id.is_empty() || p.id.trim() != p.id || p.id.contains(',') {
                        return Err(HeaderError::Fields(format!(
                            "header.humans[{i}].id: {:?} is not a valid person id (non-empty, no surrounding spaces, no comma)",
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
        let header = parsed?;
        header.check()?;
        Ok(header)
    }

    /// A header from a parsed JSON value: it must have `"type": "header"`
    /// ([`HeaderError::MissingType`]), then [`Header::validated`].
    pub fn from_value(value: serde_json::Value) -> Result<Header, HeaderError> {
        if value.get("type").and_then(|t| t.as_str()) != Some("header") {
            return Err(HeaderError::MissingType);
        }
        Self::validated(
            serde_json::from_value(value).map_err(|e| HeaderError::Fields(e.to_string())),
        )
    }

    /// A header parsed by a reader (`parsed`), [`Header::validated`]; errors name `file` and
    /// `loc`. A `{urdf, side}` robot's relative paths become relative to `file`'s directory.
    pub(crate) fn checked(
        file: &str,
        loc: crate::error::Location,
        parsed: Result<Header, serde_json::Error>,
    ) -> Result<Header, crate::error::LogError> {
        use crate::error::LogError;
        let mut header = Self::validated(parsed.map_err(|e| HeaderError::Fields(e.to_string())))
            .map_err(|p| LogError::input(file, loc, p.to_string()))?;
        header.robot.rebase(&dir_of(std::path::Path::new(file)));
        Ok(header)
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

/// One record after the header, borrowing the reader's buffers (no allocation per record).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Record<'a> {
    /// A robot sample at `t` (s): joint positions (rad) and, if logged, velocities (rad/s).
    Robot {
        /// Time (s).
        t: f64,
        /// Joint positions (rad).
        q: &'a [f64],
        /// Joint velocities (rad/s), if logged.
        dq: Option<&'a [f64]>,
        /// Joint accelerations (rad/s²), if logged (only together with `dq`).
        ddq: Option<&'a [f64]>,
    },
    /// A human measurement logged at `t`, taken at `t_meas ≤ t` (s); keypoints in model order (m).
    Human {
        /// Log time (s).
        t: f64,
        /// Measurement time stamp (s).
        t_meas: f64,
        /// The person's id (v2 `id`; `None`: the log's only person).
        person: Option<&'a str>,
        /// Keypoint positions (m).
        positions: &'a [[f64; 3]],
    },
    /// A dynamic object's measurement logged at `t`, taken at `t_meas ≤ t` (s): the object `id`
    /// of the header at `position` (m), with `velocity` (m/s) if measured.
    Object {
        /// Log time (s).
        t: f64,
        /// Measurement time stamp (s).
        t_meas: f64,
        /// The header's object id.
        id: &'a str,
        /// Measured position (m).
        position: [f64; 3],
        /// Measured velocity (m/s), if any.
        velocity: Option<[f64; 3]>,
    },
    /// Shield diagnostics (ignored by the verdict).
    Shield {
        /// Time (s).
        t: f64,
    },
    /// A named event (`episode_start`, `success`, `failure`, or any other name).
    Event {
        /// Time (s).
        t: f64,
        /// Event name.
        name: &'a str,
    },
}

impl Record<'_> {
    /// The record's time (s).
    pub fn t(&self) -> f64 {
        match *self {
            Record::Robot { t, .. }
            | Record::Human { t, .. }
            | Record::Object { t, .. }
            | Record::Shield { t }
            | Record::Event { t, .. } => t,
        }
    }
}

/// A streaming source of records: the header first, then records in file order.
pub trait RecordReader {
    /// The file's header (already read and checked for type, format and version).
    fn header(&self) -> &Header;
    /// The next record, `None` at a clean end of file. Errors name the file and location.
    fn next_record(&mut self) -> Result<Option<Record<'_>>, crate::LogError>;
    /// Where the last returned record was found (for errors detected downstream).
    fn location(&self) -> crate::Location;
    /// Where the header was found (for errors in its models). Default: line 1.
    fn header_location(&self) -> crate::Location {
        crate::Location::Line(1)
    }
    /// The file name used in errors.
    fn file(&self) -> &str;
}

/// Errors of [`LogWriter`].
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    /// A value is NaN or infinite (the format only holds finite numbers).
    #[error("{field}: value {value} is not finite")]
    NotFinite {
        /// Field name.
        field: &'static str,
        /// The value.
        value: f64,
    },
    /// Time went backwards.
    #[error("t = {t} s is before the previous record's t = {previous} s")]
    Backwards {
        /// This record's time (s).
        t: f64,
        /// Previous time (s).
        previous: f64,
    },
    /// The header was not written first, or written twice.
    #[error("{0}")]
    Order(&'static str),
    /// Accelerations without velocities (the format holds `ddq` only together with `dq`).
    #[error("ddq: accelerations are written only together with velocities (dq)")]
    AccelerationsWithoutVelocities,
    /// A measurement stamped after the record's time (the audit refuses such a log: a
    /// measurement cannot come from the future).
    #[error(
        "t_meas = {t_meas} s is after the record's t = {t} s (a measurement cannot come from the future)"
    )]
    FromFuture {
        /// The measurement's stamp (s).
        t_meas: f64,
        /// The record's time (s).
        t: f64,
    },
    /// Serialization or I/O failed.
    #[error("write failed: {0}")]
    Io(#[from] std::io::Error),
}

/// Writes a v1 JSON Lines log. Guarantees: header first, finite numbers only, non-decreasing `t`;
/// floats are written in shortest round-trip form, so a reader gets back the exact values.
pub struct LogWriter<W: Write> {
    out: W,
    header_written: bool,
    last_t: f64,
}

fn finite(field: &'static str, v: f64) -> Result<(), WriteError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(WriteError::NotFinite { field, value: v })
    }
}

fn write_list<W: Write>(out: &mut W, field: &'static str, v: &[f64]) -> Result<(), WriteError> {
    out.write_all(b"[")?;
    for (i, x) in v.iter().enumerate() {
        finite(field, *x)?;
        if i > 0 {
            out.write_all(b",")?;
        }
        write!(out, "{x:?}")?;
    }
    out.write_all(b"]")?;
    Ok(())
}

impl<W: Write> LogWriter<W> {
    /// A writer on `out` (wrap files in a `BufWriter`).
    pub fn new(out: W) -> Self {
        Self {
            out,
            header_written: false,
            last_t: f64::NEG_INFINITY,
        }
    }

    /// Write the header line (must be first).
    pub fn write_header(&mut self, h: &Header) -> Result<(), WriteError> {
        if self.header_written {
            return Err(WriteError::Order("header written twice"));
        }
        serde_json::to_writer(&mut self.out, h).map_err(std::io::Error::from)?;
        self.out.write_all(b"\n")?;
        self.header_written = true;
        Ok(())
    }

    fn begin(&mut self, t: f64) -> Result<(), WriteError> {
        if !self.header_written {
            return Err(WriteError::Order("write_header must come first"));
        }
        finite("t", t)?;
        if t < self.last_t {
            return Err(WriteError::Backwards {
                t,
                previous: self.last_t,
            });
        }
        self.last_t = t;
        Ok(())
    }

    /// A robot sample: time (s), joint positions (rad), optional velocities (rad/s).
    pub fn write_robot(&mut self, t: f64, q: &[f64], dq: Option<&[f64]>) -> Result<(), WriteError> {
        self.write_robot_with_acc(t, q, dq, None)
    }

    /// A robot sample with optional accelerations (rad/s²; only together with `dq`: `ddq`
    /// without `dq` is refused, never dropped silently).
    pub fn write_robot_with_acc(
        &mut self,
        t: f64,
        q: &[f64],
        dq: Option<&[f64]>,
        ddq: Option<&[f64]>,
    ) -> Result<(), WriteError> {
        if dq.is_none() && ddq.is_some() {
            return Err(WriteError::AccelerationsWithoutVelocities);
        }
        self.begin(t)?;
        write!(self.out, "{{\"type\":\"robot\",\"t\":{t:?},\"q\":")?;
        write_list(&mut self.out, "q", q)?;
        if let Some(dq) = dq {
            self.out.write_all(b",\"dq\":")?;
            write_list(&mut self.out, "dq", dq)?;
            if let Some(ddq) = ddq {
                self.out.write_all(b",\"ddq\":")?;
                write_list(&mut self.out, "ddq", ddq)?;
            }
        }
        self.out.write_all(b"}\n")?;
        Ok(())
    }

    /// A human measurement: log time `t`, measurement time `t_meas` (s), keypoints (m), without
    /// a person id (a v1 log, or a v2 log of one person).
    pub fn write_human(
        &mut self,
        t: f64,
        t_meas: f64,
        positions: &[[f64; 3]],
    ) -> Result<(), WriteError> {
        self.write_person(t, t_meas, None, positions)
    }

    /// A measurement of person `id` (a v2 header's `humans[].id`; `None`: the only person):
    /// log time `t`, measurement time `t_meas` (s), keypoints (m).
    pub fn write_person(
        &mut self,
        t: f64,
        t_meas: f64,
        id: Option<&str>,
        positions: &[[f64; 3]],
    ) -> Result<(), WriteError> {
        finite("t_meas", t_meas)?;
        if t_meas > t {
            return Err(WriteError::FromFuture { t_meas, t });
        }
        self.begin(t)?;
        write!(
            self.out,
            "{{\"type\":\"human\",\"t\":{t:?},\"t_meas\":{t_meas:?},"
        )?;
        if let Some(id) = id {
            self.out.write_all(b"\"id\":")?;
            serde_json::to_writer(&mut self.out, id).map_err(std::io::Error::from)?;
            self.out.write_all(b",")?;
        }
        self.out.write_all(b"\"positions\":[")?;
        for (i, p) in positions.iter().enumerate() {
            if i > 0 {
                self.out.write_all(b",")?;
            }
            write_list(&mut self.out, "positions", p)?;
        }
        self.out.write_all(b"]}\n")?;
        Ok(())
    }

    /// A measurement of the header's object `id` logged at `t`, taken at `t_meas` (s): position
    /// (m) and, if measured, velocity (m/s).
    pub fn write_object(
        &mut self,
        t: f64,
        t_meas: f64,
        id: &str,
        position: [f64; 3],
        velocity: Option<[f64; 3]>,
    ) -> Result<(), WriteError> {
        finite("t_meas", t_meas)?;
        if t_meas > t {
            return Err(WriteError::FromFuture { t_meas, t });
        }
        self.begin(t)?;
        let id = serde_json::to_string(id).map_err(|e| WriteError::Io(std::io::Error::other(e)))?;
        write!(
            self.out,
            "{{\"type\":\"object\",\"t\":{t:?},\"t_meas\":{t_meas:?},\"id\":{id},\"position\":"
        )?;
        write_list(&mut self.out, "position", &position)?;
        if let Some(v) = velocity {
            self.out.write_all(b",\"velocity\":")?;
            write_list(&mut self.out, "velocity", &v)?;
        }
        self.out.write_all(b"}\n")?;
        Ok(())
    }

    /// A named event at `t` (s).
    pub fn write_event(&mut self, t: f64, name: &str) -> Result<(), WriteError> {
        self.begin(t)?;
        write!(self.out, "{{\"type\":\"event\",\"t\":{t:?},\"name\":")?;
        serde_json::to_writer(&mut self.out, name).map_err(std::io::Error::from)?;
        self.out.write_all(b"}\n")?;
        Ok(())
    }

    /// Shield diagnostics at `t` (s): `fields` (a JSON object) is merged into the record.
    pub fn write_shield(
        &mut self,
        t: f64,
        fields: &serde_json::Map<String, serde_json::Value>,
    ) -> Result<(), WriteError> {
        self.begin(t)?;
        let mut m = fields.clone();
        m.insert("type".into(), "shield".into());
        m.insert("t".into(), t.into());
        serde_json::to_writer(&mut self.out, &m).map_err(std::io::Error::from)?;
        self.out.write_all(b"\n")?;
        Ok(())
    }

    /// The time (s) of the last record written (−∞ before the first).
    pub fn last_time(&self) -> f64 {
        self.last_t
    }

    /// Flush and return the inner writer.
    pub fn finish(mut self) -> Result<W, WriteError> {
        self.out.flush()?;
        Ok(self.out)
    }
}
