//! The kinetic-energy bound of [`RobotReach`] over joint and velocity boxes (claim C5): per
//! link ½·m·sup‖v_c‖² + ½·λ̄·sup‖ω‖² in round-to-nearest interval arithmetic with one final
//! widening ([`energy_iv`]), summed per sub-chain; the last entry bounds the whole robot.

use super::*;

/// Sound bounds of link velocities over joint and velocity boxes: interval arithmetic with
/// endpoints rounded to nearest and one final widening.
///
/// Each interval operation (sum, difference, product as min/max of the four endpoint
/// products) is evaluated in round-to-nearest. Compared with exact interval arithmetic on the
/// same inputs, every computed endpoint is off by at most γ_d·M, where d ≤ 24 is the depth of
/// the expression (midpoint ± radius → lower/upper bound, difference c − o, the two products and
/// the difference of a cross-product component, the velocity product, ≤ 16 sums, plus margin)
/// and M is the same expression evaluated on magnitudes (Higham, *Accuracy and Stability*,
/// Thm 3.1 and Lemma 3.3; min/max are exact and move an endpoint by at most the error of their
/// arguments). γ₂₄ < 2.7e-15 < [`GAMMA_E`]. Each velocity component is widened by `GAMMA_E·M` with
/// M accumulated alongside (plus `TINY_V` for underflow); squares and the final sums are
/// non-negative and covered by [`INFLATE`] and [`TINY_E`].
pub(super) mod energy_iv {
    /// Bound on the relative rounding error of the endpoint computations (module docs).
    pub const GAMMA_E: f64 = 1e-14;
    /// Final relative inflation of non-negative results (≤ 30 roundings each).
    pub const INFLATE: f64 = 1.0 + 1e-13;
    /// Absolute slack (J) for underflow in the squares and their weighted sum (each operation
    /// loses < 2⁻¹⁰⁷⁵ absolutely; a few dozen of them, scaled by masses and moments < 10³).
    pub const TINY_E: f64 = 1e-315;
    /// Absolute widening of each velocity component (m/s, rad/s) for underflow in the products
    /// and sums (< 2⁻¹⁰⁷⁵ each, a few hundred of them).
    const TINY_V: f64 = 1e-300;
    /// Inputs beyond this magnitude (never physical) make the bound +∞ (no overflow to NaN).
    pub const HUGE: f64 = 1e100;

    /// An interval [lo, hi] with endpoints rounded to nearest.
    pub type NearestInterval = (f64, f64);
    /// An interval 3-vector.
    pub type NearestInterval3 = [NearestInterval; 3];

    // Plain comparisons (one instruction each): no NaN can arise here, since every input is
    // finite and bounded (frames of finite joint values, velocities within `HUGE`).
    #[inline(always)]
    fn min(a: f64, b: f64) -> f64 {
        if a < b { a } else { b }
    }
    #[inline(always)]
    fn max(a: f64, b: f64) -> f64 {
        if a > b { a } else { b }
    }
    #[inline(always)]
    fn mul(a: NearestInterval, b: NearestInterval) -> NearestInterval {
        let (p, q, r, s) = (a.0 * b.0, a.0 * b.1, a.1 * b.0, a.1 * b.1);
        (min(min(p, q), min(r, s)), max(max(p, q), max(r, s)))
    }
    #[inline(always)]
    fn mag(a: NearestInterval) -> f64 {
        max(a.0.abs(), a.1.abs())
    }

    /// Upper bound (J) of one link's kinetic energy from the bounds `v2 ≥ sup‖v_c‖²` (m²/s²) and
    /// `w2 ≥ sup‖ω‖²` (rad²/s²): ½·m·v2 + ½·λ̄·w2 in round-to-nearest, inflated by [`INFLATE`]
    /// plus [`TINY_E`].
    ///
    /// # Soundness
    /// For `mass`, `lambda_max`, `v2`, `w2` ≥ 0 and finite (no overflow): the result is ≥ the
    /// exact ½·m·v2 + ½·λ̄·w2 (five roundings, each losing at most a factor 1 − u, and underflow
    /// below `TINY_E`). Harnesses `g1_link_energy_rounds_up` (Kani on a grid where the products
    /// round; its twin any inputs) and `g1_link_energy_exact_products` (Kani: 3-bit
    /// significands); mutant `x29` caught by both.
    #[inline(always)]
    pub fn link_energy(mass: f64, lambda_max: f64, v2: f64, w2: f64) -> f64 {
        (0.5 * mass * v2 + 0.5 * lambda_max * w2) * INFLATE + TINY_E
    }

    /// Upper bounds of sup‖v_c‖² and sup‖ω‖² for v_c = Σ_{j<k} (z_j × (c − o_j))·q̇_j and
    /// ω = Σ_{j<k} z_j·q̇_j.
    #[inline(always)]
    pub fn velocity_bounds(
        z: &[NearestInterval3],
        o: &[NearestInterval3],
        dq: &[NearestInterval],
        c: &NearestInterval3,
        k: usize,
    ) -> (f64, f64) {
        let mut v = [(0.0, 0.0); 3];
        let mut w = [(0.0, 0.0); 3];
        let (mut vg, mut wg) = ([0.0; 3], [0.0; 3]);
        for j in 0..k {
            let (zj, oj, d) = (&z[j], &o[j], dq[j]);
            let dmag = mag(d);
            let mut r = [(0.0, 0.0); 3];
            let mut rmag = [0.0; 3];
            for i in 0..3 {
                r[i] = (c[i].0 - oj[i].1, c[i].1 - oj[i].0);
                rmag[i] = mag(c[i]) + mag(oj[i]);
            }
            for i in 0..3 {
                let (a, b) = ((i + 1) % 3, (i + 2) % 3);
                // cross_i = z_a r_b − z_b r_a
                let p1 = mul(zj[a], r[b]);
                let p2 = mul(zj[b], r[a]);
                let x = (p1.0 - p2.1, p1.1 - p2.0);
                let t = mul(x, d);
                v[i] = (v[i].0 + t.0, v[i].1 + t.1);
                vg[i] += (mag(zj[a]) * rmag[b] + mag(zj[b]) * rmag[a]) * dmag;
                let u = mul(zj[i], d);
                w[i] = (w[i].0 + u.0, w[i].1 + u.1);
                wg[i] += mag(zj[i]) * dmag;
            }
        }
        let sq = |x: &NearestInterval3, g: &[f64; 3]| {
            let mut acc = 0.0;
            for i in 0..3 {
                let b = mag(x[i]) + GAMMA_E * g[i] + TINY_V;
                acc += b * b;
            }
            acc
        };
        (sq(&v, &vg), sq(&w, &wg))
    }
}

/// The Kani proofs of this module, each also a property test (`proofs/README.md`).
#[cfg(any(test, kani))]
mod proofs;

impl RobotReach {
    /// Upper bounds (J) of the kinetic energy ½ q̇ᵀ M_k(q) q̇ of the links carried by frames
    /// `1..=k`, for k = 0..=n, valid for every configuration in the box `q` and velocity in `dq`
    /// (rad, rad/s). `out.len()` must be `dof + 1`; `out[0] = 0`. Allocates nothing.
    ///
    /// Per link: ½·m·sup‖v_c‖² + ½·λ̄·sup‖ω‖², with v_c = Σ_j (z_j × (c − o_j))·q̇_j and
    /// ω = Σ_j z_j·q̇_j evaluated in interval arithmetic over the box frames, and λ̄ ≥ the largest
    /// principal moment of inertia (Gershgorin), since ωᵀ R I Rᵀ ω ≤ λ_max(I)‖ω‖².
    ///
    /// # Soundness
    /// Claim C5: each output is ≥ ½ q̇ᵀ M_k(q) q̇ for every `q`, `q̇` in the boxes; the last
    /// (`out[dof]`) bounds the whole robot's kinetic energy, what the ISO/TS 15066 rule uses.
    /// Harness `g1_energy_bound_dominates`; mutant `m5` caught.
    pub fn subchain_energy_bounds_into(
        &self,
        q: &JointBox,
        dq: &JointBox,
        out: &mut [f64],
    ) -> Result<(), crate::ReachError> {
        self.subchain_energy_bounds_with(&mut ReachScratch::default(), q, dq, out)
    }

    /// [`Self::subchain_energy_bounds_into`] with caller-provided scratch space; the enclosed
    /// frames of an occupancy just computed for the same joint box in `scratch` are reused.
    pub fn subchain_energy_bounds_with(
        &self,
        scratch: &mut ReachScratch,
        q: &JointBox,
        dq_box: &JointBox,
        out: &mut [f64],
    ) -> Result<(), crate::ReachError> {
        use crate::ReachError;
        let n = self.dof;
        self.check_dof(q)?;
        self.check_dof(dq_box)
            .map_err(|e| ReachError::Input(format!("velocity {e}")))?;
        let (dq_lo, dq_hi) = (dq_box.lo(), dq_box.hi());
        if out.len() != n + 1 {
            return Err(ReachError::Input(format!(
                "output buffer holds {}, need {}",
                out.len(),
                n + 1
            )));
        }
        self.frames(q, scratch, true);
        let boxf = if scratch.wide { &scratch.b } else { &scratch.a };
        // Interval evaluation in round-to-nearest, widened once (module docs of `energy_iv`).
        use energy_iv::{HUGE, NearestInterval, NearestInterval3, link_energy, velocity_bounds};
        if (0..n).any(|j| !(dq_lo[j].abs() <= HUGE && dq_hi[j].abs() <= HUGE)) {
            out.fill(f64::INFINITY);
            out[0] = 0.0;
            return Ok(());
        }
        let zero = VecEnc::default();
        let iv = |v: &VecEnc| -> NearestInterval3 {
            let (m, w) = (v.m.arr(), v.w.arr());
            [0, 1, 2].map(|i| (m[i] - w[i], m[i] + w[i]))
        };
        let mut z = [[(0.0, 0.0); 3]; MAX_DOF];
        let mut o = [[(0.0, 0.0); 3]; MAX_DOF];
        let mut dq: [NearestInterval; MAX_DOF] = [(0.0, 0.0); MAX_DOF];
        for j in 0..n {
            z[j] = iv(&boxf.r[j + 1].affine(&zero, self.joints[j].axis));
            o[j] = iv(&boxf.t[j + 1]);
            dq[j] = (dq_lo[j], dq_hi[j]);
        }
        let mut per_frame = [0.0; MAX_DOF + 1];
        for l in &self.inertials {
            let k = l.frame;
            let c = iv(&boxf.r[k].affine(&boxf.t[k], l.com));
            let (v2, w2) = velocity_bounds(&z, &o, &dq, &c, k.min(n));
            let e = link_energy(l.mass, l.lambda_max, v2, w2);
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
    pub fn energy_bound(&self, q: &JointBox, dq: &JointBox) -> Result<f64, crate::ReachError> {
        let mut out = [0.0; MAX_DOF + 1];
        self.subchain_energy_bounds_into(q, dq, &mut out[..=self.dof])?;
        Ok(out[self.dof])
    }
}
