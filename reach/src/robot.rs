//! Robot reachable occupancy: capsules that contain every link capsule for every configuration in
//! a joint box `[q_lo, q_hi]` (plus a Cartesian tracking-error margin).
//!
//! Two rigorous enclosures are computed per capsule endpoint and the tighter one is used:
//! - **interval forward kinematics** over the box in midpoint-radius form: each frame's rotation
//!   and origin as a float matrix plus an elementwise radius (sin/cos enclosed by
//!   [`crate::rounding::sin_cos_interval`]; products bound their rounding error by Higham's γ₄ and
//!   every radius is inflated by 1e-13 relative to cover its own rounding); an endpoint's box is
//!   enclosed by the ball around its midpoint through the farthest corner;
//! - **mean-value form**: the endpoint at the box centre q_c (interval FK of the point box) plus
//!   Σ_j δ_j · sup‖p − o_j‖, where δ_j is the half-width of joint j's range and sup‖p − o_j‖ (over the
//!   box, from the interval FK) bounds ‖∂p/∂q_j‖ = ‖z_j × (p − o_j)‖ on the whole box (mean value
//!   theorem along the segment from q_c to q).
//!
//! A point of a link capsule is a convex combination of its endpoints plus a radius offset, so a
//! capsule between the two endpoint centres with radius max(e₁, e₂) + r contains it.
//! Frame origins and axes are taken as the f64 values of the model's rotation matrices; the
//! difference to the quaternion form used by nominal kinematics (≤ 1e-14 m over the FR3 chain) is
//! covered by [`MODEL_PAD`].

use crate::rounding::{add_up, mul_up, norm3_up, sin_cos_interval, sub_up};
use nalgebra::{Matrix3, Point3, Vector3};
use pacs_models::{Capsule, MAX_DOF, RobotModel};

/// Margin (m) covering the difference between quaternion and matrix representations of the
/// model's fixed transforms (documented bound ≤ 1e-14 m; padded a hundredfold).
pub const MODEL_PAD: f64 = 1e-12;

/// Relative bound on the rounding error of a dot product of length ≤ 4 computed in f64:
/// γ₄ = 4u/(1−4u) < 4.45e-16 (Higham, *Accuracy and Stability*, Thm 3.1), doubled for margin.
const GAMMA: f64 = 1e-15;
/// Relative inflation applied to every radius computed as a sum of ≤ 16 non-negative products:
/// round-to-nearest loses at most a factor (1 − u)^16 > 1 − 2e-15 of the exact value.
const RAD_UP: f64 = 1.0 + 1e-13;
/// Absolute slack per element for underflow (each operation loses < 2⁻¹⁰⁷⁴ absolutely).
const TINY: f64 = 1e-290;

/// A 3×3 matrix known up to an elementwise radius: every exact matrix M with
/// |M − mid| ≤ rad (elementwise) is represented.
#[derive(Debug, Clone, Copy)]
struct MatMR {
    mid: Matrix3<f64>,
    rad: Matrix3<f64>,
}

/// A 3-vector known up to an elementwise radius.
#[derive(Debug, Clone, Copy)]
struct VecMR {
    mid: Vector3<f64>,
    rad: Vector3<f64>,
}

#[inline(always)]
fn inflate_m(m: Matrix3<f64>) -> Matrix3<f64> {
    m.map(|x| x * RAD_UP + TINY)
}

#[inline(always)]
fn inflate_v(v: Vector3<f64>) -> Vector3<f64> {
    v.map(|x| x * RAD_UP + TINY)
}

/// A·B: mid = fl(Aₘ·Bₘ); rad ≥ |Aₘ|·B_r + A_r·|Bₘ| + A_r·B_r + γ·|Aₘ|·|Bₘ|
/// (the last term bounds the rounding error of the midpoint product).
#[inline(always)]
fn mat_mul(a: &MatMR, b: &MatMR) -> MatMR {
    let aa = a.mid.abs();
    let ba = b.mid.abs();
    let mid = a.mid * b.mid;
    let rad = aa * b.rad + a.rad * (ba + b.rad) + (aa * ba) * GAMMA;
    MatMR {
        mid,
        rad: inflate_m(rad),
    }
}

/// A·v + t for an exact vector v (capsule endpoints, joint offsets).
#[inline(always)]
fn affine_point(r: &MatMR, t: &VecMR, v: &Vector3<f64>) -> VecMR {
    let va = v.abs();
    let rv = r.mid * v;
    let mid = rv + t.mid;
    let rad = r.rad * va + t.rad + (r.mid.abs() * va + t.mid.abs()) * GAMMA;
    VecMR {
        mid,
        rad: inflate_v(rad),
    }
}

/// Upper bound of sup ‖x‖ over a midpoint-radius vector.
#[inline(always)]
fn mag_up(v: &VecMR) -> f64 {
    let m = v.mid.abs() + v.rad;
    norm3_up(m.x * RAD_UP, m.y * RAD_UP, m.z * RAD_UP)
}

/// Upper bound of sup ‖x − y‖ for x, y in two midpoint-radius vectors.
#[inline(always)]
fn dist_sup_up(a: &VecMR, b: &VecMR) -> f64 {
    let d = (a.mid - b.mid).abs() * (1.0 + GAMMA) + a.rad + b.rad;
    norm3_up(
        d.x * RAD_UP + TINY,
        d.y * RAD_UP + TINY,
        d.z * RAD_UP + TINY,
    )
}

/// Midpoint and an upper bound of the distance from it to any represented point.
#[inline(always)]
fn mid_radius(v: &VecMR) -> (Point3<f64>, f64) {
    (
        Point3::from(v.mid),
        mag_up(&VecMR {
            mid: Vector3::zeros(),
            rad: v.rad,
        }),
    )
}

#[derive(Debug, Clone)]
struct JointData {
    /// Origin rotation (f64 matrix, taken as exact).
    r0: Matrix3<f64>,
    /// Origin translation (exact).
    t0: Vector3<f64>,
    /// Cross-product matrix K of the unit axis and K² (Rodrigues: R = I + sK + (1−c)K²).
    k: Matrix3<f64>,
    k2: Matrix3<f64>,
    /// Axis is +z (fast path).
    z_axis: bool,
    /// Unit axis in the joint frame (exact f64 values).
    axis: Vector3<f64>,
}

#[derive(Debug, Clone)]
struct InertialData {
    frame: usize,
    mass: f64,
    com: Vector3<f64>,
    /// Upper bound of the largest principal moment (Gershgorin, rounded up), kg·m².
    lambda_max: f64,
}

#[derive(Debug, Clone)]
struct CapsuleData {
    frame: usize,
    p1: Vector3<f64>,
    p2: Vector3<f64>,
    radius: f64,
}

/// Robot occupancy computer for one robot model; queries allocate nothing.
#[derive(Debug, Clone)]
pub struct RobotReach {
    dof: usize,
    base_r: Matrix3<f64>,
    base_t: Vector3<f64>,
    joints: Vec<JointData>,
    capsules: Vec<CapsuleData>,
    /// For each link: range of its capsules in `capsules`.
    link_ranges: Vec<(usize, usize)>,
    tracking_error: f64,
    inertials: Vec<InertialData>,
}

/// Enclosed frames: rotation and origin for frames 0..=n.
struct Frames {
    r: [MatMR; MAX_DOF + 1],
    t: [VecMR; MAX_DOF + 1],
}

/// Reusable scratch space for [`RobotReach`] queries (avoids re-initialising frame buffers).
pub struct ReachScratch {
    boxf: Frames,
    cent: Frames,
}

impl std::fmt::Debug for ReachScratch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("ReachScratch")
    }
}

impl Default for ReachScratch {
    fn default() -> Self {
        Self {
            boxf: Frames::new(),
            cent: Frames::new(),
        }
    }
}

impl Frames {
    fn new() -> Self {
        let zm = MatMR {
            mid: Matrix3::zeros(),
            rad: Matrix3::zeros(),
        };
        let zv = VecMR {
            mid: Vector3::zeros(),
            rad: Vector3::zeros(),
        };
        Self {
            r: [zm; MAX_DOF + 1],
            t: [zv; MAX_DOF + 1],
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
    pub fn try_new(
        model: &RobotModel,
        tracking_error: f64,
    ) -> Result<Self, crate::human::ReachError> {
        if !(tracking_error.is_finite() && tracking_error >= 0.0) {
            return Err(crate::human::ReachError::Input(format!(
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
                JointData {
                    r0: iso_r(&j.origin),
                    t0: iso_t(&j.origin),
                    k,
                    k2: k * k,
                    z_axis: a.x == 0.0 && a.y == 0.0 && a.z == 1.0,
                    axis: a,
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
                    p1: c.p1().coords,
                    p2: c.p2().coords,
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
                    com: i.com.coords,
                    lambda_max: lambda_max * (1.0 + 1e-12),
                })
            })
            .collect();
        Ok(Self {
            dof: model.dof(),
            base_r: iso_r(model.base()),
            base_t: iso_t(model.base()),
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

    fn frames(&self, lo: &[f64], hi: &[f64], f: &mut Frames) {
        f.r[0] = MatMR {
            mid: self.base_r,
            rad: Matrix3::zeros(),
        };
        f.t[0] = VecMR {
            mid: self.base_t,
            rad: Vector3::zeros(),
        };
        for (j, jd) in self.joints.iter().enumerate() {
            let (s, c) = sin_cos_interval(lo[j], hi[j]);
            let (sm, sr) = (s.mid(), s.rad_up());
            let (cm, cr) = (c.mid(), c.rad_up());
            // Local transform R0·Rot(θ) in midpoint-radius form (R0 exact).
            let local = if jd.z_axis {
                // Columns: R0·(c, s, 0), R0·(−s, c, 0), R0·(0, 0, 1).
                let (a, b) = (jd.r0.column(0), jd.r0.column(1));
                let (aa, ba) = (a.abs(), b.abs());
                let c0 = a * cm + b * sm;
                let c1 = b * cm - a * sm;
                let r0 = aa * cr + ba * sr + (aa * cm.abs() + ba * sm.abs()) * GAMMA;
                let r1 = ba * cr + aa * sr + (ba * cm.abs() + aa * sm.abs()) * GAMMA;
                MatMR {
                    mid: Matrix3::from_columns(&[c0, c1, jd.r0.column(2).into_owned()]),
                    rad: inflate_m(Matrix3::from_columns(&[r0, r1, Vector3::zeros()])),
                }
            } else {
                // R = I + sK + (1−c)K²: elementwise, mid and radius of each term.
                let omc = 1.0 - cm;
                let mid = Matrix3::identity() + jd.k * sm + jd.k2 * omc;
                let rad = jd.k.abs() * sr
                    + jd.k2.abs() * cr
                    + (jd.k.abs() * sm.abs() + jd.k2.abs() * omc.abs() + Matrix3::identity())
                        * GAMMA;
                let rot = MatMR {
                    mid,
                    rad: inflate_m(rad),
                };
                mat_mul(
                    &MatMR {
                        mid: jd.r0,
                        rad: Matrix3::zeros(),
                    },
                    &rot,
                )
            };
            f.t[j + 1] = affine_point(&f.r[j], &f.t[j], &jd.t0);
            f.r[j + 1] = mat_mul(&f.r[j], &local);
        }
    }

    /// Capsules (link-capsule order) that contain every point of every link capsule for every
    /// configuration `q` with `q_lo ≤ q ≤ q_hi` (rad), enlarged by the tracking error.
    /// `out.len()` must be [`Self::capsule_count`]. Allocates nothing.
    ///
    /// # Errors
    /// Wrong lengths, non-finite values or `q_lo > q_hi`.
    pub fn occupancy_into(
        &self,
        q_lo: &[f64],
        q_hi: &[f64],
        out: &mut [Capsule],
    ) -> Result<(), crate::human::ReachError> {
        self.occupancy_with(&mut ReachScratch::default(), q_lo, q_hi, out)
    }

    /// [`Self::occupancy_into`] with caller-provided scratch space (the hot-path form: nothing is
    /// initialised or allocated per call).
    pub fn occupancy_with(
        &self,
        scratch: &mut ReachScratch,
        q_lo: &[f64],
        q_hi: &[f64],
        out: &mut [Capsule],
    ) -> Result<(), crate::human::ReachError> {
        use crate::human::ReachError;
        let n = self.dof;
        if q_lo.len() != n || q_hi.len() != n {
            return Err(ReachError::Input(format!(
                "joint box: expected {n} values in q_lo and q_hi, found {} and {}",
                q_lo.len(),
                q_hi.len()
            )));
        }
        for i in 0..n {
            if !(q_lo[i].is_finite() && q_hi[i].is_finite()) || q_lo[i] > q_hi[i] {
                return Err(ReachError::Input(format!(
                    "joint box: joint {i}: need finite q_lo <= q_hi, got [{}, {}]",
                    q_lo[i], q_hi[i]
                )));
            }
        }
        if out.len() != self.capsules.len() {
            return Err(ReachError::Input(format!(
                "output buffer holds {}, need {}",
                out.len(),
                self.capsules.len()
            )));
        }
        let mut qc = [0.0; MAX_DOF];
        let mut delta = [0.0; MAX_DOF];
        for i in 0..n {
            qc[i] = 0.5 * q_lo[i] + 0.5 * q_hi[i];
            qc[i] = qc[i].clamp(q_lo[i], q_hi[i]);
            delta[i] = sub_up(q_hi[i], qc[i]).max(sub_up(qc[i], q_lo[i]));
        }
        let ReachScratch { boxf, cent } = scratch;
        self.frames(q_lo, q_hi, boxf);
        self.frames(&qc[..n], &qc[..n], cent);
        let margin = add_up(self.tracking_error, MODEL_PAD);
        for (ci, c) in self.capsules.iter().enumerate() {
            let k = c.frame;
            let mut ends = [(Point3::origin(), 0.0); 2];
            for (e, p) in [&c.p1, &c.p2].into_iter().enumerate() {
                let pb = affine_point(&boxf.r[k], &boxf.t[k], p);
                let (ca, ea) = mid_radius(&pb);
                // Mean-value form around the centre configuration.
                let pc = affine_point(&cent.r[k], &cent.t[k], p);
                let (cb, mut eb) = mid_radius(&pc);
                for (j, &dj) in delta.iter().enumerate().take(k.min(n)) {
                    if dj == 0.0 {
                        continue;
                    }
                    eb = add_up(eb, mul_up(dj, dist_sup_up(&pb, &boxf.t[j + 1])));
                }
                ends[e] = if eb < ea { (cb, eb) } else { (ca, ea) };
            }
            let r = add_up(add_up(ends[0].1.max(ends[1].1), c.radius), margin);
            out[ci] = Capsule::new_unchecked(ends[0].0, ends[1].0, r);
        }
        Ok(())
    }

    /// Upper bounds (J) of the kinetic energy ½ q̇ᵀ M_k(q) q̇ of the links carried by frames
    /// `1..=k`, for k = 0..=n, valid for every `q ∈ [q_lo, q_hi]` and `q̇ ∈ [dq_lo, dq_hi]`
    /// (rad, rad/s). `out.len()` must be `dof + 1`; `out[0] = 0`. Allocates nothing.
    ///
    /// Per link: ½·m·sup‖v_c‖² + ½·λ̄·sup‖ω‖², with v_c = Σ_j (z_j × (c − o_j))·q̇_j and
    /// ω = Σ_j z_j·q̇_j evaluated in interval arithmetic over the box frames, and λ̄ ≥ the largest
    /// principal moment of inertia (Gershgorin), since ωᵀ R I Rᵀ ω ≤ λ_max(I)‖ω‖².
    pub fn subchain_energy_bounds_into(
        &self,
        q_lo: &[f64],
        q_hi: &[f64],
        dq_lo: &[f64],
        dq_hi: &[f64],
        out: &mut [f64],
    ) -> Result<(), crate::human::ReachError> {
        use crate::human::ReachError;
        use crate::interval::Interval;
        let n = self.dof;
        self.check_box(q_lo, q_hi)?;
        self.check_box(dq_lo, dq_hi)
            .map_err(|e| ReachError::Input(format!("velocity {e}")))?;
        if out.len() != n + 1 {
            return Err(ReachError::Input(format!(
                "output buffer holds {}, need {}",
                out.len(),
                n + 1
            )));
        }
        let mut boxf = Frames::new();
        self.frames(q_lo, q_hi, &mut boxf);
        let to_iv = |v: &VecMR| -> [Interval; 3] {
            let w = |i: usize| {
                Interval::point(v.mid[i])
                    + Interval::new(-v.rad[i], v.rad[i]).unwrap_or(Interval::ENTIRE)
            };
            [w(0), w(1), w(2)]
        };
        let zero = VecMR {
            mid: Vector3::zeros(),
            rad: Vector3::zeros(),
        };
        let mut z = [[Interval::ZERO; 3]; MAX_DOF];
        let mut o = [[Interval::ZERO; 3]; MAX_DOF];
        let mut dq = [Interval::ZERO; MAX_DOF];
        for j in 0..n {
            z[j] = to_iv(&affine_point(&boxf.r[j + 1], &zero, &self.joints[j].axis));
            o[j] = to_iv(&boxf.t[j + 1]);
            dq[j] = Interval::new(dq_lo[j], dq_hi[j]).unwrap_or(Interval::ENTIRE);
        }
        let norm2_up =
            |v: &[Interval; 3]| add_up(add_up(v[0].sqr().hi(), v[1].sqr().hi()), v[2].sqr().hi());
        let mut per_frame = [0.0; MAX_DOF + 1];
        for l in &self.inertials {
            let k = l.frame;
            let c = to_iv(&affine_point(&boxf.r[k], &boxf.t[k], &l.com));
            let mut v = [Interval::ZERO; 3];
            let mut w = [Interval::ZERO; 3];
            for j in 0..k.min(n) {
                let r = [c[0] - o[j][0], c[1] - o[j][1], c[2] - o[j][2]];
                let zj = &z[j];
                let cross = [
                    zj[1] * r[2] - zj[2] * r[1],
                    zj[2] * r[0] - zj[0] * r[2],
                    zj[0] * r[1] - zj[1] * r[0],
                ];
                for i in 0..3 {
                    v[i] = v[i] + cross[i] * dq[j];
                    w[i] = w[i] + zj[i] * dq[j];
                }
            }
            let e = add_up(
                mul_up(0.5 * l.mass, norm2_up(&v)),
                mul_up(0.5 * l.lambda_max, norm2_up(&w)),
            );
            per_frame[k] = add_up(per_frame[k], e);
        }
        out[0] = 0.0;
        for k in 1..=n {
            out[k] = add_up(out[k - 1], per_frame[k]);
        }
        Ok(())
    }

    /// Upper bound (J) of the whole robot's kinetic energy over the boxes (see
    /// [`Self::subchain_energy_bounds_into`]).
    pub fn energy_bound(
        &self,
        q_lo: &[f64],
        q_hi: &[f64],
        dq_lo: &[f64],
        dq_hi: &[f64],
    ) -> Result<f64, crate::human::ReachError> {
        let mut out = [0.0; MAX_DOF + 1];
        self.subchain_energy_bounds_into(q_lo, q_hi, dq_lo, dq_hi, &mut out[..=self.dof])?;
        Ok(out[self.dof])
    }

    fn check_box(&self, lo: &[f64], hi: &[f64]) -> Result<(), crate::human::ReachError> {
        use crate::human::ReachError;
        let n = self.dof;
        if lo.len() != n || hi.len() != n {
            return Err(ReachError::Input(format!(
                "box: expected {n} values in lower and upper bounds, found {} and {}",
                lo.len(),
                hi.len()
            )));
        }
        for i in 0..n {
            if !(lo[i].is_finite() && hi[i].is_finite()) || lo[i] > hi[i] {
                return Err(ReachError::Input(format!(
                    "box: joint {i}: need finite lo <= hi, got [{}, {}]",
                    lo[i], hi[i]
                )));
            }
        }
        Ok(())
    }

    /// Allocating convenience form of [`Self::occupancy_into`].
    pub fn occupancy(
        &self,
        q_lo: &[f64],
        q_hi: &[f64],
    ) -> Result<Vec<Capsule>, crate::human::ReachError> {
        let mut out = vec![
            Capsule::new_unchecked(Point3::origin(), Point3::origin(), 0.0);
            self.capsules.len()
        ];
        self.occupancy_into(q_lo, q_hi, &mut out)?;
        Ok(out)
    }
}
