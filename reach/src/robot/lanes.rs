//! Three-vectors and 3×3 matrices in four SIMD lanes for the interval forward kinematics: an
//! AVX register on x86-64 with AVX (the workspace builds for x86-64-v3), a plain array elsewhere
//! and under Kani. Every operation is lanewise and correctly rounded with either backend, so
//! the error analysis of [`super`] does not depend on it; `lanes_match_bitwise` checks that both
//! backends give the same bits.

use super::{NORM_PAD, RAD_UP, TINY};
use nalgebra::{Matrix3, Vector3};
use pacs_models::MAX_DOF;

/// Joints processed per vector chunk in the mean-value sum.
pub(super) const LANES: usize = 4;
/// Chunks of joints in the mean-value sum.
pub(super) const JCH: usize = MAX_DOF.div_ceil(LANES);
/// Lane masks: row r keeps the first r lanes.
pub(super) const LANE_MASK: [[f64; LANES]; LANES + 1] = [
    [0.0, 0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0, 0.0],
    [1.0, 1.0, 0.0, 0.0],
    [1.0, 1.0, 1.0, 0.0],
    [1.0, 1.0, 1.0, 1.0],
];

/// A 3-vector in four lanes (lane 3 is unused), one AVX register on x86-64 with AVX (the
/// workspace builds for x86-64-v3), a plain array elsewhere; every operation is lanewise and
/// correctly rounded either way, so the error analysis does not depend on the backend.
#[derive(Clone, Copy)]
#[repr(transparent)]
pub(super) struct Lanes3(pub(super) simd::Register);

// The AVX backend on x86-64 with AVX; the scalar backend elsewhere and under Kani (which
// supports no SIMD intrinsics). `lanes_match_bitwise` (tests below) checks that both give the
// same bits for every operation, so a proof over the scalar backend covers the AVX one.
#[cfg(all(target_arch = "x86_64", target_feature = "avx", not(kani)))]
pub(super) use lanes_avx as simd;
#[cfg(not(all(target_arch = "x86_64", target_feature = "avx", not(kani))))]
pub(super) use lanes_scalar as simd;

#[cfg(all(target_arch = "x86_64", target_feature = "avx", not(kani)))]
pub(super) mod lanes_avx {
    use std::arch::x86_64::*;
    pub type Register = __m256d;
    #[inline(always)]
    pub fn new(a: [f64; 4]) -> Register {
        // SAFETY: AVX is enabled for the whole build (cfg above); `a` holds four f64.
        unsafe { _mm256_loadu_pd(a.as_ptr()) }
    }
    #[inline(always)]
    pub fn arr(v: Register) -> [f64; 4] {
        // SAFETY: `__m256d` and `[f64; 4]` have the same size and every bit pattern is valid
        // for both.
        unsafe { std::mem::transmute::<Register, [f64; 4]>(v) }
    }
    #[inline(always)]
    pub fn splat(x: f64) -> Register {
        // SAFETY: AVX is enabled for the whole build (cfg above).
        unsafe { _mm256_set1_pd(x) }
    }
    #[inline(always)]
    pub fn add(a: Register, b: Register) -> Register {
        // SAFETY: AVX is enabled for the whole build (cfg above).
        unsafe { _mm256_add_pd(a, b) }
    }
    #[inline(always)]
    pub fn sub(a: Register, b: Register) -> Register {
        // SAFETY: AVX is enabled for the whole build (cfg above).
        unsafe { _mm256_sub_pd(a, b) }
    }
    #[inline(always)]
    pub fn mul(a: Register, b: Register) -> Register {
        // SAFETY: AVX is enabled for the whole build (cfg above).
        unsafe { _mm256_mul_pd(a, b) }
    }
    #[inline(always)]
    pub fn fma(a: Register, b: Register, c: Register) -> Register {
        #[cfg(target_feature = "fma")]
        // SAFETY: FMA is enabled for the whole build (cfg above).
        unsafe {
            _mm256_fmadd_pd(a, b, c)
        }
        #[cfg(not(target_feature = "fma"))]
        add(mul(a, b), c)
    }
    #[inline(always)]
    pub fn sqrt(a: Register) -> Register {
        // SAFETY: AVX is enabled for the whole build (cfg above).
        unsafe { _mm256_sqrt_pd(a) }
    }
    #[inline(always)]
    pub fn abs(a: Register) -> Register {
        // SAFETY: AVX is enabled for the whole build (cfg above).
        unsafe { _mm256_andnot_pd(_mm256_set1_pd(-0.0), a) }
    }
}

#[cfg_attr(
    all(target_arch = "x86_64", target_feature = "avx", not(kani)),
    allow(dead_code)
)]
pub(super) mod lanes_scalar {
    pub type Register = [f64; 4];
    #[inline(always)]
    fn map2(a: Register, b: Register, f: impl Fn(f64, f64) -> f64) -> Register {
        [f(a[0], b[0]), f(a[1], b[1]), f(a[2], b[2]), f(a[3], b[3])]
    }
    #[inline(always)]
    pub fn new(a: [f64; 4]) -> Register {
        a
    }
    #[inline(always)]
    pub fn arr(v: Register) -> [f64; 4] {
        v
    }
    #[inline(always)]
    pub fn splat(x: f64) -> Register {
        [x; 4]
    }
    #[inline(always)]
    pub fn add(a: Register, b: Register) -> Register {
        map2(a, b, |x, y| x + y)
    }
    #[inline(always)]
    pub fn sub(a: Register, b: Register) -> Register {
        map2(a, b, |x, y| x - y)
    }
    #[inline(always)]
    pub fn mul(a: Register, b: Register) -> Register {
        map2(a, b, |x, y| x * y)
    }
    /// Lanewise [`crate::ieee::mul_add`]: one rounding with hardware FMA (as the AVX backend),
    /// two without (and under Kani).
    #[inline(always)]
    pub fn fma(a: Register, b: Register, c: Register) -> Register {
        [
            crate::ieee::mul_add(a[0], b[0], c[0]),
            crate::ieee::mul_add(a[1], b[1], c[1]),
            crate::ieee::mul_add(a[2], b[2], c[2]),
            crate::ieee::mul_add(a[3], b[3], c[3]),
        ]
    }
    // Lane by lane rather than `array::map`, whose iterator machinery is hundreds of pointer
    // checks for the model checker (the same operations).
    #[inline(always)]
    pub fn sqrt(a: Register) -> Register {
        use crate::ieee::sqrt;
        [sqrt(a[0]), sqrt(a[1]), sqrt(a[2]), sqrt(a[3])]
    }
    #[inline(always)]
    pub fn abs(a: Register) -> Register {
        [a[0].abs(), a[1].abs(), a[2].abs(), a[3].abs()]
    }
}

impl Lanes3 {
    #[inline(always)]
    pub(super) fn splat(x: f64) -> Lanes3 {
        Lanes3(simd::splat(x))
    }
    #[inline(always)]
    pub(super) fn arr(self) -> [f64; 4] {
        simd::arr(self.0)
    }
}

impl Default for Lanes3 {
    fn default() -> Self {
        Lanes3(simd::splat(0.0))
    }
}

impl std::fmt::Debug for Lanes3 {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.arr().fmt(f)
    }
}

#[inline(always)]
pub(super) fn cadd(a: Lanes3, b: Lanes3) -> Lanes3 {
    Lanes3(simd::add(a.0, b.0))
}
#[inline(always)]
pub(super) fn csub(a: Lanes3, b: Lanes3) -> Lanes3 {
    Lanes3(simd::sub(a.0, b.0))
}
#[inline(always)]
pub(super) fn cmul(a: Lanes3, b: Lanes3) -> Lanes3 {
    Lanes3(simd::mul(a.0, b.0))
}
#[inline(always)]
pub(super) fn csqrt(a: Lanes3) -> Lanes3 {
    Lanes3(simd::sqrt(a.0))
}
#[inline(always)]
pub(super) fn cscale(a: Lanes3, s: f64) -> Lanes3 {
    Lanes3(simd::mul(a.0, simd::splat(s)))
}
#[inline(always)]
pub(super) fn cabs(a: Lanes3) -> Lanes3 {
    Lanes3(simd::abs(a.0))
}
#[inline(always)]
pub(super) fn cinflate(a: Lanes3) -> Lanes3 {
    Lanes3(simd::fma(a.0, simd::splat(RAD_UP), simd::splat(TINY)))
}
/// a·s + c (one rounding with FMA, two without).
#[inline(always)]
pub(super) fn cfma(a: Lanes3, s: f64, c: Lanes3) -> Lanes3 {
    Lanes3(simd::fma(a.0, simd::splat(s), c.0))
}
#[inline(always)]
pub(super) fn col(v: &Vector3<f64>) -> Lanes3 {
    // Construction-time only; through memory (keeps the generated code within what valgrind
    // decodes).
    Lanes3(simd::new(std::hint::black_box([v.x, v.y, v.z, 0.0])))
}
/// Upper bound of the Euclidean norm of a non-negative radius vector (lanes 0..3).
#[inline(always)]
pub(super) fn norm_up(r: Lanes3) -> f64 {
    let r = r.arr();
    crate::ieee::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]) * RAD_UP + NORM_PAD
}

/// A 3×3 matrix as three columns.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Mat3Lanes(pub(super) [Lanes3; 3]);

impl Mat3Lanes {
    #[inline(always)]
    pub(super) fn from_matrix(m: &Matrix3<f64>) -> Self {
        let c = |j: usize| col(&m.column(j).into_owned());
        Mat3Lanes([c(0), c(1), c(2)])
    }
    /// M·v (v in lanes 0..3).
    #[inline(always)]
    pub(super) fn mv(&self, v: Lanes3) -> Lanes3 {
        let v = v.arr();
        // Fused or not, each entry is a dot product of length 3 with at most 3 roundings.
        cfma(
            self.0[2],
            v[2],
            cfma(self.0[1], v[1], cscale(self.0[0], v[0])),
        )
    }
    #[inline(always)]
    pub(super) fn mm(&self, b: &Mat3Lanes) -> Mat3Lanes {
        Mat3Lanes([self.mv(b.0[0]), self.mv(b.0[1]), self.mv(b.0[2])])
    }
    #[inline(always)]
    pub(super) fn abs(&self) -> Mat3Lanes {
        Mat3Lanes([cabs(self.0[0]), cabs(self.0[1]), cabs(self.0[2])])
    }
    #[inline(always)]
    pub(super) fn add(&self, b: &Mat3Lanes) -> Mat3Lanes {
        Mat3Lanes([
            cadd(self.0[0], b.0[0]),
            cadd(self.0[1], b.0[1]),
            cadd(self.0[2], b.0[2]),
        ])
    }
    #[inline(always)]
    pub(super) fn scale(&self, s: f64) -> Mat3Lanes {
        Mat3Lanes([
            cscale(self.0[0], s),
            cscale(self.0[1], s),
            cscale(self.0[2], s),
        ])
    }
    #[inline(always)]
    pub(super) fn inflate(&self) -> Mat3Lanes {
        Mat3Lanes([
            cinflate(self.0[0]),
            cinflate(self.0[1]),
            cinflate(self.0[2]),
        ])
    }
}

#[cfg(all(test, target_arch = "x86_64", target_feature = "avx"))]
mod lanes_tests {
    use super::{lanes_avx as avx, lanes_scalar as scalar};

    fn lanes(state: &mut u64) -> [f64; 4] {
        let mut one = || {
            *state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let z = *state;
            let e = ((z >> 40) % 120) as i32 - 60;
            let v = (1.0 + (z >> 11) as f64 / (1u64 << 53) as f64) * 2f64.powi(e);
            match z % 8 {
                0 => 0.0,
                1 => -v,
                _ => v,
            }
        };
        [one(), one(), one(), one()]
    }

    /// The scalar backend (the one Kani verifies) and the AVX backend (the one that runs) give
    /// the same bits for every lanewise operation, so the occupancy code, written once over
    /// `simd::Register`, computes the same result with either.
    #[test]
    fn lanes_match_bitwise() {
        let mut state = 99u64;
        let bits = |v: [f64; 4]| v.map(f64::to_bits);
        for _ in 0..100_000 {
            let (a, b, c) = (lanes(&mut state), lanes(&mut state), lanes(&mut state));
            let (va, vb, vc) = (avx::new(a), avx::new(b), avx::new(c));
            assert_eq!(bits(avx::arr(avx::add(va, vb))), bits(scalar::add(a, b)));
            assert_eq!(bits(avx::arr(avx::sub(va, vb))), bits(scalar::sub(a, b)));
            assert_eq!(bits(avx::arr(avx::mul(va, vb))), bits(scalar::mul(a, b)));
            assert_eq!(
                bits(avx::arr(avx::fma(va, vb, vc))),
                bits(scalar::fma(a, b, c))
            );
            assert_eq!(bits(avx::arr(avx::abs(va))), bits(scalar::abs(a)));
            assert_eq!(bits(avx::arr(avx::splat(a[0]))), bits(scalar::splat(a[0])));
            let pos = a.map(f64::abs);
            assert_eq!(
                bits(avx::arr(avx::sqrt(avx::new(pos)))),
                bits(scalar::sqrt(pos))
            );
        }
    }
}
