//! Property tests of LTI reachability and of the dynamic-object occupancy against simulated
//! trajectories.

use nalgebra::{DMatrix, DVector};
use pacs_reach::lti::{LtiReach, LtiSystem, ReachError, ReachOptions};
use pacs_reach::zonotope::Zonotope;
use proptest::collection::vec;
use proptest::prelude::*;

const CASES: u32 = 10_000;

fn coef() -> impl Strategy<Value = f64> {
    prop_oneof![3 => -1.0..=1.0f64, 1 => Just(1.0), 1 => Just(-1.0)]
}

/// `(e^{Ah}, Γ(h) = ∫₀ʰ e^{As} ds)` by a 40-term Taylor series (‖A‖h < 1 here: error ≪ 1e-15).
fn exp_and_gamma(a: &DMatrix<f64>, h: f64) -> (DMatrix<f64>, DMatrix<f64>) {
    let n = a.nrows();
    let mut term = DMatrix::identity(n, n); // (Ah)^i / i!
    let mut e = DMatrix::identity(n, n);
    let mut g = DMatrix::identity(n, n) * h;
    for i in 1..40 {
        term = &term * a * (h / i as f64);
        e += &term;
        g += &term * (h / (i + 1) as f64);
    }
    (e, g)
}

/// Fails only if `x` is outside `z` by more than a simulation tolerance along a direction.
fn check_in(z: &Zonotope, x: &DVector<f64>, dirs: &[Vec<f64>]) -> Result<(), TestCaseError> {
    let n = z.dim();
    let (lo, hi) = z.interval_hull();
    let tol = |s: f64| 1e-9 * (1.0 + s);
    for i in 0..n {
        prop_assert!(
            x[i] >= lo[i] - tol(x[i].abs()) && x[i] <= hi[i] + tol(x[i].abs()),
            "axis {i}: {} vs [{}, {}]",
            x[i],
            lo[i],
            hi[i]
        );
    }
    for d in dirs {
        let d = DVector::from_column_slice(&d[..n]);
        let h = z.support_up(&d).unwrap();
        let dx = d.dot(x);
        prop_assert!(dx <= h + tol(d.abs().dot(&x.abs())), "d·x = {dx} > h = {h}");
    }
    Ok(())
}

#[derive(Debug, Clone)]
struct LtiCase {
    a: DMatrix<f64>,
    b: DMatrix<f64>,
    u: Zonotope,
    x0: Zonotope,
    r: f64,
    beta0: Vec<f64>,
    inputs: Vec<Vec<f64>>, // coefficients of U's generators per piece (4 pieces per step)
    k: usize,
    theta: f64,
    dirs: Vec<Vec<f64>>,
}

const STEPS: usize = 3;
const PIECES: usize = 4;

fn lti_case() -> impl Strategy<Value = LtiCase> {
    (1usize..=3, 1usize..=2, 1usize..=3, 0usize..=3).prop_flat_map(|(n, p, mu, mx)| {
        (
            vec(-1.0..1.0f64, n * n),
            vec(-1.0..1.0f64, n * p),
            vec(-1.0..1.0f64, p),
            vec(-0.5..0.5f64, p * mu),
            vec(-2.0..2.0f64, n),
            vec(-0.3..0.3f64, n * mx),
            0.02..0.3f64,
            vec(coef(), mx),
            vec(vec(coef(), mu), STEPS * PIECES),
            0..STEPS,
            0.0..=1.0f64,
            vec(vec(-1.0..1.0f64, n), 4),
        )
            .prop_map(
                move |(a, b, uc, ug, xc, xg, r, beta0, inputs, k, theta, dirs)| LtiCase {
                    a: DMatrix::from_row_slice(n, n, &a),
                    b: DMatrix::from_row_slice(n, p, &b),
                    u: Zonotope::new(
                        DVector::from_vec(uc),
                        DMatrix::from_column_slice(p, mu, &ug),
                    )
                    .unwrap(),
                    x0: Zonotope::new(
                        DVector::from_vec(xc),
                        DMatrix::from_column_slice(n, mx, &xg),
                    )
                    .unwrap(),
                    r,
                    beta0,
                    inputs,
                    k,
                    theta,
                    dirs,
                },
            )
    })
}

fn simulate(c: &LtiCase) -> DVector<f64> {
    let mut x = c.x0.center() + c.x0.generators() * DVector::from_column_slice(&c.beta0);
    let t_end = (c.k as f64 + c.theta) * c.r;
    let h = c.r / PIECES as f64;
    let mut t = 0.0;
    for (j, coeffs) in c.inputs.iter().enumerate() {
        if t >= t_end {
            break;
        }
        let dt = h.min(t_end - t);
        let u = c.u.center() + c.u.generators() * DVector::from_column_slice(coeffs);
        let (e, g) = exp_and_gamma(&c.a, dt);
        x = &e * x + &g * (&c.b * u);
        t = (j + 1) as f64 * h;
    }
    x
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(CASES))]

    #[test]
    fn lti_reach_contains_simulated_trajectories(c in lti_case()) {
        let sys = LtiSystem::new(c.a.clone(), c.b.clone()).unwrap();
        let reach = LtiReach::new(&sys, &c.u, c.r, ReachOptions { taylor_terms: 6, max_order: 8 }).unwrap();
        let sets = reach.reach(&c.x0, STEPS).unwrap();
        let x = simulate(&c);
        check_in(&sets[c.k], &x, &c.dirs)?;
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(CASES))]

    /// Point initial state and point (constant) input: the first-interval set must contain the
    /// curved trajectory, not only the chord — exercises the correction terms `F` and `F_u`.
    #[test]
    fn lti_first_interval_contains_curved_trajectory(
        (a, b, uc, x0, r, theta, dirs) in (1usize..=3).prop_flat_map(|n| (
            vec(-3.0..3.0f64, n * n), vec(-1.0..1.0f64, n), -2.0..2.0f64, vec(-5.0..5.0f64, n),
            0.05..0.3f64, 0.0..=1.0f64, vec(vec(-1.0..1.0f64, n), 4)))
    ) {
        let n = x0.len();
        let a = DMatrix::from_row_slice(n, n, &a);
        let b = DMatrix::from_column_slice(n, 1, &b);
        let sys = LtiSystem::new(a.clone(), b.clone()).unwrap();
        let u = Zonotope::point(DVector::from_vec(vec![uc])).unwrap();
        let x0 = DVector::from_vec(x0);
        let reach = LtiReach::new(&sys, &u, r, ReachOptions { taylor_terms: 10, max_order: 8 }).unwrap();
        let set = reach.first_interval(&Zonotope::point(x0.clone()).unwrap()).unwrap();
        let (e, g) = exp_and_gamma(&a, theta * r);
        let x = &e * &x0 + &g * (&b * uc);
        check_in(&set, &x, &dirs)?;
    }
}

#[test]
fn double_integrator_series_is_exact() {
    // x = (p, v): after r = 0.5 with zero input, (1, 2) ↦ (2, 2) exactly; no remainder term.
    let sys = LtiSystem::new(
        DMatrix::from_row_slice(2, 2, &[0.0, 1.0, 0.0, 0.0]),
        DMatrix::from_row_slice(2, 1, &[0.0, 1.0]),
    )
    .unwrap();
    let u = Zonotope::point(DVector::from_vec(vec![0.0])).unwrap();
    let x0 = Zonotope::point(DVector::from_vec(vec![1.0, 2.0])).unwrap();
    for terms in [1, 2, 5] {
        let reach = LtiReach::new(
            &sys,
            &u,
            0.5,
            ReachOptions {
                taylor_terms: terms,
                max_order: 4,
            },
        )
        .unwrap();
        let x1 = reach.point_set(&x0).unwrap();
        assert_eq!(x1.center().as_slice(), &[2.0, 2.0]);
        // No Taylor remainder: only the O(ε) bounds of floating-point rounding remain.
        assert!(
            x1.num_generators() == 0 && x1.error_box().iter().all(|&e| e < 1e-14),
            "error box {:?}",
            x1.error_box()
        );
        // the interval set is the exact segment from (1,2) to (2,2), up to O(ε) rounding bounds
        let xi = reach.first_interval(&x0).unwrap();
        let (lo, hi) = xi.interval_hull();
        assert!(
            (lo[0] - 1.0).abs() < 1e-13 && (hi[0] - 2.0).abs() < 1e-13,
            "{lo} {hi}"
        );
        assert!(
            (lo[1] - 2.0).abs() < 1e-13 && (hi[1] - 2.0).abs() < 1e-13,
            "{lo} {hi}"
        );
    }
    // With a constant input 1: p(r) = 1 + 2 r + r²/2 = 2.125 at r = 0.5, v = 2.5.
    let u = Zonotope::point(DVector::from_vec(vec![1.0])).unwrap();
    let reach = LtiReach::new(
        &sys,
        &u,
        0.5,
        ReachOptions {
            taylor_terms: 1,
            max_order: 4,
        },
    )
    .unwrap();
    let x1 = reach.point_set(&x0).unwrap();
    let (lo, hi) = x1.interval_hull();
    assert!(
        lo[0] <= 2.125 && 2.125 <= hi[0] && hi[0] - lo[0] < 1e-14,
        "{lo} {hi}"
    );
    assert!(
        lo[1] <= 2.5 && 2.5 <= hi[1] && hi[1] - lo[1] < 1e-14,
        "{lo} {hi}"
    );
}

#[test]
fn step_too_large_is_reported() {
    let sys = LtiSystem::new(
        DMatrix::from_row_slice(1, 1, &[-50.0]),
        DMatrix::from_row_slice(1, 1, &[1.0]),
    )
    .unwrap();
    let u = Zonotope::point(DVector::from_vec(vec![0.0])).unwrap();
    let r = LtiReach::new(
        &sys,
        &u,
        1.0,
        ReachOptions {
            taylor_terms: 4,
            max_order: 4,
        },
    );
    assert!(matches!(r, Err(ReachError::StepTooLarge { .. })));
}

#[test]
fn stable_system_reach_is_not_absurdly_wide() {
    // ẋ = −x + u, u ∈ [−1, 1], x0 = 1: R([0, 0.1]) ⊆ [e^{-0.1} − 0.1, 1 + 0.1] roughly.
    let sys = LtiSystem::new(
        DMatrix::from_row_slice(1, 1, &[-1.0]),
        DMatrix::from_row_slice(1, 1, &[1.0]),
    )
    .unwrap();
    let u = Zonotope::new(
        DVector::from_vec(vec![0.0]),
        DMatrix::from_row_slice(1, 1, &[1.0]),
    )
    .unwrap();
    let x0 = Zonotope::point(DVector::from_vec(vec![1.0])).unwrap();
    let reach = LtiReach::new(&sys, &u, 0.1, ReachOptions::default()).unwrap();
    let sets = reach.reach(&x0, 10).unwrap();
    let (lo, hi) = sets[0].interval_hull();
    assert!(lo[0] > 0.78 && hi[0] < 1.12, "{lo} {hi}");
    let (lo, hi) = sets[9].interval_hull();
    // exact: x(1) ∈ [e^-1 − (1 − e^-1), e^-1 + (1 − e^-1)] = [−0.264, 1]
    assert!(lo[0] > -0.45 && hi[0] < 1.15, "{lo} {hi}");
}
