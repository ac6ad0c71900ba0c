//! Static environment shapes, against which a body part may be clamped.

use pacs_models::Capsule;
use pacs_reach::geometry::capsules_may_intersect;
use serde::{Deserialize, Serialize};

/// A static environment shape (for clamping decisions): a capsule or an axis-aligned box (m).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase")]
pub enum EnvShape {
    /// Capsule (a sphere when p1 = p2).
    Capsule {
        /// First endpoint (m).
        p1: [f64; 3],
        /// Second endpoint (m).
        p2: [f64; 3],
        /// Radius (m).
        radius: f64,
    },
    /// Axis-aligned box.
    Box {
        /// Minimum corner (m).
        min: [f64; 3],
        /// Maximum corner (m).
        max: [f64; 3],
    },
}

impl From<&Capsule> for EnvShape {
    fn from(c: &Capsule) -> Self {
        EnvShape::Capsule {
            p1: c.p1().coords.into(),
            p2: c.p2().coords.into(),
            radius: c.radius(),
        }
    }
}

impl EnvShape {
    /// True unless the capsule provably does not touch the shape.
    pub fn may_touch(&self, c: &Capsule) -> bool {
        match *self {
            EnvShape::Capsule { p1, p2, radius } => {
                let e = Capsule::new_unchecked(p1.into(), p2.into(), radius);
                capsules_may_intersect(&e, c)
            }
            EnvShape::Box { min, max } => {
                // The capsule meets the box iff its segment meets the box inflated by its radius;
                // slab test on the inflated box, with a small outward tolerance.
                let r = c.radius() * (1.0 + 1e-12) + 1e-9;
                let (a, b) = (c.p1(), c.p2());
                let (mut t0, mut t1) = (0.0f64, 1.0f64);
                for k in 0..3 {
                    let (lo, hi) = (min[k] - r, max[k] + r);
                    let d = b[k] - a[k];
                    if d.abs() < 1e-300 {
                        if a[k] < lo || a[k] > hi {
                            return false;
                        }
                    } else {
                        let (mut u, mut v) = ((lo - a[k]) / d, (hi - a[k]) / d);
                        if u > v {
                            std::mem::swap(&mut u, &mut v);
                        }
                        t0 = t0.max(u - 1e-12);
                        t1 = t1.min(v + 1e-12);
                        if t0 > t1 {
                            return false;
                        }
                    }
                }
                true
            }
        }
    }
}
