//! Audit throughput (robot samples per second, one core): the SSM+PFL span checker alone and the
//! JSON Lines reader plus checker, FR3 and the default human at 1 kHz, human at 30 Hz (100 Hz in
//! the log written as `pacs simulate` writes its logs).
//!
//! Run: `CARGO_TARGET_DIR=/work/target-audit cargo bench -p pacs-audit --bench audit`.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use pacs_audit::{AuditConfig, Auditor};
use pacs_log::{Header, LogModels, LogWriter, ModelRef};
use pacs_models::{ConstraintSpec, HumanModel, RobotModel};
use std::hint::black_box;

const N: usize = 10_000;
const Q: [f64; 7] = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785];

use pacs_testkit::standing_arms_forward as standing;

struct Sample {
    t: f64,
    q: [f64; 7],
    dq: [f64; 7],
}

fn samples() -> Vec<Sample> {
    (0..N)
        .map(|i| {
            let t = i as f64 * 1e-3;
            let (q, dq) = pacs_testkit::sinusoidal_joints(Q, 0.5, 0.1, t);
            Sample { t, q, dq }
        })
        .collect()
}

fn models(task: &str) -> LogModels {
    models_with(task, HumanModel::builtin("default").unwrap())
}

fn models_with(task: &str, human: HumanModel) -> LogModels {
    LogModels {
        robot: RobotModel::builtin("fr3").unwrap(),
        human: human.clone(),
        people: vec![("human".into(), human)],
        constraints: ConstraintSpec::builtin(task).unwrap(),
        environment: vec![],
        objects: vec![],
    }
}

fn run_core(s: &[Sample], x: f64, task: &str) -> pacs_audit::RunResult {
    let mut a = Auditor::new(models(task), AuditConfig::default()).unwrap();
    let kp = standing(x);
    for (i, s) in s.iter().enumerate() {
        if i % 33 == 0 {
            a.push_human(s.t, s.t, &kp).unwrap();
        }
        a.push_robot(s.t, &s.q, Some(&s.dq)).unwrap();
    }
    a.finish("bench", Default::default())
}

/// The default human with a 2 cm position error, measured at 100 Hz with a deterministic
/// jitter of up to ±1 cm per axis (within the error): records differ by more than the person
/// may move between them, so the records just before the one in use are not covered by it and
/// each violating span is judged against them too (the audit's "every measurement still
/// usable"; up to 100 records are younger than `max_human_age`, 64 are kept).
fn run_noisy(s: &[Sample], x: f64, task: &str) -> pacs_audit::RunResult {
    let mut spec = HumanModel::builtin("default").unwrap().spec().clone();
    spec.measurement_error_pos = 0.02;
    let human = HumanModel::new(spec).unwrap();
    let mut a = Auditor::new(models_with(task, human), AuditConfig::default()).unwrap();
    let mut kp = standing(x);
    let mut seed: u64 = 1;
    for (i, s) in s.iter().enumerate() {
        if i % 10 == 0 {
            let mut rec = kp.clone();
            for p in rec.iter_mut().flatten() {
                seed = seed
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                *p += ((seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 0.02;
            }
            a.push_human(s.t, s.t, &rec).unwrap();
            kp = standing(x);
        }
        a.push_robot(s.t, &s.q, Some(&s.dq)).unwrap();
    }
    a.finish("bench", Default::default())
}

/// The run as a JSON Lines log: robot records with velocities and the person at 30 Hz; or, with
/// `simulate_like`, as `pacs simulate` writes its logs (≈ 800 bytes per sample): robot records
/// with accelerations, a shield diagnostics record after each (the fields and nesting of the
/// shield's, full-precision numbers), the person at 100 Hz.
fn jsonl(s: &[Sample], x: f64, task: &str, simulate_like: bool) -> Vec<u8> {
    let mut w = LogWriter::new(Vec::new());
    w.write_header(&Header::new(
        ModelRef::Name("fr3".into()),
        ModelRef::Name("default".into()),
        ModelRef::Name(task.into()),
    ))
    .unwrap();
    let kp = standing(x);
    let human_every = if simulate_like { 10 } else { 33 };
    for (i, s) in s.iter().enumerate() {
        if i % human_every == 0 {
            w.write_human(s.t, s.t, &kp).unwrap();
        }
        if !simulate_like {
            w.write_robot(s.t, &s.q, Some(&s.dq)).unwrap();
            continue;
        }
        // The sinusoid's accelerations (`pacs_testkit::sinusoidal_joints`: 0.3·sin(w·t)).
        let ddq: [f64; 7] = std::array::from_fn(|j| {
            let wj = 0.5 + 0.1 * j as f64;
            -0.3 * wj * wj * (wj * s.t).sin()
        });
        w.write_robot_with_acc(s.t, &s.q, Some(&s.dq), Some(&ddq))
            .unwrap();
        let e = 0.011_903_421_988_951_31 * (1.0 + s.dq[0].abs());
        let fields = serde_json::json!({
            "binding": {"body_part": i % 9, "constrained": i % 2 == 0, "energy": e,
                        "kind": "pfl", "link": 6, "threshold": 0.01},
            "contact_energy": e,
            "contact_threshold": 0.01,
            "min_separation": 0.047_863_776_319_873_92 + s.q[0],
            "on_failsafe": i % 3 == 0,
            "path_speed": 0.950_999_999_999_999_3 - 1e-4 * (i % 100) as f64,
            "verified": i % 3 != 0,
        });
        w.write_shield(s.t, fields.as_object().unwrap()).unwrap();
    }
    w.finish().unwrap()
}

/// The same run as an MCAP file of a ROS 2 recording (`JointState` at 1 kHz, `PoseArray` at
/// 30 Hz, CDR, the writer's default chunking and compression).
fn mcap_log(s: &[Sample], x: f64, task: &str) -> Vec<u8> {
    use pacs_log::mcap::{McapConfig, McapLogWriter};
    let h = Header::new(
        ModelRef::Name("fr3".into()),
        ModelRef::Name("default".into()),
        ModelRef::Name(task.into()),
    );
    let names: Vec<String> = RobotModel::builtin("fr3")
        .unwrap()
        .joints()
        .iter()
        .map(|j| j.name.clone())
        .collect();
    let names: Vec<&str> = names.iter().map(String::as_str).collect();
    let mut w = McapLogWriter::new(
        std::io::Cursor::new(Vec::new()),
        mcap::WriteOptions::default(),
        &h,
        &McapConfig::default(),
        &names,
    )
    .unwrap();
    let kp = standing(x);
    let base: i128 = 1_700_000_000_000_000_000;
    for (i, s) in s.iter().enumerate() {
        let ns = base + (s.t * 1e9).round() as i128;
        if i % 33 == 0 {
            w.write_human(ns, ns, &kp).unwrap();
        }
        w.write_robot(ns, ns, &s.q, Some(&s.dq)).unwrap();
    }
    w.finish().unwrap().into_inner()
}

/// With `PACS_BENCH_DUMP=DIR`, write the benched log to `DIR/name` (to profile `pacs audit` on
/// exactly the bytes benched, e.g. under callgrind).
fn dump(name: &str, bytes: &[u8]) {
    if let Some(dir) = std::env::var_os("PACS_BENCH_DUMP") {
        let path = std::path::Path::new(&dir).join(name);
        std::fs::write(&path, bytes).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    }
}

fn bench(c: &mut Criterion) {
    let s = samples();
    let mut g = c.benchmark_group("audit");
    g.throughput(Throughput::Elements(N as u64));
    g.sample_size(20);
    // Human 0.6 m from the base: inside the arm's reach, contacts possible on some spans.
    for (name, x, task) in [
        ("check_near_handover", 0.6, "handover"),
        ("check_near_ssm", 0.6, "ssm"),
        ("check_far_ssm", 2.5, "ssm"),
    ] {
        let r = run_core(&s, x, task);
        eprintln!(
            "{name}: verdict {:?}, violation fraction {:.3}",
            r.verdict, r.metrics.violation_fraction
        );
        g.bench_function(name, |b| b.iter(|| black_box(run_core(&s, x, task))));
    }
    let r = run_noisy(&s, 0.6, "ssm");
    eprintln!(
        "check_near_ssm_noisy: verdict {:?}, violation fraction {:.3}",
        r.verdict, r.metrics.violation_fraction
    );
    g.bench_function("check_near_ssm_noisy", |b| {
        b.iter(|| black_box(run_noisy(&s, 0.6, "ssm")))
    });
    // JSON Lines as the bench's own writer writes it, and as `pacs simulate` writes its logs
    // (the 1 M/s target of docs/performance-audit.md is stated for those).
    for (name, file, simulate_like) in [
        (
            "jsonl_read_and_check_near_handover",
            "near_handover.jsonl",
            false,
        ),
        (
            "jsonl_read_and_check_simulate_like",
            "simulate_like.jsonl",
            true,
        ),
    ] {
        let bytes = jsonl(&s, 0.6, "handover", simulate_like);
        eprintln!("{name}: {} bytes for {N} robot samples", bytes.len());
        dump(file, &bytes);
        g.bench_function(name, |b| {
            b.iter(|| {
                let mut r =
                    pacs_log::jsonl::JsonlReader::new("bench", std::io::Cursor::new(&bytes[..]))
                        .unwrap();
                black_box(pacs_audit::audit_reader(&mut r, &AuditConfig::default()).unwrap())
            })
        });
        if simulate_like {
            // A reference, not pacs's work: serde_json checking the same lines' syntax only
            // (`IgnoredAny`: numbers' grammar checked, nothing converted, no record built, no
            // check). What one JSON pass costs on these bytes bounds what any JSON Lines audit
            // of them can reach on this machine (docs/performance-audit.md, "A floor").
            g.bench_function("jsonl_syntax_only_serde_simulate_like", |b| {
                b.iter(|| {
                    let mut lines = 0usize;
                    for line in bytes.split(|&c| c == b'\n').filter(|l| !l.is_empty()) {
                        let _: serde::de::IgnoredAny = serde_json::from_slice(line).unwrap();
                        lines += 1;
                    }
                    black_box(lines)
                })
            });
        }
    }
    // The MCAP reader with the person near (the checker's share as in `check_near_handover`)
    // and far (the checker's share as in `check_far_ssm`: mostly the reader's own cost, as in
    // the db3 figure of docs/performance-audit.md).
    let cfg = AuditConfig::default();
    for (name, file, x, task) in [
        (
            "mcap_read_and_check_near_handover",
            "near_handover.mcap",
            0.6,
            "handover",
        ),
        ("mcap_read_and_check_far_ssm", "far_ssm.mcap", 2.5, "ssm"),
    ] {
        let bytes = mcap_log(&s, x, task);
        eprintln!("{name}: {} bytes for {N} robot samples", bytes.len());
        dump(file, &bytes);
        g.bench_function(name, |b| {
            b.iter(|| {
                let mut r = pacs_log::mcap::McapReader::new(
                    "bench",
                    std::io::Cursor::new(&bytes[..]),
                    &cfg.mcap,
                    &cfg.overrides(),
                    None,
                )
                .unwrap();
                black_box(pacs_audit::audit_reader(&mut r, &cfg).unwrap())
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
