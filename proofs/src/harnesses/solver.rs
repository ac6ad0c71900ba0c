//! (z) The model checker's own arithmetic: checked integer operations and float bit access give
//! the values Rust defines, under every solver `proofs/kani.sh` uses.
//!
//! Every proof above rests on the solver back end encoding the program faithfully. CBMC 6.4's
//! SMT back end (the `bitwuzla` solver here) once did not: it built the `(result, overflowed)`
//! pair of signed `+`/`−` and of `×` with the two members swapped, so every checked integer
//! operation of a debug build had a wrong result and a wrong overflow flag
//! (`proofs/smt/bitwuzla_cli.py` repairs it; `proofs/README.md`, "Solvers"). These proofs fail
//! on such an encoding; CI runs them with each solver before trusting any other result.
//! `z1_real_overflow_is_found` checks the other direction: a real overflow is still reported.

/// `x` as (unbiased exponent, significand) of its IEEE 754 bits (finite `x`).
fn exponent_significand(x: f64) -> (i32, u64) {
    let bits = x.to_bits();
    let biased = ((bits >> 52) & 0x7ff) as i32;
    let frac = bits & ((1u64 << 52) - 1);
    if biased == 0 {
        (-1074, frac)
    } else {
        (biased - 1075, frac | (1u64 << 52))
    }
}

/// Checked `+ − ×` against the same operation one width up; the float fields in range.
fn arithmetic(a32: i32, b32: i32, a16: i16, b16: i16, c16: u16, d16: u16, x: f64) {
    let w = i64::from(a32) + i64::from(b32);
    assert!(a32.overflowing_add(b32) == (w as i32, w != i64::from(w as i32)));
    let w = i64::from(a32) - i64::from(b32);
    assert!(a32.overflowing_sub(b32) == (w as i32, w != i64::from(w as i32)));
    let w = i32::from(a16) * i32::from(b16);
    assert!(a16.overflowing_mul(b16) == (w as i16, w != i32::from(w as i16)));
    let w = u32::from(c16) * u32::from(d16);
    assert!(c16.overflowing_mul(d16) == (w as u16, w > u32::from(u16::MAX)));
    let w = u32::from(c16) + u32::from(d16);
    assert!(c16.overflowing_add(d16) == (w as u16, w > u32::from(u16::MAX)));
    if x.is_finite() {
        let (e, m) = exponent_significand(x);
        assert!((-1074..=971).contains(&e) && m < (1u64 << 53));
        // Plain (overflow-checked) operations whose values matter.
        let small = (a16 % 100, b16 % 100);
        assert!(i32::from(small.0 - small.1) == i32::from(small.0) - i32::from(small.1));
        assert!(i32::from(small.0 * small.1) == i32::from(small.0) * i32::from(small.1));
    }
}

#[cfg(kani)]
#[kani::proof]
fn z0_solver_integer_semantics() {
    arithmetic(
        kani::any(),
        kani::any(),
        kani::any(),
        kani::any(),
        kani::any(),
        kani::any(),
        kani::any(),
    );
}

/// A real overflow in a checked operation is reported (the harness must panic).
#[cfg(kani)]
#[kani::proof]
#[kani::should_panic]
fn z1_real_overflow_is_found() {
    let a: i32 = kani::any();
    kani::assume(a > 0);
    let _ = std::hint::black_box(a + i32::MAX);
}

#[cfg(test)]
mod tests {
    /// The same identities on seeded random values (the twin).
    #[test]
    fn z0_solver_integer_semantics_twin() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        for _ in 0..10_000 {
            let mut next = || {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                state
            };
            let (r1, r2, r3) = (next(), next(), next());
            super::arithmetic(
                r1 as i32,
                (r1 >> 32) as i32,
                r2 as i16,
                (r2 >> 16) as i16,
                (r2 >> 32) as u16,
                (r2 >> 48) as u16,
                f64::from_bits(r3),
            );
        }
    }
}

/// A weighted difference of two points: each coordinate with its own weight, so that a
/// permutation of elements changes the value.
#[inline(never)]
fn weighted_gap(a: &nalgebra::Point3<f64>, b: &nalgebra::Point3<f64>) -> f64 {
    (a.x - b.x) + 2.0 * (a.y - b.y) + 4.0 * (a.z - b.z)
}

/// Points in an array of points (`[Point3<f64>; 4]`, as `b1`/`b2` build their segments):
/// CBMC's SMT output equates an element of such a nested array with a flattened bit-vector
/// argument, which `bitwuzla_cli.py::repair_array_elements` splits per element; these claims
/// hold only if the split keeps the element order.
#[cfg(kani)]
fn four_points() -> Option<[nalgebra::Point3<f64>; 4]> {
    let point = || {
        let v: [f64; 3] = [kani::any(), kani::any(), kani::any()];
        v.iter()
            .all(|c| c.is_finite() && c.abs() <= 2.0)
            .then(|| nalgebra::Point3::from(v))
    };
    let a0 = point()?;
    let a1 = if kani::any() { point()? } else { a0 };
    let b0 = point()?;
    let b1 = if kani::any() { point()? } else { b0 };
    Some([a0, a1, b0, b1])
}

#[cfg(kani)]
#[kani::proof]
#[kani::unwind(5)]
fn z2_solver_nested_arrays() {
    let Some([a0, _, b0, b1]) = four_points() else {
        return;
    };
    let g = weighted_gap(&a0, &b0);
    assert!(g == (a0.x - b0.x) + 2.0 * (a0.y - b0.y) + 4.0 * (a0.z - b0.z));
    let h = weighted_gap(&b1, &b0);
    assert!(h == (b1.x - b0.x) + 2.0 * (b1.y - b0.y) + 4.0 * (b1.z - b0.z));
    if a0 == nalgebra::Point3::new(1.0, 0.0, 0.0) && b0 == nalgebra::Point3::origin() {
        assert!(g == 1.0);
    }
}

/// The same points: a claim that holds only for a permuted element order must be refuted.
#[cfg(kani)]
#[kani::proof]
#[kani::unwind(5)]
#[kani::should_panic]
fn z3_nested_array_order_is_checked() {
    let Some([a0, _, b0, _]) = four_points() else {
        return;
    };
    kani::assume(a0 == nalgebra::Point3::new(1.0, 0.0, 0.0) && b0 == nalgebra::Point3::origin());
    assert!(weighted_gap(&a0, &b0) == 4.0, "a permuted order");
}

/// Four lanes by value, as the robot occupancy's `Lanes3` (a `[f64; 4]` in its scalar backend).
#[derive(Clone, Copy)]
#[repr(transparent)]
struct Four([f64; 4]);

/// The lanes' absolute values, built element by element (as `Mat3Lanes::abs`).
#[inline(never)]
fn abs_lanes(a: Four) -> Four {
    Four([a.0[0].abs(), a.0[1].abs(), a.0[2].abs(), a.0[3].abs()])
}

/// A weighted sum of lanes passed by value: each element with its own weight, so that a
/// permutation changes the value.
#[inline(never)]
fn weighted_lanes(v: Four) -> f64 {
    v.0[0] + 2.0 * v.0[1] + 4.0 * v.0[2] + 8.0 * v.0[3]
}

/// Four small floats passed by value through [`abs_lanes`]: CBMC's SMT output equates the
/// argument (a bit-vector) with the `concat` of the array's elements, which Bitwuzla rejects
/// (float arguments of a bit-vector operator) and `bitwuzla_cli.py::repair_float_array_concats`
/// splits per element (without the repair both harnesses end in a solver error). The claims
/// depend on the element order, which the program's own array carries: `z4` is proved and
/// `z5` refuted through the repaired form.
#[cfg(kani)]
fn four_lanes() -> Option<[f64; 4]> {
    let v: [f64; 4] = [kani::any(), kani::any(), kani::any(), kani::any()];
    v.iter()
        .all(|c| c.is_finite() && c.abs() <= 2.0)
        .then_some(v)
}

/// Lanes beside an integer in a struct, kept in an array and read back at a symbolic index
/// (CBMC then flattens the struct, the float array's `concat` inside it, into the elements of a
/// bit-vector array: the form `d1_affine_encloses` produces).
#[cfg(kani)]
#[derive(Clone, Copy)]
struct Tagged {
    tag: u64,
    lanes: Four,
}

#[cfg(kani)]
#[kani::proof]
#[kani::unwind(5)]
fn z4_solver_float_array_arguments() {
    let Some(v) = four_lanes() else {
        return;
    };
    let w = weighted_lanes(abs_lanes(Four(v)));
    let a = v.map(f64::abs);
    assert!(w == a[0] + 2.0 * a[1] + 4.0 * a[2] + 8.0 * a[3]);
    if v == [-1.0, 0.0, 0.0, 0.0] {
        assert!(w == 1.0);
    }
    // Small integers in the kept lanes (the solver decides the sums at once; with any floats
    // this half took 168 s).
    let small: [u8; 4] = kani::any();
    let u = small.map(|k| f64::from(k & 3) - 2.0);
    let w = u.map(f64::abs);
    let w = w[0] + 2.0 * w[1] + 4.0 * w[2] + 8.0 * w[3];
    let kept = [
        Tagged {
            tag: 1,
            lanes: abs_lanes(Four(u)),
        },
        Tagged {
            tag: 2,
            lanes: Four([0.0; 4]),
        },
    ];
    let i: usize = kani::any();
    kani::assume(i < 2);
    let t = kept[i];
    if t.tag == 1 {
        assert!(weighted_lanes(t.lanes) == w);
    } else {
        assert!(weighted_lanes(t.lanes) == 0.0);
    }
}

/// The same lanes: a claim that holds only for a permuted element order must be refuted.
#[cfg(kani)]
#[kani::proof]
#[kani::unwind(5)]
#[kani::should_panic]
fn z5_float_array_order_is_checked() {
    let Some(v) = four_lanes() else {
        return;
    };
    kani::assume(v == [-1.0, 0.0, 0.0, 0.0]);
    assert!(
        weighted_lanes(abs_lanes(Four(v))) == 8.0,
        "a permuted order"
    );
}

#[cfg(test)]
mod nested_tests {
    /// The twin of `z2`: the weighted gap of concrete points.
    #[test]
    fn z2_weighted_gap_twin() {
        let a = nalgebra::Point3::new(1.0, 0.0, 0.0);
        let b = nalgebra::Point3::origin();
        assert_eq!(super::weighted_gap(&a, &b), 1.0);
        let c = nalgebra::Point3::new(0.0, 0.0, 1.0);
        assert_eq!(super::weighted_gap(&c, &b), 4.0);
    }

    /// The twin of `z4`: the weighted lanes of concrete arrays.
    #[test]
    fn z4_weighted_lanes_twin() {
        let lanes = |v| super::weighted_lanes(super::abs_lanes(super::Four(v)));
        assert_eq!(lanes([-1.0, 0.0, 0.0, 0.0]), 1.0);
        assert_eq!(lanes([0.0, 0.0, 0.0, -1.0]), 8.0);
    }
}
