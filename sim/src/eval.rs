//! The evaluation: rollouts of tasks × methods in parallel, the paper's metrics per method, and
//! tables (Markdown, JSON) and SVG plots.

use crate::episode::{Episode, EpisodeConfig, Goal, Method, Outputs, Setup, run_setup};
use crate::task::{ConstraintMode, TaskKind, constraint_spec, native_mode, scenario, tool_point};
use pacs_shield::shield::ShieldError;
use rayon::prelude::*;
use serde::Serialize;
use std::fmt::Write as _;
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
        source: ShieldError,
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
#[derive(Debug, Clone, Serialize)]
pub struct Rollout {
    /// Task.
    pub task: TaskKind,
    /// Method label.
    pub method: String,
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
    /// People (or the sphere) present.
    pub with_human: bool,
    /// Write every rollout's audit log to this directory.
    pub log_dir: Option<PathBuf>,
    /// Keep every n-th step for plots (0: none).
    pub record_every: usize,
}

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
    let err = |source| EvalError::Episode {
        task: task.name(),
        method: v.label.clone(),
        seed,
        source,
    };
    let mut scn = scenario(task, seed, with_human);
    let spec = constraint_spec(task, variant_mode(task, v));
    let goals: Vec<Goal> = scn.goals.iter().copied().map(Goal::Tool).collect();
    let cfg = EpisodeConfig {
        max_time: scn.max_time,
        seed,
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
    let setup = Setup {
        robot: &scn.robot,
        human: &scn.human,
        spec: &spec,
        script: scn.script.as_ref(),
        policy: &mut scn.policy,
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
    let mut out: Vec<Rollout> = jobs
        .par_iter()
        .map(|&(task, v, seed)| {
            let log = cfg
                .log_dir
                .as_ref()
                .map(|d| d.join(format!("{}-{}-{seed:04}.jsonl", task.name(), v.label)));
            let r = run_rollout(
                task,
                v,
                seed,
                cfg.with_human,
                log.as_deref(),
                cfg.record_every,
            )?;
            progress(&r);
            Ok(r)
        })
        .collect::<Result<_, EvalError>>()?;
    out.sort_by(|a, b| (a.task as u8, &a.method, a.seed).cmp(&(b.task as u8, &b.method, b.seed)));
    Ok(out)
}

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

/// The method labels of `rollouts`, in first-seen order.
fn methods_in<'a>(rollouts: &[&'a Rollout]) -> Vec<&'a str> {
    let mut methods: Vec<&str> = Vec::new();
    for r in rollouts {
        if !methods.contains(&r.method.as_str()) {
            methods.push(&r.method);
        }
    }
    methods
}

fn color(speed: f64, v_max: f64) -> String {
    // Light (slow) to dark blue (fast).
    let u = (speed / v_max).clamp(0.0, 1.0);
    let lerp = |a: f64, b: f64| (a + u * (b - a)).round() as u8;
    format!(
        "#{:02x}{:02x}{:02x}",
        lerp(198.0, 8.0),
        lerp(219.0, 48.0),
        lerp(239.0, 107.0)
    )
}

/// Top view (x–y, m) of the tool paths of `rollouts` (one task) coloured by speed, with the
/// demonstrations' region (tool paths of the task's demonstrations, ±2 cm) shaded grey: one
/// panel per method. Needs rollouts recorded with `record_every > 0`.
pub fn svg_paths(task: TaskKind, rollouts: &[&Rollout]) -> String {
    let scn = scenario(task, 0, true);
    let demo_tool: Vec<Vec<[f64; 3]>> = scn
        .policy
        .demos()
        .iter()
        .map(|d| d.iter().map(|q| tool_point(&scn.robot, q)).collect())
        .collect();
    let methods = methods_in(rollouts);
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    let pts = demo_tool.iter().flatten().chain(
        rollouts
            .iter()
            .flat_map(|r| r.episode.samples.iter().map(|s| &s.tool)),
    );
    for p in pts {
        x0 = x0.min(p[0]);
        x1 = x1.max(p[0]);
        y0 = y0.min(p[1]);
        y1 = y1.max(p[1]);
    }
    let pad = 0.05;
    let (x0, x1, y0, y1) = (x0 - pad, x1 + pad, y0 - pad, y1 + pad);
    // Colour scale: 0 to the 95th percentile of the recorded tool speeds (robust to spikes).
    let mut speeds: Vec<f64> = rollouts
        .iter()
        .flat_map(|r| r.episode.samples.iter().map(|s| s.tool_speed))
        .collect();
    speeds.sort_by(f64::total_cmp);
    let v_max = speeds
        .get(speeds.len() * 95 / 100)
        .copied()
        .unwrap_or(0.1)
        .max(0.05);
    let panel = 320.0;
    let scale = panel / (x1 - x0).max(y1 - y0);
    let w = panel * methods.len().max(1) as f64 + 20.0;
    let h = panel + 74.0;
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w:.0}\" height=\"{h:.0}\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n<text x=\"10\" y=\"16\">{}: tool paths seen from above (robot base at the origin, x up the page, y to the left)</text>\n<text x=\"10\" y=\"32\">colour: tool speed 0–{v_max:.2} m/s (light to dark blue); grey band: the demonstrations ±2 cm</text>\n",
        task.name()
    );
    for (mi, m) in methods.iter().enumerate() {
        let ox = 10.0 + mi as f64 * panel;
        let oy = 44.0;
        // Screen: x axis to the right = world −y (robot's left on the left), down = world −x.
        let map = |p: &[f64; 3]| (ox + (y1 - p[1]) * scale, oy + (x1 - p[0]) * scale);
        let _ = writeln!(
            s,
            "<g><rect x=\"{ox:.1}\" y=\"{oy:.1}\" width=\"{panel:.0}\" height=\"{panel:.0}\" fill=\"none\" stroke=\"#999\"/><text x=\"{:.1}\" y=\"{:.1}\">{m}</text>",
            ox + 6.0,
            oy + 16.0
        );
        for d in &demo_tool {
            let pts: Vec<String> = d
                .iter()
                .map(|p| {
                    let (a, b) = map(p);
                    format!("{a:.1},{b:.1}")
                })
                .collect();
            let _ = writeln!(
                s,
                "<polyline points=\"{}\" fill=\"none\" stroke=\"#bbbbbb\" stroke-opacity=\"0.5\" stroke-width=\"{:.1}\" stroke-linecap=\"round\" stroke-linejoin=\"round\"/>",
                pts.join(" "),
                0.04 * scale
            );
        }
        for r in rollouts.iter().filter(|r| r.method == *m) {
            for w2 in r.episode.samples.windows(2) {
                let (a, b) = (map(&w2[0].tool), map(&w2[1].tool));
                let _ = writeln!(
                    s,
                    "<line x1=\"{:.1}\" y1=\"{:.1}\" x2=\"{:.1}\" y2=\"{:.1}\" stroke=\"{}\" stroke-width=\"2\" stroke-linecap=\"round\"/>",
                    a.0,
                    a.1,
                    b.0,
                    b.1,
                    color(w2[1].tool_speed, v_max)
                );
            }
        }
        s.push_str("</g>\n");
    }
    let _ = writeln!(
        s,
        "<text x=\"10\" y=\"{:.0}\">scale: 10 cm = {:.0} px</text>\n</svg>",
        h - 10.0,
        0.1 * scale
    );
    s
}

/// True minimum separation (m) between the moving robot and the human over time, one line per
/// rollout, coloured by method; contact (≤ 0) shaded red.
pub fn svg_separation(task: TaskKind, rollouts: &[&Rollout]) -> String {
    const PALETTE: [&str; 9] = [
        "#d62728", "#1f77b4", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2", "#17becf",
        "#7f7f7f",
    ];
    let methods = methods_in(rollouts);
    let t_max = rollouts
        .iter()
        .flat_map(|r| r.episode.samples.last().map(|s| s.t))
        .fold(1.0, f64::max);
    let d_max = 1.0;
    let d_min = -0.1;
    let (w, h, l, top, pw, ph) = (760.0, 360.0, 50.0, 30.0, 680.0, 280.0);
    let x = |t: f64| l + t / t_max * pw;
    let y = |d: f64| top + (d_max - d.clamp(d_min, d_max)) / (d_max - d_min) * ph;
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n<text x=\"10\" y=\"18\">{}: true separation robot–human (m, clipped to [−0.1, 1]) over time (s)</text>\n<rect x=\"{l}\" y=\"{:.1}\" width=\"{pw}\" height=\"{:.1}\" fill=\"#f4cccc\"/>\n<rect x=\"{l}\" y=\"{top}\" width=\"{pw}\" height=\"{ph}\" fill=\"none\" stroke=\"#999\"/>\n",
        task.name(),
        y(0.0),
        y(d_min) - y(0.0)
    );
    for k in 0..=5 {
        let d = k as f64 * 0.2;
        let _ = writeln!(
            s,
            "<text x=\"{:.0}\" y=\"{:.1}\" text-anchor=\"end\">{d:.1}</text>",
            l - 4.0,
            y(d) + 4.0
        );
    }
    let steps = (t_max / 2.0).ceil() as usize;
    for k in 0..=steps {
        let t = k as f64 * 2.0;
        let _ = writeln!(
            s,
            "<text x=\"{:.1}\" y=\"{:.0}\" text-anchor=\"middle\">{t:.0}</text>",
            x(t),
            top + ph + 16.0
        );
    }
    for (mi, m) in methods.iter().enumerate() {
        let c = PALETTE[mi % PALETTE.len()];
        for r in rollouts.iter().filter(|r| r.method == *m) {
            let pts: Vec<String> = r
                .episode
                .samples
                .iter()
                .filter(|s| s.separation.is_finite())
                .map(|s| format!("{:.1},{:.1}", x(s.t), y(s.separation)))
                .collect();
            let _ = writeln!(
                s,
                "<polyline points=\"{}\" fill=\"none\" stroke=\"{c}\" stroke-opacity=\"0.6\" stroke-width=\"1.2\"/>",
                pts.join(" ")
            );
        }
        let _ = writeln!(
            s,
            "<rect x=\"{:.0}\" y=\"{:.0}\" width=\"12\" height=\"3\" fill=\"{c}\"/><text x=\"{:.0}\" y=\"{:.0}\">{m}</text>",
            l + 10.0 + mi as f64 * 90.0,
            h - 22.0,
            l + 26.0 + mi as f64 * 90.0,
            h - 16.0
        );
    }
    s.push_str("</svg>\n");
    s
}
