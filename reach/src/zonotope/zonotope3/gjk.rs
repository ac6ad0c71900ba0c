//! GJK on the Minkowski difference of a [`Zonotope3`] and a capsule axis: it proposes the
//! separating direction that [`Zonotope3::distance_bound_along`] then evaluates rigorously (the
//! direction itself need not be trusted).

use super::Zonotope3;
use pacs_models::shape::Capsule;

impl<const N: usize> Zonotope3<N> {
    /// A point of `Z` (approximately) maximising `d·z`, ignoring the error box (for GJK).
    #[inline]
    fn support_point(&self, d: [f64; 3]) -> [f64; 3] {
        let mut p = self.c;
        for gk in self.generators() {
            let s = d[0] * gk[0] + d[1] * gk[1] + d[2] * gk[2];
            let sg = if s >= 0.0 { 1.0 } else { -1.0 };
            p[0] += sg * gk[0];
            p[1] += sg * gk[1];
            p[2] += sg * gk[2];
        }
        p
    }

    /// GJK on the Minkowski difference `Z − S` (S the capsule axis segment): approximate closest
    /// point `v` to the origin; `None` if the sets (approximately) overlap.
    pub(super) fn gjk_direction(&self, capsule: &Capsule) -> Option<[f64; 3]> {
        let a = capsule.p1();
        let b = capsule.p2();
        let (a, b) = ([a.x, a.y, a.z], [b.x, b.y, b.z]);
        let sup = |d: [f64; 3]| -> [f64; 3] {
            let pz = self.support_point(d);
            // segment support in direction -d
            let ps = if dot3(d, a) <= dot3(d, b) { a } else { b };
            sub3(pz, ps)
        };
        let mid = [
            0.5 * (a[0] + b[0]),
            0.5 * (a[1] + b[1]),
            0.5 * (a[2] + b[2]),
        ];
        let mut v = sub3(self.c, mid);
        if dot3(v, v) == 0.0 {
            v = [1.0, 0.0, 0.0];
        }
        let mut simplex = Simplex {
            p: [[0.0; 3]; 4],
            len: 0,
        };
        let w0 = sup(neg3(v));
        simplex.p[0] = w0;
        simplex.len = 1;
        v = w0;
        let scale = dot3(self.abs_sum, [1.0; 3])
            + crate::ieee::sqrt(dot3(sub3(a, b), sub3(a, b)))
            + crate::ieee::sqrt(dot3(v, v));
        for _ in 0..64 {
            let vv = dot3(v, v);
            if vv <= (1e-14 * scale) * (1e-14 * scale) {
                return None;
            }
            let w = sup(neg3(v));
            // Convergence: v·v − v·w ≤ tol · v·v.
            if vv - dot3(v, w) <= 1e-10 * vv {
                break;
            }
            if simplex.p[..simplex.len].contains(&w) {
                break;
            }
            simplex.p[simplex.len] = w;
            simplex.len += 1;
            match simplex.closest() {
                Some(nv) => v = nv,
                None => return None,
            }
        }
        Some(v)
    }
}

#[inline]
fn dot3(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
#[inline]
fn sub3(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
#[inline]
fn neg3(a: [f64; 3]) -> [f64; 3] {
    [-a[0], -a[1], -a[2]]
}
#[inline]
fn cross3(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
#[inline]
fn add_scaled(a: [f64; 3], s: f64, d: [f64; 3]) -> [f64; 3] {
    [a[0] + s * d[0], a[1] + s * d[1], a[2] + s * d[2]]
}

/// GJK simplex (≤ 4 points of the Minkowski difference).
struct Simplex {
    p: [[f64; 3]; 4],
    len: usize,
}

impl Simplex {
    /// Replace the simplex by the smallest sub-simplex containing its point closest to the origin
    /// and return that point; `None` if the origin is inside the tetrahedron.
    fn closest(&mut self) -> Option<[f64; 3]> {
        match self.len {
            1 => Some(self.p[0]),
            2 => {
                let (v, keep) = closest_segment(self.p[0], self.p[1]);
                self.keep(&keep);
                Some(v)
            }
            3 => {
                let (v, keep) = closest_triangle(self.p[0], self.p[1], self.p[2]);
                self.keep(&keep);
                Some(v)
            }
            _ => {
                let [a, b, c, d] = self.p;
                let faces = [
                    ([0, 1, 2], 3),
                    ([0, 2, 3], 1),
                    ([0, 3, 1], 2),
                    ([1, 3, 2], 0),
                ];
                let mut best: Option<([f64; 3], [usize; 3], usize)> = None;
                let pts = [a, b, c, d];
                for (f, opp) in faces {
                    let (x, y, z) = (pts[f[0]], pts[f[1]], pts[f[2]]);
                    let nrm = cross3(sub3(y, x), sub3(z, x));
                    let sp = -dot3(x, nrm);
                    let sd = dot3(sub3(pts[opp], x), nrm);
                    if sp * sd < 0.0 || sd == 0.0 {
                        let (v, keep) = closest_triangle(x, y, z);
                        let map = [f[keep[0]], f[keep[1]], f[keep[2]]];
                        let nk = keep[3];
                        if best
                            .as_ref()
                            .is_none_or(|bst| dot3(v, v) < dot3(bst.0, bst.0))
                        {
                            best = Some((v, map, nk));
                        }
                    }
                }
                let (v, map, nk) = best?;
                let old = self.p;
                for k in 0..nk {
                    self.p[k] = old[map[k]];
                }
                self.len = nk;
                Some(v)
            }
        }
    }

    fn keep(&mut self, keep: &[usize; 4]) {
        let old = self.p;
        for k in 0..keep[3] {
            self.p[k] = old[keep[k]];
        }
        self.len = keep[3];
    }
}

/// Closest point of segment `ab` to the origin; `keep[..keep[3]]` are the used vertex indices.
fn closest_segment(a: [f64; 3], b: [f64; 3]) -> ([f64; 3], [usize; 4]) {
    let ab = sub3(b, a);
    let t = -dot3(a, ab);
    if t <= 0.0 {
        return (a, [0, 0, 0, 1]);
    }
    let den = dot3(ab, ab);
    if t >= den {
        return (b, [1, 0, 0, 1]);
    }
    (add_scaled(a, t / den, ab), [0, 1, 0, 2])
}

/// Closest point of triangle `abc` to the origin (Ericson, RTCD §5.1.5); used vertex indices in
/// `keep[..keep[3]]`.
fn closest_triangle(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> ([f64; 3], [usize; 4]) {
    let ab = sub3(b, a);
    let ac = sub3(c, a);
    let ap = neg3(a);
    let d1 = dot3(ab, ap);
    let d2 = dot3(ac, ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return (a, [0, 0, 0, 1]);
    }
    let bp = neg3(b);
    let d3 = dot3(ab, bp);
    let d4 = dot3(ac, bp);
    if d3 >= 0.0 && d4 <= d3 {
        return (b, [1, 0, 0, 1]);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (add_scaled(a, v, ab), [0, 1, 0, 2]);
    }
    let cp = neg3(c);
    let d5 = dot3(ab, cp);
    let d6 = dot3(ac, cp);
    if d6 >= 0.0 && d5 <= d6 {
        return (c, [2, 0, 0, 1]);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (add_scaled(a, w, ac), [0, 2, 0, 2]);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (add_scaled(b, w, sub3(c, b)), [1, 2, 0, 2]);
    }
    let den = va + vb + vc;
    if den == 0.0 || !den.is_finite() {
        // Degenerate triangle: fall back to the best edge.
        let cands = [
            closest_segment(a, b),
            closest_segment(a, c),
            closest_segment(b, c),
        ];
        let maps = [[0, 1], [0, 2], [1, 2]];
        let mut bi = 0;
        for i in 1..3 {
            if dot3(cands[i].0, cands[i].0) < dot3(cands[bi].0, cands[bi].0) {
                bi = i;
            }
        }
        let (v, k) = cands[bi];
        let mut keep = [0, 0, 0, k[3]];
        for j in 0..k[3] {
            keep[j] = maps[bi][k[j]];
        }
        return (v, keep);
    }
    let v = vb / den;
    let w = vc / den;
    (
        [
            a[0] + ab[0] * v + ac[0] * w,
            a[1] + ab[1] * v + ac[1] * w,
            a[2] + ab[2] * v + ac[2] * w,
        ],
        [0, 1, 2, 3],
    )
}
