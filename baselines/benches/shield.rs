//! Criterion bench of one shield step (FR3 + default human walking nearby, SSM and PFL), and of
//! one CBF step. Run: `cargo bench -p pacs-shield --bench shield`.

use criterion::{Criterion, criterion_group, criterion_main};
use pacs_baselines::bench::{back_and_forth, walking_human};
use pacs_baselines::cbf::{CbfConfig, CbfFilter};
use pacs_models::{ConstraintSpec, default_human, fr3};
use pacs_motion::chunk::Chunk;
use pacs_reach::human::HumanMeasurement;
use pacs_shield::shield::{Shield, ShieldConfig};

/// The measurement of the walking human at step `k` (built outside the timed routine).
fn measurement(human: &pacs_models::HumanModel, k: usize) -> HumanMeasurement {
    let t = k as f64 * 0.001;
    HumanMeasurement::new(human, t, &walking_human(t), None).unwrap()
}

fn chunk(sign: f64) -> Chunk {
    back_and_forth(sign)
}

fn shield(c: &mut Criterion) {
    let human = default_human().with_uncertainty(0.01, 0.1, 0.02).unwrap();
    for spec in ["sorting", "handover"] {
        let cs = ConstraintSpec::builtin(spec).unwrap();
        let mut sh = Shield::new(
            fr3::fr3(),
            Some((human.clone(), &cs)),
            vec![],
            ShieldConfig::default(),
        )
        .unwrap();
        sh.start(0.0, &fr3::Q_READY).unwrap();
        let sh = std::cell::RefCell::new(sh);
        let k = std::cell::Cell::new(0usize);
        let mut sign = 1.0;
        c.bench_function(&format!("shield_step_{spec}"), |b| {
            b.iter_batched(
                || {
                    let kk = k.get();
                    if kk.is_multiple_of(200) {
                        let _ = sh.borrow_mut().set_chunk(&chunk(sign)); // planning is not part of the step
                        sign = -sign;
                    }
                    measurement(&human, kk)
                },
                |m| {
                    let kk = k.get();
                    k.set(kk + 1);
                    sh.borrow_mut()
                        .step(kk as f64 * 0.001, Some(&m))
                        .expect("started")
                },
                criterion::BatchSize::SmallInput,
            )
        });
    }
    let mut f = CbfFilter::new(fr3::fr3(), Some(human.clone()), CbfConfig::default()).unwrap();
    f.start(0.0, &fr3::Q_READY).unwrap();
    let k = std::cell::Cell::new(0usize);
    c.bench_function("cbf_step", |b| {
        b.iter_batched(
            || measurement(&human, k.get()),
            |m| {
                let kk = k.get();
                let t = kk as f64 * 0.001;
                if kk.is_multiple_of(200) {
                    let _ = f.set_chunk(t, &chunk(1.0));
                }
                k.set(kk + 1);
                f.step(t, Some(&m)).expect("started")
            },
            criterion::BatchSize::SmallInput,
        )
    });
}

criterion_group!(benches, shield);
criterion_main!(benches);
