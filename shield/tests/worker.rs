//! `ChunkWorker`: chunks planned on a thread take over exactly as
//! `Shield::set_chunk` at their handover step would, a stale offer is planned again, a refused
//! chunk is reported, and nothing the thread does can put a command off the verified path.

mod common;

use common::{Lcg, random_chunk, same, shield};
use pacs_models::fr3;
use pacs_motion::chunk::Chunk;
use pacs_reach::human::HumanMeasurement;
use pacs_shield::ChunkMotion;
use pacs_shield::shield::{Command, Shield, ShieldError};
use pacs_shield::worker::{ChunkWorker, WorkerState};

fn measure(sh: &Shield, t: f64, keypoints: &[[f64; 3]]) -> HumanMeasurement {
    HumanMeasurement::new(sh.human_model().unwrap(), t, keypoints, None).unwrap()
}

/// The unpaced loop's share before a step: wait for a plan whose handover this step is,
/// otherwise poll.
fn before_step(w: &mut ChunkWorker, sh: &mut Shield, t: f64) {
    if w.due(t) {
        w.wait().unwrap();
    }
    w.poll(sh).unwrap();
}

/// Chunks handed to a worker while the arm moves (random leads, random gaps) give bitwise the
/// commands of a shield that gets the same chunk from `set_chunk` right before the handover step
/// (or at once, where the arm rests and the handover is the current state).
#[test]
fn worker_chunks_are_set_chunk_at_their_handover() {
    let far = pacs_testkit::human_reaching(3.0, 0.0, [2.8, -0.2, 1.0]);
    let mut rng = Lcg(3);
    let mut moving_cases = 0;
    for motion in [ChunkMotion::Continuous, ChunkMotion::Stop] {
        for lead in [1usize, 3, 8] {
            let mut sync = shield(motion);
            let mut sh = shield(motion);
            let mut w = ChunkWorker::spawn(&sh, lead).unwrap();
            let dt = sh.config().safety_step;
            // (step index at which `sync` gets the chunk, the chunk)
            let mut due: Option<(usize, Chunk)> = None;
            let mut next_chunk = 0usize;
            let mut accepted = 0u64;
            let mut handover = 0usize;
            for k in 0..1500 {
                let t = k as f64 * dt;
                if k == next_chunk {
                    let c = random_chunk(&mut rng);
                    let rest = sh.handover(0).unwrap().start == sh.handover(lead).unwrap().start;
                    w.set_chunk(&mut sh, c.clone()).unwrap();
                    if rest {
                        // Taken at once, wherever the plan comes back: wait for it here.
                        w.wait().unwrap();
                        w.poll(&mut sh).unwrap();
                        // Taken over; followed after the next step.
                        assert!(
                            matches!(w.state(), WorkerState::Installed(_)),
                            "{:?}",
                            w.state()
                        );
                        handover = k;
                        sync.set_chunk(&c).unwrap();
                    } else {
                        moving_cases += 1;
                        due = Some((k + lead, c));
                        handover = k + lead;
                    }
                    accepted += 1;
                    next_chunk = k + 40 + rng.below(160);
                }
                if let Some((at, c)) = &due
                    && *at == k
                {
                    sync.set_chunk(c).unwrap();
                    due = None;
                }
                before_step(&mut w, &mut sh, t);
                if k > handover {
                    // The poll after the handover step sees the chunk taken over.
                    assert!(
                        matches!(w.state(), WorkerState::Taken(_)),
                        "step {k}: the handover passed and the chunk is {:?}",
                        w.state()
                    );
                }
                let m = measure(&sh, t, &far);
                let a = sync.step(t, Some(&m)).unwrap();
                let b = sh.step(t, Some(&m)).unwrap();
                assert!(b.diag.verified, "far human: every step verifies");
                assert!(
                    same(&a, &b),
                    "{motion:?}, lead {lead}, step {k}: {:?} vs {:?}",
                    a.q().to_vec(),
                    b.q().to_vec()
                );
            }
            assert_eq!(w.replans(), 0, "no step failed, so no offer went stale");
            assert_eq!(sh.chunk_progress().unwrap().accepted, accepted);
        }
    }
    assert!(
        moving_cases >= 20,
        "{moving_cases} chunks handed in while moving"
    );
}

/// A person stepping in front of the arm between a chunk and its handover makes the predicted
/// handover wrong (the steps are no longer verified): the offer goes stale and the worker plans
/// the chunk again, now predicting along the failsafe, which holds while the person stays. At
/// that handover the chunk is tried and not verified, so the shield drops it as `set_chunk`
/// would; the arm resumes its path once the person left, and the next chunk is followed. Every
/// command is the shield's (no jump).
#[test]
fn a_stale_offer_is_planned_again_from_the_failsafe() {
    let near = pacs_testkit::human_reaching(0.6, 0.0, [0.45, 0.0, 0.5]);
    let far = pacs_testkit::human_reaching(3.0, 0.0, [2.8, -0.2, 1.0]);
    let mut rng = Lcg(5);
    let mut sh = shield(ChunkMotion::Continuous);
    let mut w = ChunkWorker::spawn(&sh, 3).unwrap();
    let dt = sh.config().safety_step;
    let lim = fr3::fr3().limits().clone();
    let mut prev: Option<Command> = None;
    let mut unverified = 0;
    for k in 0..1500 {
        let t = k as f64 * dt;
        if k == 0 || k == 198 || k == 900 {
            w.set_chunk(&mut sh, random_chunk(&mut rng)).unwrap();
            if k == 0 {
                w.wait().unwrap();
                w.poll(&mut sh).unwrap();
            }
        }
        before_step(&mut w, &mut sh, t);
        if k == 250 {
            assert_eq!(
                *w.state(),
                WorkerState::Dropped(2),
                "tried while the person stays"
            );
            assert_eq!(w.replans(), 1, "one stale offer");
        }
        if k == 899 {
            assert_eq!(
                sh.chunk_progress().unwrap().chunk,
                1,
                "the arm kept its path"
            );
        }
        // The person steps in at 0.2 s, between the second chunk (0.198 s, lead 3) and its
        // handover, and leaves at 0.6 s.
        let kp = if (200..600).contains(&k) { &near } else { &far };
        let m = measure(&sh, t, kp);
        let cmd = sh.step(t, Some(&m)).unwrap();
        unverified += !cmd.diag.verified as usize;
        if let Some(p) = &prev {
            for i in 0..7 {
                let dq = (cmd.state.q[i] - p.state.q[i]).abs();
                assert!(dq <= lim.v_max()[i] * dt * (1.0 + 1e-9), "jump at step {k}");
            }
        }
        prev = Some(cmd);
    }
    assert!(unverified > 0, "the person must stop the arm");
    assert_eq!(
        *w.state(),
        WorkerState::Taken(3),
        "the third chunk is followed"
    );
    let progress = sh.chunk_progress().unwrap();
    assert_eq!(progress.chunk, 3);
    assert!(progress.passed > 0, "the third chunk runs: {progress:?}");
}

/// A chunk the planner refuses (a NaN action) is reported by the poll that receives it and
/// never offered; the arm keeps its motion. A lead of 0 is refused.
#[test]
fn a_refused_chunk_is_reported_and_lead_zero_is_invalid() {
    let mut sh = shield(ChunkMotion::Continuous);
    assert!(matches!(
        ChunkWorker::spawn(&sh, 0),
        Err(ShieldError::ZeroLead)
    ));
    let mut w = ChunkWorker::spawn(&sh, 2).unwrap();
    let mut bad = random_chunk(&mut Lcg(9));
    bad.actions[4][2] = f64::NAN;
    w.set_chunk(&mut sh, bad).unwrap();
    w.wait().unwrap();
    let err = w.poll(&mut sh).unwrap_err();
    assert!(matches!(err, ShieldError::Chunk(_)), "{err:?}");
    assert_eq!(*w.state(), WorkerState::Refused);
    assert_eq!(sh.chunk_progress().unwrap().accepted, 0);
    // The next chunk is planned as usual.
    w.set_chunk(&mut sh, random_chunk(&mut Lcg(10))).unwrap();
    let far = pacs_testkit::human_reaching(3.0, 0.0, [2.8, -0.2, 1.0]);
    {
        w.wait().unwrap();
        w.poll(&mut sh).unwrap();
    }
    assert_eq!(
        *w.state(),
        WorkerState::Installed(1),
        "at rest: taken at once"
    );
    let m = measure(&sh, 0.0, &far);
    sh.step(0.0, Some(&m)).unwrap();
    w.poll(&mut sh).unwrap();
    assert_eq!(*w.state(), WorkerState::Taken(1));
}

/// Steps that keep alternating between verified and not (here: the person's measurement
/// alternates between near and far) defeat both predictions, so every offer goes stale. The
/// worker then plans again after growing pauses (1, 3, 7, … steps, at most 63), not every few
/// steps: over 1 s, a handful of plans instead of one every `lead + 1` steps.
#[test]
fn stale_offers_in_a_row_are_planned_again_after_growing_pauses() {
    let near = pacs_testkit::human_reaching(0.6, 0.0, [0.45, 0.0, 0.5]);
    let far = pacs_testkit::human_reaching(3.0, 0.0, [2.8, -0.2, 1.0]);
    let mut rng = Lcg(21);
    let mut sh = shield(ChunkMotion::Continuous);
    let mut w = ChunkWorker::spawn(&sh, 3).unwrap();
    let dt = sh.config().safety_step;
    let mut flips = 0;
    let mut last = true;
    for k in 0..1200 {
        let t = k as f64 * dt;
        if k == 0 || k == 100 {
            w.set_chunk(&mut sh, random_chunk(&mut rng)).unwrap();
            if k == 0 {
                w.wait().unwrap();
                w.poll(&mut sh).unwrap();
            }
        }
        before_step(&mut w, &mut sh, t);
        let kp = if k >= 80 && k % 2 == 0 { &near } else { &far };
        let cmd = sh.step(t, Some(&measure(&sh, t, kp))).unwrap();
        flips += (cmd.diag.verified != last) as usize;
        last = cmd.diag.verified;
    }
    assert!(flips > 200, "the steps must alternate ({flips} changes)");
    let n = w.replans();
    // Pauses 0, 1, 3, 7, 15, 31, 63, 63, …: about 19 plans in 1.1 s; without pauses ~270.
    assert!((5..=25).contains(&n), "{n} plans again");
}

/// Chunks handed in faster than the thread takes them fill its queue (4 jobs); the newest waits
/// in the worker and `wait` still returns with its plan (it sends the waiting job again instead
/// of blocking on a plan that was never asked for), and that newest chunk is the one taken over.
#[test]
fn a_burst_of_chunks_is_planned_newest_first_and_wait_returns() {
    let mut sh = shield(ChunkMotion::Continuous);
    let mut w = ChunkWorker::spawn(&sh, 2).unwrap();
    let mut rng = Lcg(31);
    for _ in 0..12 {
        w.set_chunk(&mut sh, random_chunk(&mut rng)).unwrap();
    }
    w.wait().unwrap();
    w.poll(&mut sh).unwrap();
    // At rest: the 12th chunk's plan is taken over at once; no older one was offered.
    assert_eq!(*w.state(), WorkerState::Installed(1));
    assert_eq!(sh.chunk_progress().unwrap().accepted, 1);
}

/// Hand the worker the random chunk of `seed`, wait for its plan and offer it.
fn hand_in(w: &mut ChunkWorker, sh: &mut Shield, seed: u64) {
    w.set_chunk(sh, random_chunk(&mut Lcg(seed))).unwrap();
    w.wait().unwrap();
    w.poll(sh).unwrap();
}

/// A shield restarted under a worker (`Shield::start` forgets offers): a chunk taken over and
/// not yet tried is reported dropped, one still offered leaves the worker idle, and the next
/// chunk is handled as usual.
#[test]
fn a_restart_forgets_the_workers_offer() {
    let far = pacs_testkit::human_reaching(3.0, 0.0, [2.8, -0.2, 1.0]);
    let mut sh = shield(ChunkMotion::Continuous);
    let mut w = ChunkWorker::spawn(&sh, 5).unwrap();
    // At rest: taken over at once, not yet tried.
    hand_in(&mut w, &mut sh, 1);
    assert_eq!(*w.state(), WorkerState::Installed(1));
    sh.start(0.0, &common::Q0).unwrap();
    w.poll(&mut sh).unwrap();
    assert_eq!(*w.state(), WorkerState::Dropped(1));
    // Moving: offered for a handover 5 steps ahead, then the restart.
    hand_in(&mut w, &mut sh, 2);
    let dt = sh.config().safety_step;
    for k in 0..50 {
        let t = k as f64 * dt;
        let m = measure(&sh, t, &far);
        sh.step(t, Some(&m)).unwrap();
        w.poll(&mut sh).unwrap();
    }
    assert!(
        matches!(w.state(), WorkerState::Taken(_)),
        "{:?}",
        w.state()
    );
    hand_in(&mut w, &mut sh, 3);
    assert_eq!(
        *w.state(),
        WorkerState::Offered,
        "moving: waits for its handover"
    );
    sh.start(0.05, &common::Q0).unwrap();
    w.poll(&mut sh).unwrap();
    assert_eq!(*w.state(), WorkerState::Idle);
    // The next chunk is taken over and followed.
    hand_in(&mut w, &mut sh, 4);
    let t = 0.05;
    let m = measure(&sh, t, &far);
    sh.step(t, Some(&m)).unwrap();
    w.poll(&mut sh).unwrap();
    assert!(
        matches!(w.state(), WorkerState::Taken(_)),
        "{:?}",
        w.state()
    );
}
