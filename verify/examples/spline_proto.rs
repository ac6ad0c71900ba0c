//! Prototype: cubic-spline (one constant-jerk piece per segment, extra knots in first/last segment)
//! time optimisation on the anchor set.
use pacs_models::RobotModel;
use pacs_verify::problems::{anchor_set, lower_bound};
use pacs_verify::{Limits, OutOfLimits};

struct Spline {
    tau: Vec<f64>,
    y: Vec<Vec<f64>>, // [joint][knot]
    m: Vec<Vec<f64>>,
}

fn solve_dense(a: &mut Vec<Vec<f64>>, b: &mut Vec<Vec<f64>>) {
    let n = a.len();
    for c in 0..n {
        let mut piv = c;
        for r in c + 1..n {
            if a[r][c].abs() > a[piv][c].abs() {
                piv = r;
            }
        }
        a.swap(c, piv);
        b.swap(c, piv);
        for r in c + 1..n {
            let f = a[r][c] / a[c][c];
            if f != 0.0 {
                for k in c..n {
                    a[r][k] -= f * a[c][k];
                }
                let (bc, br) = (b[c].clone(), &mut b[r]);
                for (x, y) in br.iter_mut().zip(&bc) {
                    *x -= f * y;
                }
            }
        }
    }
    for c in (0..n).rev() {
        for r in 0..c {
            let f = a[r][c] / a[c][c];
            let bc = b[c].clone();
            for (x, y) in b[r].iter_mut().zip(&bc) {
                *x -= f * y;
            }
        }
        let d = a[c][c];
        for x in b[c].iter_mut() {
            *x /= d;
        }
    }
}

/// knots: per knot Some(waypoint index) or None (free position). seg durations T, split first/last.
fn spline(wp: &[Vec<f64>], t: &[f64], n: usize, split: &[usize]) -> Spline {
    let h = t.len();
    let mut tau = Vec::new();
    let mut known: Vec<Option<usize>> = vec![Some(0)];
    for k in 0..h {
        let s = split[k];
        for _ in 0..s {
            tau.push(t[k] / s as f64);
        }
        for _ in 0..s - 1 {
            known.push(None);
        }
        known.push(Some(k + 1));
    }
    let p = tau.len();
    // unknowns: M_1..M_{P-1}, then free y's
    let mut yidx = vec![usize::MAX; p + 1];
    let mut nu = p - 1;
    for (kn, kk) in known.iter().enumerate() {
        if kk.is_none() {
            yidx[kn] = nu;
            nu += 1;
        }
    }
    assert_eq!(nu, p + 1, "need exactly 2 extra knots");
    let m = nu;
    let mut a = vec![vec![0.0; m]; m];
    let mut b = vec![vec![0.0; n]; m];
    // add c*Y(knot)
    let add_y =
        |a: &mut Vec<Vec<f64>>, b: &mut Vec<Vec<f64>>, r: usize, kn: usize, c: f64| match known[kn]
        {
            Some(w) => {
                for i in 0..n {
                    b[r][i] -= c * wp[w][i];
                }
            }
            None => a[r][yidx[kn]] += c,
        };
    let add_m = |a: &mut Vec<Vec<f64>>, _b: &mut Vec<Vec<f64>>, r: usize, kn: usize, c: f64| {
        if kn >= 1 && kn < p {
            a[r][kn - 1] += c;
        } // M0 = MP = 0 (rest)
    };
    // start velocity 0: (y1-y0)/τ0 - τ0(2M0+M1)/6 = 0
    let t0 = tau[0];
    add_y(&mut a, &mut b, 0, 1, 1.0 / t0);
    add_y(&mut a, &mut b, 0, 0, -1.0 / t0);
    add_m(&mut a, &mut b, 0, 0, -t0 / 3.0);
    add_m(&mut a, &mut b, 0, 1, -t0 / 6.0);
    for q in 1..p {
        let (tl, tr) = (tau[q - 1], tau[q]);
        // v^- - v^+ = 0
        add_y(&mut a, &mut b, q, q, 1.0 / tl + 1.0 / tr);
        add_y(&mut a, &mut b, q, q - 1, -1.0 / tl);
        add_y(&mut a, &mut b, q, q + 1, -1.0 / tr);
        add_m(&mut a, &mut b, q, q - 1, tl / 6.0);
        add_m(&mut a, &mut b, q, q, tl / 3.0 + tr / 3.0);
        add_m(&mut a, &mut b, q, q + 1, tr / 6.0);
    }
    let tl = tau[p - 1];
    add_y(&mut a, &mut b, p, p, 1.0 / tl);
    add_y(&mut a, &mut b, p, p - 1, -1.0 / tl);
    add_m(&mut a, &mut b, p, p - 1, tl / 6.0);
    add_m(&mut a, &mut b, p, p, tl / 3.0);
    solve_dense(&mut a, &mut b);
    let mut ys = vec![vec![0.0; p + 1]; n];
    let mut ms = vec![vec![0.0; p + 1]; n];
    for i in 0..n {
        for kn in 0..=p {
            ys[i][kn] = match known[kn] {
                Some(w) => wp[w][i],
                None => b[yidx[kn]][i],
            };
            ms[i][kn] = if kn >= 1 && kn < p { b[kn - 1][i] } else { 0.0 };
        }
    }
    Spline { tau, y: ys, m: ms }
}

/// per piece ratio (scale exponent-normalised)
fn ratios(s: &Spline, l: &Limits) -> Vec<f64> {
    let p = s.tau.len();
    let n = s.y.len();
    let mut r = vec![0.0f64; p];
    for i in 0..n {
        for q in 0..p {
            let t = s.tau[q];
            let (m0, m1) = (s.m[i][q], s.m[i][q + 1]);
            let j = (m1 - m0) / t;
            let v0 = (s.y[i][q + 1] - s.y[i][q]) / t - t * (2.0 * m0 + m1) / 6.0;
            let mut vmax = v0.abs();
            let v1 = v0 + t * (m0 + m1) / 2.0;
            vmax = vmax.max(v1.abs());
            if m0 * m1 < 0.0 {
                let d = -m0 / j;
                vmax = vmax.max((v0 + m0 * d + 0.5 * j * d * d).abs());
            }
            let rr = (j.abs() / l.j[i])
                .cbrt()
                .max((m0.abs().max(m1.abs()) / l.a[i]).sqrt())
                .max(vmax / l.v[i]);
            r[q] = r[q].max(rr);
        }
    }
    r
}

fn eval(wp: &[Vec<f64>], t: &[f64], n: usize, l: &Limits, split: &[usize]) -> (f64, Vec<f64>) {
    let s = spline(wp, t, n, split);
    let r = ratios(&s, l);
    // map pieces to segments
    let mut rk = vec![0.0f64; t.len()];
    let mut q = 0;
    for k in 0..t.len() {
        for _ in 0..split[k] {
            rk[k] = rk[k].max(r[q]);
            q += 1;
        }
    }
    let lam = rk.iter().cloned().fold(0.0, f64::max);
    (lam * t.iter().sum::<f64>(), rk)
}

fn main() {
    let robot = RobotModel::builtin("fr3").unwrap();
    let hw = Limits::from_joint_limits(robot.limits());
    let l = hw.with_uniform_acc_jerk(10.0, 400.0);
    let probs = anchor_set(robot.limits(), 200, 7);
    let mode: usize = std::env::args()
        .nth(1)
        .map(|s| s.parse().unwrap())
        .unwrap_or(0);
    let iters: usize = std::env::args()
        .nth(2)
        .map(|s| s.parse().unwrap())
        .unwrap_or(30);
    let beta: f64 = std::env::args()
        .nth(3)
        .map(|s| s.parse().unwrap())
        .unwrap_or(0.5);
    let mut ls = 0.0;
    let mut ls0 = 0.0;
    for p in &probs {
        let wp = p
            .chunk
            .waypoints(&p.q0, robot.limits(), OutOfLimits::Reject)
            .unwrap();
        let h = wp.segments();
        let rows: Vec<Vec<f64>> = (0..=h).map(|k| wp.row(k).to_vec()).collect();
        let lb = lower_bound(&wp, &l.v[..7]);
        let mut split = vec![1; h];
        split[0] += 1;
        split[h - 1] += 1;
        let mut t: Vec<f64> = (1..=h)
            .map(|k| {
                (0..7)
                    .map(|i| {
                        pacs_verify::intended::rest_to_rest_time(
                            (rows[k][i] - rows[k - 1][i]).abs(),
                            l.v[i],
                            l.a[i],
                            l.j[i],
                        )
                    })
                    .fold(0.0, f64::max)
            })
            .collect();
        let init: usize = std::env::args()
            .nth(4)
            .map(|s| s.parse().unwrap())
            .unwrap_or(0);
        for k in 0..h {
            let lbk = (0..7)
                .map(|i| (rows[k + 1][i] - rows[k][i]).abs() / l.v[i])
                .fold(0.0, f64::max);
            match init {
                1 => t[k] = lbk.max(1e-4),
                2 => t[k] = (t[k] * lbk).sqrt().max(1e-4),
                3 => t[k] = t[k].powf(0.75) * lbk.powf(0.25),
                _ => {}
            }
        }
        let (mut best, mut rk) = eval(&rows, &t, 7, &l, &split);
        let first = best;
        // heuristic equalisation
        for _ in 0..iters {
            for k in 0..h {
                t[k] *= rk[k].powf(beta);
            }
            let (tot, r2) = eval(&rows, &t, 7, &l, &split);
            rk = r2;
            if tot < best {
                best = tot;
            }
        }
        let heur = best;
        if mode == 1 {
            // coordinate descent ceiling
            let lam = rk.iter().cloned().fold(0.0, f64::max);
            for x in t.iter_mut() {
                *x *= lam;
            }
            let mut tb = t.clone();
            let mut bestv = eval(&rows, &tb, 7, &l, &split).0;
            let mut step = 0.2;
            for _ in 0..60 {
                let mut improved = false;
                for k in 0..h {
                    for sgn in [-1.0, 1.0] {
                        let mut tt = tb.clone();
                        tt[k] *= 1.0 + sgn * step;
                        let v = eval(&rows, &tt, 7, &l, &split).0;
                        if v < bestv {
                            bestv = v;
                            let lam = v / tt.iter().sum::<f64>();
                            tb = tt.iter().map(|x| x * lam).collect();
                            improved = true;
                        }
                    }
                }
                if !improved {
                    step *= 0.5;
                    if step < 1e-4 {
                        break;
                    }
                }
            }
            best = best.min(bestv);
        }
        ls += (best / lb).ln();
        ls0 += (first / lb).ln();
        let _ = heur;
    }
    println!(
        "spline: first {:.2} final {:.2}",
        (ls0 / probs.len() as f64).exp(),
        (ls / probs.len() as f64).exp()
    );
}
