//! The solved spline measured against the limits (per-segment ratios, the largest of them) and
//! assembled into a trajectory.

use super::{FREE, SplineSolver};
use crate::chunk::Waypoints;
use crate::profile::Piece;
use crate::trajectory::{EndCondition, JointState, Limits, Trajectory};
use pacs_models::MAX_DOF;

impl SplineSolver {
    /// Velocity at the start of piece `q` for joint `i`.
    #[inline]
    fn v_start(&self, q: usize, i: usize) -> f64 {
        let t = self.tau[q];
        (self.y[q + 1][i] - self.y[q][i]) / t
            - t * (2.0 * self.acc[q][i] + self.acc[q + 1][i]) / 6.0
    }

    /// Per-segment limit ratios of the current spline (into `rj`, `ra`, `rv`).
    pub(super) fn ratios(&mut self, n: usize, lim: &Limits, h: usize) {
        self.rj.clear();
        self.rj.resize(h, 0.0);
        self.ra.clear();
        self.ra.resize(h, 0.0);
        self.rv.clear();
        self.rv.resize(h, 0.0);
        for q in 0..self.tau.len() {
            let k = self.seg_of[q];
            let t = self.tau[q];
            let (mut rj, mut ra, mut rv) = (self.rj[k], self.ra[k], self.rv[k]);
            for i in 0..n {
                let (m0, m1) = (self.acc[q][i], self.acc[q + 1][i]);
                let j = (m1 - m0) / t;
                let v0 = self.v_start(q, i);
                let v1 = v0 + 0.5 * t * (m0 + m1);
                let mut vm = v0.abs().max(v1.abs());
                if m0 * m1 < 0.0 {
                    let d = -m0 / j;
                    vm = vm.max((v0 + d * (m0 + 0.5 * j * d)).abs());
                }
                rj = rj.max(j.abs() / lim.j[i]);
                ra = ra.max(m0.abs().max(m1.abs()) / lim.a[i]);
                rv = rv.max(vm / lim.v[i]);
            }
            self.rj[k] = rj;
            self.ra[k] = ra;
            self.rv[k] = rv;
        }
        self.rs.clear();
        for k in 0..h {
            self.rs
                .push(self.rj[k].cbrt().max(self.ra[k].sqrt()).max(self.rv[k]));
        }
    }

    /// Scale-normalised ratio of segment k (> 1: too fast, < 1: slack), as of the last
    /// [`SplineSolver::ratios`].
    #[inline]
    pub(super) fn seg_ratio(&self, k: usize) -> f64 {
        self.rs[k]
    }

    /// Largest limit ratio of the spline with durations `seg_t` (∞ if singular).
    pub(super) fn lambda(
        &mut self,
        lim: &Limits,
        start: &JointState,
        wp: &Waypoints,
        end: EndCondition,
        seg_t: &[f64],
    ) -> f64 {
        let n = lim.dof;
        let h = seg_t.len();
        if !self.solve(lim, n, start, wp, end, seg_t) {
            return f64::INFINITY;
        }
        self.ratios(n, lim, h);
        (0..h).map(|k| self.seg_ratio(k)).fold(0.0, f64::max)
    }

    /// The trajectory of the last solved spline.
    pub(super) fn assemble(
        &self,
        n: usize,
        start: &JointState,
        wp: &Waypoints,
        end: EndCondition,
    ) -> Trajectory {
        let p = self.tau.len();
        let h = wp.segments();
        let mut pieces = Vec::with_capacity(n * (p + 1));
        let mut offsets = [0usize; MAX_DOF + 1];
        let mut times = Vec::with_capacity(h);
        let mut t = 0.0;
        for q in 0..p {
            t += self.tau[q];
            if self.knot_wp[q + 1] != FREE {
                times.push(t);
            }
        }
        let duration = t;
        for i in 0..n {
            offsets[i] = pieces.len();
            let mut t = 0.0;
            for q in 0..p {
                let tq = self.tau[q];
                let (v, a) = if q == 0 {
                    (start.dq[i], start.ddq[i])
                } else {
                    (self.v_start(q, i), self.acc[q][i])
                };
                pieces.push(Piece {
                    t,
                    q: self.y[q][i],
                    v,
                    a,
                    j: (self.acc[q + 1][i] - self.acc[q][i]) / tq,
                });
                t += tq;
            }
            pieces.push(Piece {
                t: duration,
                q: wp.row(h)[i],
                v: self.v_end[i],
                a: 0.0,
                j: 0.0,
            });
        }
        offsets[n] = pieces.len();
        Trajectory::from_parts(n, pieces, offsets, duration, times, end)
    }
}
