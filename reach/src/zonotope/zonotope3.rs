//! [`Zonotope3`]: the fixed-capacity 3-D zonotope of the hot path (no heap): support function,
//! interval hull and rigorous distance bounds against capsules.

mod gjk;

use super::{Zonotope, ZonotopeError, check_finite, nonneg_sum_up, rnd_err};
use crate::rounding::{add_up, div_down, norm3_up, sub_down};
use nalgebra::{DMatrix, DVector};
use pacs_models::shape::Capsule;

/// Capacity of [`Zonotope3`] generator storage.
pub const MAX_GENERATORS_3D: usize = 48;

/// A 3-D zonotope with inline storage (no heap): `{c + Σ β_k g_k + diag(e) γ}` (m), at most
/// `N` generators. The default capacity is [`MAX_GENERATORS_3D`]; the object occupancy uses the
/// capacity its model needs (`MAX_OCCUPANCY_GENERATORS`), which keeps it small to build and copy
/// in the shield's step (the capacity changes no result: only the first `len` generators count).
#[derive(Debug, Clone, PartialEq)]
pub struct Zonotope3<const N: usize = MAX_GENERATORS_3D> {
    c: [f64; 3],
    g: [[f64; 3]; N],
    len: usize,
    e: [f64; 3],
    /// Plain `Σ_k |g_k| + e` per axis (for the rounding-error bound of the support function).
    abs_sum: [f64; 3],
}

impl Zonotope3 {
    /// Build from centre, generators (at most [`MAX_GENERATORS_3D`]) and error box radius `e ≥ 0`.
    pub fn new(c: [f64; 3], gens: &[[f64; 3]], e: [f64; 3]) -> Result<Self, ZonotopeError> {
        Self::from_parts(c, gens, e)
    }

    /// Convert a 3-D [`Zonotope`], Girard-reducing first if it has too many generators (⊇ input).
    pub fn from_zonotope(z: &Zonotope) -> Result<Self, ZonotopeError> {
        if z.dim() != 3 {
            return Err(ZonotopeError::DimensionMismatch {
                what: "Zonotope3 dimension",
                expected: 3,
                got: z.dim(),
            });
        }
        let z = z.compact();
        let z = if z.num_generators() > MAX_GENERATORS_3D {
            z.reduce_girard(MAX_GENERATORS_3D / 3)?
        } else {
            z
        };
        let gens: Vec<[f64; 3]> = (0..z.num_generators())
            .map(|j| [z.g[(0, j)], z.g[(1, j)], z.g[(2, j)]])
            .collect();
        Self::new([z.c[0], z.c[1], z.c[2]], &gens, [z.e[0], z.e[1], z.e[2]])
    }
}

impl<const N: usize> Zonotope3<N> {
    /// Build a zonotope of capacity `N` from centre, generators (at most `N`) and error box
    /// radius `e ≥ 0` ([`Zonotope3::new`] for the default capacity).
    pub fn from_parts(c: [f64; 3], gens: &[[f64; 3]], e: [f64; 3]) -> Result<Self, ZonotopeError> {
        Self::check_parts(c, gens, e)?;
        Ok(Self::assemble(c, gens, e))
    }

    /// The checks of [`Self::from_parts`]: at most `N` generators, every number finite, `e ≥ 0`.
    pub(crate) fn check_parts(
        c: [f64; 3],
        gens: &[[f64; 3]],
        e: [f64; 3],
    ) -> Result<(), ZonotopeError> {
        if gens.len() > N {
            return Err(ZonotopeError::DimensionMismatch {
                what: "Zonotope3 generators",
                expected: N,
                got: gens.len(),
            });
        }
        check_finite(
            "Zonotope3",
            c.iter().chain(gens.iter().flatten()).chain(e.iter()),
        )?;
        if e.iter().any(|&v| v < 0.0) {
            return Err(ZonotopeError::Invalid {
                what: "error box",
                reason: "radii must be >= 0",
            });
        }
        Ok(())
    }

    /// The zonotope of parts that passed [`Self::check_parts`] (the proofs beside this module
    /// build it this way: a `Result` carrying the float arrays reaches the model checker's SMT
    /// back end as a `concat` of float terms, which Bitwuzla rejects).
    pub(crate) fn assemble(c: [f64; 3], gens: &[[f64; 3]], e: [f64; 3]) -> Self {
        let mut g = [[0.0; 3]; N];
        g[..gens.len()].copy_from_slice(gens);
        let mut abs_sum = e;
        for gk in gens {
            for i in 0..3 {
                abs_sum[i] += gk[i].abs();
            }
        }
        Self {
            c,
            g,
            len: gens.len(),
            e,
            abs_sum,
        }
    }

    /// The general-dimension form (same set).
    pub fn to_zonotope(&self) -> Zonotope {
        let c = DVector::from_column_slice(&self.c);
        let g = DMatrix::from_fn(3, self.len, |i, j| self.g[j][i]);
        Zonotope {
            c,
            g,
            e: DVector::from_column_slice(&self.e),
        }
    }

    /// Centre (m).
    #[inline]
    pub fn center(&self) -> [f64; 3] {
        self.c
    }
    /// Generators (m).
    #[inline]
    pub fn generators(&self) -> &[[f64; 3]] {
        &self.g[..self.len]
    }
    /// Error box radius (m).
    #[inline]
    pub fn error_box(&self) -> [f64; 3] {
        self.e
    }

    /// Support function upper bound `≥ max_{z ∈ Z} d·z` (rigorous; `d` need not be unit).
    #[inline]
    pub fn support_up(&self, d: [f64; 3]) -> f64 {
        let mut s = d[0] * self.c[0] + d[1] * self.c[1] + d[2] * self.c[2];
        s += d[0].abs() * self.e[0] + d[1].abs() * self.e[1] + d[2].abs() * self.e[2];
        for gk in self.generators() {
            s += (d[0] * gk[0] + d[1] * gk[1] + d[2] * gk[2]).abs();
        }
        let a = d[0].abs() * (self.c[0].abs() + self.abs_sum[0])
            + d[1].abs() * (self.c[1].abs() + self.abs_sum[1])
            + d[2].abs() * (self.c[2].abs() + self.abs_sum[2]);
        // depth: 3-term dots inside a sum of len + 6 terms; a itself is a plain sum of ≤ len + 3
        // terms per axis, whose relative error is covered by the factor-two slack of rnd_err.
        add_up(s, rnd_err(self.len + 12, 3 * self.len + 12, a))
    }

    /// Interval hull `(lo, hi)` ⊇ Z (m, rounded outward).
    pub fn interval_hull(&self) -> ([f64; 3], [f64; 3]) {
        let mut lo = [0.0; 3];
        let mut hi = [0.0; 3];
        for i in 0..3 {
            let r = nonneg_sum_up(self.len + 1, self.abs_sum[i]);
            lo[i] = sub_down(self.c[i], r);
            hi[i] = add_up(self.c[i], r);
        }
        (lo, hi)
    }

    /// Rigorous lower bound of the distance between `Z ⊕ B(inflate)` and `capsule`, from the
    /// separating direction `n` (any non-zero `n` gives a valid bound; 0 if `n` separates nothing).
    ///
    /// `(min_Z n·z − max_segment n·p) / ‖n‖ − inflate − capsule radius`, each step rounded down.
    pub fn distance_bound_along(&self, inflate: f64, capsule: &Capsule, n: [f64; 3]) -> f64 {
        let nn = norm3_up(n[0], n[1], n[2]);
        if !(nn > 0.0 && nn.is_finite()) {
            return 0.0;
        }
        let zmin = -self.support_up([-n[0], -n[1], -n[2]]);
        let p1 = capsule.p1();
        let p2 = capsule.p2();
        let smax = dot3_up(n, [p1.x, p1.y, p1.z]).max(dot3_up(n, [p2.x, p2.y, p2.z]));
        let gap = sub_down(zmin, smax);
        if gap.is_nan() || gap <= 0.0 {
            return 0.0;
        }
        let d = sub_down(sub_down(div_down(gap, nn), inflate), capsule.radius());
        if d > 0.0 { d } else { 0.0 }
    }

    /// Rigorous lower bound `L` with `0 ≤ L ≤ dist(Z ⊕ B(inflate), capsule)` (m); `L > 0` proves
    /// the sets disjoint. The direction comes from a small GJK on `Z − segment`; only its rigorous
    /// evaluation ([`Self::distance_bound_along`]) matters for soundness.
    ///
    /// # Soundness
    /// Claim C2: never above the exact distance, whatever direction the GJK proposes. Harness
    /// `b4_zonotope_capsule_conservative` (twin; Kani times out).
    pub fn distance_lower_bound(&self, inflate: f64, capsule: &Capsule) -> f64 {
        match self.gjk_direction(capsule) {
            Some(n) => self.distance_bound_along(inflate, capsule, n),
            None => 0.0,
        }
    }

    /// `true` only if `Z ⊕ B(inflate)` and `capsule` are proven disjoint.
    #[inline]
    pub fn is_disjoint(&self, inflate: f64, capsule: &Capsule) -> bool {
        self.distance_lower_bound(inflate, capsule) > 0.0
    }
}

/// Rigorous upper bound of `a·b` (3 terms).
#[inline]
fn dot3_up(a: [f64; 3], b: [f64; 3]) -> f64 {
    let s = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let t = (a[0] * b[0]).abs() + (a[1] * b[1]).abs() + (a[2] * b[2]).abs();
    add_up(s, rnd_err(3, 3, t))
}
