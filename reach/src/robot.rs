//! Robot reachable occupancy: capsules that contain every link capsule for every configuration in
//! a joint box `[q_lo, q_hi]` (plus a Cartesian tracking-error margin).
//!
//! One forward-kinematics chain is evaluated per query, at the box centre q_c (libm `sin`/`cos`
//! of q_c), in midpoint-radius form with **two radii** around the shared midpoint:
//! - `e`, valid at q_c only: libm error ([`TRIG_PAD`]) and the rounding of the midpoint chain;
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
use crate::rounding::{TRIG_PAD, add_up, mul_up, sin_cos_interval, sub_up};
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
/// Joints processed per vector chunk in the mean-value sum.
const LANES: usize = 4;
/// Chunks of joints in the mean-value sum.
const JCH: usize = MAX_DOF.div_ceil(LANES);
/// Lane masks: row r keeps the first r lanes.
const LANE_MASK: [[f64; LANES]; LANES + 1] = [
    [0.0, 0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0, 0.0],
    [1.0, 1.0, 0.0, 0.0],
    [1.0, 1.0, 1.0, 0.0],
    [1.0, 1.0, 1.0, 1.0],
];

// The kinetic-energy bound over joint and velocity boxes (claim C5).
mod energy;

/// A 3-vector in four lanes (lane 3 is unused), one AVX register on x86-64 with AVX (the
/// workspace builds for x86-64-v3), a plain array elsewhere; every operation is lanewise and
/// correctly rounded either way, so the error analysis does not depend on the backend.
#[derive(Clone, Copy)]
#[repr(transparent)]
struct Lanes3(simd::V);

// The AVX backend on x86-64 with AVX; the scalar backend elsewhere and under Kani (which
// supports no SIMD intrinsics). `lanes_match_bitwise` (tests below) checks that both give the
// same bits for every operation, so a proof over the scalar backend covers the AVX one.
#[cfg(all(target_arch = "x86_64", target_feature = "avx", not(kani)))]
use lanes_avx as simd;
#[cfg(not(all(target_arch = "x86_64", target_feature = "avx", not(kani))))]
use lanes_scalar as simd;

#[cfg(all(target_arch = "x86_64", target_feature = "avx", not(kani)))]
mod lanes_avx {
    use std::arch::x86_64::*;
    pub type V = __m256d;
    #[inline(always)]
    pub fn new(a: [f64; 4]) -> V {
        // SAFETY: AVX is enabled for the whole build (cfg above); `a` holds four f64.
        unsafe { _mm256_loadu_pd(a.as_ptr()) }
    }
    #[inline(always)]
    pub fn arr(v: V) -> [f64; 4] {
        // SAFETY: `__m256d` and `[f64; 4]` have the same size and every bit pattern is valid
        // for both.
        unsafe { std::mem::transmute::<V, [f64; 4]>(v) }
    }
    #[inline(always)]
    pub fn splat(x: f64) -> V {
        // SAFETY: AVX is enabled for the whole build (cfg above).
        unsafe { _mm256_set1_pd(x) }
    }
    #[inline(always)]
    pub fn add(a: V, b: V) -> V {
        // SAFETY: AVX is enabled for the whole build (cfg above).
        unsafe { _mm256_add_pd(a, b) }
    }
    #[inline(always)]
    pub fn sub(a: V, b: V) -> V {
        // SAFETY: AVX is enabled for the whole build (cfg above).
        unsafe { _mm256_sub_pd(a, b) }
    }
    #[inline(always)]
    pub fn mul(a: V, b: V) -> V {
        // SAFETY: AVX is enabled for the whole build (cfg above).
        unsafe { _mm256_mul_pd(a, b) }
    }
    #[inline(always)]
    pub fn fma(a: V, b: V, c: V) -> V {
        #[cfg(target_feature = "fma")]
        // SAFETY: FMA is enabled for the whole build (cfg above).
        unsafe {
            _mm256_fmadd_pd(a, b, c)
        }
        #[cfg(not(target_feature = "fma"))]
        add(mul(a, b), c)
    }
    #[inline(always)]
    pub fn sqrt(a: V) -> V {
        // SAFETY: AVX is enabled for the whole build (cfg above).
        unsafe { _mm256_sqrt_pd(a) }
    }
    #[inline(always)]
    pub fn abs(a: V) -> V {
        // SAFETY: AVX is enabled for the whole build (cfg above).
        unsafe { _mm256_andnot_pd(_mm256_set1_pd(-0.0), a) }
    }
}

#[cfg_attr(
    all(target_arch = "x86_64", target_feature = "avx", not(kani)),
    allow(dead_code)
)]
mod lanes_scalar {
    pub type V = [f64; 4];
    #[inline(always)]
    fn map2(a: V, b: V, f: impl Fn(f64, f64) -> f64) -> V {
        [f(a[0], b[0]), f(a[1], b[1]), f(a[2], b[2]), f(a[3], b[3])]
    }
    #[inline(always)]
    pub fn new(a: [f64; 4]) -> V {
        a
    }
    #[inline(always)]
    pub fn arr(v: V) -> [f64; 4] {
        v
    }
    #[inline(always)]
    pub fn splat(x: f64) -> V {
        [x; 4]
    }
    #[inline(always)]
    pub fn add(a: V, b: V) -> V {
        map2(a, b, |x, y| x + y)
    }
    #[inline(always)]
    pub fn sub(a: V, b: V) -> V {
        map2(a, b, |x, y| x - y)
    }
    #[inline(always)]
    pub fn mul(a: V, b: V) -> V {
        map2(a, b, |x, y| x * y)
    }
    /// Lanewise [`crate::ieee::mul_add`]: one rounding with hardware FMA (as the AVX backend),
    /// two without (and under Kani).
    #[inline(always)]
    pub fn fma(a: V, b: V, c: V) -> V {
        [
            crate::ieee::mul_add(a[0], b[0], c[0]),
            crate::ieee::mul_add(a[1], b[1], c[1]),
            crate::ieee::mul_add(a[2], b[2], c[2]),
            crate::ieee::mul_add(a[3], b[3], c[3]),
        ]
    }
    #[inline(always)]
    pub fn sqrt(a: V) -> V {
        a.map(crate::ieee::sqrt)
    }
    #[inline(always)]
    pub fn abs(a: V) -> V {
        a.map(f64::abs)
    }
}

impl Lanes3 {
    #[inline(always)]
    fn splat(x: f64) -> Lanes3 {
        Lanes3(simd::splat(x))
    }
    #[inline(always)]
    fn arr(self) -> [f64; 4] {
        simd::arr(self.0)
    }
}

impl Default for Lanes3 {
    fn default() -> Self {
        Lanes3(simd::splat(0.0))
    }
}

impl std::fmt::Debug for Lanes3 {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.arr().fmt(f)
    }
}

#[inline(always)]
fn cadd(a: Lanes3, b: Lanes3) -> Lanes3 {
    Lanes3(simd::add(a.0, b.0))
}
#[inline(always)]
fn csub(a: Lanes3, b: Lanes3) -> Lanes3 {
    Lanes3(simd::sub(a.0, b.0))
}
#[inline(always)]
fn cmul(a: Lanes3, b: Lanes3) -> Lanes3 {
    Lanes3(simd::mul(a.0, b.0))
}
#[inline(always)]
fn csqrt(a: Lanes3) -> Lanes3 {
    Lanes3(simd::sqrt(a.0))
}
#[inline(always)]
fn cscale(a: Lanes3, s: f64) -> Lanes3 {
    Lanes3(simd::mul(a.0, simd::splat(s)))
}
#[inline(always)]
fn cabs(a: Lanes3) -> Lanes3 {
    Lanes3(simd::abs(a.0))
}
#[inline(always)]
fn cinflate(a: Lanes3) -> Lanes3 {
    Lanes3(simd::fma(a.0, simd::splat(RAD_UP), simd::splat(TINY)))
}
/// a·s + c (one rounding with FMA, two without).
#[inline(always)]
fn cfma(a: Lanes3, s: f64, c: Lanes3) -> Lanes3 {
    Lanes3(simd::fma(a.0, simd::splat(s), c.0))
}
#[inline(always)]
fn col(v: &Vector3<f64>) -> Lanes3 {
    // Construction-time only; through memory (keeps the generated code within what valgrind
    // decodes).
    Lanes3(simd::new(std::hint::black_box([v.x, v.y, v.z, 0.0])))
}
/// Upper bound of the Euclidean norm of a non-negative radius vector (lanes 0..3).
#[inline(always)]
fn norm_up(r: Lanes3) -> f64 {
    let r = r.arr();
    crate::ieee::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]) * RAD_UP + NORM_PAD
}

/// A 3×3 matrix as three columns.
#[derive(Debug, Clone, Copy, Default)]
struct Mat3Lanes([Lanes3; 3]);

impl Mat3Lanes {
    #[inline(always)]
    fn from_matrix(m: &Matrix3<f64>) -> Self {
        let c = |j: usize| col(&m.column(j).into_owned());
        Mat3Lanes([c(0), c(1), c(2)])
    }
    /// M·v (v in lanes 0..3).
    #[inline(always)]
    fn mv(&self, v: Lanes3) -> Lanes3 {
        let v = v.arr();
        // Fused or not, each entry is a dot product of length 3 with at most 3 roundings.
        cfma(
            self.0[2],
            v[2],
            cfma(self.0[1], v[1], cscale(self.0[0], v[0])),
        )
    }
    #[inline(always)]
    fn mm(&self, b: &Mat3Lanes) -> Mat3Lanes {
        Mat3Lanes([self.mv(b.0[0]), self.mv(b.0[1]), self.mv(b.0[2])])
    }
    #[inline(always)]
    fn abs(&self) -> Mat3Lanes {
        Mat3Lanes([cabs(self.0[0]), cabs(self.0[1]), cabs(self.0[2])])
    }
    #[inline(always)]
    fn add(&self, b: &Mat3Lanes) -> Mat3Lanes {
        Mat3Lanes([
            cadd(self.0[0], b.0[0]),
            cadd(self.0[1], b.0[1]),
            cadd(self.0[2], b.0[2]),
        ])
    }
    #[inline(always)]
    fn scale(&self, s: f64) -> Mat3Lanes {
        Mat3Lanes([
            cscale(self.0[0], s),
            cscale(self.0[1], s),
            cscale(self.0[2], s),
        ])
    }
    #[inline(always)]
    fn inflate(&self) -> Mat3Lanes {
        Mat3Lanes([
            cinflate(self.0[0]),
            cinflate(self.0[1]),
            cinflate(self.0[2]),
        ])
    }
}

/// Enclosure of a frame rotation: every exact rotation at the box centre lies within `e` of `m`
/// (elementwise), every exact rotation over the box within `w` of `m`.
#[derive(Debug, Clone, Copy, Default)]
struct RotationEnclosure {
    m: Mat3Lanes,
    e: Mat3Lanes,
    w: Mat3Lanes,
}

/// Enclosure of a vector (frame origin or point), as [`RotationEnclosure`].
#[derive(Debug, Clone, Copy, Default)]
struct VecEnc {
    m: Lanes3,
    e: Lanes3,
    w: Lanes3,
}

impl RotationEnclosure {
    /// An exactly known matrix.
    fn exact(m: &Matrix3<f64>) -> Self {
        let m = Mat3Lanes::from_matrix(m);
        RotationEnclosure {
            m,
            e: Mat3Lanes::default(),
            w: Mat3Lanes::default(),
        }
    }

    /// A·B: mid = fl(Aₘ·Bₘ); each radius R ≥ |Aₘ|·B_R + A_R·(|Bₘ| + B_R) + γ·|Aₘ|·|Bₘ| (the
    /// last term bounds the rounding error of the midpoint product).
    #[inline(always)]
    fn mul(&self, b: &RotationEnclosure) -> RotationEnclosure {
        let (aa, ba) = (self.m.abs(), b.m.abs());
        let m = self.m.mm(&b.m);
        let g = aa.mm(&ba).scale(GAMMA);
        let e = aa.mm(&b.e).add(&self.e.mm(&ba.add(&b.e))).add(&g).inflate();
        let w = aa.mm(&b.w).add(&self.w.mm(&ba.add(&b.w))).add(&g).inflate();
        RotationEnclosure { m, e, w }
    }

    /// A·v + t for an exact vector v.
    #[inline(always)]
    fn affine(&self, t: &VecEnc, v: Lanes3) -> VecEnc {
        let va = cabs(v);
        let m = cadd(self.m.mv(v), t.m);
        let g = cscale(cadd(self.m.abs().mv(va), cabs(t.m)), GAMMA);
        VecEnc {
            m,
            e: cinflate(cadd(cadd(self.e.mv(va), t.e), g)),
            w: cinflate(cadd(cadd(self.w.mv(va), t.w), g)),
        }
    }
}

/// sin/cos of the box centre and their radii: `(ŝ, ĉ, e, w_s, w_c)` with |sin q_c − ŝ| ≤ e,
/// |cos q_c − ĉ| ≤ e, and |sin q − ŝ| ≤ w_s, |cos q − ĉ| ≤ w_c for every |q − q_c| ≤ δ.
#[inline(always)]
fn centre_trig(qc: f64, delta: f64) -> (f64, f64, f64, f64, f64) {
    let (s, c) = crate::ieee::sin_cos(qc);
    let (sa, ca) = (s.abs(), c.abs());
    // sin(q_c + t) − sin q_c = sin q_c (cos t − 1) + cos q_c sin t, 1 − cos t ≤ min(t²/2, 2),
    // |sin t| ≤ min(|t|, 1); the exact sin q_c, cos q_c are within TRIG_PAD of ŝ, ĉ.
    let h = (0.5 * delta * delta).min(2.0);
    let sd = delta.min(1.0);
    let (sp, cp) = (sa + TRIG_PAD, ca + TRIG_PAD);
    let ws = (sp * h + cp * sd).min(1.0 + sa) + 2.0 * TRIG_PAD;
    let wc = (cp * h + sp * sd).min(1.0 + ca) + 2.0 * TRIG_PAD;
    (s, c, TRIG_PAD, ws * RAD_UP + TINY, wc * RAD_UP + TINY)
}

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

/// Enclosed frames: rotation and origin for frames 0..=n, plus the joint origins and half-widths
/// in joint-major arrays for the vectorised mean-value sum.
#[derive(Clone, Copy)]
struct Frames {
    r: [RotationEnclosure; MAX_DOF + 1],
    t: [VecEnc; MAX_DOF + 1],
    /// Midpoint and box radius of the origin of joint j (= frame j + 1), per coordinate.
    om: [[Lanes3; JCH]; 3],
    ow: [[Lanes3; JCH]; 3],
}

impl Default for Frames {
    fn default() -> Self {
        Frames {
            r: [RotationEnclosure::default(); MAX_DOF + 1],
            t: [VecEnc::default(); MAX_DOF + 1],
            om: [[Lanes3::default(); JCH]; 3],
            ow: [[Lanes3::default(); JCH]; 3],
        }
    }
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
    /// The box the frames belong to (valid when `n > 0`).
    lo: [f64; MAX_DOF],
    hi: [f64; MAX_DOF],
    n: usize,
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
            lo: [0.0; MAX_DOF],
            hi: [0.0; MAX_DOF],
            n: 0,
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

    /// Enclosed frames for the box `[lo, hi]` (validated by the caller), stored in `scratch`
    /// together with the box; with `reuse`, does nothing if `scratch` already holds this box
    /// computed by this `RobotReach`.
    fn frames(&self, lo: &[f64], hi: &[f64], scratch: &mut ReachScratch, reuse: bool) {
        let n = self.dof;
        if reuse
            && scratch.owner == self.id
            && scratch.n == n
            && scratch.lo[..n] == *lo
            && scratch.hi[..n] == *hi
        {
            return;
        }
        let mut qc = [0.0; MAX_DOF];
        let mut delta = [0.0; JCH * LANES];
        for j in 0..n {
            qc[j] = (0.5 * lo[j] + 0.5 * hi[j]).clamp(lo[j], hi[j]);
            delta[j] = sub_up(hi[j], qc[j]).max(sub_up(qc[j], lo[j]));
        }
        for ch in 0..JCH {
            scratch.delta[ch] = Lanes3(simd::new(
                delta[ch * LANES..(ch + 1) * LANES]
                    .try_into()
                    .expect("chunk"),
            ));
        }
        scratch.wide = delta.iter().any(|&d| d > WIDE_DELTA);
        self.chain(&mut scratch.a, |j| centre_trig(qc[j], delta[j]));
        if scratch.wide {
            self.chain(&mut scratch.b, |j| {
                let (s, c) = sin_cos_interval(lo[j], hi[j]);
                let (ws, wc) = (s.rad_up(), c.rad_up());
                (s.mid(), c.mid(), ws.max(wc), ws, wc)
            });
        }
        scratch.lo[..n].copy_from_slice(lo);
        scratch.hi[..n].copy_from_slice(hi);
        scratch.n = n;
        scratch.owner = self.id;
    }

    /// One enclosed frame chain; `trig(j)` gives joint j's `(ŝ, ĉ, e, w_s, w_c)` as
    /// [`centre_trig`] does (midpoints and radii of sin/cos at the centre and over the box).
    #[inline(always)]
    fn chain(&self, f: &mut Frames, trig: impl Fn(usize) -> (f64, f64, f64, f64, f64)) {
        f.r[0] = self.base_r;
        f.t[0] = VecEnc {
            m: self.base_t,
            ..VecEnc::default()
        };
        let mut om = [[0.0; JCH * LANES]; 3];
        let mut ow = [[0.0; JCH * LANES]; 3];
        for (j, jd) in self.joints.iter().enumerate() {
            let (sm, cm, e, ws, wc) = trig(j);
            // Local transform R0·Rot(θ) in midpoint-radius form (R0 exact).
            let local = if jd.z_axis {
                // Columns: R0·(c, s, 0), R0·(−s, c, 0), R0·(0, 0, 1).
                let ([a, b, z], [aa, ba]) = (jd.r0c, jd.r0a);
                let c0 = cadd(cscale(a, cm), cscale(b, sm));
                let c1 = csub(cscale(b, cm), cscale(a, sm));
                let g0 = cscale(cadd(cscale(aa, cm.abs()), cscale(ba, sm.abs())), GAMMA);
                let g1 = cscale(cadd(cscale(ba, cm.abs()), cscale(aa, sm.abs())), GAMMA);
                let ab = cscale(cadd(aa, ba), e);
                let m = Mat3Lanes([c0, c1, z]);
                RotationEnclosure {
                    m,
                    e: Mat3Lanes([
                        cinflate(cadd(ab, g0)),
                        cinflate(cadd(ab, g1)),
                        Lanes3::default(),
                    ]),
                    w: Mat3Lanes([
                        cinflate(cadd(cadd(cscale(aa, wc), cscale(ba, ws)), g0)),
                        cinflate(cadd(cadd(cscale(ba, wc), cscale(aa, ws)), g1)),
                        Lanes3::default(),
                    ]),
                }
            } else {
                // R = I + sK + (1−c)K²: elementwise, mid and radius of each term.
                let omc = 1.0 - cm;
                let id = self.identity;
                let (ka, k2a) = (jd.k.abs(), jd.k2.abs());
                let m = id.add(&jd.k.scale(sm)).add(&jd.k2.scale(omc));
                let g = ka
                    .scale(sm.abs())
                    .add(&k2a.scale(omc.abs()))
                    .add(&id)
                    .scale(GAMMA);
                let rot = RotationEnclosure {
                    m,
                    e: ka.scale(e).add(&k2a.scale(e)).add(&g).inflate(),
                    w: ka.scale(ws).add(&k2a.scale(wc)).add(&g).inflate(),
                };
                jd.r0.mul(&rot)
            };
            let t = f.r[j].affine(&f.t[j], jd.t0);
            f.r[j + 1] = f.r[j].mul(&local);
            f.t[j + 1] = t;
            let (tm, tw) = (t.m.arr(), t.w.arr());
            for i in 0..3 {
                om[i][j] = tm[i];
                ow[i][j] = tw[i];
            }
        }
        for i in 0..3 {
            for ch in 0..JCH {
                let r = ch * LANES..(ch + 1) * LANES;
                f.om[i][ch] = Lanes3(simd::new(om[i][r.clone()].try_into().expect("chunk")));
                f.ow[i][ch] = Lanes3(simd::new(ow[i][r].try_into().expect("chunk")));
            }
        }
    }

    /// Upper bounds (before the final pad) of Σ_{j<k} δ_j · sup‖p − o_j‖ for the two points of
    /// `p` over their box enclosures and those of the joint origins, evaluated in
    /// round-to-nearest (module docs). Both points are processed together (independent
    /// dependency chains interleave).
    #[inline(always)]
    fn mean_value_sums(f: &Frames, delta: &[Lanes3; JCH], p: [&VecEnc; 2], k: usize) -> [f64; 2] {
        let (pm0, pw0, pm1, pw1) = (p[0].m.arr(), p[0].w.arr(), p[1].m.arr(), p[1].w.arr());
        let mut acc0 = Lanes3::default();
        let mut acc1 = Lanes3::default();
        for ch in 0..k.div_ceil(LANES) {
            let mut d20 = Lanes3::default();
            let mut d21 = Lanes3::default();
            for i in 0..3 {
                let (om, ow) = (f.om[i][ch], f.ow[i][ch]);
                let d0 = cadd(
                    cadd(cabs(csub(Lanes3::splat(pm0[i]), om)), Lanes3::splat(pw0[i])),
                    ow,
                );
                let d1 = cadd(
                    cadd(cabs(csub(Lanes3::splat(pm1[i]), om)), Lanes3::splat(pw1[i])),
                    ow,
                );
                d20 = cadd(d20, cmul(d0, d0));
                d21 = cadd(d21, cmul(d1, d1));
            }
            // Lanes of joints ≥ k are multiplied by 0 (a NaN there only ever discards this form).
            let mask = Lanes3(simd::new(LANE_MASK[(k - ch * LANES).min(LANES)]));
            let dl = cmul(delta[ch], mask);
            acc0 = cadd(acc0, cmul(csqrt(d20), dl));
            acc1 = cadd(acc1, cmul(csqrt(d21), dl));
        }
        let (a0, a1) = (acc0.arr(), acc1.arr());
        [
            (a0[0] + a0[1]) + (a0[2] + a0[3]),
            (a1[0] + a1[1]) + (a1[2] + a1[3]),
        ]
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
        self.frames(q_lo, q_hi, scratch, false);
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

#[cfg(all(test, target_arch = "x86_64", target_feature = "avx"))]
mod lanes_tests {
    use super::{lanes_avx as avx, lanes_scalar as scalar};

    fn lanes(state: &mut u64) -> [f64; 4] {
        let mut one = || {
            *state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let z = *state;
            let e = ((z >> 40) % 120) as i32 - 60;
            let v = (1.0 + (z >> 11) as f64 / (1u64 << 53) as f64) * 2f64.powi(e);
            match z % 8 {
                0 => 0.0,
                1 => -v,
                _ => v,
            }
        };
        [one(), one(), one(), one()]
    }

    /// The scalar backend (the one Kani verifies) and the AVX backend (the one that runs) give
    /// the same bits for every lanewise operation, so the occupancy code, written once over
    /// `simd::V`, computes the same result with either.
    #[test]
    fn lanes_match_bitwise() {
        let mut state = 99u64;
        let bits = |v: [f64; 4]| v.map(f64::to_bits);
        for _ in 0..100_000 {
            let (a, b, c) = (lanes(&mut state), lanes(&mut state), lanes(&mut state));
            let (va, vb, vc) = (avx::new(a), avx::new(b), avx::new(c));
            assert_eq!(bits(avx::arr(avx::add(va, vb))), bits(scalar::add(a, b)));
            assert_eq!(bits(avx::arr(avx::sub(va, vb))), bits(scalar::sub(a, b)));
            assert_eq!(bits(avx::arr(avx::mul(va, vb))), bits(scalar::mul(a, b)));
            assert_eq!(
                bits(avx::arr(avx::fma(va, vb, vc))),
                bits(scalar::fma(a, b, c))
            );
            assert_eq!(bits(avx::arr(avx::abs(va))), bits(scalar::abs(a)));
            assert_eq!(bits(avx::arr(avx::splat(a[0]))), bits(scalar::splat(a[0])));
            let pos = a.map(f64::abs);
            assert_eq!(
                bits(avx::arr(avx::sqrt(avx::new(pos)))),
                bits(scalar::sqrt(pos))
            );
        }
    }
}
