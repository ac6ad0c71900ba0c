//! `profile::Range` against `inari`: the padded extrema of a constant-jerk piece contain inari's
//! rigorous enclosure of the piece's exact real value at sampled instants of the span (5000
//! random pieces and spans, 33 instants each), and a `Range` only ever widens.

use inari::{Interval as Exact, interval};
use pacs_motion::profile::{Piece, Range};
use proptest::prelude::*;

fn pt(x: f64) -> Exact {
    interval!(x, x).unwrap()
}

/// Inari's enclosures of q, q̇, q̈ of `p` at local instant `d` (exact real arithmetic on the
/// floating-point inputs, rounded outward).
fn exact_state(p: &Piece, d: f64) -> [Exact; 3] {
    let (q, v, a, j, d) = (pt(p.q), pt(p.v), pt(p.a), pt(p.j), pt(d));
    let half = pt(0.5);
    let sixth = pt(1.0) / pt(6.0);
    [
        q + v * d + half * a * d * d + sixth * j * d * d * d,
        v + a * d + half * j * d * d,
        a + j * d,
    ]
}

fn contains(r: &Range, x: Exact) -> bool {
    r.lo <= x.inf() && x.sup() <= r.hi
}

fn piece() -> impl Strategy<Value = Piece> {
    (
        -10.0f64..10.0,
        -10.0f64..10.0,
        -100.0f64..100.0,
        prop_oneof![Just(0.0), -1e4f64..1e4],
    )
        .prop_map(|(q, v, a, j)| Piece { t: 0.0, q, v, a, j })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(5000))]

    #[test]
    fn range_contains_inari(p in piece(), d0 in 0.0f64..0.5, w in 0.0f64..0.5) {
        let d1 = d0 + w;
        let mut r = [Range::EMPTY; 3];
        p.extend_bounds(d0, d1, &mut r);
        let mut rd = [Range::EMPTY; 2];
        p.extend_deriv_bounds(d0, d1, &mut rd);
        for k in 0..=32 {
            let d = if k == 32 { d1 } else { d0 + w * (k as f64 / 32.0) };
            let d = d.min(d1);
            let e = exact_state(&p, d);
            for i in 0..3 {
                prop_assert!(contains(&r[i], e[i]), "{i}: {:?} ∌ {:?} at d = {d}", r[i], e[i]);
            }
            prop_assert!(contains(&rd[0], e[1]) && contains(&rd[1], e[2]));
        }
    }

    #[test]
    fn range_only_widens(xs in prop::collection::vec((-1e3f64..1e3, 0.0f64..1.0), 1..20)) {
        let mut r = Range::EMPTY;
        for (x, pad) in xs {
            let before = r;
            r.include_padded(x, pad);
            prop_assert!(r.lo <= before.lo && r.hi >= before.hi);
            prop_assert!(r.lo <= x - pad && r.hi >= x + pad);
            let mut u = r;
            u.union(Range::point(x));
            prop_assert_eq!(u, r);
        }
    }
}
