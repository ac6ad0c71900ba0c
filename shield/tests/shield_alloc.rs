//! The shield step performs no heap allocation (counting global allocator).

use pacs_models::object::{ObjectContact, ObjectModel, default_ball};
use pacs_models::{ConstraintSpec, default_human, fr3};
use pacs_motion::chunk::{ActionKind, Chunk};
use pacs_reach::human::HumanMeasurement;
use pacs_reach::object::ObjectMeasurement;
use pacs_shield::shield::{Shield, ShieldConfig};
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicUsize, Ordering};

struct Counting;
static COUNT: AtomicUsize = AtomicUsize::new(0);
thread_local! {
    /// Armed on the stepping thread only: libtest's own threads may allocate meanwhile (a global
    /// flag made the test flaky).
    static ARMED: Cell<bool> = const { Cell::new(false) };
}

fn armed() -> bool {
    ARMED.try_with(Cell::get).unwrap_or(false)
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        if armed() {
            COUNT.fetch_add(1, Ordering::SeqCst);
        }
        unsafe { System.alloc(l) }
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        unsafe { System.dealloc(p, l) }
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, n: usize) -> *mut u8 {
        if armed() {
            COUNT.fetch_add(1, Ordering::SeqCst);
        }
        unsafe { System.realloc(p, l, n) }
    }
}

#[global_allocator]
static A: Counting = Counting;

#[test]
fn step_allocates_nothing() {
    for (spec, objects) in [("sorting", false), ("handover", false), ("sorting", true)] {
        let human = default_human().with_uncertainty(0.01, 0.1, 0.02).unwrap();
        let cs = ConstraintSpec::builtin(spec).unwrap();
        let mut sh = Shield::new(
            fr3::fr3(),
            Some((human.clone(), &cs)),
            vec![],
            ShieldConfig::default(),
        )
        .unwrap();
        if objects {
            let ball = ObjectModel::new(&default_ball()).unwrap();
            sh.add_object(ball, ObjectContact::NoContact).unwrap();
            sh.add_object(ball, ObjectContact::Ssm).unwrap();
        }
        sh.start(0.0, &fr3::Q_READY).unwrap();
        let chunk = Chunk {
            kind: ActionKind::Delta,
            actions: vec![vec![0.02; 7]; 16],
            execute: 8,
            gripper: None,
        };
        // Human walking toward the robot and back: steps verify, brake, resume.
        let meas: Vec<HumanMeasurement> = (0..2000)
            .map(|k| {
                let t = k as f64 * 0.001;
                let d = 0.55 + 0.45 * (3.0 * t).cos();
                let kp: Vec<[f64; 3]> = (0..9)
                    .map(|i| {
                        [
                            d + 0.02 * i as f64,
                            0.1 * i as f64 - 0.4,
                            0.8 + 0.1 * i as f64,
                        ]
                    })
                    .collect();
                HumanMeasurement::new(&human, t, &kp, None).unwrap()
            })
            .collect();
        let mut verified = 0;
        let mut failsafe = 0;
        let mut planner = sh.chunk_planner();
        for (k, m) in meas.iter().enumerate() {
            if k % 300 == 0 {
                sh.set_chunk(&chunk).ok(); // planning may allocate: not part of the step
            }
            if k % 300 == 150 {
                // A chunk planned off the loop, taken over (or dropped) by a step below.
                if let Some(ho) = sh.handover(5)
                    && let Ok(p) = planner.prepare(&ho, &chunk)
                {
                    sh.offer(p).ok();
                }
            }
            ARMED.with(|a| a.set(true));
            if objects {
                let t = k as f64 * 0.001;
                // One ball rolling through the arm's reach, one resting beside it.
                let rolling = ObjectMeasurement {
                    time: t,
                    position: [0.5, 0.6 - 0.4 * t, 0.3],
                    velocity: Some([0.0, -0.4, 0.0]),
                };
                let resting = ObjectMeasurement {
                    time: t,
                    position: [0.3, 0.6, 0.04],
                    velocity: None,
                };
                sh.measure_object(0, &rolling).unwrap();
                sh.measure_object(1, &resting).unwrap();
            }
            let cmd = sh.step(k as f64 * 0.001, Some(m)).expect("started");
            ARMED.with(|a| a.set(false));
            verified += cmd.diag.verified as usize;
            failsafe += cmd.diag.on_failsafe as usize;
        }
        assert_eq!(
            COUNT.load(Ordering::SeqCst),
            0,
            "{spec} (objects: {objects}): the step allocated"
        );
        // The scenario exercised both branches.
        assert!(
            verified > 0 && failsafe > 0,
            "{spec} (objects: {objects}): verified {verified}, failsafe {failsafe}"
        );
    }
}

/// Measurements delivered by the inbox (late, several per step, a person and an object):
/// delivery allocates nothing once the measurements are queued (the log writer is not part of
/// it: its object records format the id).
#[test]
fn inbox_delivery_allocates_nothing() {
    use pacs_shield::session::MeasurementInbox;
    use pacs_shield::shield_log::ShieldLog;
    let human = default_human().with_uncertainty(0.01, 0.1, 0.02).unwrap();
    let cs = ConstraintSpec::builtin("sorting").unwrap();
    let mut sh = Shield::new(
        fr3::fr3(),
        Some((human.clone(), &cs)),
        vec![],
        ShieldConfig::default(),
    )
    .unwrap();
    let ball = ObjectModel::new(&default_ball()).unwrap();
    sh.add_object(ball, ObjectContact::NoContact).unwrap();
    sh.start(0.0, &fr3::Q_READY).unwrap();
    let mut inbox: MeasurementInbox = MeasurementInbox::new(1, vec!["ball".into()]);
    let kp: Vec<[f64; 3]> = (0..9).map(|i| [2.0, 0.1 * i as f64, 1.0]).collect();
    for k in 0..1000 {
        let t = k as f64 * 0.001;
        let m = HumanMeasurement::new(&human, t, &kp, None).unwrap();
        // Arrives 0, 0.4 or 0.8 ms late: some steps get none, some two.
        inbox
            .push_person(t + (k % 3) as f64 * 0.0004, 0, m)
            .unwrap();
        if k % 10 == 0 {
            let o = ObjectMeasurement {
                time: t,
                position: [0.3, 0.6, 0.04],
                velocity: None,
            };
            inbox.push_object(t + 0.0025, 0, o).unwrap();
        }
    }
    let mut delivered = 0;
    for k in 0..1000 {
        let t = k as f64 * 0.001;
        ARMED.with(|a| a.set(true));
        let due = inbox
            .deliver(t, &mut sh, None::<&mut ShieldLog<std::io::Sink>>)
            .unwrap();
        let first = due.first;
        delivered += first.is_some() as usize;
        let cmd = sh.step(t, first).expect("started");
        ARMED.with(|a| a.set(false));
        assert!(cmd.t > t);
    }
    assert_eq!(COUNT.load(Ordering::SeqCst), 0, "delivery allocated");
    assert!(delivered > 600, "{delivered}");
}

/// A session's step (measurements through its inbox, the grid check, the shield's step) with no
/// log allocates nothing once the measurements are queued: what a real-time loop runs.
#[test]
fn session_step_allocates_nothing() {
    use pacs_shield::session::Session;
    let human = default_human().with_uncertainty(0.01, 0.1, 0.02).unwrap();
    let cs = ConstraintSpec::builtin("sorting").unwrap();
    let ball = ObjectModel::new(&default_ball()).unwrap();
    let sh = Shield::builder(fr3::fr3())
        .person(human.clone(), &cs)
        .person(human.clone(), &cs)
        .object(ball, ObjectContact::NoContact)
        .build()
        .unwrap();
    let mut s: Session<std::io::Sink> = Session::new(sh, vec!["ball".into()]);
    s.start(0.0, &fr3::Q_READY).unwrap();
    let chunk = Chunk {
        kind: ActionKind::Delta,
        actions: vec![vec![0.02; 7]; 16],
        execute: 8,
        gripper: None,
    };
    s.set_chunk(&chunk).unwrap();
    for k in 0..1000 {
        let t = k as f64 * 0.001;
        for (p, x) in [(0, 2.0), (1, 0.6 + 0.4 * (3.0 * t).cos())] {
            let kp: Vec<[f64; 3]> = (0..9).map(|i| [x, 0.1 * i as f64 - 0.4, 1.0]).collect();
            let m = HumanMeasurement::new(&human, t, &kp, None).unwrap();
            // Arriving 0 or 0.5 ms late.
            s.measure_person_at(t + (k % 2) as f64 * 0.0005, p, m)
                .unwrap();
        }
        if k % 10 == 0 {
            let o = ObjectMeasurement {
                time: t,
                position: [0.3, 0.6, 0.04],
                velocity: None,
            };
            s.measure_object(0, o).unwrap();
        }
    }
    let (mut verified, mut failsafe) = (0, 0);
    for k in 0..1000 {
        let t = k as f64 * 0.001;
        ARMED.with(|a| a.set(true));
        let cmd = s.step(t).expect("on the grid");
        ARMED.with(|a| a.set(false));
        verified += cmd.diag.verified as usize;
        failsafe += cmd.diag.on_failsafe as usize;
    }
    assert_eq!(
        COUNT.load(Ordering::SeqCst),
        0,
        "the session's step allocated"
    );
    assert!(
        verified > 0 && failsafe > 0,
        "verified {verified}, failsafe {failsafe}"
    );
}
