//! Criterion benches of the zonotope / LTI / object-occupancy hot paths.
//!
//! Run: `CARGO_TARGET_DIR=/work/target-zono cargo bench -p pacs-reach --bench zonotope`

use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::{DMatrix, DVector, Point3};
use pacs_models::object::{ObjectModel, ObjectSpec, ShapeSpec, default_ball};
use pacs_models::shape::Capsule;
use pacs_reach::lti::{LtiReach, LtiSystem, ReachOptions};
use pacs_reach::object::{ObjectMeasurement, occupancy};
use pacs_reach::zonotope::{BallApprox, Zonotope, ball_zonotope};
use std::hint::black_box;

fn lcg(seed: &mut u64) -> f64 {
    *seed = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    ((*seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
}

fn random_zonotope(n: usize, m: usize, seed: &mut u64) -> Zonotope {
    let c = DVector::from_fn(n, |_, _| lcg(seed));
    let g = DMatrix::from_fn(n, m, |_, _| 0.1 * lcg(seed));
    Zonotope::new(c, g).unwrap()
}

fn bench_object(c: &mut Criterion) {
    let meas = ObjectMeasurement {
        time: 10.0,
        position: [0.6, 0.1, 0.05],
        velocity: Some([0.2, -0.1, 0.0]),
    };
    let ball = ObjectModel::new(&default_ball()).unwrap();
    let boxed = ObjectModel::new(&ObjectSpec {
        name: "tote".into(),
        shape: ShapeSpec::Box {
            half_extents: [0.2, 0.15, 0.1],
        },
        max_acc: 2.0,
        acc_bias: [0.0, 0.0, -9.81],
        acc_generators: vec![[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        max_speed: Some(1.5),
        measurement_error_pos: 0.01,
        measurement_error_vel: 0.05,
        delay: 0.03,
    })
    .unwrap();
    for (name, model) in [("ball", &ball), ("box_biased_4gen", &boxed)] {
        c.bench_function(&format!("object_occupancy_one_interval/{name}"), |b| {
            b.iter(|| black_box(occupancy(model, black_box(&meas), 10.05, 10.06).unwrap()))
        });
    }
    let occ = occupancy(&ball, &meas, 10.05, 10.06).unwrap();
    let far = Capsule::new(Point3::new(0.3, 0.4, 0.1), Point3::new(0.3, 0.4, 0.5), 0.06).unwrap();
    let near = Capsule::new(
        Point3::new(0.62, 0.1, 0.05),
        Point3::new(0.62, 0.1, 0.5),
        0.06,
    )
    .unwrap();
    c.bench_function("zonotope_capsule/occupancy_disjoint", |b| {
        b.iter(|| black_box(occ.distance_lower_bound(black_box(&far))))
    });
    c.bench_function("zonotope_capsule/occupancy_overlap", |b| {
        b.iter(|| black_box(occ.distance_lower_bound(black_box(&near))))
    });
    let occ_box = occupancy(&boxed, &meas, 10.05, 10.06).unwrap();
    c.bench_function("zonotope_capsule/box_occupancy_disjoint", |b| {
        b.iter(|| black_box(occ_box.distance_lower_bound(black_box(&far))))
    });
    println!(
        "occupancy: {} generators; bound far = {:.6} m, near = {:.6} m",
        occ.zonotope().generators().len(),
        occ.distance_lower_bound(&far),
        occ.distance_lower_bound(&near)
    );
}

fn bench_zonotope_capsule(c: &mut Criterion) {
    let mut seed = 7u64;
    let z =
        pacs_reach::zonotope::Zonotope3::from_zonotope(&random_zonotope(3, 24, &mut seed)).unwrap();
    let cap = Capsule::new(Point3::new(2.0, 0.5, 0.0), Point3::new(2.0, 0.5, 1.0), 0.1).unwrap();
    c.bench_function("zonotope_capsule/z3_24gen_disjoint", |b| {
        b.iter(|| black_box(z.distance_lower_bound(0.05, black_box(&cap))))
    });
}

fn bench_reduction(c: &mut Criterion) {
    let mut seed = 11u64;
    let z6 = random_zonotope(6, 60, &mut seed);
    c.bench_function("reduce_girard/6d_60gen_to_order4", |b| {
        b.iter(|| black_box(z6.reduce_girard(4).unwrap()))
    });
    let z3 = random_zonotope(3, 100, &mut seed);
    c.bench_function("reduce_girard/3d_100gen_to_order8", |b| {
        b.iter(|| black_box(z3.reduce_girard(8).unwrap()))
    });
}

fn bench_lti(c: &mut Criterion) {
    let sys = LtiSystem::double_integrator_3d();
    let u = ball_zonotope([0.0; 3], 3.0, BallApprox::Seven).unwrap();
    let opts = ReachOptions {
        taylor_terms: 2,
        max_order: 6,
    };
    c.bench_function("lti/precompute_6d_double_integrator", |b| {
        b.iter(|| black_box(LtiReach::new(&sys, black_box(&u), 0.01, opts).unwrap()))
    });
    let reach = LtiReach::new(&sys, &u, 0.01, opts).unwrap();
    let mut seed = 3u64;
    let x = random_zonotope(6, 36, &mut seed);
    c.bench_function("lti/point_step_6d_36gen", |b| {
        b.iter(|| black_box(reach.point_set(black_box(&x)).unwrap()))
    });
    c.bench_function("lti/interval_step_6d_36gen", |b| {
        b.iter(|| black_box(reach.first_interval(black_box(&x)).unwrap()))
    });
    // A general (non-nilpotent) 4-D system with remainder terms.
    let a = DMatrix::from_row_slice(
        4,
        4,
        &[
            0.0, 1.0, 0.0, 0.0, -2.0, -0.5, 0.3, 0.0, 0.0, 0.0, 0.0, 1.0, 0.1, 0.0, -3.0, -0.2,
        ],
    );
    let b = DMatrix::from_row_slice(4, 1, &[0.0, 1.0, 0.0, 1.0]);
    let sys4 = LtiSystem::new(a, b).unwrap();
    let u1 = Zonotope::new(
        DVector::from_vec(vec![0.1]),
        DMatrix::from_row_slice(1, 1, &[1.0]),
    )
    .unwrap();
    let reach4 = LtiReach::new(
        &sys4,
        &u1,
        0.01,
        ReachOptions {
            taylor_terms: 8,
            max_order: 10,
        },
    )
    .unwrap();
    let x4 = random_zonotope(4, 20, &mut seed);
    c.bench_function("lti/point_step_4d_general_20gen", |b| {
        b.iter(|| black_box(reach4.point_set(black_box(&x4)).unwrap()))
    });
}

criterion_group!(
    benches,
    bench_object,
    bench_zonotope_capsule,
    bench_reduction,
    bench_lti
);
criterion_main!(benches);
