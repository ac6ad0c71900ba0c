//! `pacs simulate`: the paper's evaluation in the kinematic simulation — rollouts of tasks ×
//! methods in parallel, every rollout's audit log, tables (Markdown, JSON) and SVG plots.

use super::CliError;
use pacs_sim::eval::{
    self, EvalConfig, METHOD_NAMES, Rollout, Variant, markdown, summarize, svg_paths,
    svg_separation,
};
use pacs_sim::task::TaskKind;
use serde_json::{Value, json};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

/// Size of a rollout's audit log per simulated second (MB): 1000 robot and shield records of
/// ≈ 0.7 kB, measured on the sphere task's logs (5.0–5.5 MB for 7.2 s).
const LOG_MB_PER_SECOND: f64 = 0.75;

/// Arguments of `pacs simulate`.
#[derive(clap::Args, Debug)]
#[command(after_long_help = "\
Tasks (FR3 on a table top, H = 16 actions per chunk, h = 8 executed, Δt = 33 ms):
  sorting   pick a block, place it in a box; a person walks up and reaches across the table (SSM)
  handover  take a block from a person's (moving) hand, place it in the box (PFL hand)
  feeding   bring a fork to a seated person's mouth and withdraw it (PFL head, 1 mJ)
  sphere    pick and place while a 10 cm sphere rolls on the table (a dynamic object: SSM)
  crowded   sorting while a person reaches across, a second person (a passer-by) walks up and
            reaches across too, and two spheres roll on the table (SSM)

Methods:
  off                  intended chunk trajectories, never brake (unsafe reference)
  pacs                 PACS with the task's own constraints (SSM: sorting, sphere, crowded;
                       PFL: handover, feeding)
  pacs-ssm, pacs-pfl   PACS enforcing SSM / PFL
  single-action[-ssm|-pfl]  PACS planning each action as its own stop-at-target motion
  cbf                  control-barrier-function filter (clarabel QP, distance constraints)
  direct               no time parameterisation: each action sent as a target every Δt to a
                       jerk-limited controller (the paper's H4 speed baseline, no safety filter)

Metrics per task and method: Success, Safe Success (success without any violation), Safety Viol.
(fraction of 1 ms steps in violation, from the offline audit of the rollout against the true human
motion), violations at the sampled states, duration of successful rollouts, path deviation from the
demonstrations (rad), fraction of rollouts in which the policy left its training distribution.

Outputs in --out: summary.md, summary.json (rows), rollouts.json (every rollout), TASK-paths.svg
(tool paths coloured by speed, demonstrations shaded), TASK-separation.svg, logs/*.jsonl (audit
format v2, every person by id: human0, human1; check them with `pacs audit DIR/logs/*.jsonl`). Stdout: a JSON object with the
policy, the rows, the summary path, the plot paths and the log directory.

Policies (--policy): nearest (default; the hand-written nearest-neighbour stand-in), kernel
(kernel regression learned from the demonstrations, observing the last two timesteps),
kernel-paced (the same, also trained on the demonstrations replayed at 1/2 and 1/4 pace),
kernel-shield-paced (the same, also trained on the demonstrations replayed with the shield's
braking and resuming: one pause and one slow passage each, as pacs.lerobot.paced_replays).

Examples:
  pacs simulate --task sorting --method off,pacs,cbf --rollouts 20
  pacs simulate --task all --method all --rollouts 10 --seed 7 --out eval
  pacs simulate --task sorting --method direct,pacs --no-human   # H4 speed ablation")]
pub struct SimulateArgs {
    /// Tasks, comma-separated, or `all`.
    #[arg(long, value_name = "T[,T...]", default_value = "sorting")]
    pub task: String,
    /// Methods, comma-separated, or `all`.
    #[arg(
        long,
        value_name = "M[,M...]",
        default_value = "off,pacs,single-action,cbf"
    )]
    pub method: String,
    /// Rollouts per task and method (rollout i uses seed S + i for every method).
    #[arg(long, value_name = "N", default_value_t = 10)]
    pub rollouts: usize,
    /// Base seed (human motion, start configuration, camera noise).
    #[arg(long, value_name = "S", default_value_t = 1)]
    pub seed: u64,
    /// Output directory.
    #[arg(long, value_name = "DIR", default_value = "pacs-out/sim")]
    pub out: PathBuf,
    /// Keep people and objects far away (speed ablation).
    #[arg(long)]
    pub no_human: bool,
    /// How off, pacs and cbf-free chunk methods move across chunks: `stop` (each chunk planned
    /// to rest at its last waypoint, a new chunk every h·Δt) or `continuous` (time-optimised
    /// spline passing the last waypoint moving, the next chunk handed over as the robot
    /// reaches it). Single actions, direct and cbf are unaffected.
    #[arg(long, value_name = "MODE", default_value = "continuous", value_parser = ["continuous", "stop"])]
    pub chunk_motion: String,
    /// The policy stand-in: `nearest` (nearest demonstrated state from the joint angles, a
    /// phase cost, random drift beyond 0.12 rad from the data), `kernel` (kernel regression
    /// learned from the demonstrations, observing the last two timesteps and the sub-goals
    /// reached; its kernel width chosen by leave-one-demonstration-out cross-validation) or
    /// `kernel-paced` (the same, also trained on every demonstration replayed at 1/2 and 1/4
    /// of its pace) or `kernel-shield-paced` (the same, also trained on every demonstration
    /// replayed with the shield's braking and resuming: a pause, a slow passage).
    #[arg(long, value_name = "P", default_value = "nearest")]
    pub policy: String,
    /// Do not write per-rollout audit logs (each is a few MB).
    #[arg(long)]
    pub no_logs: bool,
    /// Worker threads (default: all cores).
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
    /// Every rollout's time limit in seconds (default: each task's own, 20 s; feeding 60 s).
    /// A rollout that has not reached all its sub-goals by then fails; its duration counts as
    /// the limit.
    #[arg(long, value_name = "SECONDS")]
    pub time_limit: Option<f64>,
}

fn parse_list<T: std::str::FromStr<Err = pacs_sim::UnknownName>>(
    s: &str,
    all: &[&str],
    what: &str,
) -> Result<Vec<T>, CliError> {
    let names: Vec<&str> = if s == "all" {
        all.to_vec()
    } else {
        s.split(',')
            .map(str::trim)
            .filter(|x| !x.is_empty())
            .collect()
    };
    if names.is_empty() {
        return Err(CliError::Input(format!("--{what}: empty list")));
    }
    if let Some(n) = names
        .iter()
        .enumerate()
        .find(|(i, n)| names[..*i].contains(n))
        .map(|(_, n)| *n)
    {
        return Err(CliError::Input(format!(
            "--{what}: `{n}` is given twice (its rollouts would count twice)"
        )));
    }
    names
        .into_iter()
        .map(|n| {
            n.parse::<T>()
                .map_err(|e| CliError::Input(format!("--{what}: {e}")))
        })
        .collect()
}

fn write(path: &Path, text: &str) -> Result<(), CliError> {
    std::fs::write(path, text)
        .map_err(|e| CliError::Output(format!("cannot write {}: {e}", path.display())))
}

/// Run `pacs simulate`.
pub fn run(args: &SimulateArgs) -> Result<Value, CliError> {
    let task_names: Vec<&str> = TaskKind::ALL.iter().map(|t| t.name()).collect();
    let tasks: Vec<TaskKind> = parse_list(&args.task, &task_names, "task")?;
    let mut variants: Vec<Variant> = parse_list(&args.method, &METHOD_NAMES, "method")?;
    let motion = if args.chunk_motion == "continuous" {
        pacs_shield::ChunkMotion::Continuous
    } else {
        pacs_shield::ChunkMotion::Stop
    };
    let policy: pacs_sim::eval::PolicyKind = args
        .policy
        .parse()
        .map_err(|e| CliError::Input(format!("--policy: {e}")))?;
    variants.iter_mut().for_each(|v| {
        v.motion = motion;
        v.policy = policy;
    });
    if args.rollouts == 0 {
        return Err(CliError::Input("--rollouts: must be at least 1".into()));
    }
    if args.threads == Some(0) {
        return Err(CliError::Input("--threads: must be at least 1".into()));
    }
    if let Some(t) = args.time_limit {
        eval::check_time_limit(t).map_err(|e| CliError::Input(format!("--time-limit: {e}")))?;
    }
    std::fs::create_dir_all(&args.out)
        .map_err(|e| CliError::Output(format!("cannot create {}: {e}", args.out.display())))?;
    let cfg = EvalConfig {
        tasks: tasks.clone(),
        variants,
        rollouts: args.rollouts,
        seed: args.seed,
        with_human: !args.no_human,
        log_dir: (!args.no_logs).then(|| args.out.join("logs")),
        record_every: 10,
        time_limit: args.time_limit,
    };
    let total = (cfg.tasks.len() * cfg.variants.len() * cfg.rollouts) as u64;
    if let Some(dir) = &cfg.log_dir {
        // Upper bound: every rollout runs to its task's time limit.
        let seconds: f64 = tasks
            .iter()
            .map(|&t| {
                args.time_limit
                    .unwrap_or_else(|| pacs_sim::task::scenario(t, 0, true).max_time)
            })
            .sum::<f64>()
            * (cfg.variants.len() * cfg.rollouts) as f64;
        eprintln!(
            "pacs simulate: {total} rollouts; their audit logs take up to {:.0} MB in {} \
             (≈ {LOG_MB_PER_SECOND} MB per simulated second; --no-logs skips them)",
            seconds * LOG_MB_PER_SECOND,
            dir.display()
        );
    }
    let bar = indicatif::ProgressBar::new(total);
    if std::io::stderr().is_terminal() {
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "{spinner} simulate [{elapsed_precise}] {bar:40} {pos}/{len} rollouts (eta {eta}) {msg}",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
    } else {
        bar.set_draw_target(indicatif::ProgressDrawTarget::hidden());
    }
    let progress = |r: &Rollout| {
        bar.set_message(format!("{} {} #{}", r.task.name(), r.method, r.seed));
        bar.inc(1);
    };
    let pool = {
        let mut b = rayon::ThreadPoolBuilder::new();
        if let Some(n) = args.threads {
            b = b.num_threads(n);
        }
        b.build()
            .map_err(|e| CliError::Internal(format!("thread pool: {e}")))?
    };
    let rollouts = pool
        .install(|| eval::evaluate(&cfg, &progress))
        .map_err(|e| match e {
            eval::EvalError::Io { .. } => CliError::Output(e.to_string()),
            eval::EvalError::Input { .. } => CliError::Input(e.to_string()),
            other => CliError::Internal(other.to_string()),
        })?;
    bar.finish_and_clear();
    let rows = summarize(&rollouts);
    let mut md = format!(
        "# pacs simulate\n\nCommand: `pacs simulate --task {} --method {} --rollouts {} --seed {}{}{}{}`\n\n",
        args.task,
        args.method,
        args.rollouts,
        args.seed,
        if args.no_human { " --no-human" } else { "" },
        if args.chunk_motion == "stop" {
            " --chunk-motion stop"
        } else {
            ""
        },
        if args.policy == "nearest" {
            String::new()
        } else {
            format!(" --policy {}", args.policy)
        }
    );
    md.push_str(&markdown(&rows));
    write(&args.out.join("summary.md"), &md)?;
    let rows_json = serde_json::to_value(&rows).map_err(|e| CliError::Internal(e.to_string()))?;
    write(
        &args.out.join("summary.json"),
        &serde_json::to_string_pretty(&rows_json).unwrap_or_default(),
    )?;
    write(
        &args.out.join("rollouts.json"),
        &serde_json::to_string_pretty(&rollouts).unwrap_or_default(),
    )?;
    let mut plots = Vec::new();
    for &task in &tasks {
        // At most 5 rollouts per method in the plots, to keep them readable.
        let sel: Vec<&Rollout> = rollouts
            .iter()
            .filter(|r| r.task == task && r.seed < args.seed + 5)
            .collect();
        let p = args.out.join(format!("{}-paths.svg", task.name()));
        write(&p, &svg_paths(task, &sel))?;
        plots.push(p.display().to_string());
        let p = args.out.join(format!("{}-separation.svg", task.name()));
        write(&p, &svg_separation(task, &sel))?;
        plots.push(p.display().to_string());
    }
    if std::io::stderr().is_terminal() {
        eprintln!("{md}");
    }
    Ok(json!({
        "policy": args.policy,
        "rows": rows_json,
        "summary": args.out.join("summary.md").display().to_string(),
        "plots": plots,
        "logs": cfg.log_dir.map(|d| d.display().to_string()),
    }))
}
