//! Occupancy benchmarks: default human (all body parts, one interval, each model), FR3 joint box,
//! capsule–capsule test. Run: `cargo bench -p pacs-reach --bench occupancy`.

use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::Point3;
use pacs_models::{Capsule, default_human, fr3};
use pacs_reach::JointBox;
use pacs_reach::geometry::{capsule_distance_lower_bound, capsules_disjoint};
use pacs_reach::human::{HumanMeasurement, HumanReach, HumanReachModel};
use pacs_reach::robot::{ReachScratch, RobotReach};
use std::hint::black_box;

fn human(c: &mut Criterion) {
    let h = default_human().with_uncertainty(0.01, 0.1, 0.04).unwrap();
    let pos: Vec<[f64; 3]> = (0..9)
        .map(|k| {
            [
                0.8 + 0.01 * k as f64,
                0.1 * k as f64 - 0.4,
                1.0 + 0.05 * k as f64,
            ]
        })
        .collect();
    let vel: Vec<[f64; 3]> = (0..9).map(|k| [-0.3, 0.05 * k as f64, 0.1]).collect();
    let m = HumanMeasurement::new(&h, 0.0, &pos, Some(&vel)).unwrap();
    let mut out =
        vec![Capsule::new_unchecked(Point3::origin(), Point3::origin(), 0.0); h.body_parts().len()];
    for (name, kind) in [
        ("combined", HumanReachModel::Combined),
        ("vel", HumanReachModel::Vel),
        ("acc", HumanReachModel::Acc),
        ("pos", HumanReachModel::Pos),
    ] {
        let mut r = HumanReach::new(h.clone(), kind);
        c.bench_function(&format!("human_occupancy_default_{name}_1_interval"), |b| {
            b.iter(|| {
                r.occupancy_into(black_box(&m), black_box(0.01), black_box(0.02), &mut out)
                    .unwrap()
            })
        });
    }
}

fn robot(c: &mut Criterion) {
    let robot = fr3::fr3();
    let reach = RobotReach::new(&robot, 0.005);
    let q = fr3::Q_READY;
    let lo: Vec<f64> = q.iter().map(|x| x - 0.002).collect();
    let hi: Vec<f64> = q.iter().map(|x| x + 0.002).collect();
    let qb = JointBox::new(&lo, &hi).expect("valid box");
    let mut out = vec![
        Capsule::new_unchecked(Point3::origin(), Point3::origin(), 0.0);
        reach.capsule_count()
    ];
    // The hot-path form (the shield's): caller-provided scratch, frames recomputed every call.
    let mut scratch = ReachScratch::default();
    c.bench_function("fr3_occupancy_1_joint_box", |b| {
        b.iter(|| {
            reach
                .occupancy_with(&mut scratch, black_box(&qb), &mut out)
                .unwrap()
        })
    });
    // The convenience form (fresh scratch per call).
    c.bench_function("fr3_occupancy_1_joint_box_into", |b| {
        b.iter(|| reach.occupancy_into(black_box(&qb), &mut out).unwrap())
    });
}

fn capsule(c: &mut Criterion) {
    let a = Capsule::new(
        Point3::new(0.1, 0.2, 0.3),
        Point3::new(0.5, -0.1, 0.7),
        0.08,
    )
    .unwrap();
    let b = Capsule::new(Point3::new(0.9, 0.4, 1.1), Point3::new(0.7, 0.3, 0.6), 0.1).unwrap();
    c.bench_function("capsule_capsule_disjoint", |bch| {
        bch.iter(|| capsules_disjoint(black_box(&a), black_box(&b)))
    });
    c.bench_function("capsule_capsule_distance_lower_bound", |bch| {
        bch.iter(|| capsule_distance_lower_bound(black_box(&a), black_box(&b)))
    });
}

criterion_group!(benches, human, robot, capsule);
criterion_main!(benches);
