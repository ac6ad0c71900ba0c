//! Geometric primitives shared by the models: capsules (a sphere is a capsule with `p1 == p2`).

use crate::error::{ModelError, non_negative};
use nalgebra::{Isometry3, Point3};
use serde::{Deserialize, Serialize};

/// A capsule: all points within `radius` (m) of the segment `p1`–`p2`.
///
/// Valid by construction: finite endpoints and a finite radius `>= 0`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "CapsuleSpec", into = "CapsuleSpec")]
pub struct Capsule {
    p1: Point3<f64>,
    p2: Point3<f64>,
    radius: f64,
}

/// Serde form of a capsule: `{"p1": [x,y,z], "p2": [x,y,z], "radius": r}` in metres.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CapsuleSpec {
    /// First segment endpoint (m).
    pub p1: [f64; 3],
    /// Second segment endpoint (m).
    pub p2: [f64; 3],
    /// Radius around the segment (m).
    pub radius: f64,
}

impl Capsule {
    /// Build a capsule; fails on non-finite coordinates or a negative/non-finite radius.
    pub fn new(p1: Point3<f64>, p2: Point3<f64>, radius: f64) -> Result<Self, ModelError> {
        for (i, v) in p1.iter().chain(p2.iter()).enumerate() {
            if !v.is_finite() {
                let which = if i < 3 { "p1" } else { "p2" };
                return Err(ModelError::InvalidValue {
                    field: format!("{which}[{}]", i % 3),
                    value: *v,
                    reason: "must be finite",
                });
            }
        }
        non_negative(|| "radius".into(), radius)?;
        Ok(Self { p1, p2, radius })
    }

    /// A ball of `radius` around `centre`.
    pub fn sphere(centre: Point3<f64>, radius: f64) -> Result<Self, ModelError> {
        Self::new(centre, centre, radius)
    }

    /// Build without checks. Caller guarantees finite endpoints and `radius >= 0` (hot paths).
    #[inline]
    pub fn new_unchecked(p1: Point3<f64>, p2: Point3<f64>, radius: f64) -> Self {
        debug_assert!(radius >= 0.0 && radius.is_finite(), "radius {radius}");
        Self { p1, p2, radius }
    }

    /// First endpoint of the axis segment (m).
    #[inline]
    pub fn p1(&self) -> Point3<f64> {
        self.p1
    }
    /// Second endpoint of the axis segment (m).
    #[inline]
    pub fn p2(&self) -> Point3<f64> {
        self.p2
    }
    /// Radius (m).
    #[inline]
    pub fn radius(&self) -> f64 {
        self.radius
    }

    /// The capsule moved by a rigid transform (rounded to nearest; not an outer bound).
    pub fn transformed(&self, iso: &Isometry3<f64>) -> Self {
        Self {
            p1: iso * self.p1,
            p2: iso * self.p2,
            radius: self.radius,
        }
    }

    /// The serde form.
    pub fn to_spec(&self) -> CapsuleSpec {
        CapsuleSpec {
            p1: self.p1.coords.into(),
            p2: self.p2.coords.into(),
            radius: self.radius,
        }
    }
}

impl TryFrom<CapsuleSpec> for Capsule {
    type Error = ModelError;
    fn try_from(s: CapsuleSpec) -> Result<Self, ModelError> {
        Capsule::new(Point3::from(s.p1), Point3::from(s.p2), s.radius)
    }
}

impl From<Capsule> for CapsuleSpec {
    fn from(c: Capsule) -> Self {
        c.to_spec()
    }
}
