//! The evaluation: rollouts of tasks × methods in parallel, the paper's metrics per method, and
//! tables (Markdown, JSON) and SVG plots.

mod metrics;
mod plots;

pub use metrics::{Row, Stat, markdown, summarize, wilson95};
pub use plots::{svg_paths, svg_separation};

use crate::episode::{Episode, EpisodeConfig, Goal, Method, Outputs, Setup, run_setup};
use crate::task::{ConstraintMode, TaskKind, constraint_spec, native_mode, scenario};
use pacs_shield::ChunkMotion;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// A method as evaluated: a filter and the constraints it enforces.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Variant {
    /// The filter.
    pub method: Method,
    /// Constraints it enforces (None: the task's own, see [`native_mode`]).
    pub mode: Option<ConstraintMode>,
    /// Name as given on the command line.
    pub label: String,
    /// How chunk filters move across chunks (`pacs simulate --chunk-motion`).
    pub motion: ChunkMotion,
    /// The policy that produces the chunks (`pacs simulate --policy`).
    pub policy: PolicyKind,
}

/// Which policy stand-in an evaluation runs (`pacs simulate --policy`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum PolicyKind {
    /// [`crate::policy::DemoSet`]: nearest demonstrated state from the joint angles, with a
    /// phase cost; random drift beyond 0.12 rad (the default).
    #[default]
    Nearest,
    /// [`crate::policy::KernelPolicy`]: kernel regression learned from the demonstrations,
    /// observing the last two timesteps and the sub-goals reached.
    Kernel,
    /// [`PolicyKind::Kernel`], also trained on the demonstrations replayed at
    /// [`crate::task::REPLAY_PACES`] of their pace.
    KernelPaced,
    /// [`PolicyKind::Kernel`], also trained on the demonstrations replayed with the shield's
    /// braking and resuming along their paths ([`crate::task::Replays::Shield`]).
    KernelShieldPaced,
    /// A policy the caller supplies ([`run_rollout_in`]; Python's `pacs.simulate(policy=…)`
    /// with a policy object, e.g. a LeRobot diffusion policy). Not selectable by name.
    External,
}

impl PolicyKind {
    /// The replays a learned kind is also trained on (`Replays::None` for the others, which
    /// are not trained).
    fn replays(self) -> crate::task::Replays {
        match self {
            Self::KernelPaced => crate::task::Replays::Constant,
            Self::KernelShieldPaced => crate::task::Replays::Shield,
            Self::Nearest | Self::Kernel | Self::External => crate::task::Replays::None,
        }
    }
}

impl std::str::FromStr for PolicyKind {
    type Err = crate::UnknownName;
    fn from_str(s: &str) -> Result<Self, crate::UnknownName> {
        match s {
            "nearest" => Ok(Self::Nearest),
            "kernel" => Ok(Self::Kernel),
            "kernel-paced" => Ok(Self::KernelPaced),
            "kernel-shield-paced" => Ok(Self::KernelShieldPaced),
            o => Err(crate::UnknownName {
                kind: "policy",
                given: o.into(),
                choices: "nearest, kernel, kernel-paced, kernel-shield-paced".into(),
            }),
        }
    }
}

/// Every method name `pacs simulate --method` accepts.
pub const METHOD_NAMES: [&str; 9] = [
    "off",
    "pacs",
    "pacs-ssm",
    "pacs-pfl",
    "single-action",
    "single-action-ssm",
    "single-action-pfl",
    "cbf",
    "direct",
];

impl std::str::FromStr for Variant {
    type Err = crate::UnknownName;
    fn from_str(s: &str) -> Result<Self, crate::UnknownName> {
        let (method, mode) = match s {
            "off" => (Method::Off, None),
            "pacs" => (Method::Pacs, None),
            "pacs-ssm" => (Method::Pacs, Some(ConstraintMode::Ssm)),
            "pacs-pfl" => (Method::Pacs, Some(ConstraintMode::Pfl)),
            "single-action" => (Method::SingleAction, None),
            "single-action-ssm" => (Method::SingleAction, Some(ConstraintMode::Ssm)),
            "single-action-pfl" => (Method::SingleAction, Some(ConstraintMode::Pfl)),
            "cbf" => (Method::Cbf, None),
            "direct" => (Method::Direct, None),
            o => {
                return Err(crate::UnknownName {
                    kind: "method",
                    given: o.into(),
                    choices: format!("one of: {}", METHOD_NAMES.join(", ")),
                });
            }
        };
        Ok(Self {
            method,
            mode,
            label: s.into(),
            motion: ChunkMotion::Stop,
            policy: PolicyKind::Nearest,
        })
    }
}

/// Errors of the evaluation.
#[derive(Debug, thiserror::Error)]
pub enum EvalError {
    /// A filter could not be built or an episode failed.
    #[error("{task} / {method} rollout {seed}: {source}")]
    Episode {
        /// Task.
        task: &'static str,
        /// Method label.
        method: String,
        /// Rollout seed.
        seed: u64,
        /// Cause.
        source: Box<crate::SimError>,
    },
    /// A variant names the caller's policy ([`PolicyKind::External`]) and none was given.
    #[error(
        "{task} / {method} rollout {seed}: the variant runs the caller's policy, and none was given"
    )]
    NoPolicy {
        /// Task.
        task: &'static str,
        /// Method label.
        method: String,
        /// Rollout seed.
        seed: u64,
    },
    /// An input of the evaluation is invalid (e.g. a time limit that is not positive).
    #[error("{reason}")]
    Input {
        /// What is wrong, with the value.
        reason: String,
    },
    /// Writing an output failed.
    #[error("cannot write {path}: {source}")]
    Io {
        /// File.
        path: PathBuf,
        /// Cause.
        source: std::io::Error,
    },
}

/// One finished rollout.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Rollout {
    /// Task.
    pub task: TaskKind,
    /// Method label.
    pub method: String,
    /// The policy that produced the chunks.
    pub policy: PolicyKind,
    /// Rollout seed.
    pub seed: u64,
    /// The audit log written, if any.
    pub log: Option<PathBuf>,
    /// The episode and its metrics.
    pub episode: Episode,
}

/// Evaluation settings.
#[derive(Debug, Clone)]
pub struct EvalConfig {
    /// Tasks.
    pub tasks: Vec<TaskKind>,
    /// Methods.
    pub variants: Vec<Variant>,
    /// Rollouts per task and method.
    pub rollouts: usize,
    /// Base seed: rollout i uses seed + i (the same humans for every method).
    pub seed: u64,
    /// People and objects present (false: far away, the speed ablation).
    pub with_human: bool,
    /// Write every rollout's audit log to this directory.
    pub log_dir: Option<PathBuf>,
    /// Keep every n-th step for plots (0: none).
    pub record_every: usize,
    /// Every rollout's time limit (s); `None`: each task's own ([`crate::task::Scenario`]'s
    /// `max_time`: 20 s, feeding 60 s). A rollout that has not succeeded by then fails.
    pub time_limit: Option<f64>,
}

/// A rollout time limit given by a user: finite and positive (s), at most [`MAX_TIME_LIMIT`].
/// The error says what was expected and the value (the caller names the option).
pub fn check_time_limit(t: f64) -> Result<f64, String> {
    if t.is_finite() && t > 0.0 && t <= MAX_TIME_LIMIT {
        Ok(t)
    } else {
        Err(format!(
            "expected seconds in (0, {MAX_TIME_LIMIT}], got {t}"
        ))
    }
}

/// The longest rollout time limit accepted (s): one hour of 1 ms steps.
pub const MAX_TIME_LIMIT: f64 = 3600.0;

/// The constraint spec a variant enforces on `task` (and is scored against).
pub fn variant_mode(task: TaskKind, v: &Variant) -> ConstraintMode {
    v.mode.unwrap_or(native_mode(task))
}

/// Run one rollout.
pub fn run_rollout(
    task: TaskKind,
    v: &Variant,
    seed: u64,
    with_human: bool,
    log: Option<&Path>,
    record_every: usize,
) -> Result<Rollout, EvalError> {
    run_rollout_in(
        task,
        v,
        seed,
        Scene::of(with_human),
        log,
        record_every,
        None,
    )
}

/// What a rollout's scene adds to the task's: people present or far away, and further
/// scripted people (the tolerance tool's intruder, [`crate::tolerance`]).
pub struct Scene {
    /// People and objects present (false: far away).
    pub with_human: bool,
    /// Further people, seen by the filter and scored like the scene's own, not observed by
    /// the policy.
    pub extra_people: Vec<Box<dyn crate::humans::HumanScript>>,
    /// The rollout's time limit (s); `None`: the task's own.
    pub time_limit: Option<f64>,
}

impl Scene {
    /// The task's scene, people present or far away, nobody added, the task's time limit.
    pub fn of(with_human: bool) -> Self {
        Self {
            with_human,
            extra_people: Vec::new(),
            time_limit: None,
        }
    }

    /// The same scene with the time limit `limit` (s; `None`: the task's own).
    pub fn with_time_limit(mut self, limit: Option<f64>) -> Self {
        self.time_limit = limit;
        self
    }
}

/// Run one rollout in `scene` (the task's, with further people if any) of `policy`, a policy
/// the caller supplies (its rows and rollouts then say [`PolicyKind::External`]; `v.policy` is
/// ignored), or of `v.policy` when `external` is None. The filter, the scoring and the log are those of
/// [`run_rollout`]; a caller's policy's deviation is measured against the task's built-in
/// demonstrations (its `TaskPolicy::deviation`).
#[allow(clippy::too_many_arguments)]
pub fn run_rollout_in(
    task: TaskKind,
    v: &Variant,
    seed: u64,
    scene: Scene,
    log: Option<&Path>,
    record_every: usize,
    external: Option<&mut (dyn crate::policy::TaskPolicy + '_)>,
) -> Result<Rollout, EvalError> {
    let v = &match external {
        Some(_) => Variant {
            policy: PolicyKind::External,
            ..v.clone()
        },
        None => v.clone(),
    };
    let err = |source: crate::SimError| EvalError::Episode {
        task: task.name(),
        method: v.label.clone(),
        seed,
        source: Box::new(source),
    };
    let mut scn = scenario(task, seed, scene.with_human);
    scn.others.extend(scene.extra_people);
    if let Some(limit) = scene.time_limit {
        scn.max_time = check_time_limit(limit).map_err(|e| EvalError::Input {
            reason: format!("time limit: {e}"),
        })?;
    }
    scn.set_mode(variant_mode(task, v));
    let spec = constraint_spec(task, variant_mode(task, v));
    let goals: Vec<Goal> = scn.goals.iter().copied().map(Goal::Tool).collect();
    let cfg = EpisodeConfig {
        max_time: scn.max_time,
        seed,
        chunk_motion: v.motion,
        ..EpisodeConfig::default()
    };
    let mut file = match log {
        Some(p) => Some(std::io::BufWriter::new(std::fs::File::create(p).map_err(
            |source| EvalError::Io {
                path: p.to_path_buf(),
                source,
            },
        )?)),
        None => None,
    };
    let mut learned;
    let policy: &mut dyn crate::policy::TaskPolicy = match (external, v.policy) {
        (Some(p), _) => p,
        (None, PolicyKind::Nearest) => &mut scn.policy,
        (None, PolicyKind::External) => {
            return Err(EvalError::NoPolicy {
                task: task.name(),
                method: v.label.clone(),
                seed,
            });
        }
        (None, PolicyKind::Kernel | PolicyKind::KernelPaced | PolicyKind::KernelShieldPaced) => {
            learned = crate::task::learned_policy(task, v.policy.replays());
            &mut learned
        }
    };
    let setup = Setup {
        robot: &scn.robot,
        human: &scn.human,
        spec: &spec,
        script: scn.script.as_ref(),
        others: &scn.others,
        objects: &scn.objects,
        policy,
        goals: &goals,
        start: &scn.start,
        label: &v.label,
        task: task.name(),
        max_time: scn.max_time,
    };
    let episode = run_setup(
        v.method,
        setup,
        &cfg,
        Outputs {
            log: file.as_mut().map(|f| f as &mut dyn std::io::Write),
            record_every,
            truth_audit: true,
        },
    )
    .map_err(err)?;
    Ok(Rollout {
        task,
        method: v.label.clone(),
        policy: v.policy,
        seed,
        log: log.map(Path::to_path_buf),
        episode,
    })
}

/// Run every task × method × rollout in parallel (rayon); `progress` is called after each.
pub fn evaluate(
    cfg: &EvalConfig,
    progress: &(dyn Fn(&Rollout) + Sync),
) -> Result<Vec<Rollout>, EvalError> {
    if let Some(d) = &cfg.log_dir {
        std::fs::create_dir_all(d).map_err(|source| EvalError::Io {
            path: d.clone(),
            source,
        })?;
    }
    let mut jobs = Vec::new();
    for &task in &cfg.tasks {
        for v in &cfg.variants {
            for i in 0..cfg.rollouts {
                jobs.push((task, v, cfg.seed + i as u64));
            }
        }
    }
    let out: Vec<Rollout> = jobs
        .par_iter()
        .map(|&(task, v, seed)| {
            let log = cfg
                .log_dir
                .as_ref()
                .map(|d| d.join(format!("{}-{}-{seed:04}.jsonl", task.name(), v.label)));
            let r = run_rollout_in(
                task,
                v,
                seed,
                Scene::of(cfg.with_human).with_time_limit(cfg.time_limit),
                log.as_deref(),
                cfg.record_every,
                None,
            )?;
            progress(&r);
            Ok(r)
        })
        .collect::<Result<_, EvalError>>()?;
    Ok(merge([out]))
}

/// Rollouts of one or several evaluations (e.g. seed ranges run on different machines, Python's
/// `pacs.simulate` on Dask) in the order [`evaluate`] returns them: by task, method label and
/// seed. Evaluations of disjoint seed ranges merged give exactly the rollouts, in the same
/// order, of one evaluation of all the seeds (each rollout depends only on its task, method and
/// seed), and so the same [`summarize`] rows.
pub fn merge(parts: impl IntoIterator<Item = Vec<Rollout>>) -> Vec<Rollout> {
    let mut out: Vec<Rollout> = parts.into_iter().flatten().collect();
    out.sort_by(|a, b| (a.task as u8, &a.method, a.seed).cmp(&(b.task as u8, &b.method, b.seed)));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_variant_naming_the_callers_policy_without_one_is_refused() {
        let v = Variant {
            policy: PolicyKind::External,
            ..("pacs".parse::<Variant>().unwrap())
        };
        let e = run_rollout(TaskKind::Sorting, &v, 1, true, None, 0).unwrap_err();
        assert!(matches!(e, EvalError::NoPolicy { seed: 1, .. }), "{e}");
        assert!(e.to_string().contains("none was given"));
    }
}
