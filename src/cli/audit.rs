//! `pacs audit LOG... [--config task.toml] [--out DIR] [--json]`: offline SSM/PFL audit of logs,
//! in parallel, with an optional certification report. Exit codes: 0 all pass, 1 any fail,
//! 2 any inconclusive and none fail, 3 invalid input (any log or the config), 70 internal error.

use super::CliError;
use pacs_audit::{AuditConfig, RunResult, Verdict};
use pacs_log::LogError;
use pacs_reports::{InputFile, ReportInput};
use rayon::prelude::*;
use std::io::{IsTerminal, Write};
use std::path::PathBuf;
use std::process::ExitCode;

/// Arguments of `pacs audit`.
#[derive(clap::Args, Debug)]
pub struct AuditArgs {
    /// Log files (format v1, or v2 with up to 32 people: JSON Lines, CSV for `*.csv`, or MCAP of a ROS 2 recording, detected
    /// by its magic bytes or `*.mcap`; or a ROS 2 bag: `*.db3`, or a bag directory with
    /// metadata.yaml in the sqlite3 or the MCAP storage; see docs/log-format.md). Any other directory stands for its logs (*.jsonl,
    /// *.csv, *.mcap, *.db3 and bag directories, also in subdirectories), sorted by path
    /// (docs/fleet.md).
    #[arg(required = true, value_name = "LOG")]
    pub logs: Vec<PathBuf>,
    /// Audit settings (TOML: max_gap, max_human_age, rest_speed, human_model, tracking_error,
    /// limit_slack, and optional robot/human/constraints overrides; see docs/audit.md).
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// Write report.json, report.md and report.html into this directory.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Print `{"runs": [...]}` as JSON on stdout instead of a text summary.
    #[arg(long)]
    pub json: bool,
    /// Write a Foxglove replay of the (one) log here: an MCAP file with the robot and human
    /// capsules, their occupancies, violation markers and the separation/energy/threshold
    /// series, which Foxglove opens (topics in docs/audit.md).
    #[arg(long, value_name = "FILE.mcap")]
    pub scene: Option<PathBuf>,
    /// MCAP logs and ROS 2 bags only: the pacs header (JSON, or TOML for `*.toml`) instead of the
    /// logs' `pacs` metadata records (bags: their custom_data `pacs_header`). Among several logs
    /// (an archive mixing bags and JSON Lines), JSON Lines and CSV logs keep their own header;
    /// given alone with --header they are an input error.
    #[arg(long, value_name = "FILE")]
    pub header: Option<PathBuf>,
    /// MCAP logs and ROS 2 bags only: topic of the robot's sensor_msgs/msg/JointState (overrides the config's
    /// `mcap.robot_topic`; default /joint_states).
    #[arg(long, value_name = "TOPIC")]
    pub robot_topic: Option<String>,
    /// MCAP logs and ROS 2 bags only: topic of the human keypoints, geometry_msgs/msg/PoseArray (overrides the
    /// config's `mcap.human_topic`; default /human/keypoints).
    #[arg(long, value_name = "TOPIC")]
    pub human_topic: Option<String>,
}

/// Exit code for invalid input.
const EXIT_INVALID: u8 = 3;

fn load_config(args: &AuditArgs) -> Result<(AuditConfig, Option<InputFile>), CliError> {
    let invalid = |m: String| CliError::Input(m);
    let (mut cfg, hash) = match &args.config {
        None => (AuditConfig::default(), None),
        Some(p) => {
            let name = p.display().to_string();
            let text = std::fs::read_to_string(p)
                .map_err(|e| invalid(format!("{name}: cannot read: {e}")))?;
            let cfg = pacs_audit::parse_config(&name, &text).map_err(|e| invalid(e.to_string()))?;
            let hash = InputFile::hash(p).map_err(|e| invalid(e.to_string()))?;
            (cfg, Some(hash))
        }
    };
    if let Some(t) = &args.robot_topic {
        cfg.mcap.robot_topic.clone_from(t);
    }
    if let Some(t) = &args.human_topic {
        cfg.mcap.human_topic.clone_from(t);
    }
    cfg.validate()
        .map_err(|p| invalid(format!("invalid settings: {p}")))?;
    Ok((cfg, hash))
}

/// Run the audit; returns the process exit code.
pub fn main(args: AuditArgs) -> ExitCode {
    match run(args) {
        Ok(code) => code,
        Err(stop) => {
            if let Some(m) = stop.message {
                eprintln!("pacs: {m}");
            }
            ExitCode::from(stop.code)
        }
    }
}

/// Why the command stops early: what it prints after `pacs: ` (if not printed already) and its
/// exit code.
struct Stop {
    code: u8,
    message: Option<String>,
}

/// Invalid input (exit 3): `pacs: error: …`.
fn invalid(e: impl std::fmt::Display) -> Stop {
    Stop {
        code: EXIT_INVALID,
        message: Some(format!("error: {e}")),
    }
}

/// An output that cannot be written (exit 74): `pacs: cannot write <what>: …`.
fn cannot_write(what: &str, e: impl std::fmt::Display) -> Stop {
    Stop {
        code: super::EXIT_CANNOT_WRITE as u8,
        message: Some(format!("cannot write {what}: {e}")),
    }
}

/// The audit: its inputs checked, every log audited, the verdicts printed, the report and the
/// replay written; returns the exit code of the combined verdict.
fn run(mut args: AuditArgs) -> Result<ExitCode, Stop> {
    let listing = pacs_reports::fleet::list_logs(&args.logs).map_err(invalid)?;
    args.logs = listing.logs;
    let skipped: Vec<String> = listing
        .skipped
        .iter()
        .map(|p| p.display().to_string())
        .collect();
    if let Some(note) = pacs_reports::skipped_note(&skipped) {
        eprintln!("pacs: note: {note}");
    }
    let (cfg, cfg_file) = load_config(&args).map_err(|e| invalid(e.message()))?;
    if args.scene.is_some() && args.logs.len() != 1 {
        return Err(invalid(format!(
            "--scene writes the replay of one log; {} logs given",
            args.logs.len()
        )));
    }
    // A given header names itself in every run it is used for (`meta.header_file`, with its
    // SHA-256): the report says which header the verdict rests on.
    let header = match &args.header {
        None => None,
        Some(p) => {
            let mut h = pacs_log::mcap::load_header_file(p).map_err(invalid)?;
            let file = InputFile::hash(p).map_err(invalid)?;
            h.meta
                .insert("header_file".into(), p.display().to_string().into());
            h.meta
                .insert("header_file_sha256".into(), file.sha256.into());
            Some(h)
        }
    };
    if header.is_some() && args.logs.len() > 1 {
        eprintln!(
            "pacs: note: --header is the pacs header of every MCAP log and ROS 2 bag among these {} logs, replacing the header of one that carries its own; JSON Lines and CSV logs keep theirs",
            args.logs.len()
        );
    }
    // With a report: the logs' hashes before the audit, compared with those after it, so that a
    // report never binds a verdict to bytes that were not the ones audited.
    let hashed_before = match args.out {
        Some(_) => Some(hash_logs(&args.logs)?),
        None => None,
    };
    if let Some((a, b)) = hashed_before.as_deref().and_then(pacs_reports::same_bytes) {
        return Err(invalid(pacs_reports::same_bytes_message(a, b)));
    }
    let runs = audit_logs(&args.logs, &cfg, header.as_ref())?;
    let verdict = Verdict::combine(runs.iter().map(|r| r.verdict));
    print_runs(&runs, args.json).map_err(|e| cannot_write("output", e))?;
    if let Some(dir) = &args.out {
        let logs = hash_logs(&args.logs)?;
        for (before, after) in hashed_before.iter().flatten().zip(&logs) {
            if before.sha256 != after.sha256 {
                return Err(invalid(format!(
                    "{} changed while it was audited (sha256 {} before, {} after): no report written; audit it again",
                    after.path, before.sha256, after.sha256
                )));
            }
        }
        let input = ReportInput {
            runs: &runs,
            logs,
            config: cfg_file,
            settings: serde_json::to_value(&cfg).unwrap_or_default(),
            generated: pacs_reports::utc_now(),
            skipped,
        };
        pacs_reports::write_reports(dir, &input).map_err(|e| cannot_write("report", e))?;
        eprintln!("{}", report_written(dir, verdict));
    }
    if let Some(path) = &args.scene {
        write_scene(&args.logs[0], &cfg, header.as_ref(), &runs[0], path).map_err(
            |(code, e)| Stop {
                code,
                message: Some(e),
            },
        )?;
        eprintln!(
            "pacs: replay written: {} (open it in Foxglove)",
            path.display()
        );
    }
    Ok(ExitCode::from(verdict.exit_code()))
}

/// The SHA-256 of every log (what a report binds its verdicts to).
fn hash_logs(logs: &[PathBuf]) -> Result<Vec<InputFile>, Stop> {
    logs.iter()
        .map(|p| InputFile::hash(p))
        .collect::<Result<_, _>>()
        .map_err(invalid)
}

/// Whether `p` carries its own header (not [`pacs_log::takes_header`]). A file that cannot be
/// read is taken to need the given one: its audit names the problem.
fn carries_own_header(p: &std::path::Path) -> bool {
    !pacs_log::takes_header(p).unwrap_or(true)
}

/// Audit every log in parallel (a progress bar on a terminal); every log that cannot be read is
/// reported, then the command stops (exit 3).
fn audit_logs(
    logs: &[PathBuf],
    cfg: &AuditConfig,
    header: Option<&pacs_log::Header>,
) -> Result<Vec<RunResult>, Stop> {
    let bar = indicatif::ProgressBar::new(logs.len() as u64);
    if !std::io::stderr().is_terminal() {
        bar.set_draw_target(indicatif::ProgressDrawTarget::hidden());
    }
    let results: Vec<Result<RunResult, LogError>> = logs
        .par_iter()
        .map(|p| {
            // Among several logs a JSON Lines or CSV log keeps the header it carries (the given
            // one is for the archive's bags and MCAP logs); alone, the reader refuses the pair.
            let own = logs.len() > 1 && carries_own_header(p);
            let r = pacs_audit::audit_file_with_header(p, cfg, header.filter(|_| !own));
            bar.inc(1);
            r
        })
        .collect();
    bar.finish_and_clear();
    let mut runs = Vec::with_capacity(results.len());
    let mut refused = false;
    for r in results {
        match r {
            Ok(run) => runs.push(run),
            Err(e) => {
                eprintln!("pacs: error: {e}");
                refused = true;
            }
        }
    }
    if refused {
        return Err(Stop {
            code: EXIT_INVALID,
            message: None,
        });
    }
    Ok(runs)
}

/// Each run's verdict on stdout: a line per run, or (`json`) every run with its violation
/// episodes beside the intervals (as in report.json).
fn print_runs(runs: &[RunResult], json: bool) -> std::io::Result<()> {
    let mut out = std::io::stdout().lock();
    if json {
        let runs_json: Vec<serde_json::Value> = runs
            .iter()
            .map(|r| {
                let mut v = serde_json::to_value(r).unwrap_or_default();
                v["episodes"] =
                    serde_json::to_value(pacs_reports::episodes::episodes(&r.violations))
                        .unwrap_or_default();
                v
            })
            .collect();
        serde_json::to_writer(&mut out, &serde_json::json!({ "runs": runs_json }))
            .map_err(std::io::Error::from)?;
        return writeln!(out);
    }
    runs.iter().try_for_each(|r| {
        writeln!(
            out,
            "{}: {:?} — {} samples, {:.3} s, violation fraction {:.4}, {} violation episode(s) ({} interval(s)), {} inconclusive stretch(es) ({:.3} s not checked){}",
            r.log,
            r.verdict,
            r.metrics.samples,
            r.metrics.duration,
            r.metrics.violation_fraction,
            pacs_reports::episodes::episodes(&r.violations).len(),
            r.violations.len(),
            r.inconclusive.len(),
            r.metrics.inconclusive_duration,
            match r.evidence.completeness {
                pacs_audit::Completeness::Incomplete => format!(
                    "; INCOMPLETE log (incomplete_log): its samples run {:.3}–{:.3} s, and the start or end record its writer promised is missing or beyond them",
                    r.evidence.t_start, r.evidence.t_end
                ),
                pacs_audit::Completeness::NotPromised => format!(
                    "; completeness not promised by the log's writer: the samples run {:.3}–{:.3} s, whether that is the whole run cannot be told",
                    r.evidence.t_start, r.evidence.t_end
                ),
                pacs_audit::Completeness::EndOnly => {
                    "; end event reached, no start promised (a cut at the beginning cannot be told)".into()
                }
                pacs_audit::Completeness::Complete => String::new(),
            }
        )
    })
}

/// The Foxglove replay of `log` (audited as `run`) into `path`.
/// What `--out` says on stderr once the report is written: where, and the exit code to expect
/// (a failing run exits 1 although the report was written).
fn report_written(dir: &std::path::Path, verdict: Verdict) -> String {
    let d = dir.display();
    format!(
        "pacs: report written: {d}/report.html, {d}/report.pdf, {d}/report.md, {d}/report.json, {d}/violations.csv (overall verdict {}: exit {})",
        format!("{verdict:?}").to_uppercase(),
        verdict.exit_code()
    )
}

fn write_scene(
    log: &std::path::Path,
    cfg: &AuditConfig,
    header: Option<&pacs_log::Header>,
    run: &RunResult,
    path: &std::path::Path,
) -> Result<(), (u8, String)> {
    let invalid = |e: String| (EXIT_INVALID, format!("error: {e}"));
    let opts = pacs_replay::SceneOptions {
        human_model: cfg.human_model,
        tracking_error: cfg.tracking_error,
        ..Default::default()
    };
    // The log read as the audit read it (`pacs_log::read_log`): the scene is written afresh if
    // a bag is read again through its time index.
    pacs_log::read_log(
        log,
        &cfg.mcap,
        &cfg.overrides(),
        header,
        |reader| {
            let h = reader.header().with_overrides(&cfg.overrides());
            let models = pacs_log::LogModels::from_header(&h)
                .map_err(|e| pacs_replay::ReplayError::Model(e.to_string()))?;
            let file = std::fs::File::create(path)
                .map_err(|e| pacs_replay::ReplayError::Write(e.to_string()))?;
            pacs_replay::write_scene(reader, &models, run, std::io::BufWriter::new(file), &opts)
                .map(|_| ())
        },
        |e| {
            matches!(
                e,
                pacs_replay::ReplayError::Log(LogError::RowsNotInTimeOrder { .. })
            )
        },
    )
    .map_err(|e| match e {
        pacs_replay::ReplayError::Write(m) => (
            super::EXIT_CANNOT_WRITE as u8,
            format!("cannot write the scene {}: {m}", path.display()),
        ),
        other => invalid(other.to_string()),
    })
}
