//! Robot reachable occupancy: capsules that contain every link capsule for every configuration in
//! a joint box `[q_lo, q_hi]` (plus a Cartesian tracking-error margin).
//!
//! One forward-kinematics chain is evaluated per query, at the box centre q_c (libm `sin`/`cos`
//! of q_c), in midpoint-radius form with **two radii** around the shared midpoint:
//! - `e`, valid at q_c only: libm error ([`crate::rounding::TRIG_PAD`]) and the rounding of the midpoint chain;
//! - `w`, valid over the whole box: additionally |sin q − sin q_c| ≤ |sin q_c|·min(δ²/2, 2) +
//!   |cos q_c|·min(δ, 1) for |q − q_c| ≤ δ (and likewise for cos), capped by 1 + |sin q_c|.
//!
//! Products bound the rounding error of the midpoint product by Higham's γ₄ (`GAMMA`) and
//! inflate every radius by 1e-13 relative to cover its own rounding. Two rigorous enclosures of
//! each capsule endpoint share the midpoint p̂ (the endpoint at q_c) and the tighter radius is
//! used:
//! - **interval forward kinematics** over the box: ‖w_p‖ (the box of the endpoint, enclosed by the
//!   ball through its farthest corner);
//! - **mean-value form**: ‖e_p‖ + Σ_j δ_j · sup‖p − o_j‖, where δ_j is the half-width of joint j's
//!   range and sup‖p − o_j‖ (over the box enclosures of p and of the joint origin o_j) bounds
//!   ‖∂p/∂q_j‖ = ‖z_j × (p − o_j)‖ on the whole box (mean value theorem along the segment from q_c
//!   to q).
//!
//! The mean-value sum is evaluated in round-to-nearest, vectorised over the joints, and padded
//! once at the end: it is an expression of at most 30 correctly rounded operations (one
//! subtraction of floats, which is relatively exact: fl(a − b) = (a − b)(1 + ε), |ε| ≤ u; the rest
//! `+ × √` on non-negative values), so the computed value is at least (1 − u)³⁰ > 1 − 4e-15 times
//! the exact one; multiplying by `RAD_UP` = 1 + 1e-13 covers that, and [`NORM_PAD`]·(1 + Σ (hi −
//! lo)) covers underflow (a square below the normal range loses < 2⁻¹⁰⁷⁴ absolutely, which a
//! square root turns into < 1e-161, then scaled by δ_j ≤ hi − lo in the sum).
//!
//! A point of a link capsule is a convex combination of its endpoints plus a radius offset, so a
//! capsule between the two endpoint centres with radius max(e₁, e₂) + r contains it.
//! Frame origins and axes are taken as the f64 values of the model's rotation matrices; the
//! difference to the quaternion form used by nominal kinematics (≤ 1e-14 m over the FR3 chain) is
//! covered by [`MODEL_PAD`].

use crate::joint_box::JointBox;
use crate::rounding::{add_up, mul_up, sub_up};
use nalgebra::{Matrix3, Point3, Vector3};
use pacs_models::{Capsule, MAX_DOF, RobotModel};

/// Margin (m) covering the difference between quaternion and matrix representations of the
/// model's fixed transforms (documented bound ≤ 1e-14 m; padded a hundredfold).
pub const MODEL_PAD: f64 = 1e-12;

/// Absolute pad (m) added to every Euclidean norm computed in round-to-nearest: covers the
/// underflow of squares of tiny components (see the module docs).
pub const NORM_PAD: f64 = 1e-150;

/// Relative bound on the rounding error of a dot product of length ≤ 4 computed in f64:
/// γ₄ = 4u/(1−4u) < 4.45e-16 (Higham, *Accuracy and Stability*, Thm 3.1), doubled for margin.
const GAMMA: f64 = 1e-15;
/// Relative inflation applied to every radius computed as an expression of ≤ 30 correctly
/// rounded operations on non-negative values: round-to-nearest loses at most a factor
/// (1 − u)^30 > 1 − 4e-15 of the exact value.
const RAD_UP: f64 = 1.0 + 1e-13;
/// Absolute slack per element for underflow (each operation loses < 2⁻¹⁰⁷⁴ absolutely).
const TINY: f64 = 1e-290;
/// Largest joint half-width (rad) for which one chain around the box centre serves both
/// enclosures; wider boxes also evaluate the chain with hull sin/cos enclosures (tighter there).
const WIDE_DELTA: f64 = 0.025;
// The kinetic-energy bound over joint and velocity boxes (claim C5).
mod energy;
// Enclosed frames of the chain and the mean-value sums.
mod frames;
// Vectors and matrices in SIMD lanes.
mod lanes;
/// The Kani splits of claim C4 on the building blocks of the enclosed frames (`trig_radii`,
/// `RotationEnclosure::mul`, `affine`), each also a property test (`proofs/README.md`).
#[cfg(any(test, kani))]
mod proofs;

use frames::*;
use lanes::*;

#[derive(Debug, Clone)]
struct JointData {
    /// Origin rotation (f64 matrix, taken as exact).
    r0: RotationEnclosure,
    /// Origin translation (exact).
    t0: Lanes3,
    /// Cross-product matrix K of the unit axis and K² (Rodrigues: R = I + sK + (1−c)K²).
    k: Mat3Lanes,
    k2: Mat3Lanes,
    /// Axis is +z (fast path).
    z_axis: bool,
    /// Unit axis in the joint frame (exact f64 values).
    axis: Lanes3,
    /// Columns of `r0` and their absolute values (z-axis fast path).
    r0c: [Lanes3; 3],
    r0a: [Lanes3; 2],
}

#[derive(Debug, Clone)]
struct InertialData {
    frame: usize,
    mass: f64,
    com: Lanes3,
    /// Upper bound of the largest principal moment (Gershgorin, rounded up), kg·m².
    lambda_max: f64,
}

#[derive(Debug, Clone)]
struct CapsuleData {
    frame: usize,
    p1: Lanes3,
    p2: Lanes3,
    radius: f64,
}

/// Robot occupancy computer for one robot model; queries allocate nothing.
#[derive(Debug, Clone)]
pub struct RobotReach {
    /// Unique per construction (clones share it: they hold the same model), keys frame reuse.
    id: u64,
    dof: usize,
    base_r: RotationEnclosure,
    base_t: Lanes3,
    identity: Mat3Lanes,
    joints: Vec<JointData>,
    capsules: Vec<CapsuleData>,
    /// For each link: range of its capsules in `capsules`.
    link_ranges: Vec<(usize, usize)>,
    tracking_error: f64,
    inertials: Vec<InertialData>,
}

/// Reusable scratch space for [`RobotReach`] queries (avoids re-initialising frame buffers).
/// It remembers the last joint box, so that an energy bound over the same box reuses the frames
/// of the occupancy computed just before.
#[derive(Clone)]
pub struct ReachScratch {
    /// The chain around the box centre (radius `e` at the centre, `w` over the box).
    a: Frames,
    /// For wide boxes only: the chain with the tightest sin/cos enclosures over the box (hull of
    /// the range, own midpoints), used for the interval form and the sup‖p − o_j‖ bounds.
    b: Frames,
    /// Whether `b` is in use (some half-width above [`WIDE_DELTA`]).
    wide: bool,
    /// Half-width δ_j of joint j's range around the centre (0 beyond the dof).
    delta: [Lanes3; JCH],
    /// The box the frames belong to (`None`: no frames yet).
    held: Option<JointBox>,
    /// Identity of the [`RobotReach`] that computed the frames (0: none).
    owner: u64,
}

impl std::fmt::Debug for ReachScratch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("ReachScratch")
    }
}

impl Default for ReachScratch {
    fn default() -> Self {
        Self {
            a: Frames::default(),
            b: Frames::default(),
            wide: false,
            delta: [Lanes3::default(); JCH],
            held: None,
            owner: 0,
        }
    }
}

impl RobotReach {
    /// Prepare for `model`; `tracking_error` (m, ≥ 0, finite) is added to every radius.
    ///
    /// # Panics
    /// Never for a validated model; a negative or non-finite `tracking_error` is clamped to be
    /// rejected by [`Self::try_new`] instead.
    pub fn new(model: &RobotModel, tracking_error: f64) -> Self {
        Self::try_new(model, tracking_error).expect("tracking error must be finite and >= 0")
    }

    /// Like [`Self::new`] but rejects a negative or non-finite tracking error.
    pub fn try_new(model: &RobotModel, tracking_error: f64) -> Result<Self, crate::ReachError> {
        if !(tracking_error.is_finite() && tracking_error >= 0.0) {
            return Err(crate::ReachError::Input(format!(
                "tracking_error: value {tracking_error} must be finite and >= 0"
            )));
        }
        let iso_r = |iso: &nalgebra::Isometry3<f64>| *iso.rotation.to_rotation_matrix().matrix();
        let iso_t = |iso: &nalgebra::Isometry3<f64>| iso.translation.vector;
        let joints = model
            .joints()
            .iter()
            .map(|j| {
                let a: Vector3<f64> = j.axis.into_inner();
                let k = Matrix3::new(0.0, -a.z, a.y, a.z, 0.0, -a.x, -a.y, a.x, 0.0);
                let r0 = iso_r(&j.origin);
                let c = |i: usize| col(&r0.column(i).into_owned());
                JointData {
                    r0: RotationEnclosure::exact(&r0),
                    t0: col(&iso_t(&j.origin)),
                    k: Mat3Lanes::from_matrix(&k),
                    k2: Mat3Lanes::from_matrix(&(k * k)),
                    z_axis: a.x == 0.0 && a.y == 0.0 && a.z == 1.0,
                    axis: col(&a),
                    r0c: [c(0), c(1), c(2)],
                    r0a: [cabs(c(0)), cabs(c(1))],
                }
            })
            .collect();
        let mut capsules = Vec::new();
        let mut link_ranges = Vec::new();
        for l in model.links() {
            let start = capsules.len();
            for c in &l.capsules {
                capsules.push(CapsuleData {
                    frame: l.frame,
                    p1: col(&c.p1().coords),
                    p2: col(&c.p2().coords),
                    radius: c.radius(),
                });
            }
            link_ranges.push((start, capsules.len()));
        }
        let inertials = model
            .links()
            .iter()
            .filter(|l| l.frame > 0)
            .filter_map(|l| {
                let i = l.inertial?;
                let m = &i.inertia;
                let lambda_max = (0..3)
                    .map(|r| {
                        let off = (0..3)
                            .filter(|&c| c != r)
                            .fold(0.0, |acc, c| add_up(acc, m[(r, c)].abs()));
                        add_up(m[(r, r)], off)
                    })
                    .fold(0.0, f64::max);
                // 1e-12 relative covers the rounding of the model's frame rotation of the tensor.
                Some(InertialData {
                    frame: l.frame,
                    mass: i.mass,
                    com: col(&i.com.coords),
                    lambda_max: lambda_max * (1.0 + 1e-12),
                })
            })
            .collect();
        static NEXT_ID: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);
        Ok(Self {
            id: NEXT_ID.fetch_add(1, std::sync::atomic::Ordering::Relaxed),
            dof: model.dof(),
            base_r: RotationEnclosure::exact(&iso_r(model.base())),
            base_t: col(&iso_t(model.base())),
            identity: Mat3Lanes::from_matrix(&Matrix3::identity()),
            joints,
            capsules,
            link_ranges,
            tracking_error,
            inertials,
        })
    }

    /// Number of output capsules (all link capsules, link order).
    pub fn capsule_count(&self) -> usize {
        self.capsules.len()
    }

    /// Index range of each link's capsules in the output.
    pub fn link_ranges(&self) -> &[(usize, usize)] {
        &self.link_ranges
    }

    /// Carrying frame of each output capsule (0 = base; i = after joint i).
    pub fn capsule_frame(&self, i: usize) -> usize {
        self.capsules[i].frame
    }

    /// Tracking-error margin (m).
    pub fn tracking_error(&self) -> f64 {
        self.tracking_error
    }

    /// Capsules (link-capsule order) that contain every point of every link capsule for every
    /// configuration `q` in the joint box `q` (rad), enlarged by the tracking error.
    /// `out.len()` must be [`Self::capsule_count`]. Allocates nothing.
    ///
    /// # Soundness
    /// Claim C4 (proofs/README.md): for every `q` in the box, every link capsule at `q` (enlarged
    /// by `tracking_error`) lies inside its output capsule. Harness `d1_robot_link_enlargement`
    /// (FR3, boxes ≤ 1 rad wide); mutant `x5` caught. Assumes the model's fixed transforms are
    /// exact up to `MODEL_PAD`.
    ///
    /// # Errors
    /// A box with another number of joints than the model, or a wrong `out` length.
    pub fn occupancy_into(
        &self,
        q: &JointBox,
        out: &mut [Capsule],
    ) -> Result<(), crate::ReachError> {
        self.occupancy_with(&mut ReachScratch::default(), q, out)
    }

    /// [`Self::occupancy_into`] with caller-provided scratch space (the hot-path form: nothing is
    /// initialised or allocated per call).
    pub fn occupancy_with(
        &self,
        scratch: &mut ReachScratch,
        q: &JointBox,
        out: &mut [Capsule],
    ) -> Result<(), crate::ReachError> {
        use crate::ReachError;
        let n = self.dof;
        self.check_dof(q)?;
        let (q_lo, q_hi) = (q.lo(), q.hi());
        if out.len() != self.capsules.len() {
            return Err(ReachError::Input(format!(
                "output buffer holds {}, need {}",
                out.len(),
                self.capsules.len()
            )));
        }
        self.frames(q, scratch, false);
        let (fa, fb) = (&scratch.a, &scratch.b);
        let margin = add_up(self.tracking_error, MODEL_PAD);
        // Underflow pad of the mean-value form: each square root's underflow loss (< 1e-161) is
        // scaled by δ_j before the sum, so the pad grows with Σ δ_j ≤ Σ (hi − lo).
        let mv_pad = {
            let mut w = 1.0;
            for i in 0..n {
                w = add_up(w, sub_up(q_hi[i], q_lo[i]));
            }
            mul_up(NORM_PAD, w)
        };
        for (ci, c) in self.capsules.iter().enumerate() {
            let k = c.frame;
            let kk = k.min(n);
            let (r, t) = (&fa.r[k], &fa.t[k]);
            let pa = [r.affine(t, c.p1), r.affine(t, c.p2)];
            let point = |v: &VecEnc| {
                let m = v.m.arr();
                Point3::new(m[0], m[1], m[2])
            };
            let e_centre = |v: &VecEnc| {
                let e = v.e.arr();
                crate::ieee::sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2])
            };
            let ends = if scratch.wide {
                // Interval FK over the box (own midpoint) vs the mean-value form around the
                // centre.
                let (r, t) = (&fb.r[k], &fb.t[k]);
                let pb = [r.affine(t, c.p1), r.affine(t, c.p2)];
                let mv = Self::mean_value_sums(fb, &scratch.delta, [&pb[0], &pb[1]], kk);
                let end = |e: usize| {
                    let ea = norm_up(pb[e].w);
                    let eb = (e_centre(&pa[e]) + mv[e]) * RAD_UP + mv_pad;
                    if eb < ea {
                        (point(&pa[e]), eb)
                    } else {
                        (point(&pb[e]), ea)
                    }
                };
                [end(0), end(1)]
            } else {
                // Both forms share the centre midpoint.
                let mv = Self::mean_value_sums(fa, &scratch.delta, [&pa[0], &pa[1]], kk);
                let end = |e: usize| {
                    let ea = norm_up(pa[e].w);
                    let eb = (e_centre(&pa[e]) + mv[e]) * RAD_UP + mv_pad;
                    (point(&pa[e]), ea.min(eb))
                };
                [end(0), end(1)]
            };
            let r = add_up(add_up(ends[0].1.max(ends[1].1), c.radius), margin);
            if !r.is_finite() {
                return Err(ReachError::Input(format!(
                    "capsule {ci}: the occupancy radius overflows (the joint box or tracking_error {:?} is too large)",
                    self.tracking_error
                )));
            }
            out[ci] = Capsule::new_unchecked(ends[0].0, ends[1].0, r);
        }
        Ok(())
    }

    /// A box over this model's joints (the box itself is valid by construction).
    fn check_dof(&self, b: &JointBox) -> Result<(), crate::ReachError> {
        if b.dof() != self.dof {
            return Err(crate::ReachError::Input(format!(
                "joint box: expected {} joints, found {}",
                self.dof,
                b.dof()
            )));
        }
        Ok(())
    }

    /// Allocating convenience form of [`Self::occupancy_into`].
    pub fn occupancy(&self, q: &JointBox) -> Result<Vec<Capsule>, crate::ReachError> {
        let mut out = vec![
            Capsule::new_unchecked(Point3::origin(), Point3::origin(), 0.0);
            self.capsules.len()
        ];
        self.occupancy_into(q, &mut out)?;
        Ok(out)
    }
}
