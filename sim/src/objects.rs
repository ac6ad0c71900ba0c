//! Scripted dynamic objects (ground truth) and their measurement model: the paper's rolling
//! sphere, as a [`pacs_models::object::ObjectModel`] that the filters, the log and the audit
//! treat as an object (not as a one-keypoint human).

use crate::humans::Rng;
use pacs_models::object::{ObjectContact, ObjectModel, ObjectSpec, ShapeSpec};
use pacs_models::{Capsule, ModelError};
use pacs_reach::object::ObjectMeasurement;

/// A ground-truth object motion: the reference point's position (m) and velocity (m/s) at time
/// `t` (s).
pub trait ObjectScript: Send + Sync {
    /// Position and velocity at `t`.
    fn state(&self, t: f64) -> ([f64; 3], [f64; 3]);
    /// Short description.
    fn name(&self) -> &str;
}

/// The paper's simulated obstacle: a sphere rolling on the table surface, on a circle of radius
/// `radius` (m) around `center` at angular speed `omega` (rad/s), or back and forth along y
/// when `radius` is negative (amplitude |radius|). Speed |radius|·ω, acceleration |radius|·ω².
#[derive(Debug, Clone)]
pub struct RollingSphere {
    /// Centre of the pattern (m); z is the sphere centre's height.
    pub center: [f64; 3],
    /// Pattern radius / amplitude (m); negative: back and forth along y.
    pub radius: f64,
    /// Angular speed (rad/s).
    pub omega: f64,
    /// Phase (rad).
    pub phase: f64,
}

impl ObjectScript for RollingSphere {
    fn state(&self, t: f64) -> ([f64; 3], [f64; 3]) {
        let a = self.omega * t + self.phase;
        let (c, r, w) = (self.center, self.radius, self.omega);
        if r >= 0.0 {
            (
                [c[0] + r * a.cos(), c[1] + r * a.sin(), c[2]],
                [-r * w * a.sin(), r * w * a.cos(), 0.0],
            )
        } else {
            (
                [c[0], c[1] - r * a.sin(), c[2]],
                [0.0, -r * w * a.cos(), 0.0],
            )
        }
    }
    fn name(&self) -> &str {
        "rolling-sphere"
    }
}

/// The task sphere's model: radius 5 cm, speed ≤ 0.6 m/s, |a| ≤ 2 m/s², position and velocity
/// measured within 5 mm and 5 cm/s, 20 ms sensor delay. Every [`RollingSphere`] of the tasks
/// stays within these bounds (checked by `sim/tests/evaluation.rs`).
pub fn sphere_spec() -> ObjectSpec {
    ObjectSpec {
        name: "sphere".into(),
        shape: ShapeSpec::Sphere { radius: 0.05 },
        max_acc: 2.0,
        acc_bias: [0.0; 3],
        acc_generators: vec![],
        max_speed: Some(0.6),
        measurement_error_pos: 0.005,
        measurement_error_vel: 0.05,
        delay: 0.02,
    }
}

/// An object of a scenario: its id (in logs), model, allowed contact and true motion.
pub struct SimObject {
    /// Id in the log header and the `object` records.
    pub id: String,
    /// The model as written to the log header.
    pub spec: ObjectSpec,
    /// The validated model the filters use.
    pub model: ObjectModel,
    /// What contact the task allows.
    pub contact: ObjectContact,
    /// Ground-truth motion.
    pub script: Box<dyn ObjectScript>,
}

impl SimObject {
    /// An object from its spec (validated).
    pub fn new(
        id: &str,
        spec: ObjectSpec,
        contact: ObjectContact,
        script: Box<dyn ObjectScript>,
    ) -> Result<Self, ModelError> {
        Ok(Self {
            id: id.into(),
            model: ObjectModel::new(&spec)?,
            spec,
            contact,
            script,
        })
    }

    /// The same object known exactly: no measurement error and no delay (the truth audit's
    /// model: it is fed the true states).
    pub fn exact_model(&self) -> Result<ObjectModel, ModelError> {
        ObjectModel::new(&ObjectSpec {
            measurement_error_pos: 0.0,
            measurement_error_vel: 0.0,
            delay: 0.0,
            ..self.spec.clone()
        })
    }

    /// Distance (m) between the true object at time `t` and a robot capsule (≤ 0: contact).
    /// Exact for a sphere; for other shapes a lower bound (the zonotope–capsule bound), so
    /// contact is never missed.
    pub fn separation(&self, t: f64, capsule: &Capsule) -> f64 {
        let (p, _) = self.script.state(t);
        let gens = self.model.shape_generators();
        match pacs_reach::object::OccupancyZonotope::from_parts(p, gens, [0.0; 3]) {
            Ok(z) => z.distance_lower_bound(self.model.shape_radius(), capsule),
            Err(_) => f64::NEG_INFINITY,
        }
    }
}

/// A camera for one object: position within the model's error (uniform in its ball) and
/// velocity within its error, of the state `delay` ago, every `period` seconds.
pub struct ObjectCamera {
    period: f64,
    rng: Rng,
    next: f64,
}

impl ObjectCamera {
    /// A camera with the given period (s) and noise seed.
    pub fn new(period: f64, seed: u64) -> Self {
        Self {
            period,
            rng: Rng::new(seed),
            next: 0.0,
        }
    }

    /// The measurement of `object` due at time `t`, if any.
    pub fn measure(&mut self, object: &SimObject, t: f64) -> Option<ObjectMeasurement> {
        if t + 1e-12 < self.next {
            return None;
        }
        self.next = t + self.period;
        let m = &object.model;
        let (p, v) = object.script.state(t - m.delay());
        // Stay strictly inside the error balls (the noise ball's radius is rounded).
        let ep = self.rng.in_ball(m.pos_error() * 0.999);
        let ev = self.rng.in_ball(m.vel_error() * 0.999);
        Some(ObjectMeasurement {
            time: t,
            position: [p[0] + ep[0], p[1] + ep[1], p[2] + ep[2]],
            velocity: Some([v[0] + ev[0], v[1] + ev[1], v[2] + ev[2]]),
        })
    }
}
