//! The paper's metrics per task and method, aggregated over rollouts, and their Markdown table.

use super::{Rollout, Variant, variant_mode};
use crate::episode::{Episode, Method};
use crate::task::{ConstraintMode, TaskKind};
use serde::Serialize;
use std::fmt::Write as _;

/// Mean and (sample) standard deviation.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Stat {
    /// Mean.
    pub mean: f64,
    /// Standard deviation (0 for one value).
    pub std: f64,
}

impl Stat {
    fn of(v: &[f64]) -> Self {
        if v.is_empty() {
            return Self {
                mean: f64::NAN,
                std: f64::NAN,
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
    /// Constraints enforced and scored (`ssm` / `pfl`).
    pub constraints: ConstraintMode,
    /// Rollouts.
    pub rollouts: usize,
    /// Fraction of successful rollouts.
    pub success: f64,
    /// Fraction of successful rollouts without any violation.
    pub safe_success: f64,
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
            let rs: Vec<&Episode> = rollouts
                .iter()
                .filter(|r| r.task == task && r.method == method)
                .map(|r| &r.episode)
                .collect();
            let n = rs.len().max(1) as f64;
            let frac = |f: &dyn Fn(&Episode) -> bool| rs.iter().filter(|e| f(e)).count() as f64 / n;
            let stat = |f: &dyn Fn(&Episode) -> Option<f64>| {
                Stat::of(&rs.iter().filter_map(|e| f(e)).collect::<Vec<_>>())
            };
            let v: Variant = method.parse().unwrap_or(Variant {
                method: Method::Off,
                mode: None,
                label: method.clone(),
            });
            Row {
                task,
                constraints: variant_mode(task, &v),
                method,
                rollouts: rs.len(),
                success: frac(&|e| e.success),
                safe_success: frac(&|e| e.safe_success),
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
        format!("{:.d$} ± {:.d$}", s.mean, s.std, d = digits)
    }
}

/// The rows as a Markdown table (the paper's "Impact of safeguarding" columns and more).
pub fn markdown(rows: &[Row]) -> String {
    let mut s = String::from(
        "| task | method | constraints | rollouts | Success | Safe Success | Safety Viol. | Possible viol. (audit bound) | Duration (s, successes) | Path deviation (rad) | OOD rollouts | Tool speed (m/s) | Min. separation (m) |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {:.2} | {:.2} | {} | {} | {} | {} | {:.2} | {} | {} |",
            r.task.name(),
            r.method,
            match r.constraints {
                ConstraintMode::Ssm => "SSM",
                ConstraintMode::Pfl => "PFL",
            },
            r.rollouts,
            r.success,
            r.safe_success,
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
