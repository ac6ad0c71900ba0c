//! # pacs-proof-kit
//!
//! One harness body, two checks. Every harness is a function generic over an input [`Source`];
//! the [`harness!`] macro emits it twice:
//! - `#[cfg(kani)] #[kani::proof] #[kani::unwind(N)]`: the body over [`KaniSource`]
//!   (`kani::any()` + `kani::assume`), for `cargo kani`;
//! - `#[cfg(test)] #[test]`: the body over [`RandomSource`] (seeded SplitMix64, biased toward
//!   interval endpoints, neighbours of endpoints and extreme magnitudes), run for
//!   [`DEFAULT_CASES`] accepted cases (or `PACS_PROOFS_CASES`), for `cargo test`.
//!
//! Harnesses of single functions sit beside the function as `#[cfg(any(test, kani))] mod proofs`
//! (e.g. `pacs_reach::rounding`); harnesses of compositions live in `pacs-proofs`. Both use this
//! kit, which depends on nothing but (under Kani) the `kani` crate.

/// Accepted cases per harness twin under `cargo test` (override with `PACS_PROOFS_CASES`).
pub const DEFAULT_CASES: usize = 10_000;

/// A source of harness inputs: symbolic under Kani, seeded pseudo-random under `cargo test`.
pub trait Source {
    /// A value in `[lo, hi]` (`lo <= hi`, finite).
    fn f64_in(&mut self, lo: f64, hi: f64) -> f64;
    /// A value in `[lo, hi]` whose significand has at most `bits` leading bits under Kani (the
    /// trailing `52 − bits` stored bits zero), any value in property tests. Keeps the model
    /// checker's multipliers narrow where a claim multiplies two symbolic floats; the proof
    /// then covers every value with a short significand, the twin all values (`proofs/README.md`
    /// names each harness that uses it).
    fn f64_short(&mut self, lo: f64, hi: f64, bits: u32) -> f64 {
        let _ = bits;
        self.f64_in(lo, hi)
    }
    /// A value in `[lo, hi]` with any significand, whatever the harness's `bits` (for a value
    /// that must be able to hit a given real closely, such as a point of an enclosure of π/2).
    fn f64_full(&mut self, lo: f64, hi: f64) -> f64 {
        self.f64_in(lo, hi)
    }
    /// Any boolean.
    fn bool(&mut self) -> bool;
    /// A value in `0..n` (`n >= 1`).
    fn index(&mut self, n: usize) -> usize;
    /// Restrict to inputs with `cond`; returns `cond` (a harness returns early when it is false).
    fn assume(&mut self, cond: bool) -> bool;

    /// A vector with each coordinate in `[lo, hi]`.
    fn vec3(&mut self, lo: f64, hi: f64) -> [f64; 3] {
        [
            self.f64_in(lo, hi),
            self.f64_in(lo, hi),
            self.f64_in(lo, hi),
        ]
    }
    /// A vector of Euclidean length at most `r * (1 - 1e-9)` (`r >= 0`), any direction, length
    /// biased toward `r` by the endpoint bias of [`Self::f64_in`].
    fn in_ball(&mut self, r: f64) -> [f64; 3] {
        let d = self.vec3(-1.0, 1.0);
        self.in_ball_along(d, r)
    }
    /// A vector of length at most `r * (1 - 1e-9)` along `d` (any non-zero `d`; 0 if `|d|` is
    /// below 1e-3), length biased toward `r`. Sums of such vectors along one direction reach
    /// the boundary of a sum of balls.
    fn in_ball_along(&mut self, d: [f64; 3], r: f64) -> [f64; 3] {
        let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        let len = self.f64_in(0.0, 1.0) * r * (1.0 - 1e-9);
        if n < 1e-3 {
            return [0.0; 3];
        }
        // |d / n| ≤ 1 + 2u; the 1e-9 shrink above absorbs it.
        [d[0] / n * len, d[1] / n * len, d[2] / n * len]
    }
}

/// Kani's nondeterministic inputs: every `f64_in` value has at most `bits` leading significand
/// bits (52: any float). Harnesses whose formulas are too large for the model checker with
/// full-width inputs (each `f64` product is a 53 × 53-bit multiplier in the SAT formula) declare
/// `bits = N` in [`harness!`]: the proof then covers every input of at most N significant bits,
/// any magnitude in the range; the property-test twin draws all floats. `proofs/README.md` lists
/// the width of each harness.
#[cfg(kani)]
pub struct KaniSource {
    /// Leading significand bits an input may use (1..=52).
    pub bits: u32,
}

/// Any float whose significand has at most `bits` leading bits (`bits < 52`), built from its
/// fields so that the trailing significand bits are constant zeros in the model checker's
/// formula (rather than variables constrained by an assumption): the same set of floats, a
/// smaller circuit for every operation on it.
#[cfg(kani)]
fn short_float(bits: u32) -> f64 {
    let sign_exponent = u64::from(kani::any::<u16>()) & 0xfff;
    let significand = kani::any::<u64>() & ((1u64 << bits) - 1);
    f64::from_bits((sign_exponent << 52) | (significand << (52 - bits)))
}

#[cfg(kani)]
impl Source for KaniSource {
    fn f64_in(&mut self, lo: f64, hi: f64) -> f64 {
        let x: f64 = if self.bits < 52 {
            short_float(self.bits)
        } else {
            kani::any()
        };
        kani::assume(x >= lo && x <= hi);
        x
    }
    fn f64_short(&mut self, lo: f64, hi: f64, bits: u32) -> f64 {
        let x = short_float(bits.min(self.bits).min(51));
        kani::assume(x >= lo && x <= hi);
        x
    }
    fn f64_full(&mut self, lo: f64, hi: f64) -> f64 {
        let x: f64 = kani::any();
        kani::assume(x >= lo && x <= hi);
        x
    }
    /// Any point of the ball (no square root: `|v|² ≤ (r(1 − 1e-9))²` in floating point, which
    /// the 1e-9 shrink keeps inside the exact ball).
    fn in_ball(&mut self, r: f64) -> [f64; 3] {
        let v = self.vec3(-r, r);
        let rr = r * (1.0 - 1e-9);
        kani::assume(v[0] * v[0] + v[1] * v[1] + v[2] * v[2] <= rr * rr);
        v
    }
    /// Any point of the ball, whatever `d` (a superset of the twin's samples along `d`).
    fn in_ball_along(&mut self, d: [f64; 3], r: f64) -> [f64; 3] {
        let _ = d;
        self.in_ball(r)
    }
    fn bool(&mut self) -> bool {
        kani::any()
    }
    fn index(&mut self, n: usize) -> usize {
        let i: usize = kani::any();
        kani::assume(i < n);
        i
    }
    fn assume(&mut self, cond: bool) -> bool {
        kani::assume(cond);
        cond
    }
}

/// `v` itself. Under Kani a fresh symbolic array whose elements are assumed to have `v`'s bits:
/// an array passed by value that is built from computed floats reaches CBMC's SMT back end as a
/// `concat` of float terms, which Bitwuzla rejects (`proofs/smt/bitwuzla_cli.py` repairs float
/// *symbols* and literals there, not compound terms); a symbol with the same bits is the same
/// value to the code under proof.
#[inline]
pub fn pinned3(v: [f64; 3]) -> [f64; 3] {
    #[cfg(kani)]
    {
        let w: [f64; 3] = kani::any();
        kani::assume(w[0].to_bits() == v[0].to_bits());
        kani::assume(w[1].to_bits() == v[1].to_bits());
        kani::assume(w[2].to_bits() == v[2].to_bits());
        w
    }
    #[cfg(not(kani))]
    v
}

/// Seeded pseudo-random inputs (SplitMix64) with a bias toward boundary values.
#[derive(Debug, Clone)]
pub struct RandomSource {
    state: u64,
    rejected: bool,
}

impl RandomSource {
    /// A source for case `case` of the harness named `name` (reproducible).
    pub fn new(name: &str, case: u64) -> Self {
        let mut h = 0xcbf2_9ce4_8422_2325u64;
        for b in name.bytes() {
            h = (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
        let mut s = Self {
            state: h ^ case.wrapping_mul(0x9e37_79b9_7f4a_7c15),
            rejected: false,
        };
        s.next_u64();
        s
    }

    /// Next raw 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Whether an `assume` of this case failed.
    pub fn rejected(&self) -> bool {
        self.rejected
    }
}

impl Source for RandomSource {
    fn f64_in(&mut self, lo: f64, hi: f64) -> f64 {
        assert!(
            lo <= hi && lo.is_finite() && hi.is_finite(),
            "f64_in({lo}, {hi})"
        );
        if lo == hi {
            return lo;
        }
        let x = match self.next_u64() % 16 {
            0 => lo,
            1 => hi,
            2 => lo.next_up(),
            3 => hi.next_down(),
            4 if lo <= 0.0 && 0.0 <= hi => 0.0,
            5 | 6 => {
                // Any magnitude 2^-60 … 2^60, either sign.
                let e = (self.next_u64() % 121) as i32 - 60;
                let m = 1.0 + self.unit();
                let v = m * 2f64.powi(e);
                if self.next_u64() & 1 == 0 { v } else { -v }
            }
            _ => lo + self.unit() * (hi - lo),
        };
        if x.is_finite() && lo <= x && x <= hi {
            x
        } else {
            lo + self.unit() * (hi - lo)
        }
        .clamp(lo, hi)
    }
    fn bool(&mut self) -> bool {
        self.next_u64() & 1 == 1
    }
    fn index(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
    fn assume(&mut self, cond: bool) -> bool {
        if !cond {
            self.rejected = true;
        }
        cond
    }
}

/// Run `body` on seeded random sources until `cases` cases were accepted (not rejected by an
/// `assume`); panics if fewer than `cases` are accepted within `20 * cases` attempts. The case
/// count can be overridden with `PACS_PROOFS_CASES`. Returns the number of attempts.
pub fn run_cases(name: &str, cases: usize, mut body: impl FnMut(&mut RandomSource)) -> usize {
    let cases = std::env::var("PACS_PROOFS_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(cases);
    let mut accepted = 0;
    let mut attempt = 0u64;
    while accepted < cases {
        assert!(
            attempt < 20 * cases as u64 + 100,
            "{name}: only {accepted} of {cases} cases accepted in {attempt} attempts"
        );
        let mut src = RandomSource::new(name, attempt);
        body(&mut src);
        if !src.rejected() {
            accepted += 1;
        }
        attempt += 1;
    }
    attempt as usize
}

/// Emit a harness twice: a Kani proof (`cfg(kani)`) and a seeded property test (`cfg(test)`).
///
/// `harness!(name, unwind = N, cases = C, body)`; `harness!(name, unwind = N, bits = B, cases =
/// C, body)` limits the Kani inputs to B significand bits (see [`KaniSource`]);
/// `harness!(name, unwind = N, bits = B, stub = (f => g), cases = C, body)` replaces `f` by `g`
/// in the Kani proof (`#[kani::stub]`, run with `-Z stubbing`): `g` must over-approximate `f`
/// (every result `f` can give, `g` can give), so a claim proved with `g` holds with `f`; the
/// twin runs `f`. `harness!(name, twin_only, cases = C, body)` emits only the property test (a composition too
/// large for the model checker, whose building blocks have proofs of their own; listed in
/// `proofs/README.md`). `body` is a generic function
/// `fn body<S: Source>(s: &mut S)` in the same module. The proof is the function `name`; the
/// property test is `name::property_test` (a module, so both can coexist under
/// `cargo kani --tests`).
#[macro_export]
macro_rules! harness {
    ($name:ident, twin_only, cases = $cases:expr, $body:ident) => {
        #[cfg(test)]
        mod $name {
            #[test]
            fn property_test() {
                $crate::run_cases(stringify!($name), $cases, |s| super::$body(s));
            }
        }
    };
    ($name:ident, unwind = $n:literal, bits = $bits:literal, stub = ($orig:path => $repl:path), cases = $cases:expr, $body:ident) => {
        #[cfg(kani)]
        #[kani::proof]
        #[kani::unwind($n)]
        #[kani::stub($orig, $repl)]
        pub fn $name() {
            $body(&mut $crate::KaniSource { bits: $bits });
        }

        #[cfg(test)]
        mod $name {
            #[test]
            fn property_test() {
                $crate::run_cases(stringify!($name), $cases, |s| super::$body(s));
            }
        }
    };
    ($name:ident, unwind = $n:literal, bits = $bits:literal, stubs = [$(($orig:path => $repl:path)),+ $(,)?], cases = $cases:expr, $body:ident) => {
        #[cfg(kani)]
        #[kani::proof]
        #[kani::unwind($n)]
        $(#[kani::stub($orig, $repl)])+
        pub fn $name() {
            $body(&mut $crate::KaniSource { bits: $bits });
        }

        #[cfg(test)]
        mod $name {
            #[test]
            fn property_test() {
                $crate::run_cases(stringify!($name), $cases, |s| super::$body(s));
            }
        }
    };
    // A body with arguments after the source: `body(args…)` is called as `body(source, args…)`
    // (one body shared by harnesses that differ in constants).
    ($name:ident, unwind = $n:literal, bits = $bits:literal, cases = $cases:expr, $body:ident($($arg:expr),+ $(,)?)) => {
        #[cfg(kani)]
        #[kani::proof]
        #[kani::unwind($n)]
        pub fn $name() {
            $body(&mut $crate::KaniSource { bits: $bits }, $($arg),+);
        }

        #[cfg(test)]
        mod $name {
            #[test]
            fn property_test() {
                $crate::run_cases(stringify!($name), $cases, |s| super::$body(s, $($arg),+));
            }
        }
    };
    ($name:ident, unwind = $n:literal, bits = $bits:literal, cases = $cases:expr, $body:ident) => {
        #[cfg(kani)]
        #[kani::proof]
        #[kani::unwind($n)]
        pub fn $name() {
            $body(&mut $crate::KaniSource { bits: $bits });
        }

        #[cfg(test)]
        mod $name {
            #[test]
            fn property_test() {
                $crate::run_cases(stringify!($name), $cases, |s| super::$body(s));
            }
        }
    };
    ($name:ident, unwind = $n:literal, cases = $cases:expr, $body:ident) => {
        #[cfg(kani)]
        #[kani::proof]
        #[kani::unwind($n)]
        pub fn $name() {
            $body(&mut $crate::KaniSource { bits: 52 });
        }

        #[cfg(test)]
        mod $name {
            #[test]
            fn property_test() {
                $crate::run_cases(stringify!($name), $cases, |s| super::$body(s));
            }
        }
    };
}
