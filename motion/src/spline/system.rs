//! The linear system of a spline for given segment durations: the knot layout, the equations
//! (velocity at the start, continuity at every inner knot, velocity at the end) and their banded
//! solution for all joints at once.

use super::{FREE, SplineSolver};
use crate::chunk::Waypoints;
use crate::trajectory::{EndCondition, JointState, Limits};
use pacs_models::MAX_DOF;

impl SplineSolver {
    /// Knot layout for `h` segments: the first and last segment split in two (one segment: three).
    pub(super) fn layout(&mut self, h: usize) {
        self.split.clear();
        for k in 0..h {
            self.split.push(if h == 1 {
                3
            } else if k == 0 || k == h - 1 {
                2
            } else {
                1
            });
        }
        self.seg_of.clear();
        self.knot_wp.clear();
        self.knot_var.clear();
        self.knot_wp.push(0);
        for k in 0..h {
            for s in 0..self.split[k] {
                self.seg_of.push(k);
                self.knot_wp
                    .push(if s + 1 == self.split[k] { k + 1 } else { FREE });
            }
        }
        // Unknowns interleaved in knot order (free position, then acceleration) so that the
        // system is banded: equation q couples only knots q − 1, q, q + 1.
        let p = self.seg_of.len();
        self.acc_var.clear();
        let mut next = 0;
        for (q, &w) in self.knot_wp.iter().enumerate() {
            if w == FREE {
                self.knot_var.push(next);
                next += 1;
            } else {
                self.knot_var.push(FREE);
            }
            if q > 0 && q < p {
                self.acc_var.push(next);
                next += 1;
            } else {
                self.acc_var.push(FREE);
            }
        }
        debug_assert_eq!(next, p + 1);
        // Equation q couples the unknowns of knots q − 1, q, q + 1.
        let (mut lb, mut ub) = (0usize, 0usize);
        for q in 0..=p {
            for k in q.saturating_sub(1)..=(q + 1).min(p) {
                for v in [self.knot_var[k], self.acc_var[k]] {
                    if v != FREE {
                        lb = lb.max(q.saturating_sub(v));
                        ub = ub.max(v.saturating_sub(q));
                    }
                }
            }
        }
        self.band = (lb, ub);
        self.tau.resize(p, 0.0);
        self.y.resize(p + 1, [0.0; MAX_DOF]);
        self.acc.resize(p + 1, [0.0; MAX_DOF]);
        self.mat.resize((p + 1) * (p + 1), 0.0);
    }

    /// Spline for the segment durations `seg_t`: knot positions and accelerations of every joint.
    /// Returns false if the system is singular.
    pub(super) fn solve(
        &mut self,
        lim: &Limits,
        n: usize,
        start: &JointState,
        wp: &Waypoints,
        end: EndCondition,
        seg_t: &[f64],
    ) -> bool {
        let p = self.seg_of.len();
        let m = p + 1;
        let h = seg_t.len();
        for (q, t) in self.tau.iter_mut().enumerate() {
            let k = self.seg_of[q];
            *t = seg_t[k] / self.split[k] as f64;
        }
        if self.split[0] == 2 && self.first_ramp > 0.0 {
            self.tau[0] = self.first_ramp.clamp(0.1 * seg_t[0], 0.5 * seg_t[0]);
            self.tau[1] = seg_t[0] - self.tau[0];
        }
        match end {
            EndCondition::AtRest => self.v_end[..n].iter_mut().for_each(|x| *x = 0.0),
            EndCondition::Moving => self.end_velocity(lim, wp, seg_t[h - 1]),
        }
        self.mat.iter_mut().for_each(|x| *x = 0.0);
        self.rhs.clear();
        self.rhs.resize(m * n, 0.0);
        self.rhs[..n].copy_from_slice(&start.dq[..n]);
        self.rhs[p * n..(p + 1) * n].copy_from_slice(&self.v_end[..n]);
        // Velocity at the start of piece q: (y_{q+1} − y_q)/τ − τ(2M_q + M_{q+1})/6;
        // at its end: (y_{q+1} − y_q)/τ + τ(M_q + 2M_{q+1})/6.
        // Row 0: start velocity; row q (1..p−1): continuity at knot q; row p: end velocity.
        for row in 0..=p {
            if row < p {
                // − v_start of piece `row`.
                let t = self.tau[row];
                let s = if row == 0 { 1.0 } else { -1.0 };
                self.coef_y(n, m, start, wp, row, row + 1, s / t);
                self.coef_y(n, m, start, wp, row, row, -s / t);
                self.coef_m(n, m, start, row, row, -s * t / 3.0);
                self.coef_m(n, m, start, row, row + 1, -s * t / 6.0);
            }
            if row > 0 {
                // + v_end of piece `row − 1`.
                let t = self.tau[row - 1];
                self.coef_y(n, m, start, wp, row, row, 1.0 / t);
                self.coef_y(n, m, start, wp, row, row - 1, -1.0 / t);
                self.coef_m(n, m, start, row, row - 1, t / 6.0);
                self.coef_m(n, m, start, row, row, t / 3.0);
            }
        }
        // Banded Gaussian elimination with partial pivoting, all joints' right-hand sides at
        // once; pivoting widens the upper band by the lower bandwidth.
        let (lb, ub) = self.band;
        let ub = ub + lb;
        for c in 0..m {
            let r_end = m.min(c + lb + 1);
            let k_end = m.min(c + ub + 1);
            let mut piv = c;
            let mut best = self.mat[c * m + c].abs();
            for r in c + 1..r_end {
                let v = self.mat[r * m + c].abs();
                if v > best {
                    best = v;
                    piv = r;
                }
            }
            if best == 0.0 || !best.is_finite() {
                return false;
            }
            if piv != c {
                for k in c..k_end {
                    self.mat.swap(c * m + k, piv * m + k);
                }
                for i in 0..n {
                    self.rhs.swap(c * n + i, piv * n + i);
                }
            }
            let d = 1.0 / self.mat[c * m + c];
            for r in c + 1..r_end {
                let f = self.mat[r * m + c] * d;
                if f != 0.0 {
                    for k in c + 1..k_end {
                        self.mat[r * m + k] -= f * self.mat[c * m + k];
                    }
                    let (top, bottom) = self.rhs.split_at_mut(r * n);
                    let rc = &top[c * n..(c + 1) * n];
                    for (x, y) in bottom[..n].iter_mut().zip(rc) {
                        *x -= f * y;
                    }
                }
            }
        }
        for c in (0..m).rev() {
            let d = 1.0 / self.mat[c * m + c];
            let (top, bottom) = self.rhs.split_at_mut((c + 1) * n);
            let x = &mut top[c * n..];
            for k in c + 1..m.min(c + ub + 1) {
                let f = self.mat[c * m + k];
                if f != 0.0 {
                    let xk = &bottom[(k - c - 1) * n..(k - c) * n];
                    for (xi, yi) in x.iter_mut().zip(xk) {
                        *xi -= f * yi;
                    }
                }
            }
            for xi in x.iter_mut() {
                *xi *= d;
            }
        }
        // Knot accelerations and positions from the unknowns.
        for q in 0..=p {
            for i in 0..n {
                self.acc[q][i] = if q == 0 {
                    start.ddq[i]
                } else if q == p {
                    0.0
                } else {
                    self.rhs[self.acc_var[q] * n + i]
                };
                self.y[q][i] = match self.knot_wp[q] {
                    FREE => self.rhs[self.knot_var[q] * n + i],
                    0 => start.q[i],
                    w => wp.row(w)[i],
                };
            }
        }
        self.y.iter().all(|r| r[..n].iter().all(|x| x.is_finite()))
            && self
                .acc
                .iter()
                .all(|r| r[..n].iter().all(|x| x.is_finite()))
    }

    /// Add `c`·y_knot to equation `row` (known positions go to the right-hand side).
    #[allow(clippy::too_many_arguments)]
    #[inline]
    fn coef_y(
        &mut self,
        n: usize,
        m: usize,
        start: &JointState,
        wp: &Waypoints,
        row: usize,
        knot: usize,
        c: f64,
    ) {
        match self.knot_wp[knot] {
            FREE => self.mat[row * m + self.knot_var[knot]] += c,
            w => {
                let q = if w == 0 { &start.q[..n] } else { wp.row(w) };
                for i in 0..n {
                    self.rhs[row * n + i] -= c * q[i];
                }
            }
        }
    }

    /// Add `c`·M_knot to equation `row` (M_0 = start acceleration and M_p = 0 are known).
    #[inline]
    fn coef_m(&mut self, n: usize, m: usize, start: &JointState, row: usize, knot: usize, c: f64) {
        let p = m - 1;
        if knot == 0 {
            for i in 0..n {
                self.rhs[row * n + i] -= c * start.ddq[i];
            }
        } else if knot < p {
            self.mat[row * m + self.acc_var[knot]] += c;
        }
    }
}
