//! Enclosed frames of the kinematic chain over a joint box: rotation and origin enclosures in
//! midpoint-radius form (radius `e` at the box centre, `w` over the box), the chain that
//! computes them, and the vectorised mean-value sums (module docs of [`super`]).

use super::lanes::*;
use super::{GAMMA, RAD_UP, ReachScratch, RobotReach, TINY, WIDE_DELTA};
use crate::joint_box::JointBox;
use crate::rounding::{TRIG_PAD, sin_cos_interval, sub_up};
use nalgebra::Matrix3;
use pacs_models::MAX_DOF;

/// Enclosure of a frame rotation: every exact rotation at the box centre lies within `e` of `m`
/// (elementwise), every exact rotation over the box within `w` of `m`.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct RotationEnclosure {
    pub(super) m: Mat3Lanes,
    pub(super) e: Mat3Lanes,
    pub(super) w: Mat3Lanes,
}

/// Enclosure of a vector (frame origin or point), as [`RotationEnclosure`].
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct VecEnc {
    pub(super) m: Lanes3,
    pub(super) e: Lanes3,
    pub(super) w: Lanes3,
}

impl RotationEnclosure {
    /// An exactly known matrix.
    pub(super) fn exact(m: &Matrix3<f64>) -> Self {
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
    pub(super) fn mul(&self, b: &RotationEnclosure) -> RotationEnclosure {
        let (aa, ba) = (self.m.abs(), b.m.abs());
        let m = self.m.mm(&b.m);
        let g = aa.mm(&ba).scale(GAMMA);
        let e = aa.mm(&b.e).add(&self.e.mm(&ba.add(&b.e))).add(&g).inflate();
        let w = aa.mm(&b.w).add(&self.w.mm(&ba.add(&b.w))).add(&g).inflate();
        RotationEnclosure { m, e, w }
    }

    /// A·v + t for an exact vector v.
    #[inline(always)]
    pub(super) fn affine(&self, t: &VecEnc, v: Lanes3) -> VecEnc {
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
pub(super) fn centre_trig(qc: f64, delta: f64) -> (f64, f64, f64, f64, f64) {
    let (s, c) = crate::ieee::sin_cos(qc);
    trig_radii(s, c, delta)
}

/// [`centre_trig`] for the libm values `s` = ŝ, `c` = ĉ at the centre (the arithmetic after
/// libm, separate so that the proofs beside it, `d1_centre_trig_radii` and
/// `d1_trig_radii_contract`, can take ŝ, ĉ as inputs): the same tuple, under the contract
/// |sin q_c − ŝ| ≤ `TRIG_PAD`, |cos q_c − ĉ| ≤ `TRIG_PAD`.
///
/// # Soundness
/// Kani contract ([`trig_radii_cover`], for the inputs [`trig_input`] admits): the midpoints are
/// ŝ, ĉ bit for bit, `e ≥ TRIG_PAD`, and `w_s ≥ min(|ŝ|·h + |ĉ|·s_δ + T·(h + s_δ + 1), 1 + |ŝ|)`
/// with h = min(δ²/2, 2), s_δ = min(δ, 1), T = `TRIG_PAD` (and `w_c` likewise, ŝ and ĉ swapped),
/// each bound evaluated with every operation rounded up, so the real-number bound of the module
/// doc of [`super`] holds. Proven on this function by `d1_trig_radii_contract`
/// (`proof_for_contract`; 4-bit ŝ, ĉ and δ a power of two); twin `d1_trig_radii_contract_holds`.
#[cfg_attr(kani, kani::requires(trig_input(s, c, delta)))]
#[cfg_attr(kani, kani::ensures(|r: &(f64, f64, f64, f64, f64)| trig_radii_cover(s, c, delta, *r)))]
#[inline(always)]
pub(super) fn trig_radii(s: f64, c: f64, delta: f64) -> (f64, f64, f64, f64, f64) {
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

/// The inputs [`trig_radii`]'s contract admits: libm's ŝ, ĉ in `[−1, 1]`, a half-width
/// `0 ≤ δ ≤ 1e100`.
#[cfg(any(test, kani))]
#[cfg_attr(kani, allow(dead_code))]
pub(super) fn trig_input(s: f64, c: f64, delta: f64) -> bool {
    s.abs() <= 1.0 && c.abs() <= 1.0 && (0.0..=1e100).contains(&delta)
}

/// The contract of [`trig_radii`]: `r = (ŝ, ĉ, e, w_s, w_c)` with the midpoints `s`, `c` bit for
/// bit, `e ≥ TRIG_PAD`, and each radius at least its bound ([`trig_radius_covers`]), all finite.
#[cfg(any(test, kani))]
#[cfg_attr(kani, allow(dead_code))]
pub(super) fn trig_radii_cover(s: f64, c: f64, delta: f64, r: (f64, f64, f64, f64, f64)) -> bool {
    let (s_out, c_out, e, ws, wc) = r;
    s_out.to_bits() == s.to_bits()
        && c_out.to_bits() == c.to_bits()
        && e.is_finite()
        && e >= TRIG_PAD
        && trig_radius_covers(s.abs(), c.abs(), delta, ws)
        && trig_radius_covers(c.abs(), s.abs(), delta, wc)
}

/// `w ≥ min(a·h + b·s_δ + T·(h + s_δ + 1), 1 + a)` with h = min(δ²/2, 2), s_δ = min(δ, 1),
/// T = `TRIG_PAD`, `w` finite: the right side evaluated with every product and sum rounded up
/// (`mul_up`, `add_up`: at least the exact value, claim C1), so the inequality holds for the
/// exact real numbers too.
#[cfg(any(test, kani))]
#[cfg_attr(kani, allow(dead_code))]
pub(super) fn trig_radius_covers(a: f64, b: f64, delta: f64, w: f64) -> bool {
    use crate::rounding::{add_up, mul_up};
    let (main, pad) = trig_radius_terms(a, b, delta, TRIG_PAD, mul_up, add_up);
    w.is_finite() && (w >= add_up(main, pad) || w >= add_up(1.0, a))
}

/// The two terms `(a·h + b·s_δ, T·(h + s_δ + 1))` of the radius bound of [`trig_radius_covers`]
/// (h = min(δ²/2, 2), s_δ = min(δ, 1); δ ≥ 2 ⟺ δ²/2 ≥ 2), each product and sum evaluated by
/// `mul`, `add`: rounded up in the contract, exactly on the grid of the split
/// `d1_centre_trig_radii` (whose oracle compares their exact sum).
#[cfg(any(test, kani))]
#[cfg_attr(kani, allow(dead_code))]
pub(super) fn trig_radius_terms(
    a: f64,
    b: f64,
    delta: f64,
    t: f64,
    mul: impl Fn(f64, f64) -> f64,
    add: impl Fn(f64, f64) -> f64,
) -> (f64, f64) {
    let h = if delta >= 2.0 {
        2.0
    } else {
        mul(mul(0.5, delta), delta)
    };
    let sd = delta.min(1.0);
    let main = add(mul(a, h), mul(b, sd));
    let pad = mul(add(add(h, sd), 1.0), t);
    (main, pad)
}

/// Enclosed frames: rotation and origin for frames 0..=n, plus the joint origins and half-widths
/// in joint-major arrays for the vectorised mean-value sum.
#[derive(Clone, Copy)]
pub(super) struct Frames {
    pub(super) r: [RotationEnclosure; MAX_DOF + 1],
    pub(super) t: [VecEnc; MAX_DOF + 1],
    /// Midpoint and box radius of the origin of joint j (= frame j + 1), per coordinate.
    pub(super) om: [[Lanes3; JCH]; 3],
    pub(super) ow: [[Lanes3; JCH]; 3],
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

impl RobotReach {
    /// Enclosed frames for the box `q` (of this model's dof: checked by the caller), stored
    /// in `scratch` together with the box; with `reuse`, does nothing if `scratch` already
    /// holds this box computed by this `RobotReach`.
    pub(super) fn frames(&self, q: &JointBox, scratch: &mut ReachScratch, reuse: bool) {
        let n = self.dof;
        if reuse && scratch.owner == self.id && scratch.held.as_ref() == Some(q) {
            return;
        }
        let (lo, hi) = (q.lo(), q.hi());
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
        scratch.held = Some(*q);
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
    pub(super) fn mean_value_sums(
        f: &Frames,
        delta: &[Lanes3; JCH],
        p: [&VecEnc; 2],
        k: usize,
    ) -> [f64; 2] {
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
}
