//! Dense interval matrices (outward rounded): the matrix series of [`super::LtiReach`] and their
//! action on zonotopes.

use super::{IZERO, pt};
use crate::interval::Interval;
use crate::rounding::{add_up, mul_up, sub_up};
use crate::zonotope::{Zonotope, ZonotopeError};
use nalgebra::{DMatrix, DVector};

#[inline]
fn is_zero(x: Interval) -> bool {
    x.lo() == 0.0 && x.hi() == 0.0
}

/// A dense interval matrix (row-major).
#[derive(Debug, Clone, PartialEq)]
pub struct IntervalMatrix {
    rows: usize,
    cols: usize,
    v: Vec<Interval>,
}

impl IntervalMatrix {
    /// The zero matrix.
    pub fn zeros(rows: usize, cols: usize) -> Self {
        Self {
            rows,
            cols,
            v: vec![IZERO; rows * cols],
        }
    }
    /// Point intervals of `m`.
    pub fn from_matrix(m: &DMatrix<f64>) -> Self {
        Self {
            rows: m.nrows(),
            cols: m.ncols(),
            v: (0..m.nrows() * m.ncols())
                .map(|k| pt(m[(k / m.ncols(), k % m.ncols())]))
                .collect(),
        }
    }
    /// The identity.
    pub fn identity(n: usize) -> Self {
        let mut s = Self::zeros(n, n);
        for i in 0..n {
            s.v[i * n + i] = pt(1.0);
        }
        s
    }
    /// Entry `(i, j)`.
    #[inline]
    pub fn get(&self, i: usize, j: usize) -> Interval {
        self.v[i * self.cols + j]
    }
    #[inline]
    fn set(&mut self, i: usize, j: usize, x: Interval) {
        self.v[i * self.cols + j] = x;
    }
    /// Enclosure of the product `self · rhs`.
    pub fn mul(&self, rhs: &IntervalMatrix) -> IntervalMatrix {
        assert_eq!(self.cols, rhs.rows);
        let mut out = Self::zeros(self.rows, rhs.cols);
        for i in 0..self.rows {
            for j in 0..rhs.cols {
                let mut acc = IZERO;
                for k in 0..self.cols {
                    let (a, b) = (self.get(i, k), rhs.get(k, j));
                    // [0,0]·x = [0,0] exactly: skipping it changes nothing (sparse A is common).
                    if is_zero(a) || is_zero(b) {
                        continue;
                    }
                    acc += a * b;
                }
                out.set(i, j, acc);
            }
        }
        out
    }
    /// Enclosure of `self · s` for the interval scalar `s`.
    pub fn scale(&self, s: Interval) -> IntervalMatrix {
        Self {
            rows: self.rows,
            cols: self.cols,
            v: self.v.iter().map(|&x| x * s).collect(),
        }
    }
    /// `self += rhs · s` (enclosure; exact-zero entries of `rhs` are skipped, which is exact).
    pub fn add_scaled(&mut self, rhs: &IntervalMatrix, s: Interval) {
        assert_eq!((self.rows, self.cols), (rhs.rows, rhs.cols));
        for (a, &b) in self.v.iter_mut().zip(&rhs.v) {
            if !is_zero(b) {
                *a += b * s;
            }
        }
    }
    /// Enclosure of the sum.
    pub fn add(&self, rhs: &IntervalMatrix) -> IntervalMatrix {
        assert_eq!((self.rows, self.cols), (rhs.rows, rhs.cols));
        Self {
            rows: self.rows,
            cols: self.cols,
            v: self.v.iter().zip(&rhs.v).map(|(&a, &b)| a + b).collect(),
        }
    }
    /// Adds `[-w_i, w_i]` to every entry of row `i`.
    pub(super) fn widen_rows(&mut self, w: &[f64]) {
        for (i, &wi) in w.iter().enumerate().take(self.rows) {
            if wi > 0.0 {
                let iv = Interval::new(-wi, wi).unwrap_or(Interval::ENTIRE);
                for j in 0..self.cols {
                    self.v[i * self.cols + j] += iv;
                }
            }
        }
    }
    /// `true` if every entry is exactly `[0, 0]`.
    pub fn is_zero(&self) -> bool {
        self.v.iter().all(|&x| is_zero(x))
    }
    /// `(mid, rad)` with `[mid − rad, mid + rad] ⊇` each entry (rad rounded up).
    pub fn mid_rad(&self) -> (DMatrix<f64>, DMatrix<f64>) {
        let mut mid = DMatrix::zeros(self.rows, self.cols);
        let mut rad = DMatrix::zeros(self.rows, self.cols);
        for i in 0..self.rows {
            for j in 0..self.cols {
                let x = self.get(i, j);
                let (lo, hi) = (x.lo(), x.hi());
                if lo == hi {
                    mid[(i, j)] = lo; // point interval: exact, radius 0
                } else {
                    let m = x.mid();
                    mid[(i, j)] = m;
                    // [m − r, m + r] ⊇ [lo, hi] with both differences rounded up.
                    rad[(i, j)] = sub_up(hi, m).max(sub_up(m, lo));
                }
            }
        }
        (mid, rad)
    }
    /// Entrywise magnitude `max |x|` (exact upper bounds).
    pub fn mag(&self) -> DMatrix<f64> {
        DMatrix::from_fn(self.rows, self.cols, |i, j| self.get(i, j).mag())
    }
    /// Zonotope ⊇ `{M z : M ∈ self, z ∈ Z}`: `mid Z ⊕ box(rad |Z|)`.
    pub fn map_zonotope(&self, z: &Zonotope) -> Result<Zonotope, ZonotopeError> {
        let (mid, rad) = self.mid_rad();
        let mut out = z.linear_map(&mid)?;
        let b = mat_vec_up(&rad, &z.abs_bound());
        out.add_box(&b);
        Ok(out)
    }
}

/// Upper bound of `M v` for `M, v ≥ 0`.
pub(super) fn mat_vec_up(m: &DMatrix<f64>, v: &DVector<f64>) -> DVector<f64> {
    DVector::from_fn(m.nrows(), |i, _| {
        let mut s = 0.0;
        for j in 0..m.ncols() {
            s = add_up(s, mul_up(m[(i, j)], v[j]));
        }
        s
    })
}
