//! (b) Segment–segment distance bounds and capsule / zonotope intersection tests are
//! conservative.

use crate::exact::dist3_le;
use crate::{Source, harness};
use nalgebra::Vector3;
use nalgebra::{DVector, Point3};
use pacs_models::Capsule;
use pacs_reach::Interval;
use pacs_reach::geometry::{
    capsule_distance_lower_bound, capsules_disjoint, segment_distance_lower_bound,
    separating_axis_lower_bound,
};
use pacs_reach::rounding::{add_down, norm3_up};
use pacs_reach::zonotope::{Zonotope, Zonotope3};

/// A point with coordinates in [-2, 2] (0 or magnitude ≥ 1e-100).
fn point<S: Source>(s: &mut S) -> Option<Point3<f64>> {
    let v = s.vec3(-2.0, 2.0);
    s.assume(v.iter().all(|c| crate::exact::tame(*c)))
        .then(|| Point3::from(v))
}

/// Enclosure of the exact point `a + t (b − a)` (interval arithmetic, checked by (a)).
fn on_segment(a: &Point3<f64>, b: &Point3<f64>, t: f64) -> [Interval; 3] {
    std::array::from_fn(|i| {
        Interval::point(a[i]) + (Interval::point(b[i]) - Interval::point(a[i])).scale(t)
    })
}

/// Upper bound of the exact distance between two enclosed points.
fn dist_up(p: &[Interval; 3], q: &[Interval; 3]) -> f64 {
    let d: [f64; 3] = std::array::from_fn(|i| (p[i] - q[i]).mag());
    norm3_up(d[0], d[1], d[2])
}

/// Segments `a0a1`, `b0b1` (either possibly degenerate) and points on them.
#[allow(clippy::type_complexity)]
fn segments<S: Source>(s: &mut S) -> Option<([Point3<f64>; 4], [Interval; 3], [Interval; 3])> {
    let a0 = point(s)?;
    let a1 = if s.bool() { point(s)? } else { a0 };
    // Often very close to a0 (where the dot products' rounding matters most).
    let b0 = if s.bool() {
        point(s)?
    } else {
        let d = s.vec3(-1e-6, 1e-6);
        Point3::new(a0.x + d[0], a0.y + d[1], a0.z + d[2])
    };
    let b1 = if s.bool() { point(s)? } else { b0 };
    let (t, u) = (s.f64_in(0.0, 1.0), s.f64_in(0.0, 1.0));
    Some((
        [a0, a1, b0, b1],
        on_segment(&a0, &a1, t),
        on_segment(&b0, &b1, u),
    ))
}

/// The separating-axis lower bound never exceeds the distance of any two points of the segments
/// (so never the exact segment distance): in half the cases the segments of
/// [`plane_grid_segments`] and points of them at `t, u ∈ {0, ½, 1}`, against the exact distance
/// ([`below_distance`]); in every case any segments in `[−2, 2]³` (ends often 10⁻⁶ apart) and
/// any points of them.
fn segment_lb<S: Source>(s: &mut S) {
    if s.bool() {
        let [a0, a1, b0, b1] = plane_grid_segments(s);
        let lb = segment_distance_lower_bound(&a0, &a1, &b0, &b1);
        assert!((0.0..=8.0).contains(&lb), "bound {lb} out of range");
        let (p, q) = (half_point(s, &a0, &a1), half_point(s, &b0, &b1));
        assert!(below_distance(lb, &p, &q), "lb {lb} > |{p:?} − {q:?}|");
    }
    let Some(([a0, a1, b0, b1], p, q)) = segments(s) else {
        return;
    };
    let lb = segment_distance_lower_bound(&a0, &a1, &b0, &b1);
    assert!(lb >= 0.0);
    let ub = dist_up(&p, &q);
    assert!(lb <= ub, "lb {lb} > |p - q| ≤ {ub}");
    // Endpoints are exact points: compare with the exact distance directly.
    let (a, b) = ([a0.x, a0.y, a0.z], [b0.x, b0.y, b0.z]);
    if a0 == a1 && b0 == b1 {
        // A proof of |a − b| ≤ pred(lb) < lb would be a violation.
        assert!(
            lb == 0.0 || !dist3_le(&a, &b, lb.next_down()),
            "point lb {lb} too large"
        );
    }
}
// Property test only: the Kani proofs are the floating-point steps beside the code
// (`b1_dot_bounds_enclose`, with a1 `sub_down`, a2 `div_down`, a3 `norm3_up`) and the real-number
// argument in the doc of `separating_axis_lower_bound` (proofs/README.md, "What the splits leave").
// Its Kani attempts (the plane grid below among them) and why they fail: proofs/README.md.
harness!(
    b1_segment_distance_lower_bound,
    twin_only,
    cases = crate::DEFAULT_CASES,
    segment_lb
);

/// An integer in `[−2, 2]` as a float.
fn small_int<S: Source>(s: &mut S) -> f64 {
    s.index(5) as f64 - 2.0
}

/// A point with integer coordinates in `[−2, 2]`.
fn int_point<S: Source>(s: &mut S) -> Point3<f64> {
    Point3::new(small_int(s), small_int(s), small_int(s))
}

/// Two segments (either possibly a point) with integer ends in `[−2, 2]` in the plane `z = 0`,
/// where points at `t ∈ {0, ½, 1}` and their squared distances are exact (the divisions, the
/// norm and the outward rounding of the bound still round).
fn plane_grid_segments<S: Source>(s: &mut S) -> [Point3<f64>; 4] {
    let mut plane = || Point3::new(small_int(s), small_int(s), 0.0);
    [plane(), plane(), plane(), plane()]
}

/// An end of the segment `ab`, or its midpoint: exact for integer `a`, `b` (multiples of 1/2).
fn half_point<S: Source>(s: &mut S, a: &Point3<f64>, b: &Point3<f64>) -> [f64; 3] {
    let t = s.index(3) as f64 * 0.5;
    std::array::from_fn(|i| a[i] + t * (b[i] - a[i]))
}

/// `lb ≤ |p − q|` exactly, for `p`, `q` multiples of 1/2 in `[−2, 2]³` (their squared distance
/// `d2` is an exact float): `√d2` vs `lb` on integer significands
/// ([`crate::exact::cmp_sqrt`]).
fn below_distance(lb: f64, p: &[f64; 3], q: &[f64; 3]) -> bool {
    let d2 = (0..3).map(|i| (p[i] - q[i]) * (p[i] - q[i])).sum::<f64>();
    crate::exact::cmp_sqrt(d2, lb) != std::cmp::Ordering::Less
}

/// The separating-axis certificate is a lower bound along **any** direction (the closest-point
/// direction only makes it tight): random directions, half of them near `p − q`; in half the
/// cases also the integer grid of [`separating_axis_grid`], decided exactly.
fn separating_axis_any<S: Source>(s: &mut S) {
    if s.bool() {
        separating_axis_grid(s);
    }
    let Some(([a0, a1, b0, b1], p, q)) = segments(s) else {
        return;
    };
    let n = if s.bool() {
        Vector3::from(s.vec3(-2.0, 2.0))
    } else {
        let e = s.vec3(-1e-3, 1e-3);
        Vector3::from(std::array::from_fn(|i| p[i].mid() - q[i].mid() + e[i]))
    };
    let lb = separating_axis_lower_bound(&n, &a0, &a1, &b0, &b1);
    assert!(lb >= 0.0);
    let ub = dist_up(&p, &q);
    assert!(lb <= ub, "along {n:?}: lb {lb} > |p - q| ≤ {ub}");
}

/// [`separating_axis_lower_bound`] on a grid where the exact distance is decided in floating
/// point: segment ends and the direction with integer coordinates in `[−2, 2]` (every product
/// and the dot products' sums exact, while the bound's own error terms, `norm3_up` and
/// `div_down` round), points of the segments at `t, u ∈ {0, ½, 1}`; the bound is in
/// `[0, 8]` and at most their exact distance ([`below_distance`]).
fn separating_axis_grid<S: Source>(s: &mut S) {
    let (a0, a1, b0, b1) = (int_point(s), int_point(s), int_point(s), int_point(s));
    let n = Vector3::new(small_int(s), small_int(s), small_int(s));
    let lb = separating_axis_lower_bound(&n, &a0, &a1, &b0, &b1);
    assert!((0.0..=8.0).contains(&lb), "bound {lb} out of range");
    let (p, q) = (half_point(s, &a0, &a1), half_point(s, &b0, &b1));
    assert!(
        below_distance(lb, &p, &q),
        "along {n:?}: lb {lb} > |{p:?} − {q:?}|"
    );
}
// Property test only (proofs/README.md). The grid above under Kani, with `norm3_up` and
// `div_down` replaced by one-multiplier over-approximations (a rounded square at least the
// rounded sum of squares less 2⁻⁵⁰ relative; a rounded product at most the dividend), timed
// out at 300 s with Bitwuzla (twice, the second with the exact `cmp_sqrt` oracle and
// half-point samples) and with the SAT back end: the four `dot_bounds` of a symbolic direction
// are twelve full multipliers.
harness!(
    b1_separating_axis_any_direction,
    twin_only,
    cases = crate::DEFAULT_CASES,
    separating_axis_any
);

/// Capsules that share a point are never reported disjoint, and the capsule distance bound is
/// at most the distance of any two axis points minus the radii. Radii are drawn so that the
/// capsules often exactly touch. In half the cases also [`capsules_on_the_plane_grid`], decided
/// exactly.
fn capsules<S: Source>(s: &mut S) {
    if s.bool() {
        capsules_on_the_plane_grid(s);
    }
    let Some(([a0, a1, b0, b1], p, q)) = segments(s) else {
        return;
    };
    let ub = dist_up(&p, &q);
    let ra = s.f64_in(0.0, 1.0);
    let rb = if s.bool() {
        s.f64_in(0.0, 1.0)
    } else {
        // Touching (or overlapping by rounding): ra + rb ≥ ub ≥ |p − q|.
        (ub - ra).max(0.0).next_up()
    };
    let ca = Capsule::new_unchecked(a0, a1, ra);
    let cb = Capsule::new_unchecked(b0, b1, rb);
    let lb = capsule_distance_lower_bound(&ca, &cb);
    assert!(lb >= 0.0);
    // |p − q| ≤ ub ≤ ra + rb (exactly, as add_down(ra, rb) ≤ ra + rb) ⇒ the capsules intersect.
    if ub <= add_down(ra, rb) {
        assert!(
            !capsules_disjoint(&ca, &cb),
            "touching capsules reported disjoint"
        );
        assert!(lb == 0.0);
    }
    assert!(lb <= (ub - ra - rb).max(0.0) * (1.0 + 1e-12) + 1e-300);
}
/// The capsules of [`plane_grid_segments`] with radii multiples of 1/4 in `[0, 2]` and points
/// of their axes at `t, u ∈ {0, ½, 1}`, decided exactly (every square and sum below exact): if
/// the points are within the sum of the radii, the capsules share a point and are never
/// reported disjoint, and their distance bound is 0; the bound is 0 or at most the points'
/// distance less the radii ([`crate::exact::cmp_sqrt`] against the sum rounded up).
fn capsules_on_the_plane_grid<S: Source>(s: &mut S) {
    let [a0, a1, b0, b1] = plane_grid_segments(s);
    let (p, q) = (half_point(s, &a0, &a1), half_point(s, &b0, &b1));
    let (ra, rb) = (s.index(9) as f64 * 0.25, s.index(9) as f64 * 0.25);
    let (ca, cb) = (
        Capsule::new_unchecked(a0, a1, ra),
        Capsule::new_unchecked(b0, b1, rb),
    );
    let lb = capsule_distance_lower_bound(&ca, &cb);
    assert!(lb >= 0.0);
    let d2 = (0..3).map(|i| (p[i] - q[i]) * (p[i] - q[i])).sum::<f64>();
    let r = ra + rb;
    if d2 <= r * r {
        assert!(
            !capsules_disjoint(&ca, &cb),
            "capsules sharing a point reported disjoint"
        );
        assert!(lb == 0.0, "bound {lb} for capsules sharing a point");
    }
    assert!(
        lb == 0.0
            || crate::exact::cmp_sqrt(d2, crate::exact::ceil_sum(lb, r))
                != std::cmp::Ordering::Less,
        "bound {lb} above |{p:?} − {q:?}| − {r}"
    );
}
// Property test only: the Kani proofs are `b2_capsule_margin_sound` (the rounding of the margin,
// beside the code) and the b1 split for the segment distance; its Kani attempts (the plane grid
// above among them): proofs/README.md.
harness!(
    b2_capsule_intersection_conservative,
    twin_only,
    cases = crate::DEFAULT_CASES,
    capsules
);

/// A box zonotope is never reported `Outside` for one of its points (boundary points included:
/// the endpoint bias of the input source puts many on the boundary): neither the hull test nor
/// the separating-direction certificate accepts any direction; under `cargo test` also the whole
/// `contains` with its LP.
fn zonotope_box<S: Source>(s: &mut S) {
    let (lo, hi, x, d) = if cfg!(kani) || s.index(4) == 0 {
        box_on_the_grid(s)
    } else {
        let (lo0, lo1) = (s.f64_in(-2.0, 2.0), s.f64_in(-2.0, 2.0));
        let (w0, w1) = (s.f64_in(0.0, 1.0), s.f64_in(0.0, 1.0));
        let (hi0, hi1) = (lo0 + w0, lo1 + w1);
        let x = vec![s.f64_in(lo0, hi0), s.f64_in(lo1, hi1)];
        let d = vec![s.f64_in(-1e3, 1e3), s.f64_in(-1e3, 1e3)];
        (vec![lo0, lo1], vec![hi0, hi1], x, d)
    };
    let x = DVector::from_vec(x);
    let z = Zonotope::from_interval(
        &DVector::from_vec(lo.clone()),
        &DVector::from_vec(hi.clone()),
    )
    .expect("valid box");
    // The two outside certificates of `contains`, for any direction (the LP only proposes one).
    assert!(!z.hull_excludes(&x), "{x:?} outside the hull of its box");
    let d = DVector::from_vec(d);
    assert!(
        !z.separates(&x, &d).expect("dimensions"),
        "direction {d:?} separates {x:?} from the box {lo:?}..{hi:?}"
    );
    // The whole decision with the LP (not under Kani: the solver's runtime is out of its reach).
    #[cfg(not(kani))]
    {
        let c = z.contains(&x).expect("valid point");
        assert!(
            c != pacs_reach::zonotope::Containment::Outside,
            "{x:?} in the box {lo:?}..{hi:?} reported outside"
        );
    }
}

/// Under Kani: a one-dimensional box `[lo, lo + w]` with `lo` a multiple of 1/16 in `[−2, 2]`
/// and `w` one in `[0, 1]`, a point of it on the same grid (its ends included), and a direction
/// of `0, ±1, ±2⁻⁶⁰, ±3·2⁻⁵` (exact products, and ones of very different magnitudes). Integers
/// converted and scaled by 1/16 (exact; cheaper for the model checker than floats of any
/// exponent constrained to the grid).
fn box_on_the_grid<S: Source>(s: &mut S) -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>) {
    let sixteenth = 0.0625;
    let lo = s.index(65) as f64 * sixteenth - 2.0;
    let w = s.index(17);
    let x = lo + s.index(w + 1) as f64 * sixteenth;
    let d = [0.0, 1.0, f64::from_bits((1023 - 60) << 52), 0.09375][s.index(4)];
    let d = if s.bool() { -d } else { d };
    (vec![lo], vec![lo + w as f64 * sixteenth], vec![x], vec![d])
}
// Kani (outside CI): one dimension on the grid of [`box_on_the_grid`], `from_interval`, the hull
// test and the separating-direction certificate on the dynamic zonotope; the twin: two
// dimensions, any floats and directions, and the LP (proofs/README.md). Its splits beside the
// code (`reach/src/zonotope/proofs.rs`) check the same arithmetic on plain fields.
harness!(
    b3_zonotope_contains_conservative,
    unwind = 4,
    bits = 52,
    cases = crate::DEFAULT_CASES,
    zonotope_box
);

/// `Zonotope3 ⊕ Ball(inflate)` and a capsule that contains one of its points are never reported
/// disjoint, and their distance lower bound is 0 (dynamic-object occupancy vs robot capsule):
/// along any direction (Kani: one generator; twin: up to three), and with the GJK direction
/// (twin).
fn zonotope_capsule<S: Source>(s: &mut S) {
    let c = s.vec3(-2.0, 2.0);
    let m = if cfg!(kani) { 1 } else { 1 + s.index(3) };
    let gens: Vec<[f64; 3]> = (0..m).map(|_| s.vec3(-1.0, 1.0)).collect();
    let e = s.vec3(0.0, 0.1);
    let inflate = s.f64_in(0.0, 0.2);
    let z = Zonotope3::new(c, &gens, e).expect("valid zonotope");
    // A point of Z ⊕ B(inflate): c + Σ β_k g_k + diag(e) γ + w, |β|, |γ| ≤ 1, |w| ≤ inflate.
    let mut p = c;
    for g in &gens {
        let b = s.f64_in(-1.0, 1.0);
        for i in 0..3 {
            p[i] += b * g[i];
        }
    }
    let w = s.in_ball(inflate);
    for i in 0..3 {
        p[i] += s.f64_in(-1.0, 1.0) * e[i] + w[i];
    }
    // The capsule contains the exact point: its axis starts at the computed point, whose
    // rounding error (≤ 1e-14 m here) is below the radius.
    let r = s.f64_in(1e-9, 0.5);
    let p2 = if s.bool() { p } else { s.vec3(-3.0, 3.0) };
    let cap = Capsule::new_unchecked(Point3::from(p), Point3::from(p2), r);
    // The rigorous evaluation along any direction (GJK only proposes one): never a positive
    // distance for sets that share a point.
    let n = s.vec3(-1.0, 1.0);
    assert_eq!(
        z.distance_bound_along(inflate, &cap, n),
        0.0,
        "{z:?} ⊕ B({inflate}) separated along {n:?} from {cap:?} containing {p:?}"
    );
    if cfg!(kani) {
        // Split (proofs/README.md): the GJK iteration that proposes the direction is the twin's.
        return;
    }
    assert!(
        !z.is_disjoint(inflate, &cap),
        "{z:?} ⊕ B({inflate}) reported disjoint from {cap:?} containing {p:?}"
    );
    assert_eq!(z.distance_lower_bound(inflate, &cap), 0.0);
}
// Property test only. Of the splits beside the code (`reach/src/zonotope/proofs.rs`), Kani
// proves `b4_support_up_member` (the support function's outward rounding, on a grid) and
// `b4_distance_bound_shared_point` (this claim along any grid direction, on a restricted grid:
// proofs/README.md).
harness!(
    b4_zonotope_capsule_conservative,
    twin_only,
    cases = crate::DEFAULT_CASES,
    zonotope_capsule
);
