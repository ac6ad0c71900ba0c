//! The paper's metrics per task and method, aggregated over rollouts, and their Markdown table.

use super::{Rollout, Variant, variant_mode};
use crate::episode::{Episode, Method};
use crate::task::{ConstraintMode, TaskKind};
use serde::Serialize;
use std::fmt::Write as _;

/// Mean, (sample) standard deviation and the half-width of the mean's 95 % confidence interval.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Stat {
    /// Mean.
    pub mean: f64,
    /// Standard deviation (0 for one value).
    pub std: f64,
    /// Half-width of the 95 % confidence interval of the mean, 1.96·std/√n (normal
    /// approximation; 0 for one value).
    pub ci95: f64,
}

/// The 95 % Wilson score interval of a proportion `p` observed in `n` trials: [lo, hi] (better
/// behaved than p ± 1.96·√(p(1−p)/n) near 0 and 1, where most of our success rates lie).
pub fn wilson95(p: f64, n: usize) -> [f64; 2] {
    if n == 0 {
        return [0.0, 1.0];
    }
    let (z, n) = (1.96_f64, n as f64);
    let z2 = z * z;
    let centre = (p + z2 / (2.0 * n)) / (1.0 + z2 / n);
    let half = z * (p * (1.0 - p) / n + z2 / (4.0 * n * n)).sqrt() / (1.0 + z2 / n);
    [(centre - half).max(0.0), (centre + half).min(1.0)]
}

impl Stat {
    fn of(v: &[f64]) -> Self {
        if v.is_empty() {
            return Self {
                mean: f64::NAN,
                std: f64::NAN,
                ci95: f64::NAN,
            };
        }
        let n = v.len() as f64;
        let mean = v.iter().sum::<f64>() / n;
        let var = if v.len() > 1 {
            v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)
        } else {
            0.0
        };
        Self {
            mean,
            std: var.sqrt(),
            ci95: 1.96 * var.sqrt() / n.sqrt(),
        }
    }
}

/// The paper's metrics for one task and method.
#[derive(Debug, Clone, Serialize)]
pub struct Row {
    /// Task.
    pub task: TaskKind,
    /// Method label.
    pub method: String,
    /// The policy that produced the chunks (the row's first rollout's; `external`: a policy
    /// object from Python).
    pub policy: crate::eval::PolicyKind,
    /// Constraints enforced and scored (`ssm` / `pfl`).
    pub constraints: ConstraintMode,
    /// Rollouts.
    pub rollouts: usize,
    /// Fraction of successful rollouts.
    pub success: f64,
    /// Its 95 % Wilson interval.
    pub success_ci95: [f64; 2],
    /// Fraction of successful rollouts without any violation.
    pub safe_success: f64,
    /// Its 95 % Wilson interval.
    pub safe_success_ci95: [f64; 2],
    /// Safety Viol. (the paper's): fraction of 1 ms steps whose recorded state violates the
    /// constraints against the true human, from the offline audit (its `certain` violations).
    pub safety_violation: Stat,
    /// Fraction of steps where the audit cannot exclude a violation (possible between samples:
    /// only joint limits are assumed between 1 ms samples).
    pub possible_violation: Stat,
    /// Fraction of steps violating at the sampled states by the simulator's own exact geometry
    /// (cross-check of `safety_violation`).
    pub exact_violation: Stat,
    /// Duration of successful rollouts (s).
    pub duration: Stat,
    /// Largest joint-space distance to the demonstrations (rad) per rollout.
    pub path_deviation: Stat,
    /// Fraction of rollouts in which the policy went out of distribution at least once.
    pub ood_rollouts: f64,
    /// Mean tool speed until success (m/s), successful rollouts.
    pub tool_speed: Stat,
    /// Smallest true separation (m) per rollout.
    pub min_separation: Stat,
}

/// Aggregate rollouts into one row per task and method (in first-seen order).
pub fn summarize(rollouts: &[Rollout]) -> Vec<Row> {
    let mut keys: Vec<(TaskKind, String)> = Vec::new();
    for r in rollouts {
        let k = (r.task, r.method.clone());
        if !keys.contains(&k) {
            keys.push(k);
        }
    }
    keys.into_iter()
        .map(|(task, method)| {
            let of_row = || {
                rollouts
                    .iter()
                    .filter(|r| r.task == task && r.method == method)
            };
            let policy = of_row().next().map(|r| r.policy).unwrap_or_default();
            let rs: Vec<&Episode> = of_row().map(|r| &r.episode).collect();
            let n = rs.len().max(1) as f64;
            let frac = |f: &dyn Fn(&Episode) -> bool| rs.iter().filter(|e| f(e)).count() as f64 / n;
            let stat = |f: &dyn Fn(&Episode) -> Option<f64>| {
                Stat::of(&rs.iter().filter_map(|e| f(e)).collect::<Vec<_>>())
            };
            let v: Variant = method.parse().unwrap_or(Variant {
                method: Method::Off,
                mode: None,
                label: method.clone(),
                motion: Default::default(),
                policy: Default::default(),
            });
            Row {
                task,
                policy,
                constraints: variant_mode(task, &v),
                method,
                rollouts: rs.len(),
                success: frac(&|e| e.success),
                success_ci95: wilson95(frac(&|e| e.success), rs.len()),
                safe_success: frac(&|e| e.safe_success),
                safe_success_ci95: wilson95(frac(&|e| e.safe_success), rs.len()),
                safety_violation: stat(&|e| {
                    Some(
                        e.truth_audit
                            .as_ref()
                            .map_or(e.violation_fraction, |a| a.certain_fraction),
                    )
                }),
                possible_violation: stat(&|e| e.truth_audit.as_ref().map(|a| a.violation_fraction)),
                exact_violation: stat(&|e| Some(e.violation_fraction)),
                duration: stat(&|e| e.success.then_some(e.duration)),
                path_deviation: stat(&|e| Some(e.max_deviation)),
                ood_rollouts: frac(&|e| e.ood_chunks > 0),
                tool_speed: stat(&|e| e.success.then_some(e.mean_tool_speed)),
                min_separation: stat(&|e| Some(e.min_separation)),
            }
        })
        .collect()
}

fn pm(s: Stat, digits: usize) -> String {
    if s.mean.is_nan() {
        "–".into()
    } else {
        format!("{:.d$} ± {:.d$}", s.mean, s.ci95, d = digits)
    }
}

fn rate(p: f64, ci: [f64; 2]) -> String {
    format!("{p:.2} [{:.2}, {:.2}]", ci[0], ci[1])
}

/// The rows as a Markdown table (the paper's "Impact of safeguarding" columns and more): rates
/// with their 95 % Wilson interval, other figures as mean ± the half-width of the mean's 95 %
/// confidence interval (`summary.json` also has the standard deviations).
pub fn markdown(rows: &[Row]) -> String {
    let mut s = String::from(
        "| task | method | constraints | rollouts | Success [95 % CI] | Safe Success [95 % CI] | Safety Viol. | Possible viol. (audit bound) | Duration (s, successes) | Path deviation (rad) | OOD rollouts | Tool speed (m/s) | Min. separation (m) |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {:.2} | {} | {} |",
            r.task.name(),
            r.method,
            match r.constraints {
                ConstraintMode::Ssm => "SSM",
                ConstraintMode::Pfl => "PFL",
            },
            r.rollouts,
            rate(r.success, r.success_ci95),
            rate(r.safe_success, r.safe_success_ci95),
            pm(r.safety_violation, 3),
            pm(r.possible_violation, 3),
            pm(r.duration, 2),
            pm(r.path_deviation, 3),
            r.ood_rollouts,
            pm(r.tool_speed, 3),
            pm(r.min_separation, 3),
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wilson_interval_matches_hand_computed_values() {
        // 9/10: centre (0.9 + 1.96²/20)/(1 + 1.96²/10) = 0.78898, half-width 0.19314.
        let [lo, hi] = wilson95(0.9, 10);
        assert!(
            (lo - 0.59585).abs() < 1e-4 && (hi - 0.98212).abs() < 1e-4,
            "{lo} {hi}"
        );
        // 10/10: [0.7225, 1].
        let [lo, hi] = wilson95(1.0, 10);
        assert!((lo - 0.72246).abs() < 1e-4 && hi == 1.0, "{lo} {hi}");
        // 0/100: [0, 0.037].
        let [lo, hi] = wilson95(0.0, 100);
        assert!(lo == 0.0 && (hi - 0.03699).abs() < 1e-4, "{lo} {hi}");
    }

    #[test]
    fn stat_ci_is_1_96_standard_errors() {
        let s = Stat::of(&[1.0, 2.0, 3.0, 4.0]);
        // mean 2.5, sample std √(5/3) = 1.29099, ci 1.96·1.29099/2 = 1.26517.
        assert!((s.mean - 2.5).abs() < 1e-12);
        assert!((s.std - 1.290_994_448_7).abs() < 1e-9);
        assert!((s.ci95 - 1.265_174_559_7).abs() < 1e-9);
    }
}
