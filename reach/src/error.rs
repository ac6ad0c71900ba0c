//! The one error type of `pacs-reach`.

use crate::zonotope::ZonotopeError;
use thiserror::Error;

/// Errors of reachability computations: invalid inputs (measurements, intervals, joint boxes,
/// models), bounds that overflow, and the LTI/zonotope method's own limits.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ReachError {
    /// The input is invalid or a bound overflows; the message names the field and value.
    #[error("{0}")]
    Input(String),
    /// A joint box is invalid.
    #[error(transparent)]
    JointBox(#[from] crate::joint_box::JointBoxError),
    /// A zonotope operation failed.
    #[error(transparent)]
    Zonotope(#[from] ZonotopeError),
    /// `‖|A| r‖∞ / (η + 2) ≥ 1`: the remainder bound does not converge; use a smaller step or more terms.
    #[error("time step {step} s too large for {terms} Taylor terms (‖|A|r‖∞ = {norm})")]
    StepTooLarge {
        /// Step (s).
        step: f64,
        /// Taylor terms η.
        terms: usize,
        /// Upper bound of `‖|A| r‖∞`.
        norm: f64,
    },
    /// A human measurement puts keypoint `keypoint` farther than 10⁶ m from the world origin
    /// (beyond any robot's reach: a tracker's lost-track value, no measurement of a person in
    /// the cell). Typed, formatted only when shown: the shield meets it every step while a
    /// tracker has lost the person.
    #[error(
        "human measurement: positions[{keypoint}][{axis}] = {value} m, farther than 10^6 m from the world origin (a tracker's lost-track value?): no measurement of a person in the cell"
    )]
    BeyondReach {
        /// Keypoint index (the model's order).
        keypoint: usize,
        /// Axis (0 = x, 1 = y, 2 = z).
        axis: usize,
        /// The coordinate (m).
        value: f64,
    },
    /// A human occupancy was asked for an interval that starts before the measured state
    /// (`time − delay`) by more than a rounding: a typed error, formatted only when shown, since
    /// the audit asks every still-usable measurement and expects this for the newer ones.
    #[error(
        "interval [{t_a}, {t_b}] starts before the measured state (time {time} - delay {delay})"
    )]
    BeforeMeasurement {
        /// Interval start (s).
        t_a: f64,
        /// Interval end (s).
        t_b: f64,
        /// The measurement's time stamp (s).
        time: f64,
        /// The model's sensor delay (s).
        delay: f64,
    },
    /// An argument is outside its valid range.
    #[error("invalid {what}: {reason}")]
    Invalid {
        /// Which argument.
        what: &'static str,
        /// Why.
        reason: &'static str,
    },
}
