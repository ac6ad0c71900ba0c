//! The shield in a 1 kHz control loop, through the Rust API: a policy hands over an action chunk
//! every 264 ms (H = 16 joint deltas, h = 8 executed, Δt = 33 ms), a camera measures a person
//! every 10 ms, and every 1 ms the shield returns the command for the robot's low-level
//! controller — the intended motion when it verified it, the braking failsafe along the same
//! path otherwise.
//!
//! Chunks are planned **off the loop**, as a real-time loop must (planning takes 0.1–2 ms, the
//! step a few µs), by a `ChunkWorker`: its `set_chunk` predicts where the commands will be
//! `LEAD` steps ahead and sends the chunk to the worker's planning thread; its `poll`, before
//! every step, offers a plan that came back (`Shield::offer`). The step at the handover takes it
//! over only if the commands really got there, else the worker plans it again. The loop's share
//! of a chunk is the prediction, the send and the offer. `Shield::set_chunk` plans in the
//! caller's thread instead, which is simpler where the loop has the time.
//!
//! Run: `cargo run --release --example control_loop` (2 s of wall-clock time, paced at 1 kHz;
//! `-- --fast` runs unpaced). Prints how many steps were verified, when the arm stopped for the
//! person, the step times and the loop's share of each chunk (µs).

use pacs::models::{ConstraintSpec, RobotModel, default_human, fr3};
use pacs::motion::chunk::{ActionKind, Chunk};
use pacs::reach::human::HumanMeasurement;
use pacs::shield::shield::{Binding, Shield, ShieldConfig};
use pacs::shield::worker::{ChunkWorker, WorkerState};
use std::time::{Duration, Instant};

/// Safety steps between asking for a handover and the step that takes the chunk over: 5 ms
/// for planning (planning times: `docs/performance.md#chunk-planning-time`).
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
    let mut shield = Shield::builder(robot)
        .person(human.clone(), &constraints)
        .config(ShieldConfig::default())
        .build()?;
    shield.start(0.0, &fr3::Q_READY)?;
    let dt = shield.config().safety_step; // 1 ms
    let steps = 2000;
    let (mut verified, mut stopped_at, mut resumed_at) = (0usize, None, None);
    let mut step_us = Vec::with_capacity(steps);
    let mut last_q = fr3::Q_READY.to_vec();
    // The planning thread: `set_chunk` predicts the handover LEAD steps ahead and sends the
    // chunk there; `poll` offers what came back and plans again where an offer went stale.
    let mut worker = ChunkWorker::spawn(&shield, LEAD)?;
    let (mut loop_share_us, mut plan_us) = (Vec::new(), Vec::new());
    let (mut handed_in, mut followed, mut plans_seen) = (0usize, 0usize, 0u64);
    let mut last_state = WorkerState::Idle;
    let start = Instant::now();
    for k in 0..steps {
        let t = k as f64 * dt;
        // A new chunk every h·Δt = 264 ms.
        if k % 264 == 0 {
            let clock = Instant::now();
            worker.set_chunk(&mut shield, policy_chunk())?;
            loop_share_us.push(clock.elapsed().as_secs_f64() * 1e6);
            handed_in += 1;
        }
        // Unpaced (`--fast`) the loop's clock is not the wall clock: wait for a plan whose
        // handover this step is (a 1 kHz loop has had the time).
        if fast && worker.due(t) {
            worker.wait()?;
        }
        let clock = Instant::now();
        if let Err(e) = worker.poll(&mut shield) {
            // A chunk the planner refused: the robot keeps following its current trajectory.
            eprintln!("t = {t:.3} s: {e}");
        }
        if worker.plans() != plans_seen {
            plans_seen = worker.plans();
            loop_share_us.push(clock.elapsed().as_secs_f64() * 1e6);
            if let Some(d) = worker.last_planning() {
                plan_us.push(d.as_secs_f64() * 1e6);
            }
        }
        if *worker.state() != last_state {
            last_state = worker.state().clone();
            followed += matches!(last_state, WorkerState::Taken(_)) as usize;
        }
        // The camera: every 10 ms, stamped now, describing the person 30 ms ago (the model's
        // delay), within 1 cm. Every person is measured the same way (`measure_human(index, …)`);
        // the shield uses the newest measurement of each at every step.
        if k % 10 == 0 {
            let m = HumanMeasurement::new(&human, t, &true_person(t - 0.03), None)?;
            shield.measure_human(0, &m)?;
        }
        let clock = Instant::now();
        let cmd = shield.step(t, None)?;
        step_us.push(clock.elapsed().as_secs_f64() * 1e6);
        // Send cmd.state.q / dq / ddq (rad, rad/s, rad/s²) for time cmd.t to the robot here.
        last_q.copy_from_slice(cmd.q());
        if cmd.diag.verified {
            verified += 1;
            if stopped_at.is_some() && resumed_at.is_none() && cmd.diag.path_speed > 0.5 {
                resumed_at = Some(cmd.t);
            }
        } else if stopped_at.is_none() && matches!(cmd.diag.binding, Binding::Ssm { .. }) {
            // The first step the person's possible contact refused: braking along the path.
            // Name the link and body part: `binding_json` puts the names beside the indices.
            let b = shield.binding_json(&cmd.diag.binding);
            let name = |k: &str| b[k].as_str().unwrap_or("?").to_string();
            stopped_at = Some((
                cmd.t,
                format!(
                    "SSM: {} could touch the person's {}",
                    name("link_name"),
                    name("body_part_name")
                ),
            ));
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
        "chunks: {handed_in} handed in, {followed} followed, {} planned again; the loop's share \
         (set_chunk, and the poll that offers a plan, µs): median {:.1}, max {:.1}; planning on \
         its thread (µs): median {:.0}, max {:.0}",
        worker.replans(),
        pct(&loop_share_us, 0.5),
        pct(&loop_share_us, 1.0),
        pct(&plan_us, 0.5),
        pct(&plan_us, 1.0)
    );
    println!("final q (rad): {last_q:.3?}");
    Ok(())
}
