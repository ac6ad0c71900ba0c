//! The baselines and bench scenarios against the shield: the CBF tracks its reference and
//! leaves the path near a person; the shield's separation figure changes no decision on the
//! bench's walking-human scenario; the bench's planning-thread scenario offers and takes over.

use pacs_baselines::bench::{back_and_forth, shield_scenario_offloop, walking_human};
use pacs_baselines::cbf::{CbfConfig, CbfFilter};
use pacs_models::{ConstraintSpec, default_human, fr3};
use pacs_motion::chunk::{ActionKind, Chunk};
use pacs_reach::human::HumanMeasurement;
use pacs_shield::ChunkMotion;
use pacs_shield::shield::{FilterMode, Shield, ShieldConfig};

const Q0: [f64; 7] = fr3::Q_READY;

const DELTA: [f64; 7] = [0.01, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];

use pacs_testkit::true_separation;

fn chunk(delta: [f64; 7], h: usize) -> Chunk {
    Chunk {
        kind: ActionKind::Delta,
        actions: vec![delta.to_vec(); 16],
        execute: h,
        gripper: None,
    }
}

#[test]
fn cbf_baseline_tracks_reference_and_leaves_the_path_near_a_person() {
    let robot = fr3::fr3();
    let human = default_human().with_uncertainty(0.01, 0.1, 0.02).unwrap();
    let run_cbf = |script: &dyn Fn(f64) -> Vec<[f64; 3]>| {
        let mut f =
            CbfFilter::new(robot.clone(), Some(human.clone()), CbfConfig::default()).unwrap();
        f.start(0.0, &Q0).unwrap();
        let mut off_path = 0.0f64;
        let mut contacts = 0;
        for k in 0..1500 {
            let t = k as f64 * 0.001;
            if k % 400 == 0 {
                let _ = f.set_chunk(t, &chunk(DELTA, 8)); // a rejected chunk keeps the old reference
            }
            let m = HumanMeasurement::new(&human, t, &script(t - human.delay()), None).unwrap();
            let cmd = f.step(t, Some(&m)).expect("started");
            let q = cmd.q();
            if std::env::var("SHIELD_DEBUG").is_ok() && k % 100 == 0 {
                eprintln!(
                    "cbf t={t:.2} q1={:.4} q2={:.4} sep={:.3} bind={:?} ok={}",
                    q[0], q[1], cmd.diag.min_separation, cmd.diag.binding, cmd.diag.verified
                );
            }
            for i in 1..7 {
                off_path = off_path.max((q[i] - Q0[i]).abs());
            }
            if true_separation(&robot, &human, q, &script(cmd.t)) <= 0.0
                && cmd.dq().iter().any(|v| v.abs() > 1e-9)
            {
                contacts += 1;
            }
        }
        (f.q()[0] - Q0[0], off_path, contacts)
    };
    let far = |_t: f64| pacs_testkit::human_reaching(3.0, 0.0, [2.8, -0.2, 1.0]);
    let (progress, off_path, _) = run_cbf(&far);
    assert!(
        progress > 0.2,
        "CBF should track the reference without a human: {progress}"
    );
    assert!(off_path < 1e-3, "no reason to leave the path: {off_path}");
    // The hand waits on the robot's upcoming path (joint 1 turns the tool toward +y).
    let close = |_t: f64| pacs_testkit::human_reaching(0.9, 0.6, [0.28, 0.32, 0.5]);
    let (_, off_path, _) = run_cbf(&close);
    assert!(
        off_path > 1e-3,
        "the barrier should push the robot off its path ({off_path} rad)"
    );
}

/// The separation figure is a diagnostic: with `separation_figure` off the shield makes the same
/// decisions and commands bitwise (3000 steps of the bench's walking-human scenario, with and
/// without continuous chunks), and reports a figure that is never below the computed one (the
/// free workspace-ball figure, 0 on possible contact, +∞ where not computed). Also checks that
/// the figure is computed (finite) in a fair share of the steps, so the comparison is not vacuous.
#[test]
fn separation_figure_off_changes_no_decision() {
    for motion in [ChunkMotion::Stop, ChunkMotion::Continuous] {
        let human = default_human().with_uncertainty(0.01, 0.1, 0.02).unwrap();
        let spec = ConstraintSpec::builtin("sorting").unwrap();
        let shield = |figure: bool| {
            let mut cfg = ShieldConfig {
                separation_figure: figure,
                ..ShieldConfig::default()
            };
            motion.apply(&mut cfg);
            let mut sh =
                Shield::new(fr3::fr3(), Some((human.clone(), &spec)), vec![], cfg).unwrap();
            sh.start(0.0, &Q0).unwrap();
            sh
        };
        let (mut on, mut off) = (shield(true), shield(false));
        let (mut sign, mut finite, mut differ) = (1.0, 0, 0);
        for k in 0..3000 {
            let t = k as f64 * 0.001;
            if k % 200 == 0 {
                let c = back_and_forth(sign);
                sign = -sign;
                assert_eq!(on.set_chunk(&c).is_ok(), off.set_chunk(&c).is_ok());
            }
            let m = HumanMeasurement::new(&human, t, &walking_human(t), None).unwrap();
            let (a, b) = (
                on.step(t, Some(&m)).unwrap(),
                off.step(t, Some(&m)).unwrap(),
            );
            assert_eq!(a.diag.verified, b.diag.verified, "step {k}");
            assert_eq!(a.diag.on_failsafe, b.diag.on_failsafe, "step {k}");
            for i in 0..7 {
                assert_eq!(a.state.q[i].to_bits(), b.state.q[i].to_bits(), "step {k}");
                assert_eq!(a.state.dq[i].to_bits(), b.state.dq[i].to_bits(), "step {k}");
            }
            let (fa, fb) = (a.diag.min_separation, b.diag.min_separation);
            assert!(fb >= fa, "step {k}: figure off {fb} below figure on {fa}");
            finite += fa.is_finite() as usize;
            differ += (fa != fb) as usize;
        }
        assert!(
            finite > 1000 && differ > 100,
            "finite {finite}, differ {differ}"
        );
    }
}

/// The bench's planning-thread scenario exercises what it reports: every chunk is handed to the
/// worker, planned on its thread and nearly every one followed (counts only; the times are
/// measured by `pacs bench shield`).
#[test]
fn the_offloop_bench_scenario_offers_and_takes_over() {
    let s = shield_scenario_offloop("sorting", FilterMode::Pacs, 3, 2000);
    assert_eq!(s.steps, 2000);
    assert_eq!(s.offers, 10, "a chunk every 200 steps");
    // A chunk reversing the arm while it moves toward the walking person can fail its first
    // step and be dropped, as with `set_chunk` (3 of 10 here); the rest are followed.
    assert!(
        s.offers_taken >= 6,
        "{} of {} followed",
        s.offers_taken,
        s.offers
    );
    assert!(s.plan_max > 0.0 && s.chunk_max > 0.0);
}
