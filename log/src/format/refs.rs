//! Models by built-in name, as a URDF with its side file, or as an inline spec.

use pacs_models::{RobotModel, RobotSpec};
use serde::{Deserialize, Serialize};

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
