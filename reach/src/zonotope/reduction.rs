//! Girard order reduction: fewer generators, the dropped ones replaced by their interval hull
//! (the result contains the input).

use super::{Zonotope, ZonotopeError, nonneg_sum_up};
use nalgebra::DMatrix;

impl Zonotope {
    /// Girard order reduction to at most `order · n` generators (result ⊇ input).
    ///
    /// Keeps the `n (order - 1)` generators with the largest `‖g‖₁ - ‖g‖∞` and replaces the others
    /// by their interval hull (axis-aligned generators, sums rounded up). `order ≥ 1`.
    pub fn reduce_girard(&self, order: usize) -> Result<Zonotope, ZonotopeError> {
        if order == 0 {
            return Err(ZonotopeError::Invalid {
                what: "order",
                reason: "must be >= 1",
            });
        }
        let n = self.dim();
        let m = self.num_generators();
        if m <= order * n {
            return Ok(self.clone());
        }
        let keep = n * (order - 1);
        let mut idx: Vec<(f64, usize)> = (0..m)
            .map(|j| {
                let col = self.g.column(j);
                let l1: f64 = col.iter().map(|v| v.abs()).sum();
                let linf = col.iter().fold(0.0f64, |a, v| a.max(v.abs()));
                (l1 - linf, j)
            })
            .collect();
        idx.sort_unstable_by(|a, b| b.0.total_cmp(&a.0));
        let mut boxr = vec![0.0; n];
        for &(_, j) in &idx[keep..] {
            for (i, b) in boxr.iter_mut().enumerate() {
                *b += self.g[(i, j)].abs();
            }
        }
        let nb = m - keep;
        let box_axes: Vec<usize> = (0..n).filter(|&i| boxr[i] > 0.0).collect();
        let mut g = DMatrix::zeros(n, keep + box_axes.len());
        for (k, &(_, j)) in idx[..keep].iter().enumerate() {
            g.set_column(k, &self.g.column(j));
        }
        for (k, &i) in box_axes.iter().enumerate() {
            g[(i, keep + k)] = nonneg_sum_up(nb, boxr[i]);
        }
        Ok(Zonotope {
            c: self.c.clone(),
            g,
            e: self.e.clone(),
        })
    }
}
