//! A capsule around a vertex set.
//!
//! **Guarantee** ([`fit_capsule`]): every input vertex lies within `radius` of the segment
//! `p1`–`p2`, checked after the fit for each vertex with the exact segment-distance formula in
//! f64, and the radius is then raised to that largest distance plus a margin of 1e-9 m + 1e-12
//! relative (far above the formula's rounding error, a few ulps of the coordinates, for meshes
//! within 10³ m of their origin). A capsule is convex, so it also contains the vertices' convex
//! hull — which contains every face of the mesh. The search for a small capsule is a heuristic;
//! the containment is not.
//!
//! Search: candidate axes (principal axes of the vertex covariance, the coordinate axes, the
//! direction of an approximate diameter); for each axis the smallest enclosing circle of the
//! vertices projected onto the plane normal to it (Welzl's algorithm) gives the axis line and the
//! smallest radius; then the radius is traded against the segment length (larger radius, shorter
//! segment) for the least capsule volume. Tightness = convex hull volume / capsule volume (1 would
//! be a mesh that is itself a capsule).

use crate::error::MeshError;
use nalgebra::{Matrix3, Point2, Point3, SymmetricEigen, Vector2, Vector3};
use std::path::PathBuf;

/// A capsule that contains every vertex it was fitted to.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FittedCapsule {
    /// Segment endpoints (m).
    pub p1: Point3<f64>,
    pub p2: Point3<f64>,
    /// Radius (m), rounded outward over the largest vertex distance.
    pub radius: f64,
    /// Vertices fitted.
    pub vertices: usize,
    /// Largest vertex distance from the segment (m), before the margin.
    pub max_distance: f64,
    /// Volume of the capsule (m³).
    pub capsule_volume: f64,
    /// Volume of the vertices' convex hull (m³; 0 for flat or degenerate vertex sets).
    pub hull_volume: f64,
}

impl FittedCapsule {
    /// Convex hull volume / capsule volume, in [0, 1].
    pub fn tightness(&self) -> f64 {
        if self.capsule_volume > 0.0 {
            (self.hull_volume / self.capsule_volume).clamp(0.0, 1.0)
        } else {
            0.0
        }
    }
}

/// Distance from `p` to the segment `a`–`b`.
pub fn segment_distance(p: &Point3<f64>, a: &Point3<f64>, b: &Point3<f64>) -> f64 {
    let ab = b - a;
    let l2 = ab.norm_squared();
    let t = if l2 > 0.0 {
        ((p - a).dot(&ab) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + ab * t)).norm()
}

fn capsule_volume(r: f64, len: f64) -> f64 {
    std::f64::consts::PI * r * r * len + 4.0 / 3.0 * std::f64::consts::PI * r * r * r
}

/// Smallest circle containing 2-D points (Welzl, iterative move-to-front form, deterministic
/// shuffle). Returns centre and radius.
fn min_circle(pts: &mut [Point2<f64>]) -> (Point2<f64>, f64) {
    // Deterministic shuffle: a fixed LCG keeps fits reproducible.
    let mut s: u64 = 0x9E37_79B9_7F4A_7C15;
    for i in (1..pts.len()).rev() {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let j = (s >> 33) as usize % (i + 1);
        pts.swap(i, j);
    }
    let inside =
        |c: &Point2<f64>, r: f64, p: &Point2<f64>| (p - c).norm() <= r * (1.0 + 1e-12) + 1e-15;
    let mut c = pts[0];
    let mut r = 0.0;
    for i in 1..pts.len() {
        if inside(&c, r, &pts[i]) {
            continue;
        }
        c = pts[i];
        r = 0.0;
        for j in 0..i {
            if inside(&c, r, &pts[j]) {
                continue;
            }
            c = Point2::from((pts[i].coords + pts[j].coords) / 2.0);
            r = (pts[i] - c).norm();
            for k in 0..j {
                if inside(&c, r, &pts[k]) {
                    continue;
                }
                (c, r) = circle3(&pts[i], &pts[j], &pts[k]);
            }
        }
    }
    (c, r)
}

/// Circumcircle of three points (the widest pair's circle if they are collinear).
fn circle3(a: &Point2<f64>, b: &Point2<f64>, c: &Point2<f64>) -> (Point2<f64>, f64) {
    let (bx, by) = (b.x - a.x, b.y - a.y);
    let (cx, cy) = (c.x - a.x, c.y - a.y);
    let d = 2.0 * (bx * cy - by * cx);
    if d.abs() < 1e-300 {
        let pairs = [(a, b), (a, c), (b, c)];
        let (p, q) = pairs
            .into_iter()
            .max_by(|x, y| (x.0 - x.1).norm().total_cmp(&(y.0 - y.1).norm()))
            .expect("three pairs");
        let m = Point2::from((p.coords + q.coords) / 2.0);
        return (m, (p - m).norm());
    }
    let b2 = bx * bx + by * by;
    let c2 = cx * cx + cy * cy;
    let ux = (cy * b2 - by * c2) / d;
    let uy = (bx * c2 - cx * b2) / d;
    let center = Point2::new(a.x + ux, a.y + uy);
    (center, Vector2::new(ux, uy).norm())
}

/// The least-volume capsule with axis direction `d` (unit); returns (p1, p2, radius, volume).
fn fit_axis(pts: &[Point3<f64>], d: &Vector3<f64>) -> (Point3<f64>, Point3<f64>, f64, f64) {
    // An orthonormal frame (u, w) of the plane normal to d.
    let helper = if d.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let u = d.cross(&helper).normalize();
    let w = d.cross(&u);
    let mut proj: Vec<Point2<f64>> = pts
        .iter()
        .map(|p| Point2::new(p.coords.dot(&u), p.coords.dot(&w)))
        .collect();
    let (c2, rho_max) = min_circle(&mut proj);
    let axial: Vec<(f64, f64)> = pts
        .iter()
        .map(|p| {
            let s = p.coords.dot(d);
            let q = Point2::new(p.coords.dot(&u), p.coords.dot(&w));
            (s, (q - c2).norm())
        })
        .collect();
    // For radius r: segment [a, b] with a = min(s + h), b = max(s − h), h = sqrt(r² − ρ²).
    let seg = |r: f64| {
        let (mut a, mut b) = (f64::INFINITY, f64::NEG_INFINITY);
        for &(s, rho) in &axial {
            let h = (r * r - rho * rho).max(0.0).sqrt();
            a = a.min(s + h);
            b = b.max(s - h);
        }
        if a > b {
            let m = 0.5 * (a + b);
            (m, m)
        } else {
            (a, b)
        }
    };
    let (s_lo, s_hi) = axial
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &(s, _)| {
            (l.min(s), h.max(s))
        });
    let span = (s_hi - s_lo).max(0.0);
    let mut best = (f64::INFINITY, rho_max, 0.0, 0.0);
    // Radii from the smallest possible up to half the axial span beyond it (a sphere-like fit).
    let steps = 48;
    for k in 0..=steps {
        let r = rho_max + (0.5 * span + rho_max) * (k as f64 / steps as f64).powi(2);
        let (a, b) = seg(r);
        let v = capsule_volume(r, b - a);
        if v < best.0 {
            best = (v, r, a, b);
        }
    }
    let (v, r, a, b) = best;
    let base = c2.x * u + c2.y * w;
    (Point3::from(base + d * a), Point3::from(base + d * b), r, v)
}

/// Volume of the convex hull of `pts` (0 if it is flat or the hull cannot be built).
fn hull_volume(pts: &[Point3<f64>]) -> f64 {
    use parry3d_f64::math::Vector3 as PVec;
    let owned: Vec<PVec> = pts.iter().map(|p| PVec::new(p.x, p.y, p.z)).collect();
    let hull = std::panic::catch_unwind(|| parry3d_f64::transformation::try_convex_hull(&owned));
    let Ok(Ok((v, idx))) = hull else { return 0.0 };
    let v: Vec<Vector3<f64>> = v.iter().map(|p| Vector3::new(p.x, p.y, p.z)).collect();
    let Some(o) = v.first().copied() else {
        return 0.0;
    };
    let mut vol = 0.0;
    for t in &idx {
        let (a, b, c) = (
            v[t[0] as usize] - o,
            v[t[1] as usize] - o,
            v[t[2] as usize] - o,
        );
        vol += a.dot(&b.cross(&c)) / 6.0;
    }
    vol.abs()
}

/// Fit a capsule containing every point of `pts` (m). `what` names the mesh in errors.
///
/// The least-volume capsule among those along the coordinate axes, the principal axes, an
/// approximate diameter and the ball about the centroid (length 0); its radius is then never
/// larger than that ball's (property test `every_vertex_is_inside_the_fitted_capsule`). Every
/// point is checked against the final segment and the radius covers the farthest.
pub fn fit_capsule(pts: &[Point3<f64>], what: &str) -> Result<FittedCapsule, MeshError> {
    if pts.is_empty() {
        return Err(MeshError::Empty {
            path: PathBuf::from(what),
        });
    }
    if let Some(p) = pts.iter().find(|p| !p.iter().all(|x| x.is_finite())) {
        return Err(MeshError::Parse {
            path: PathBuf::from(what),
            what: format!("a vertex is not finite: {:?}", p.coords.as_slice()),
        });
    }
    let n = pts.len() as f64;
    let mean = pts.iter().fold(Vector3::zeros(), |s, p| s + p.coords) / n;
    // Work relative to the centroid (smaller coordinates, smaller rounding).
    let local: Vec<Point3<f64>> = pts.iter().map(|p| Point3::from(p.coords - mean)).collect();
    let cov = local
        .iter()
        .fold(Matrix3::zeros(), |m, p| m + p.coords * p.coords.transpose())
        / n;
    let mut axes: Vec<Vector3<f64>> = vec![Vector3::x(), Vector3::y(), Vector3::z()];
    let eig = SymmetricEigen::new(cov);
    for i in 0..3 {
        let v = eig.eigenvectors.column(i).into_owned();
        if v.iter().all(|x| x.is_finite()) && v.norm() > 0.5 {
            axes.push(v.normalize());
        }
    }
    // An approximate diameter: the point farthest from the centroid, then the one farthest from it.
    let far = |from: &Point3<f64>| {
        *local
            .iter()
            .max_by(|a, b| (*a - from).norm().total_cmp(&(*b - from).norm()))
            .expect("non-empty")
    };
    let a = far(&Point3::origin());
    let b = far(&a);
    if (b - a).norm() > 0.0 {
        axes.push((b - a).normalize());
    }
    // The ball about the centroid is a candidate too (a capsule of length 0): the least volume
    // then never exceeds its volume, so the radius never exceeds the ball's.
    let ball = local.iter().map(|p| p.coords.norm()).fold(0.0f64, f64::max);
    let mut best: Option<(Point3<f64>, Point3<f64>, f64, f64)> = Some((
        Point3::origin(),
        Point3::origin(),
        ball,
        capsule_volume(ball, 0.0),
    ));
    for d in &axes {
        let fit = fit_axis(&local, d);
        if best.is_none_or(|b| fit.3 < b.3) {
            best = Some(fit);
        }
    }
    let (q1, q2, r, _) = best.expect("at least the centroid ball");
    let (p1, p2) = (
        Point3::from(q1.coords + mean),
        Point3::from(q2.coords + mean),
    );
    // The check that makes the guarantee: every vertex, against the final segment.
    let max_distance = pts
        .iter()
        .map(|p| segment_distance(p, &p1, &p2))
        .fold(0.0f64, f64::max);
    let radius = r.max(max_distance) * (1.0 + 1e-12) + 1e-9;
    Ok(FittedCapsule {
        p1,
        p2,
        radius,
        vertices: pts.len(),
        max_distance,
        capsule_volume: capsule_volume(radius, (p2 - p1).norm()),
        hull_volume: hull_volume(pts),
    })
}
