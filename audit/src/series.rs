//! The plot series of an audit: per time bucket the separation bound, energy bound and
//! threshold, and whether a violation or an inconclusive span falls in it. At most
//! [`SERIES_BUCKETS`] buckets per log: when full, neighbouring buckets merge (the width doubles),
//! so memory stays bounded for logs of any length.

use crate::verdict::SeriesPoint;
use pacs_models::robot::MAX_DOF;

/// Maximum number of plot buckets per log.
pub const SERIES_BUCKETS: usize = 1024;

pub(crate) struct Series {
    pub(crate) t0: f64,
    pub(crate) width: f64,
    pub(crate) buckets: Vec<SeriesPoint>,
    /// Per bucket, the joint state its `energy_nominal` is evaluated at (the first span checked
    /// in it), kept and merged like the bucket; the energies are computed once at the end, for
    /// the buckets that remain (at most [`SERIES_BUCKETS`], where merging would otherwise
    /// compute and discard one per new bucket).
    pub(crate) nominal: Vec<Option<NominalAt>>,
}

/// A joint state (rad, rad/s) whose nominal kinetic energy a plot bucket shows.
#[derive(Debug, Clone, Copy)]
pub(crate) struct NominalAt {
    pub(crate) q: [f64; MAX_DOF],
    pub(crate) dq: [f64; MAX_DOF],
}

fn empty_point(t: f64, t_end: f64) -> SeriesPoint {
    SeriesPoint {
        t,
        t_end,
        min_separation: None,
        far_separation: None,
        energy_nominal: None,
        energy_bound: None,
        threshold: None,
        violation: false,
        inconclusive: false,
        at_rest: true,
    }
}

pub(crate) fn min_opt(a: Option<f64>, b: Option<f64>) -> Option<f64> {
    match (a, b) {
        (Some(x), Some(y)) => Some(x.min(y)),
        (x, None) => x,
        (None, y) => y,
    }
}
pub(crate) fn max_opt(a: Option<f64>, b: Option<f64>) -> Option<f64> {
    match (a, b) {
        (Some(x), Some(y)) => Some(x.max(y)),
        (x, None) => x,
        (None, y) => y,
    }
}

impl Series {
    /// The bucket for time `t`, merging pairs (doubling the width) when full. Returns the index
    /// and whether the bucket is new.
    pub(crate) fn bucket(&mut self, t: f64) -> (usize, bool) {
        loop {
            let idx = ((t - self.t0) / self.width).floor().max(0.0) as usize;
            if idx < SERIES_BUCKETS {
                let mut new = false;
                while self.buckets.len() <= idx {
                    let k = self.buckets.len() as f64;
                    self.buckets.push(empty_point(
                        self.t0 + k * self.width,
                        self.t0 + (k + 1.0) * self.width,
                    ));
                    self.nominal.push(None);
                    new = true;
                }
                return (idx, new);
            }
            // Merge pairs.
            let n = self.buckets.len();
            for i in 0..n.div_ceil(2) {
                let a = self.buckets[2 * i];
                let merged = if 2 * i + 1 < n {
                    let b = self.buckets[2 * i + 1];
                    SeriesPoint {
                        t: a.t,
                        t_end: b.t_end,
                        min_separation: min_opt(a.min_separation, b.min_separation),
                        far_separation: min_opt(a.far_separation, b.far_separation),
                        energy_nominal: a.energy_nominal.or(b.energy_nominal),
                        energy_bound: max_opt(a.energy_bound, b.energy_bound),
                        threshold: min_opt(a.threshold, b.threshold),
                        violation: a.violation || b.violation,
                        inconclusive: a.inconclusive || b.inconclusive,
                        at_rest: a.at_rest && b.at_rest,
                    }
                } else {
                    SeriesPoint {
                        t_end: a.t + 2.0 * self.width,
                        ..a
                    }
                };
                self.buckets[i] = merged;
                // As `energy_nominal` above: the first bucket's state, else the second's.
                self.nominal[i] =
                    self.nominal[2 * i].or(self.nominal.get(2 * i + 1).copied().flatten());
            }
            self.buckets.truncate(n.div_ceil(2));
            self.nominal.truncate(n.div_ceil(2));
            self.width *= 2.0;
        }
    }
}
