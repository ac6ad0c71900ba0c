//! Does a policy still succeed when the shield slows or stops it along its path?
//!
//! PACS keeps a policy on its path but changes the timing: it brakes along the path when a
//! person comes close, holds, and resumes. A policy that learned only demonstrations at one
//! pace may fail after such an interruption (it sees itself slower than it ever was). This
//! module measures that on the policy's own rollouts, with the real shield: each rollout is
//! run once undisturbed (PACS, the task's scene) and then again with an *intruder* — a person
//! who walks in beside the table at a chosen time, reaches a hand to where the tool was at that
//! time in the undisturbed rollout, keeps it there for `hold` seconds, withdraws and leaves.
//! The shield brakes along the path (to rest under SSM, slower under PFL), holds, and resumes
//! once the hand is gone. The intruder is seen by the shield and scored like the scene's own
//! people, but the policy does not observe it (its observations are those of the undisturbed
//! scene), so what changes for the policy is only the timing of its own motion.

use crate::eval::{EvalError, Rollout, Scene, Variant, run_rollout_in, wilson95};
use crate::humans::{FLOOR_Z, HumanScript, ease, lerp, standing_on};
use crate::policy::TaskPolicy;
use crate::task::{TaskKind, tool_point};
use pacs_models::fr3;
use serde::Serialize;

/// Walking in or out (s) (1.3 m, eased: at most 1.6 m/s, within the default model's 2 m/s).
const WALK: f64 = 1.2;
/// Raising or lowering the hand (s) (≤ 1 m eased: at most 1.9 m/s).
const REACH: f64 = 0.8;
/// How far (m) beyond the tool, across the table, the intruder stands.
const STAND_OFF: f64 = 0.55;

/// A person who walks in to stand at `stand` (m, floor), reaches the right hand to `reach` (m)
/// at `t_reach` (s; the hand arrives `REACH` later), holds it there for `hold` (s),
/// withdraws it and walks away.
#[derive(Debug, Clone)]
pub struct Intruder {
    /// Where the person stands (x, y) (m).
    pub stand: [f64; 2],
    /// Where the hand is held (m).
    pub reach: [f64; 3],
    /// When the hand starts to rise (s).
    pub t_reach: f64,
    /// How long (s) the hand stays at `reach`.
    pub hold: f64,
}

impl Intruder {
    /// When the hand is back down (s).
    pub fn t_withdrawn(&self) -> f64 {
        self.t_reach + REACH + self.hold + REACH
    }
}

impl HumanScript for Intruder {
    fn keypoints(&self, t: f64) -> Vec<[f64; 3]> {
        let arrive = self.t_reach - WALK;
        let leave = self.t_withdrawn();
        let far = self.stand[0] + 1.3;
        let w = ease(t, arrive, self.t_reach) - ease(t, leave, leave + WALK);
        let x = far + w * (self.stand[0] - far);
        let y = self.stand[1];
        let rest = [x - 0.05, y - 0.25, FLOOR_Z + 0.95];
        let up = self.t_reach + REACH + self.hold;
        let arm = ease(t, self.t_reach, self.t_reach + REACH) * (1.0 - ease(t, up, up + REACH));
        standing_on(x, y, FLOOR_Z, lerp(rest, self.reach, arm))
    }
    fn name(&self) -> &str {
        "intruder"
    }
}

/// One interrupted rollout against its undisturbed twin.
#[derive(Debug, Clone, Serialize)]
pub struct ToleranceRun {
    /// Rollout seed.
    pub seed: u64,
    /// When the intruder's hand starts to rise, as a fraction of the undisturbed rollout's
    /// duration.
    pub at: f64,
    /// How long (s) the hand is held.
    pub hold: f64,
    /// Success of the undisturbed rollout.
    pub baseline_success: bool,
    /// Duration (s) of the undisturbed rollout.
    pub baseline_duration: f64,
    /// Success with the intruder.
    pub success: bool,
    /// Duration (s) with the intruder.
    pub duration: f64,
    /// Time (s) the robot stood still (tool speed below [`AT_REST`]) between the hand's rise
    /// and its withdrawal, with the intruder.
    pub stopped: f64,
    /// Time (s) the robot moved at under half its undisturbed tool speed in that window.
    pub slowed: f64,
    /// Largest deviation (rad) from the demonstrations with the intruder.
    pub max_deviation: f64,
    /// Ground-truth violation fraction with the intruder (PACS keeps it 0).
    pub violation_fraction: f64,
}

/// Tool speed (m/s) below which the robot counts as at rest (the simulated controller's
/// tracking error keeps the joint speeds from being exactly zero).
pub const AT_REST: f64 = 0.005;

/// Record every n-th safety step of the undisturbed rollout (10 ms).
const RECORD: usize = 10;

/// Which interrupted rollouts [`tolerance`] runs: every seed × `at` × `hold`.
#[derive(Debug, Clone, Copy)]
pub struct Interruptions<'a> {
    /// Rollout seeds.
    pub seeds: &'a [u64],
    /// When the intruder's hand rises, as fractions of the undisturbed rollout's duration.
    pub at: &'a [f64],
    /// How long (s) the hand is held.
    pub holds: &'a [f64],
}

/// Interrupted rollouts of `task` under `variant` (a PACS method) for every seed × `at` ×
/// `hold` of `grid`, each against its undisturbed twin. `policy`: a caller's policy, or None for the
/// variant's built-in policy; `reset(seed)` is called before each rollout (a caller's policy
/// starts each rollout afresh); `progress(done, total)` after each rollout.
pub fn tolerance(
    task: TaskKind,
    variant: &Variant,
    grid: &Interruptions,
    mut policy: Option<&mut (dyn TaskPolicy + '_)>,
    reset: &mut dyn FnMut(u64),
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Vec<ToleranceRun>, EvalError> {
    let Interruptions { seeds, at, holds } = grid;
    let robot = fr3::fr3();
    let mut out = Vec::new();
    let total = seeds.len() * (1 + at.len() * holds.len());
    let mut done = 0;
    for &seed in *seeds {
        reset(seed);
        let base = run_rollout_in(
            task,
            variant,
            seed,
            Scene::of(true),
            None,
            RECORD,
            policy.as_deref_mut(),
        )?;
        done += 1;
        progress(done, total);
        let ep = &base.episode;
        for &f in *at {
            let t_reach = (f * ep.duration).max(WALK);
            // The tool where the undisturbed rollout had it when the hand starts to rise.
            let sample = ep
                .samples
                .iter()
                .min_by(|a, b| (a.t - t_reach).abs().total_cmp(&(b.t - t_reach).abs()));
            let tool = sample.map_or_else(|| tool_point(&robot, &fr3::Q_READY), |s| s.tool);
            for &hold in *holds {
                reset(seed);
                let intruder = Intruder {
                    stand: [tool[0] + STAND_OFF, tool[1]],
                    reach: [tool[0] + 0.12, tool[1], tool[2] + 0.05],
                    t_reach,
                    hold,
                };
                let (from, until) = (t_reach, intruder.t_withdrawn());
                let r = run_rollout_in(
                    task,
                    variant,
                    seed,
                    Scene {
                        with_human: true,
                        extra_people: vec![Box::new(intruder)],
                        time_limit: None,
                    },
                    None,
                    RECORD,
                    policy.as_deref_mut(),
                )?;
                out.push(summarize(&base, &r, seed, f, hold, (from, until)));
                done += 1;
                progress(done, total);
            }
        }
    }
    Ok(out)
}

/// The tolerance runs per hold time: the first row the undisturbed rollouts (hold 0, one per
/// seed), then one per hold of `holds`, in order.
#[derive(Debug, Clone, Serialize)]
pub struct ToleranceRow {
    /// How long (s) the hand was held (0: undisturbed).
    #[serde(rename = "hold_s")]
    pub hold: f64,
    /// Rollouts in the row.
    pub rollouts: usize,
    /// Fraction that succeeded.
    pub success: f64,
    /// Its 95 % Wilson interval.
    #[serde(rename = "success_wilson95")]
    pub success_ci95: [f64; 2],
    /// Mean time (s) at rest while the hand was there.
    #[serde(rename = "mean_stopped_s")]
    pub mean_stopped: f64,
    /// Mean extra duration (s) over the pairs that succeeded both ways (a failure runs to the
    /// time limit, so its duration says nothing about the delay); 0 without such pairs.
    #[serde(rename = "mean_extra_duration_s")]
    pub mean_extra_duration: f64,
    /// How many pairs that mean is over.
    pub extra_duration_pairs: usize,
}

/// [`ToleranceRow`]s of `runs` (from [`tolerance`] with these `holds`).
pub fn rows(runs: &[ToleranceRun], holds: &[f64]) -> Vec<ToleranceRow> {
    let mean = |v: &[f64]| {
        if v.is_empty() {
            0.0
        } else {
            v.iter().sum::<f64>() / v.len() as f64
        }
    };
    let mut seen: Vec<(u64, bool)> = Vec::new();
    for r in runs {
        if !seen.iter().any(|(s, _)| *s == r.seed) {
            seen.push((r.seed, r.baseline_success));
        }
    }
    let k = seen.iter().filter(|(_, ok)| *ok).count();
    let frac = |k: usize, n: usize| if n == 0 { 0.0 } else { k as f64 / n as f64 };
    let mut out = vec![ToleranceRow {
        hold: 0.0,
        rollouts: seen.len(),
        success: frac(k, seen.len()),
        success_ci95: wilson95(frac(k, seen.len()), seen.len()),
        mean_stopped: 0.0,
        mean_extra_duration: 0.0,
        extra_duration_pairs: k,
    }];
    for &h in holds {
        let rs: Vec<&ToleranceRun> = runs.iter().filter(|r| r.hold == h).collect();
        let ok = rs.iter().filter(|r| r.success).count();
        let extra: Vec<f64> = rs
            .iter()
            .filter(|r| r.success && r.baseline_success)
            .map(|r| r.duration - r.baseline_duration)
            .collect();
        let stopped: Vec<f64> = rs.iter().map(|r| r.stopped).collect();
        out.push(ToleranceRow {
            hold: h,
            rollouts: rs.len(),
            success: frac(ok, rs.len()),
            success_ci95: wilson95(frac(ok, rs.len()), rs.len()),
            mean_stopped: mean(&stopped),
            mean_extra_duration: mean(&extra),
            extra_duration_pairs: extra.len(),
        });
    }
    out
}

fn summarize(
    base: &Rollout,
    r: &Rollout,
    seed: u64,
    at: f64,
    hold: f64,
    (from, until): (f64, f64),
) -> ToleranceRun {
    let period = RECORD as f64 * 0.001;
    let window = r
        .episode
        .samples
        .iter()
        .filter(|s| s.t >= from && s.t <= until);
    let (mut stopped, mut slowed) = (0.0, 0.0);
    let nominal = base.episode.mean_tool_speed.max(1e-9);
    for s in window {
        if s.tool_speed < AT_REST {
            stopped += period;
        } else if s.tool_speed < 0.5 * nominal {
            slowed += period;
        }
    }
    ToleranceRun {
        seed,
        at,
        hold,
        baseline_success: base.episode.success,
        baseline_duration: base.episode.duration,
        success: r.episode.success,
        duration: r.episode.duration,
        stopped,
        slowed,
        max_deviation: r.episode.max_deviation,
        violation_fraction: r.episode.violation_fraction,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_intruder_stops_the_shield_and_the_demonstration_policy_still_succeeds() {
        let v: Variant = "pacs".parse().unwrap();
        let grid = Interruptions {
            seeds: &[1],
            at: &[0.4],
            holds: &[0.5, 2.0],
        };
        let runs = tolerance(
            TaskKind::Sorting,
            &v,
            &grid,
            None,
            &mut |_| {},
            &mut |_, _| {},
        )
        .unwrap();
        assert_eq!(runs.len(), 2);
        for r in &runs {
            assert!(r.baseline_success);
            assert_eq!(r.violation_fraction, 0.0);
            // The robot is stopped or slowed while the hand is there.
            assert!(r.stopped + r.slowed >= 0.5 * r.hold, "{r:?}");
            assert!(r.stopped > 0.0, "{r:?}");
            assert!(r.duration > r.baseline_duration, "{r:?}");
        }
        // Holding longer costs more time.
        assert!(runs[1].duration > runs[0].duration);
        // The nearest-neighbour policy sees only the joint angles: being stopped keeps it on
        // its path, and it finishes.
        assert!(runs.iter().all(|r| r.success));
    }

    #[test]
    fn rows_count_each_seed_once_and_average_only_pairs_that_succeeded() {
        let run = |seed, hold, base_ok, ok, dur| ToleranceRun {
            seed,
            at: 0.5,
            hold,
            baseline_success: base_ok,
            baseline_duration: 10.0,
            success: ok,
            duration: dur,
            stopped: hold,
            slowed: 0.0,
            max_deviation: 0.0,
            violation_fraction: 0.0,
        };
        let runs = [
            run(1, 1.0, true, true, 12.0),
            run(1, 2.0, true, false, 20.0),
            run(2, 1.0, false, true, 14.0),
            run(2, 2.0, false, false, 20.0),
        ];
        let r = rows(&runs, &[1.0, 2.0]);
        assert_eq!(r.len(), 3);
        assert_eq!((r[0].rollouts, r[0].success), (2, 0.5));
        assert_eq!(r[0].success_ci95, wilson95(0.5, 2));
        assert_eq!((r[1].rollouts, r[1].success), (2, 1.0));
        // Only seed 1 succeeded both ways at hold 1: +2 s; seed 2's baseline failed.
        assert_eq!(
            (r[1].mean_extra_duration, r[1].extra_duration_pairs),
            (2.0, 1)
        );
        assert_eq!((r[2].success, r[2].extra_duration_pairs), (0.0, 0));
        assert_eq!(r[2].mean_extra_duration, 0.0);
        assert_eq!(r[2].mean_stopped, 2.0);
    }

    #[test]
    fn the_intruder_moves_within_the_human_model() {
        let i = Intruder {
            stand: [1.0, 0.0],
            reach: [0.5, 0.0, 0.3],
            t_reach: 2.0,
            hold: 1.0,
        };
        let dt = 0.001;
        let mut prev = i.keypoints(0.0);
        let mut fastest = 0.0f64;
        let mut t = dt;
        while t < 8.0 {
            let k = i.keypoints(t);
            for (a, b) in k.iter().zip(&prev) {
                let d =
                    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
                fastest = fastest.max(d / dt);
            }
            prev = k;
            t += dt;
        }
        assert!(fastest <= 2.0, "{fastest} m/s");
        // The hand is at the reach point while held, far away before and after.
        let at_reach = |p: &[f64; 3]| (0..3).all(|j| (p[j] - i.reach[j]).abs() < 1e-9);
        assert!(i.keypoints(3.3).iter().any(at_reach));
        assert!(!i.keypoints(1.0).iter().any(at_reach));
        assert!(i.keypoints(0.0).iter().all(|p| p[0] > 2.0));
        assert!(i.keypoints(7.5).iter().all(|p| p[0] > 2.0));
    }
}
