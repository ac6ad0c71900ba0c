//! Dynamic objects: things that move near the robot but are not people (a rolling ball, a cart, a
//! tool in someone's hand), described by a shape, bounded translational dynamics and the
//! sensor's errors and delay — the same kind of assumptions as for humans.
//!
//! The model (what every occupancy of `pacs_reach::object` relies on):
//! - **Shape**: a rigid body that translates without rotating: a centred zonotope `S` (up to
//!   [`MAX_SHAPE_GENERATORS`] generators, m) dilated by a radius `r` (m). A sphere is `S = {0}`, a
//!   capsule one generator (its half axis), an axis-aligned box three. The reference point is the
//!   measured position.
//! - **Dynamics**: a double integrator `p̈ = u` with the acceleration set
//!   `U = acc_bias ⊕ G_u·[−1, 1]^k ⊕ B(max_acc)` (m/s²; `acc_bias` e.g. gravity for a falling
//!   object, `G_u` up to [`MAX_ACC_GENERATORS`] generators for direction-dependent bounds,
//!   `B(max_acc)` a Euclidean ball), and optionally `‖ṗ‖ ≤ max_speed` (m/s) at all times.
//! - **Measurement**: a measurement stamped `t_m` describes the state at `t_m − delay` (s); its
//!   position is within `measurement_error_pos` (m, Euclidean) of the truth and its velocity, when
//!   measured, within `measurement_error_vel` (m/s). Without a measured velocity the speed bound
//!   is required (the velocity is then anywhere in `B(0, max_speed)`).

use crate::error::{ModelError, finite, non_negative, positive};
use serde::{Deserialize, Serialize};

/// Most generators of an object's shape zonotope.
pub const MAX_SHAPE_GENERATORS: usize = 4;
/// Most generators of the zonotope part of an object's acceleration set.
pub const MAX_ACC_GENERATORS: usize = 4;

/// The shape of an object (JSON: `{"sphere": {"radius": 0.04}}`, `{"capsule": {"half_axis":
/// [0, 0, 0.1], "radius": 0.03}}`, `{"box": {"half_extents": [0.2, 0.1, 0.05]}}` or
/// `{"zonotope": {"generators": [[…], …], "radius": 0.0}}`; all in metres).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum ShapeSpec {
    /// A ball of `radius` around the reference point.
    Sphere {
        /// Radius (m, > 0).
        radius: f64,
    },
    /// All points within `radius` of the segment from `−half_axis` to `+half_axis`.
    Capsule {
        /// Half of the segment, from the reference point to one end (m).
        half_axis: [f64; 3],
        /// Radius (m, ≥ 0).
        radius: f64,
    },
    /// An axis-aligned box (the model does not rotate objects).
    Box {
        /// Half extents along x, y, z (m, ≥ 0, not all 0).
        half_extents: [f64; 3],
    },
    /// A centred zonotope `Σ ξ_k g_k, |ξ_k| ≤ 1`, dilated by `radius`.
    Zonotope {
        /// Generators (m), at most [`MAX_SHAPE_GENERATORS`].
        generators: Vec<[f64; 3]>,
        /// Dilation radius (m, ≥ 0).
        #[serde(default)]
        radius: f64,
    },
}

/// The JSON/TOML form of a dynamic object (see the module docs for what each bound means).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectSpec {
    /// Name (unique within a scene).
    #[serde(default = "default_name")]
    pub name: String,
    /// The shape.
    pub shape: ShapeSpec,
    /// Bound on the Euclidean norm of the acceleration beyond `acc_bias` and `acc_generators`
    /// (m/s², ≥ 0).
    pub max_acc: f64,
    /// Constant part of the acceleration, e.g. `[0, 0, -9.81]` for a falling object (m/s²).
    #[serde(default)]
    pub acc_bias: [f64; 3],
    /// Generators of the zonotope part of the acceleration set (m/s²).
    #[serde(default)]
    pub acc_generators: Vec<[f64; 3]>,
    /// Bound on the speed at all times (m/s, > 0), if known.
    #[serde(default)]
    pub max_speed: Option<f64>,
    /// Bound on the position measurement error, Euclidean (m).
    #[serde(default)]
    pub measurement_error_pos: f64,
    /// Bound on the velocity measurement error, Euclidean (m/s).
    #[serde(default)]
    pub measurement_error_vel: f64,
    /// Sensor delay: a measurement stamped `t` describes the state at `t − delay` (s).
    #[serde(default)]
    pub delay: f64,
}

fn default_name() -> String {
    "object".into()
}

/// A validated dynamic object: fixed-size, `Copy`, ready for allocation-free occupancy queries.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObjectModel {
    shape_generators: [[f64; 3]; MAX_SHAPE_GENERATORS],
    n_shape: usize,
    shape_radius: f64,
    max_acc: f64,
    acc_bias: [f64; 3],
    acc_generators: [[f64; 3]; MAX_ACC_GENERATORS],
    n_acc: usize,
    max_speed: Option<f64>,
    pos_error: f64,
    vel_error: f64,
    delay: f64,
}

fn vec3(field: impl Fn(usize) -> String, v: [f64; 3]) -> Result<[f64; 3], ModelError> {
    for (i, x) in v.iter().enumerate() {
        finite(|| field(i), *x)?;
    }
    Ok(v)
}

impl ObjectModel {
    /// Validate a spec: every number finite, bounds and radii ≥ 0, at most
    /// [`MAX_SHAPE_GENERATORS`] / [`MAX_ACC_GENERATORS`] generators, and a shape with some extent
    /// (an object of no size would make every check against it vacuous).
    pub fn new(spec: &ObjectSpec) -> Result<Self, ModelError> {
        let mut shape_generators = [[0.0; 3]; MAX_SHAPE_GENERATORS];
        let (gens, shape_radius): (Vec<[f64; 3]>, f64) = match &spec.shape {
            ShapeSpec::Sphere { radius } => {
                (vec![], positive(|| "shape.sphere.radius".into(), *radius)?)
            }
            ShapeSpec::Capsule { half_axis, radius } => (
                vec![vec3(
                    |i| format!("shape.capsule.half_axis[{i}]"),
                    *half_axis,
                )?],
                non_negative(|| "shape.capsule.radius".into(), *radius)?,
            ),
            ShapeSpec::Box { half_extents } => {
                let mut g = vec![];
                for (i, h) in half_extents.iter().enumerate() {
                    non_negative(|| format!("shape.box.half_extents[{i}]"), *h)?;
                    let mut e = [0.0; 3];
                    e[i] = *h;
                    g.push(e);
                }
                (g, 0.0)
            }
            ShapeSpec::Zonotope { generators, radius } => {
                if generators.len() > MAX_SHAPE_GENERATORS {
                    return Err(ModelError::LengthMismatch {
                        field: "shape.zonotope.generators".into(),
                        expected: MAX_SHAPE_GENERATORS,
                        found: generators.len(),
                    });
                }
                let mut g = vec![];
                for (k, v) in generators.iter().enumerate() {
                    g.push(vec3(
                        |i| format!("shape.zonotope.generators[{k}][{i}]"),
                        *v,
                    )?);
                }
                (g, non_negative(|| "shape.zonotope.radius".into(), *radius)?)
            }
        };
        let extent = shape_radius > 0.0 || gens.iter().flatten().any(|x| *x != 0.0);
        if !extent {
            return Err(ModelError::Invalid(format!(
                "object `{}`: the shape has no extent (a point object would make every check against it vacuous)",
                spec.name
            )));
        }
        for (k, g) in gens.iter().enumerate() {
            shape_generators[k] = *g;
        }
        if spec.acc_generators.len() > MAX_ACC_GENERATORS {
            return Err(ModelError::LengthMismatch {
                field: "acc_generators".into(),
                expected: MAX_ACC_GENERATORS,
                found: spec.acc_generators.len(),
            });
        }
        let mut acc_generators = [[0.0; 3]; MAX_ACC_GENERATORS];
        for (k, v) in spec.acc_generators.iter().enumerate() {
            acc_generators[k] = vec3(|i| format!("acc_generators[{k}][{i}]"), *v)?;
        }
        let max_speed = match spec.max_speed {
            Some(v) => Some(positive(|| "max_speed".into(), v)?),
            None => None,
        };
        Ok(Self {
            shape_generators,
            n_shape: gens.len(),
            shape_radius,
            max_acc: non_negative(|| "max_acc".into(), spec.max_acc)?,
            acc_bias: vec3(|i| format!("acc_bias[{i}]"), spec.acc_bias)?,
            acc_generators,
            n_acc: spec.acc_generators.len(),
            max_speed,
            pos_error: non_negative(
                || "measurement_error_pos".into(),
                spec.measurement_error_pos,
            )?,
            vel_error: non_negative(
                || "measurement_error_vel".into(),
                spec.measurement_error_vel,
            )?,
            delay: non_negative(|| "delay".into(), spec.delay)?,
        })
    }

    /// The shape's generators (m).
    pub fn shape_generators(&self) -> &[[f64; 3]] {
        &self.shape_generators[..self.n_shape]
    }
    /// The shape's dilation radius (m).
    pub fn shape_radius(&self) -> f64 {
        self.shape_radius
    }
    /// Euclidean acceleration bound beyond bias and generators (m/s²).
    pub fn max_acc(&self) -> f64 {
        self.max_acc
    }
    /// Constant acceleration (m/s²).
    pub fn acc_bias(&self) -> [f64; 3] {
        self.acc_bias
    }
    /// Generators of the zonotope part of the acceleration set (m/s²).
    pub fn acc_generators(&self) -> &[[f64; 3]] {
        &self.acc_generators[..self.n_acc]
    }
    /// Speed bound (m/s), if any.
    pub fn max_speed(&self) -> Option<f64> {
        self.max_speed
    }
    /// Position measurement error bound (m).
    pub fn pos_error(&self) -> f64 {
        self.pos_error
    }
    /// Velocity measurement error bound (m/s).
    pub fn vel_error(&self) -> f64 {
        self.vel_error
    }
    /// Sensor delay (s).
    pub fn delay(&self) -> f64 {
        self.delay
    }
}

impl TryFrom<&ObjectSpec> for ObjectModel {
    type Error = ModelError;
    fn try_from(spec: &ObjectSpec) -> Result<Self, ModelError> {
        Self::new(spec)
    }
}

/// The rolling ball of the paper's robomimic experiment: radius 4 cm, |a| ≤ 3 m/s², speed ≤ 1
/// m/s, 5 mm / 2 cm/s measurement errors, 30 ms delay.
pub fn default_ball() -> ObjectSpec {
    ObjectSpec {
        name: "ball".into(),
        shape: ShapeSpec::Sphere { radius: 0.04 },
        max_acc: 3.0,
        acc_bias: [0.0; 3],
        acc_generators: vec![],
        max_speed: Some(1.0),
        measurement_error_pos: 0.005,
        measurement_error_vel: 0.02,
        delay: 0.03,
    }
}

/// What contact with a dynamic object the task allows (JSON: `"no_contact"`, `"ssm"` or
/// `{"pfl": {"threshold": 2.0}}`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum ObjectContact {
    /// No contact at all, moving or not (an inanimate object that must not be touched).
    NoContact,
    /// Contact only while the robot is at rest (every joint speed within the rest speed).
    Ssm,
    /// Contact only while the whole robot's kinetic energy is at most `threshold` (J).
    Pfl {
        /// Energy threshold (J, ≥ 0).
        threshold: f64,
    },
}

impl ObjectContact {
    /// Validate: a PFL threshold must be finite and ≥ 0.
    pub fn validated(self) -> Result<Self, ModelError> {
        if let ObjectContact::Pfl { threshold } = self {
            non_negative(|| "contact.pfl.threshold".into(), threshold)?;
        }
        Ok(self)
    }
}

/// Names of the built-in objects.
pub const BUILTIN_OBJECTS: &[&str] = &["ball"];

/// A built-in object's spec by name (`"ball"`: [`default_ball`]).
pub fn builtin_object(name: &str) -> Option<ObjectSpec> {
    match name {
        "ball" => Some(default_ball()),
        _ => None,
    }
}
