//! Robot reachable occupancy: capsules that contain every link capsule for every configuration in
//! a joint box `[q_lo, q_hi]` (plus a Cartesian tracking-error margin).
//!
//! Two rigorous enclosures are computed per capsule endpoint and the tighter one is used:
//! - **interval forward kinematics** over the box: each frame's rotation and origin as interval
//!   matrices (sin/cos enclosed by [`crate::rounding::sin_cos_interval`], products and sums by
//!   inari's outward rounding); an endpoint's interval box is enclosed by the ball around its
//!   midpoint through the farthest corner;
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

use crate::rounding::{add_up, norm3_up, sin_cos_interval, sub_up};
use inari::{Interval, interval};
use nalgebra::{Matrix3, Point3, Vector3};
use pacs_models::{Capsule, MAX_DOF, RobotModel};

/// Margin (m) covering the difference between quaternion and matrix representations of the
/// model's fixed transforms (documented bound ≤ 1e-14 m; padded a hundredfold).
pub const MODEL_PAD: f64 = 1e-12;

type IMat = [[Interval; 3]; 3];
type IVec = [Interval; 3];

#[inline(always)]
fn pt(x: f64) -> Interval {
    interval!(x, x).unwrap_or(Interval::ENTIRE)
}

fn imat(m: &Matrix3<f64>) -> IMat {
    let mut r = [[pt(0.0); 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            r[i][j] = pt(m[(i, j)]);
        }
    }
    r
}

#[inline(always)]
fn mat_mul(a: &IMat, b: &IMat) -> IMat {
    let mut r = [[pt(0.0); 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            r[i][j] = a[i][0].mul_add(b[0][j], a[i][1].mul_add(b[1][j], a[i][2] * b[2][j]));
        }
    }
    r
}

#[inline(always)]
fn mat_vec(a: &IMat, v: &IVec) -> IVec {
    let mut r = [pt(0.0); 3];
    for i in 0..3 {
        r[i] = a[i][0].mul_add(v[0], a[i][1].mul_add(v[1], a[i][2] * v[2]));
    }
    r
}

#[inline(always)]
fn vec_add(a: &IVec, b: &IVec) -> IVec {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// Upper bound of sup ‖x‖ over an interval vector.
#[inline(always)]
fn mag_up(v: &IVec) -> f64 {
    norm3_up(v[0].mag(), v[1].mag(), v[2].mag())
}

/// Midpoint and an upper bound of the distance from it to any point of the box.
#[inline(always)]
fn mid_radius(v: &IVec) -> (Point3<f64>, f64) {
    let mut m = [0.0; 3];
    let mut h = [0.0; 3];
    for i in 0..3 {
        m[i] = v[i].mid();
        h[i] = sub_up(v[i].sup(), m[i]).max(sub_up(m[i], v[i].inf()));
    }
    (Point3::from(m), norm3_up(h[0], h[1], h[2]))
}

#[derive(Debug, Clone)]
struct JointData {
    /// Origin rotation (f64 matrix, taken as exact).
    r0: IMat,
    /// Origin translation.
    t0: IVec,
    /// Cross-product matrix K of the unit axis and K² (Rodrigues: R = I + sK + (1−c)K²).
    k: IMat,
    k2: IMat,
    /// Axis is +z (fast path).
    z_axis: bool,
}

#[derive(Debug, Clone)]
struct CapsuleData {
    frame: usize,
    p1: IVec,
    p2: IVec,
    radius: f64,
}

/// Robot occupancy computer for one robot model; queries allocate nothing.
#[derive(Debug, Clone)]
pub struct RobotReach {
    dof: usize,
    base_r: IMat,
    base_t: IVec,
    joints: Vec<JointData>,
    capsules: Vec<CapsuleData>,
    /// For each link: range of its capsules in `capsules`.
    link_ranges: Vec<(usize, usize)>,
    tracking_error: f64,
}

/// Interval frames: rotation and origin for frames 0..=n.
struct Frames {
    r: [IMat; MAX_DOF + 1],
    t: [IVec; MAX_DOF + 1],
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
        let iso_r =
            |iso: &nalgebra::Isometry3<f64>| imat(iso.rotation.to_rotation_matrix().matrix());
        let iso_t = |iso: &nalgebra::Isometry3<f64>| {
            let t = iso.translation.vector;
            [pt(t.x), pt(t.y), pt(t.z)]
        };
        let joints = model
            .joints()
            .iter()
            .map(|j| {
                let a: Vector3<f64> = j.axis.into_inner();
                let k = Matrix3::new(0.0, -a.z, a.y, a.z, 0.0, -a.x, -a.y, a.x, 0.0);
                let ki = imat(&k);
                JointData {
                    r0: iso_r(&j.origin),
                    t0: iso_t(&j.origin),
                    k: ki,
                    k2: mat_mul(&ki, &ki),
                    z_axis: a.x == 0.0 && a.y == 0.0 && a.z == 1.0,
                }
            })
            .collect();
        let mut capsules = Vec::new();
        let mut link_ranges = Vec::new();
        for l in model.links() {
            let start = capsules.len();
            for c in &l.capsules {
                let v = |p: Point3<f64>| [pt(p.x), pt(p.y), pt(p.z)];
                capsules.push(CapsuleData {
                    frame: l.frame,
                    p1: v(c.p1()),
                    p2: v(c.p2()),
                    radius: c.radius(),
                });
            }
            link_ranges.push((start, capsules.len()));
        }
        Ok(Self {
            dof: model.dof(),
            base_r: iso_r(model.base()),
            base_t: iso_t(model.base()),
            joints,
            capsules,
            link_ranges,
            tracking_error,
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
        f.r[0] = self.base_r;
        f.t[0] = self.base_t;
        let one = pt(1.0);
        let zero = pt(0.0);
        for (j, jd) in self.joints.iter().enumerate() {
            let (s, c) = sin_cos_interval(lo[j], hi[j]);
            let rot: IMat = if jd.z_axis {
                [[c, -s, zero], [s, c, zero], [zero, zero, one]]
            } else {
                let omc = one - c;
                let mut r = [[zero; 3]; 3];
                for a in 0..3 {
                    for b in 0..3 {
                        let id = if a == b { one } else { zero };
                        r[a][b] = id + s * jd.k[a][b] + omc * jd.k2[a][b];
                    }
                }
                r
            };
            let local = mat_mul(&jd.r0, &rot);
            f.t[j + 1] = vec_add(&f.t[j], &mat_vec(&f.r[j], &jd.t0));
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
        let mut boxf = Frames {
            r: [[[pt(0.0); 3]; 3]; MAX_DOF + 1],
            t: [[pt(0.0); 3]; MAX_DOF + 1],
        };
        let mut cent = Frames {
            r: [[[pt(0.0); 3]; 3]; MAX_DOF + 1],
            t: [[pt(0.0); 3]; MAX_DOF + 1],
        };
        self.frames(q_lo, q_hi, &mut boxf);
        self.frames(&qc[..n], &qc[..n], &mut cent);
        let margin = add_up(self.tracking_error, MODEL_PAD);
        for (ci, c) in self.capsules.iter().enumerate() {
            let k = c.frame;
            let mut ends = [(Point3::origin(), 0.0); 2];
            for (e, p) in [&c.p1, &c.p2].into_iter().enumerate() {
                let pb = vec_add(&boxf.t[k], &mat_vec(&boxf.r[k], p));
                let (ca, ea) = mid_radius(&pb);
                // Mean-value form around the centre configuration.
                let pc = vec_add(&cent.t[k], &mat_vec(&cent.r[k], p));
                let (cb, mut eb) = mid_radius(&pc);
                for j in 0..k.min(n) {
                    if delta[j] == 0.0 {
                        continue;
                    }
                    let o = &boxf.t[j + 1];
                    let d = [pb[0] - o[0], pb[1] - o[1], pb[2] - o[2]];
                    eb = add_up(eb, crate::rounding::mul_up(delta[j], mag_up(&d)));
                }
                ends[e] = if eb < ea { (cb, eb) } else { (ca, ea) };
            }
            let r = add_up(add_up(ends[0].1.max(ends[1].1), c.radius), margin);
            out[ci] = Capsule::new_unchecked(ends[0].0, ends[1].0, r);
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
