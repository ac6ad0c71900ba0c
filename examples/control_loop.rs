//! The shield in a 1 kHz control loop, through the Rust API: a policy hands over an action chunk
//! every 264 ms (H = 16 joint deltas, h = 8 executed, Δt = 33 ms), a camera measures a person
//! every 10 ms, and every 1 ms the shield returns the command for the robot's low-level
//! controller — the intended motion when it verified it, the braking failsafe along the same
//! path otherwise.
//!
//! Chunks are planned **off the loop**, as a real-time loop must (planning takes 0.1–2 ms, the
//! step a few µs): the loop asks the shield where its commands will be `LEAD` steps ahead
//! (`Shield::handover`), a planning thread plans the chunk from there (`ChunkPlanner::prepare`),
//! and the loop hands the plan back (`Shield::offer`); the step at the handover takes it over
//! only if the commands really got there (else the loop plans again). The loop's share of a
//! chunk is the prediction and the offer. `Shield::set_chunk` plans in the caller's thread
//! instead, which is simpler where the loop has the time.
//!
//! Run: `cargo run --release --example control_loop` (2 s of wall-clock time, paced at 1 kHz;
//! `-- --fast` runs unpaced). Prints how many steps were verified, when the arm stopped for the
//! person, the step times and the loop's share of each chunk (µs).

use pacs::models::{ConstraintSpec, RobotModel, default_human, fr3};
use pacs::motion::chunk::{ActionKind, Chunk};
use pacs::reach::human::HumanMeasurement;
use pacs::shield::shield::{Binding, Handover, OfferState, Shield, ShieldConfig};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// Safety steps between asking for a handover and the step that takes the chunk over: 5 ms
/// for planning (median ≈ 0.5 ms on a 2-core machine, rarely over 2 ms).
const LEAD: usize = 5;

/// The default human's 9 keypoints (m) standing on the floor 0.75 m below the table top, torso
/// at (x, 0), right hand reaching to `hand`.
fn person(x: f64, hand: [f64; 3]) -> Vec<[f64; 3]> {
    let z0 = -0.75;
    let s = [x, -0.2, z0 + 1.4];
    let elbow = [
        0.5 * (s[0] + hand[0]),
        0.5 * (s[1] + hand[1]),
        0.5 * (s[2] + hand[2]) - 0.05,
    ];
    vec![
        [x, 0.2, z0 + 1.4],
        [x, 0.25, z0 + 1.15],
        [x, 0.25, z0 + 0.9],
        s,
        elbow,
        hand,
        [x, 0.0, z0 + 1.5],
        [x, 0.0, z0 + 1.0],
        [x, 0.0, z0 + 1.65],
    ]
}

/// The scripted person: walks up to the table (x 2.0 → 1.0 m over 0.5–1.3 s) and reaches toward
/// the arm's path with the right hand until 1.6 s.
fn true_person(t: f64) -> Vec<[f64; 3]> {
    let ease = |a: f64, b: f64| {
        let u = ((t - a) / (b - a)).clamp(0.0, 1.0);
        u * u * (3.0 - 2.0 * u)
    };
    let x = 2.0 - 1.0 * ease(0.5, 1.3);
    let reach = ease(1.0, 1.3) * (1.0 - ease(1.6, 1.9));
    let rest = [x - 0.05, -0.25, 0.2];
    let target = [0.55, 0.15, 0.3];
    let hand = [0, 1, 2].map(|i| rest[i] + reach * (target[i] - rest[i]));
    person(x, hand)
}

/// The policy stand-in: 16 deltas sweeping joint 1 (+0.012 rad per action) and joint 4.
fn policy_chunk() -> Chunk {
    Chunk {
        kind: ActionKind::Delta,
        actions: vec![vec![0.012, 0.0, 0.0, 0.006, 0.0, -0.004, 0.0]; 16],
        execute: 8,
        gripper: None,
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let fast = std::env::args().any(|a| a == "--fast");
    let robot = RobotModel::builtin("fr3")?;
    let human = default_human().with_uncertainty(0.01, 0.1, 0.03)?;
    let constraints = ConstraintSpec::builtin("sorting")?; // SSM for every body part
    let mut shield = Shield::new(
        robot,
        Some((human.clone(), &constraints)),
        vec![],
        ShieldConfig::default(),
    )?;
    shield.start(0.0, &fr3::Q_READY)?;
    let dt = shield.config().safety_step; // 1 ms
    let steps = 2000;
    let (mut verified, mut stopped_at, mut resumed_at) = (0usize, None, None);
    let mut step_us = Vec::with_capacity(steps);
    let mut last_q = fr3::Q_READY.to_vec();
    // The planning thread: chunks with their handover in, prepared plans out.
    let (to_planner, planner_in) = mpsc::channel::<(Handover, Chunk)>();
    let (planner_out, from_planner) = mpsc::channel();
    let mut planner = shield.chunk_planner();
    let planning = std::thread::spawn(move || {
        for (handover, chunk) in planner_in {
            let t0 = Instant::now();
            let plan = planner.prepare(&handover, &chunk);
            if planner_out.send((plan, t0.elapsed())).is_err() {
                break;
            }
        }
    });
    let (mut loop_share_us, mut plan_us) = (Vec::new(), Vec::new());
    let (mut offered, mut replanned) = (0usize, 0usize);
    // The chunk wanted until a step takes it over, and the plans asked for and not yet back.
    let (mut wanted, mut in_flight): (Option<Chunk>, usize) = (None, 0);
    let start = Instant::now();
    for k in 0..steps {
        let t = k as f64 * dt;
        // A new chunk every h·Δt = 264 ms, planned off the loop from the state LEAD steps ahead.
        if k % 264 == 0 {
            let clock = Instant::now();
            if let Some(h) = shield.handover(LEAD) {
                to_planner.send((h, policy_chunk()))?;
                in_flight += 1;
                wanted = Some(policy_chunk());
            }
            loop_share_us.push(clock.elapsed().as_secs_f64() * 1e6);
        }
        // A plan came back: offer it. A chunk that cannot be planned is refused (the robot keeps
        // following its current trajectory); one whose handover has passed is planned again
        // below.
        // (Unpaced, `--fast`, the loop waits for the plan: its clock is not the wall clock.)
        let back = if fast && in_flight > 0 {
            from_planner.recv().ok()
        } else {
            from_planner.try_recv().ok()
        };
        if let Some((plan, took)) = back {
            in_flight -= 1;
            plan_us.push(took.as_secs_f64() * 1e6);
            let clock = Instant::now();
            match plan {
                Ok(p) => match shield.offer(p) {
                    Ok(()) => offered += 1,
                    Err(e) => eprintln!("t = {t:.3} s: {e}"),
                },
                Err(e) => {
                    eprintln!("t = {t:.3} s: chunk refused: {e}");
                    wanted = None;
                }
            }
            loop_share_us.push(clock.elapsed().as_secs_f64() * 1e6);
        }
        // The camera: every 10 ms, stamped now, describing the person 30 ms ago (the model's
        // delay), within 1 cm.
        let measurement = (k % 10 == 0)
            .then(|| HumanMeasurement::new(&human, t, &true_person(t - 0.03), None))
            .transpose()?;
        let clock = Instant::now();
        let cmd = shield.step(t, measurement.as_ref())?;
        step_us.push(clock.elapsed().as_secs_f64() * 1e6);
        match shield.offer_state() {
            OfferState::Taken(_) => wanted = None,
            // The commands did not reach the handover (a step was not verified) or the plan came
            // back after it: plan the wanted chunk again from a newer handover.
            OfferState::Stale if in_flight == 0 => {
                if let (Some(c), Some(h)) = (wanted.clone(), shield.handover(LEAD)) {
                    to_planner.send((h, c))?;
                    in_flight += 1;
                    replanned += 1;
                }
            }
            _ => {}
        }
        // Send cmd.state.q / dq / ddq (rad, rad/s, rad/s²) for time cmd.t to the robot here.
        last_q.copy_from_slice(&cmd.state.q[..cmd.dof]);
        if cmd.diag.verified {
            verified += 1;
            if stopped_at.is_some() && resumed_at.is_none() && cmd.diag.path_speed > 0.5 {
                resumed_at = Some(cmd.t);
            }
        } else if stopped_at.is_none() && matches!(cmd.diag.binding, Binding::Ssm { .. }) {
            // The first step the person's possible contact refused: braking along the path.
            stopped_at = Some((cmd.t, format!("{:?}", cmd.diag.binding)));
        }
        if !fast {
            // Pace at 1 kHz: wait for the next tick.
            let deadline = start + Duration::from_secs_f64((k + 1) as f64 * dt);
            while Instant::now() < deadline {
                std::hint::spin_loop();
            }
        }
    }
    // The p-quantile of sorted times (0 if none).
    let pct = |v: &[f64], p: f64| {
        v.get(((v.len().max(1) - 1) as f64 * p) as usize)
            .copied()
            .unwrap_or(0.0)
    };
    for v in [&mut step_us, &mut loop_share_us, &mut plan_us] {
        v.sort_by(f64::total_cmp);
    }
    println!("{steps} steps of {} ms", dt * 1e3);
    println!(
        "verified: {verified} ({:.1} %)",
        100.0 * verified as f64 / steps as f64
    );
    match stopped_at {
        Some((t, why)) => println!("braking for the person from {t:.3} s ({why})"),
        None => println!("the person never made the arm brake"),
    }
    if let Some(t) = resumed_at {
        println!("back at half the intended speed at {t:.3} s");
    }
    println!(
        "step time (µs): median {:.1}, p99 {:.1}, max {:.1}",
        pct(&step_us, 0.5),
        pct(&step_us, 0.99),
        pct(&step_us, 1.0)
    );
    println!(
        "chunks: {offered} offered, {replanned} planned again; the loop's share per chunk \
         (handover + offer, µs): median {:.1}, max {:.1}; planning on its thread (µs): median {:.0}, max {:.0}",
        pct(&loop_share_us, 0.5),
        pct(&loop_share_us, 1.0),
        pct(&plan_us, 0.5),
        pct(&plan_us, 1.0)
    );
    println!("final q (rad): {last_q:.3?}");
    drop(to_planner);
    planning
        .join()
        .map_err(|_| "the planning thread panicked")?;
    Ok(())
}
