//! Which measurement is in use: the one rule for every stamped measurement (people and
//! objects), shared by the shield, the audit, the log writer and the runners.

use crate::human::HumanMeasurement;
use crate::object::ObjectMeasurement;

/// A measurement stamped with the time `t_meas` (s) at which it was taken.
pub trait Stamped {
    /// The measurement's time stamp (s).
    fn t_meas(&self) -> f64;
}

impl Stamped for HumanMeasurement {
    fn t_meas(&self) -> f64 {
        self.time()
    }
}

impl Stamped for ObjectMeasurement {
    fn t_meas(&self) -> f64 {
        self.time
    }
}

/// Whether a measurement stamped `new` (s) replaces the one in use, stamped `current` (`None`:
/// none in use yet).
///
/// Guarantee: it does exactly when it is strictly newer (`current < new`). An older or
/// equal-stamp measurement arriving later is ignored, so the first of equal stamps stays in
/// use; a NaN stamp on either side never replaces anything (with no measurement in use, any
/// measurement is taken).
#[inline]
pub fn stamp_supersedes(new: f64, current: Option<f64>) -> bool {
    current.is_none_or(|c| c < new)
}

/// Whether `new` replaces `current` as the measurement in use: [`stamp_supersedes`] on their
/// stamps.
#[inline]
pub fn supersedes<M: Stamped + ?Sized>(new: &M, current: Option<&M>) -> bool {
    stamp_supersedes(new.t_meas(), current.map(Stamped::t_meas))
}

/// Keep the newest of `latest` and `new` by [`supersedes`]: `new` is stored only if it
/// supersedes what `latest` holds.
#[inline]
pub fn keep_newest<M: Stamped + Clone>(new: &M, latest: &mut Option<M>) {
    if supersedes(new, latest.as_ref()) {
        *latest = Some(new.clone());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn obj(time: f64) -> ObjectMeasurement {
        ObjectMeasurement {
            time,
            position: [0.0; 3],
            velocity: None,
        }
    }

    #[test]
    fn strictly_newer_replaces_equal_and_older_do_not() {
        assert!(stamp_supersedes(1.0, None));
        assert!(stamp_supersedes(1.0, Some(0.5)));
        assert!(!stamp_supersedes(1.0, Some(1.0)));
        assert!(!stamp_supersedes(0.5, Some(1.0)));
        assert!(!stamp_supersedes(f64::NAN, Some(1.0)));
        assert!(!stamp_supersedes(1.0, Some(f64::NAN)));
        assert!(stamp_supersedes(f64::NAN, None));
        assert!(!stamp_supersedes(
            f64::NEG_INFINITY,
            Some(f64::NEG_INFINITY)
        ));
    }

    #[test]
    fn keep_newest_keeps_the_first_of_equal_stamps() {
        let mut latest = None;
        let mut a = obj(1.0);
        keep_newest(&a, &mut latest);
        a.position = [1.0; 3];
        keep_newest(&a, &mut latest);
        assert_eq!(latest.map(|m| m.position), Some([0.0; 3]));
        keep_newest(&obj(0.5), &mut latest);
        assert_eq!(latest.map(|m| m.time), Some(1.0));
        keep_newest(&obj(2.0), &mut latest);
        assert_eq!(latest.map(|m| m.time), Some(2.0));
    }
}
