//! Zonotopes that contain a Euclidean ball in 3-D, and the certified inradius bound they rest on.

use super::{Zonotope, ZonotopeError, check_finite, pt};
use crate::interval::Interval;
use crate::rounding::{add_up, div_down, mul_up, norm3_up};
use nalgebra::{DMatrix, DVector};

/// Over-approximating zonotopes of a Euclidean ball in 3-D.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BallApprox {
    /// 3 axis generators (a cube; volume ratio ≈ 1.91, support overshoot ≤ √3).
    Box,
    /// 3 axes + 4 body diagonals (7 generators).
    Seven,
    /// 3 axes + 6 face diagonals + 4 body diagonals (13 generators, support overshoot ≈ 1.1).
    Thirteen,
}

impl BallApprox {
    fn directions(self) -> &'static [[f64; 3]] {
        const D13: [[f64; 3]; 13] = [
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [1.0, 1.0, 1.0],
            [1.0, -1.0, 1.0],
            [1.0, 1.0, -1.0],
            [-1.0, 1.0, 1.0],
            [1.0, 1.0, 0.0],
            [1.0, -1.0, 0.0],
            [1.0, 0.0, 1.0],
            [1.0, 0.0, -1.0],
            [0.0, 1.0, 1.0],
            [0.0, 1.0, -1.0],
        ];
        match self {
            BallApprox::Box => &D13[..3],
            BallApprox::Seven => &D13[..7],
            BallApprox::Thirteen => &D13[..],
        }
    }
}

/// Rigorous lower bound of the inradius (about the centre) of the 3-D zonotope `Σ [-1,1] g_k`.
///
/// The zonotope is the intersection of its facet half-spaces; every facet normal is `g_i × g_j`
/// for some pair, so the inradius is `min_{i<j} h(n_ij)/‖n_ij‖`; `n_ij` is enclosed in intervals.
pub fn inradius_lower_3d(gens: &[[f64; 3]]) -> f64 {
    let mut best = f64::INFINITY;
    let iv: Vec<[Interval; 3]> = gens
        .iter()
        .map(|g| [pt(g[0]), pt(g[1]), pt(g[2])])
        .collect();
    for i in 0..gens.len() {
        for j in (i + 1)..gens.len() {
            let (a, b) = (&iv[i], &iv[j]);
            let n = [
                a[1] * b[2] - a[2] * b[1],
                a[2] * b[0] - a[0] * b[2],
                a[0] * b[1] - a[1] * b[0],
            ];
            let nn = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            if nn.lo() <= 0.0 {
                if nn.hi() > 0.0 {
                    // Possibly degenerate pair: cannot certify, give up on a positive bound.
                    return 0.0;
                }
                continue; // exactly parallel pair: not a facet normal
            }
            let mut h = 0.0f64;
            for g in &iv {
                let d = n[0] * g[0] + n[1] * g[1] + n[2] * g[2];
                h = crate::rounding::add_down(h, d.mig());
            }
            best = best.min(div_down(h, nn.hi()));
        }
    }
    if best.is_finite() { best.max(0.0) } else { 0.0 }
}

/// A 3-D zonotope (centre `centre`) ⊇ the Euclidean ball of `radius` (m), with rigorously
/// certified inradius ≥ `radius`.
pub fn ball_zonotope(
    centre: [f64; 3],
    radius: f64,
    approx: BallApprox,
) -> Result<Zonotope, ZonotopeError> {
    if !(radius.is_finite() && radius >= 0.0) {
        return Err(ZonotopeError::Invalid {
            what: "ball radius",
            reason: "must be finite and >= 0",
        });
    }
    let c = DVector::from_column_slice(&centre);
    check_finite("ball centre", c.iter())?;
    if radius == 0.0 {
        return Zonotope::new(c, DMatrix::zeros(3, 0));
    }
    let (unit, gsum) = unit_ball_generators(approx);
    // Generators fl(R'·g_k) with R' ≥ R(1 + 1e-12): the exact R'·Z_unit has inradius ≥ R', and
    // rounding moves each generator by ≤ u‖R' g_k‖, which lowers the inradius by at most
    // u R' Σ‖g_k‖ = u R' gsum ≪ 1e-12 R'. Tiny radii are raised to 1e-280 (no underflow).
    debug_assert!(gsum * f64::EPSILON < 1e-13);
    let rp = mul_up(radius.max(1e-280), 1.0 + 1e-12);
    let g = DMatrix::from_fn(3, unit.len(), |i, j| unit[j][i] * rp);
    Zonotope::new(c, g)
}

/// Unit-ball generator sets with certified inradius ≥ 1, and `Σ_k ‖g_k‖` (upper bound), cached.
fn unit_ball_generators(approx: BallApprox) -> (&'static [[f64; 3]], f64) {
    use std::sync::OnceLock;
    static CACHE: [OnceLock<(Vec<[f64; 3]>, f64)>; 3] =
        [OnceLock::new(), OnceLock::new(), OnceLock::new()];
    let k = match approx {
        BallApprox::Box => 0,
        BallApprox::Seven => 1,
        BallApprox::Thirteen => 2,
    };
    let (g, s) = CACHE[k].get_or_init(|| {
        let units: Vec<[f64; 3]> = approx
            .directions()
            .iter()
            .map(|d| {
                let nrm = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                [d[0] / nrm, d[1] / nrm, d[2] / nrm]
            })
            .collect();
        let mut s = 1.0 / inradius_lower_3d(&units) * (1.0 + 1e-12);
        loop {
            let gens: Vec<[f64; 3]> = units
                .iter()
                .map(|u| [u[0] * s, u[1] * s, u[2] * s])
                .collect();
            if inradius_lower_3d(&gens) >= 1.0 {
                let sum = gens
                    .iter()
                    .fold(0.0, |a, g| add_up(a, norm3_up(g[0], g[1], g[2])));
                return (gens, sum);
            }
            s *= 1.0 + 1e-9;
        }
    });
    (g.as_slice(), *s)
}
