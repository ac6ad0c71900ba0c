//! [`JointLimits`]: validated per-joint position, velocity, acceleration and jerk limits.

use super::MAX_DOF;
use crate::error::{ModelError, finite, positive};

/// Joint limits as arrays over the joints; checked once at load (`q_min <= q_max`, all finite,
/// velocity, acceleration and jerk limits `> 0`).
#[derive(Debug, Clone, PartialEq)]
pub struct JointLimits {
    q_min: Vec<f64>,
    q_max: Vec<f64>,
    v_max: Vec<f64>,
    a_max: Vec<f64>,
    j_max: Vec<f64>,
}

impl JointLimits {
    /// An empty limits object for the model checker only (`cfg(kani)`): the audit's span
    /// harnesses (`h2_*`) stub every accessor `span_boxes` reads with constants, because
    /// symbolic execution does not fold values read back from the heap, and [`Self::new`]'s
    /// validation then keeps its error paths (`format!`, the allocator) in the formula. Never
    /// read: the stubs answer instead.
    #[cfg(kani)]
    #[doc(hidden)]
    pub fn placeholder_for_kani() -> Self {
        JointLimits {
            q_min: Vec::new(),
            q_max: Vec::new(),
            v_max: Vec::new(),
            a_max: Vec::new(),
            j_max: Vec::new(),
        }
    }

    /// Build from arrays, validating every entry (names the index and value on error).
    pub fn new(
        q_min: Vec<f64>,
        q_max: Vec<f64>,
        v_max: Vec<f64>,
        a_max: Vec<f64>,
        j_max: Vec<f64>,
    ) -> Result<Self, ModelError> {
        let n = q_min.len();
        if n == 0 || n > MAX_DOF {
            return Err(ModelError::Invalid(format!(
                "joint count {n} not in 1..={MAX_DOF}"
            )));
        }
        for (name, v) in [
            ("q_max", &q_max),
            ("v_max", &v_max),
            ("a_max", &a_max),
            ("j_max", &j_max),
        ] {
            if v.len() != n {
                return Err(ModelError::LengthMismatch {
                    field: format!("limits.{name}"),
                    expected: n,
                    found: v.len(),
                });
            }
        }
        for i in 0..n {
            finite(|| format!("limits.q_min[{i}]"), q_min[i])?;
            finite(|| format!("limits.q_max[{i}]"), q_max[i])?;
            if q_min[i] > q_max[i] {
                return Err(ModelError::InvalidValue {
                    field: format!("limits.q_max[{i}]"),
                    value: q_max[i],
                    reason: "must be >= q_min",
                });
            }
            positive(|| format!("limits.v_max[{i}]"), v_max[i])?;
            positive(|| format!("limits.a_max[{i}]"), a_max[i])?;
            positive(|| format!("limits.j_max[{i}]"), j_max[i])?;
        }
        Ok(Self {
            q_min,
            q_max,
            v_max,
            a_max,
            j_max,
        })
    }

    /// Number of joints.
    #[inline]
    pub fn dof(&self) -> usize {
        self.q_min.len()
    }
    /// Lower position limits (rad).
    #[inline]
    pub fn q_min(&self) -> &[f64] {
        &self.q_min
    }
    /// Upper position limits (rad).
    #[inline]
    pub fn q_max(&self) -> &[f64] {
        &self.q_max
    }
    /// Velocity limits (rad/s).
    #[inline]
    pub fn v_max(&self) -> &[f64] {
        &self.v_max
    }
    /// Acceleration limits (rad/s²).
    #[inline]
    pub fn a_max(&self) -> &[f64] {
        &self.a_max
    }
    /// Jerk limits (rad/s³).
    #[inline]
    pub fn j_max(&self) -> &[f64] {
        &self.j_max
    }

    /// Velocity, acceleration and jerk limits multiplied by the given factors in (0, 1];
    /// position limits unchanged.
    pub fn scaled(&self, v: f64, a: f64, j: f64) -> Result<Self, ModelError> {
        for (name, f) in [("v", v), ("a", a), ("j", j)] {
            if !(f > 0.0 && f <= 1.0) {
                return Err(ModelError::InvalidValue {
                    field: format!("limit_scale.{name}"),
                    value: f,
                    reason: "must be in (0, 1]",
                });
            }
        }
        Ok(Self {
            q_min: self.q_min.clone(),
            q_max: self.q_max.clone(),
            v_max: self.v_max.iter().map(|x| x * v).collect(),
            a_max: self.a_max.iter().map(|x| x * a).collect(),
            j_max: self.j_max.iter().map(|x| x * j).collect(),
        })
    }

    /// Replace acceleration and jerk limits by uniform values (e.g. the paper's 10 rad/s², 400 rad/s³),
    /// never above the current ones.
    pub fn with_uniform_acc_jerk(&self, a: f64, j: f64) -> Result<Self, ModelError> {
        positive(|| "a_max".into(), a)?;
        positive(|| "j_max".into(), j)?;
        let mut out = self.clone();
        out.a_max.iter_mut().for_each(|x| *x = x.min(a));
        out.j_max.iter_mut().for_each(|x| *x = x.min(j));
        Ok(out)
    }

    /// True iff every `q[i]` lies within `[q_min[i], q_max[i]]`.
    pub fn contains(&self, q: &[f64]) -> bool {
        q.len() == self.dof()
            && q.iter()
                .zip(self.q_min.iter().zip(&self.q_max))
                .all(|(x, (lo, hi))| *lo <= *x && *x <= *hi)
    }
}
