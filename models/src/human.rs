//! Human models: keypoints with speed/acceleration bounds, body parts as capsules between two
//! keypoints, measurement errors and sensor delay. Built-in default: SaRA's 9-keypoint TUM-lab model.

use crate::error::{ModelError, non_negative, positive};
use serde::{Deserialize, Serialize};

/// A body part: every point within `thickness / 2` (m) of the segment between two keypoints
/// (`from == to` makes a ball).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodyPartSpec {
    /// Unique body-part name.
    pub name: String,
    /// Proximal keypoint name.
    pub from: String,
    /// Distal keypoint name.
    pub to: String,
    /// Diameter of the part around its segment (m).
    pub thickness: f64,
}

/// An extremity for the position-bounded ("pos") model: every point of `body_parts` stays within
/// `length + thickness / 2` (m) of the `base` keypoint.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExtremitySpec {
    /// Name.
    pub name: String,
    /// Base keypoint (e.g. the shoulder).
    pub base: String,
    /// Reach from the base keypoint (m).
    pub length: f64,
    /// Extra diameter added to the reach (m).
    #[serde(default)]
    pub thickness: f64,
    /// Body parts this extremity covers.
    pub body_parts: Vec<String>,
}

/// The JSON/TOML form of a human model (what `pacs human show default` prints).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HumanSpec {
    /// Model name.
    #[serde(default = "default_name")]
    pub name: String,
    /// Keypoint names in measurement order.
    pub keypoints: Vec<String>,
    /// Maximum speed per keypoint (m/s).
    pub v_max: Vec<f64>,
    /// Maximum acceleration per keypoint (m/s²).
    pub a_max: Vec<f64>,
    /// Body parts.
    pub body_parts: Vec<BodyPartSpec>,
    /// Bound on the position measurement error, Euclidean (m).
    #[serde(default)]
    pub measurement_error_pos: f64,
    /// Bound on the velocity measurement error, Euclidean (m/s).
    #[serde(default)]
    pub measurement_error_vel: f64,
    /// Sensor delay: a measurement stamped `t` describes the state at `t - delay` (s).
    #[serde(default)]
    pub delay: f64,
    /// Extremities for the "pos" model (parts not covered use the velocity-bounded model).
    #[serde(default)]
    pub extremities: Vec<ExtremitySpec>,
    /// Pairs of body parts between which one of them can be clamped (constrained contact).
    #[serde(default)]
    pub clamping_pairs: Vec<[String; 2]>,
}

fn default_name() -> String {
    "custom".into()
}

/// A validated body part (keypoint indices resolved).
#[derive(Debug, Clone, PartialEq)]
pub struct BodyPart {
    /// Name.
    pub name: String,
    /// Proximal keypoint index.
    pub from: usize,
    /// Distal keypoint index.
    pub to: usize,
    /// Diameter (m), `>= 0`.
    pub thickness: f64,
}

/// A validated extremity.
#[derive(Debug, Clone, PartialEq)]
pub struct Extremity {
    /// Name.
    pub name: String,
    /// Base keypoint index.
    pub base: usize,
    /// Reach (m) `>= 0`.
    pub length: f64,
    /// Extra diameter (m) `>= 0`.
    pub thickness: f64,
    /// Covered body-part indices.
    pub body_parts: Vec<usize>,
}

/// A validated human model: all limits finite and positive, errors and delay `>= 0`, names resolved.
#[derive(Debug, Clone, PartialEq)]
pub struct HumanModel {
    spec: HumanSpec,
    body_parts: Vec<BodyPart>,
    extremities: Vec<Extremity>,
    /// `clampable[i * n + j]`: part i can be clamped against part j.
    clampable: Vec<bool>,
}

impl HumanModel {
    /// Validate a spec.
    pub fn new(spec: HumanSpec) -> Result<Self, ModelError> {
        let k = spec.keypoints.len();
        if k == 0 {
            return Err(ModelError::Invalid("human model has no keypoints".into()));
        }
        for (i, name) in spec.keypoints.iter().enumerate() {
            if spec.keypoints[..i].contains(name) {
                return Err(ModelError::DuplicateName {
                    kind: "keypoint",
                    name: name.clone(),
                });
            }
        }
        for (field, v) in [("v_max", &spec.v_max), ("a_max", &spec.a_max)] {
            if v.len() != k {
                return Err(ModelError::LengthMismatch {
                    field: field.into(),
                    expected: k,
                    found: v.len(),
                });
            }
            for (i, x) in v.iter().enumerate() {
                positive(|| format!("{field}[{i}]"), *x)?;
            }
        }
        non_negative(
            || "measurement_error_pos".into(),
            spec.measurement_error_pos,
        )?;
        non_negative(
            || "measurement_error_vel".into(),
            spec.measurement_error_vel,
        )?;
        non_negative(|| "delay".into(), spec.delay)?;
        let kp = |name: &str, field: String| {
            spec.keypoints
                .iter()
                .position(|n| n == name)
                .ok_or_else(|| ModelError::UnknownName {
                    kind: "keypoint",
                    name: name.into(),
                    field,
                })
        };
        if spec.body_parts.is_empty() {
            return Err(ModelError::Invalid("human model has no body parts".into()));
        }
        let mut body_parts = Vec::with_capacity(spec.body_parts.len());
        for (i, b) in spec.body_parts.iter().enumerate() {
            if spec.body_parts[..i].iter().any(|o| o.name == b.name) {
                return Err(ModelError::DuplicateName {
                    kind: "body part",
                    name: b.name.clone(),
                });
            }
            body_parts.push(BodyPart {
                name: b.name.clone(),
                from: kp(&b.from, format!("body_parts[{i}].from"))?,
                to: kp(&b.to, format!("body_parts[{i}].to"))?,
                thickness: non_negative(|| format!("body_parts[{i}].thickness"), b.thickness)?,
            });
        }
        let part = |name: &str, field: String| {
            spec.body_parts
                .iter()
                .position(|b| b.name == name)
                .ok_or_else(|| ModelError::UnknownName {
                    kind: "body part",
                    name: name.into(),
                    field,
                })
        };
        let mut extremities = Vec::with_capacity(spec.extremities.len());
        for (i, e) in spec.extremities.iter().enumerate() {
            let mut parts = Vec::new();
            for (j, p) in e.body_parts.iter().enumerate() {
                parts.push(part(p, format!("extremities[{i}].body_parts[{j}]"))?);
            }
            extremities.push(Extremity {
                name: e.name.clone(),
                base: kp(&e.base, format!("extremities[{i}].base"))?,
                length: non_negative(|| format!("extremities[{i}].length"), e.length)?,
                thickness: non_negative(|| format!("extremities[{i}].thickness"), e.thickness)?,
                body_parts: parts,
            });
        }
        let n = body_parts.len();
        let mut clampable = vec![false; n * n];
        for (i, [a, b]) in spec.clamping_pairs.iter().enumerate() {
            let ia = part(a, format!("clamping_pairs[{i}][0]"))?;
            let ib = part(b, format!("clamping_pairs[{i}][1]"))?;
            clampable[ia * n + ib] = true;
            clampable[ib * n + ia] = true;
        }
        Ok(Self {
            spec,
            body_parts,
            extremities,
            clampable,
        })
    }

    /// Parse and validate JSON.
    pub fn from_json(text: &str) -> Result<Self, ModelError> {
        Self::new(crate::error::parse_json(text)?)
    }

    /// Parse and validate TOML.
    pub fn from_toml(text: &str) -> Result<Self, ModelError> {
        Self::new(crate::error::parse_toml(text)?)
    }

    /// A built-in human model by name (`"default"`).
    pub fn builtin(name: &str) -> Result<Self, ModelError> {
        match name {
            "default" | "tum-lab" => Ok(default_human()),
            other => Err(ModelError::UnknownName {
                kind: "human model",
                name: other.into(),
                field: "human".into(),
            }),
        }
    }

    /// The spec (what `pacs human show` prints).
    pub fn spec(&self) -> &HumanSpec {
        &self.spec
    }
    /// Number of keypoints.
    #[inline]
    pub fn keypoint_count(&self) -> usize {
        self.spec.keypoints.len()
    }
    /// Keypoint names in measurement order.
    pub fn keypoints(&self) -> &[String] {
        &self.spec.keypoints
    }
    /// Index of a keypoint by name.
    pub fn keypoint_index(&self, name: &str) -> Option<usize> {
        self.spec.keypoints.iter().position(|n| n == name)
    }
    /// Maximum speed per keypoint (m/s).
    #[inline]
    pub fn v_max(&self) -> &[f64] {
        &self.spec.v_max
    }
    /// Maximum acceleration per keypoint (m/s²).
    #[inline]
    pub fn a_max(&self) -> &[f64] {
        &self.spec.a_max
    }
    /// Body parts.
    #[inline]
    pub fn body_parts(&self) -> &[BodyPart] {
        &self.body_parts
    }
    /// Index of a body part by name.
    pub fn body_part_index(&self, name: &str) -> Option<usize> {
        self.body_parts.iter().position(|b| b.name == name)
    }
    /// Extremities of the "pos" model.
    #[inline]
    pub fn extremities(&self) -> &[Extremity] {
        &self.extremities
    }
    /// Position measurement error bound (m).
    #[inline]
    pub fn measurement_error_pos(&self) -> f64 {
        self.spec.measurement_error_pos
    }
    /// Velocity measurement error bound (m/s).
    #[inline]
    pub fn measurement_error_vel(&self) -> f64 {
        self.spec.measurement_error_vel
    }
    /// Sensor delay (s).
    #[inline]
    pub fn delay(&self) -> f64 {
        self.spec.delay
    }
    /// Whether body part `a` can be clamped against body part `b`.
    pub fn clampable(&self, a: usize, b: usize) -> bool {
        let n = self.body_parts.len();
        a < n && b < n && self.clampable[a * n + b]
    }
    /// A copy with different measurement errors and delay (validated).
    pub fn with_uncertainty(&self, e_pos: f64, e_vel: f64, delay: f64) -> Result<Self, ModelError> {
        let mut spec = self.spec.clone();
        spec.measurement_error_pos = e_pos;
        spec.measurement_error_vel = e_vel;
        spec.delay = delay;
        Self::new(spec)
    }
}

/// SaRA's TUM-lab human model (sara-shield `human_reach_TUM_lab.yaml`): 9 keypoints, speed 2 m/s,
/// acceleration 50 m/s² (arms, head) and 20 m/s² (neck, hip), 7 body parts with DIN 33402-2 P95
/// thicknesses, measurement errors 0 m / 0.1 m/s, no delay; arm extremities of 1.0 m from the
/// shoulders; clamping between the arms (both directions).
pub fn default_human() -> HumanModel {
    let s = |x: &str| x.to_string();
    let kps = [
        "lShldr", "lForeArm", "lHand", "rShldr", "rForeArm", "rHand", "neck", "hip", "head",
    ];
    let part = |name: &str, from: &str, to: &str, thickness: f64| BodyPartSpec {
        name: s(name),
        from: s(from),
        to: s(to),
        thickness,
    };
    let mut clamping_pairs = Vec::new();
    for l in ["lUpperArm", "lLowerArm", "lHand"] {
        for r in ["rUpperArm", "rLowerArm", "rHand"] {
            clamping_pairs.push([s(l), s(r)]);
        }
    }
    let spec = HumanSpec {
        name: s("default"),
        keypoints: kps.iter().map(|k| s(k)).collect(),
        v_max: vec![2.0; 9],
        a_max: vec![50.0, 50.0, 50.0, 50.0, 50.0, 50.0, 20.0, 20.0, 50.0],
        body_parts: vec![
            part("lUpperArm", "lShldr", "lForeArm", 0.2),
            part("lLowerArm", "lForeArm", "lHand", 0.132),
            part("lHand", "lHand", "lHand", 0.206),
            part("rUpperArm", "rShldr", "rForeArm", 0.2),
            part("rLowerArm", "rForeArm", "rHand", 0.132),
            part("rHand", "rHand", "rHand", 0.206),
            part("torso", "hip", "neck", 0.434),
            part("head", "head", "head", 0.434),
        ],
        measurement_error_pos: 0.0,
        measurement_error_vel: 0.1,
        delay: 0.0,
        extremities: vec![
            ExtremitySpec {
                name: s("lArm"),
                base: s("lShldr"),
                length: 1.0,
                thickness: 0.0,
                body_parts: vec![s("lUpperArm"), s("lLowerArm"), s("lHand")],
            },
            ExtremitySpec {
                name: s("rArm"),
                base: s("rShldr"),
                length: 1.0,
                thickness: 0.0,
                body_parts: vec![s("rUpperArm"), s("rLowerArm"), s("rHand")],
            },
        ],
        clamping_pairs,
    };
    HumanModel::new(spec).expect("built-in human model is valid")
}
