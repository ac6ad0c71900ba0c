//! The `pacs` command-line tool. See `docs/cli.md` for the exact input and output formats.

mod cli;

use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;

/// Path-consistent safety filtering for action-chunking robot policies (PACS).
///
/// All output is JSON on stdout; lengths in metres, angles in radians, times in seconds, energies
/// in joules. Invalid input prints a message naming the problem on stderr and exits with code 3.
#[derive(Parser)]
#[command(name = "pacs", version, about, long_about = None, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Forward kinematics: world-frame link capsules for each joint configuration.
    ///
    /// Input: {"robot": "fr3", "q": [[q1..q7], ...]} (rad).
    Fk {
        /// Input JSON file.
        #[arg(long, value_name = "FILE")]
        input: PathBuf,
    },
    /// Reachable occupancies of the robot (joint boxes), a human or a dynamic object (time
    /// intervals).
    #[command(subcommand)]
    Reach(ReachCommand),
    /// Robot models: print one as JSON (built-in or converted from a URDF), or fit capsules to a
    /// URDF's collision meshes.
    #[command(subcommand)]
    Robot(RobotCommand),
    /// Print a built-in human model as JSON (the format `"human"` inputs accept).
    #[command(subcommand)]
    Human(ShowCommand),
    /// Print a built-in dynamic object as JSON (the format `"object"` inputs accept).
    #[command(subcommand)]
    Object(ShowCommand),
    /// Run the built-in scenarios (Sorting/SSM, Handover/PFL) with PACS and with the filter OFF,
    /// audit the logs and write the certification report; print a summary.
    Demo {
        /// Output directory for logs and reports.
        #[arg(long, value_name = "DIR", default_value = "pacs-out/demo")]
        out: PathBuf,
    },
    /// Measure speed (use a release build: `cargo run --release -- bench shield`).
    #[command(subcommand)]
    Bench(BenchCommand),
    /// Time-parameterize an action chunk into a jerk-limited intended trajectory (optionally with a
    /// path-consistent failsafe).
    Trajectory {
        /// Input JSON file.
        #[arg(long, value_name = "FILE")]
        input: PathBuf,
        /// Also compute the failsafe (braking along the path) started at this time (s).
        #[arg(long, value_name = "T")]
        brake_at: Option<f64>,
    },
    /// Offline audit of logs against SSM/PFL: exit 0 all pass, 1 any fail, 2 any inconclusive
    /// (none fail), 3 invalid input. See docs/audit.md.
    Audit(cli::audit::AuditArgs),
    /// Run the shield on your own scene: robot, human, objects, constraints, timed chunks and
    /// timed measurements → the command of every safety step and an audit-format log.
    ///
    /// Writes DIR/commands.jsonl (one line per step: t, q, dq, ddq in rad, rad/s, rad/s²;
    /// verified, on_failsafe, binding, path_speed, stop_time, min_separation_m) and DIR/log.jsonl
    /// (`pacs audit DIR/log.jsonl` checks it); prints a summary. Scene format: docs/cli.md.
    /// Without --input: the built-in example (examples/scene.json: the FR3, a person walking up
    /// to the table, a rolling ball, six chunks). Exit 3 on invalid input, naming the field.
    #[command(after_help = "Examples:
  pacs shield                                   # the built-in example scene
  pacs shield --input examples/scene.json && pacs audit pacs-out/shield/log.jsonl")]
    Shield {
        /// Scene JSON file (default: built-in example).
        #[arg(long, value_name = "FILE")]
        input: Option<PathBuf>,
        /// Output directory for commands.jsonl and log.jsonl.
        #[arg(long, value_name = "DIR", default_value = "pacs-out/shield")]
        out: PathBuf,
    },
    /// Simulate the paper's evaluation: tasks × methods × rollouts in parallel, scored against
    /// the true people and objects; tables and SVG plots. Each rollout is also logged in the
    /// audit format (≈ 0.7 MB per simulated second; the disk needed is printed first;
    /// --no-logs skips the logs).
    Simulate(cli::simulate::SimulateArgs),
}

#[derive(Subcommand)]
enum BenchCommand {
    /// Time the shield in a 1 kHz loop: PACS-SSM and PACS-PFL on a fixed FR3 + walking-human
    /// scenario (a chunk every 200 ms), with continuous chunks, and with two objects. Prints per
    /// scenario the step's median, p90, p99, p99.9 and max (µs), the work time without the
    /// machine's noise, the steps over 50 µs, the slowest steps, and the loop's share of handing
    /// a chunk in (`set_chunk_*_us`).
    ///
    /// `work_*` is each step's fastest of three runs (itself and two re-runs on copies): what the
    /// step costs. `floor_*` is the machine's floor: after every step a loop that only reads the
    /// clock spins for the step's work time (plus the worker's poll) and is timed the same way; its p99.9, max and count
    /// over 50 µs are what the machine alone (interrupts, the host, other threads) does to a
    /// computation that long. Where `floor_steps_over_50_us` is about `steps_over_50_us` and
    /// `work_steps_over_50_us` is 0, the slow steps were the machine's, not the shield's.
    ///
    /// By default the chunks are planned on a planning thread (`ChunkWorker`, as a real-time
    /// loop must): the loop's share is a prediction and a send (`set_chunk_*`) and the offer
    /// before the step (inside the step's time); `planning_*_us` is the thread's planning time.
    /// `--in-loop` plans inside the loop instead (`Shield::set_chunk`). The PACS runs leave out
    /// the per-step separation figure (a diagnostic, config `separation_figure`), except the run
    /// whose name says "separation figure on".
    ///
    /// Example: `pacs bench shield --steps 1000000` (about 5.5 min on 2 cores).
    Shield {
        /// Number of 1 ms safety steps per scenario.
        #[arg(long, default_value_t = 100_000)]
        steps: usize,
        /// Safety steps between handing a chunk in and its handover (the planning thread's
        /// deadline: 1 ms each).
        #[arg(long, default_value_t = pacs_baselines::bench::BENCH_LEAD)]
        lead: usize,
        /// Plan every chunk inside the loop (`Shield::set_chunk`) instead of on the planning
        /// thread.
        #[arg(long)]
        in_loop: bool,
    },
    /// Time the control-barrier-function baseline (a QP per step) on the walking-human
    /// scenario: step and `set_chunk` figures as for `pacs bench shield`.
    Cbf {
        /// Number of 1 ms steps.
        #[arg(long, default_value_t = 20_000)]
        steps: usize,
    },
    /// Where the audit's time goes on your logs, on one thread (a sqlite3 bag's reader steps
    /// SQLite on a second one, as in `pacs audit`): reading the records alone (`read`), the
    /// whole audit (`audit`, as `pacs audit` per log), and for JSON Lines logs serde_json's
    /// syntax check of the same lines (`json_syntax`: no number converted, no record built), a
    /// reference for what a single JSON pass over the bytes costs on this machine. Prints per
    /// stage the fastest, median (for an even --runs the upper middle run) and slowest run (ms),
    /// robot samples per second and MB/s at the median, and `checker_ms_median` (audit minus
    /// read). The files are read through the page cache: run once to warm it, and pin the
    /// thread to a core for steady figures.
    ///
    /// Example: `taskset -c 0 pacs bench audit --runs 5 logs/*.jsonl`
    Audit {
        /// Log files or bag directories, as `pacs audit` takes them.
        #[arg(required = true)]
        logs: Vec<PathBuf>,
        /// MCAP logs and ROS 2 bags only: the pacs header (JSON, or TOML for `*.toml`), as
        /// `pacs audit --header`.
        #[arg(long)]
        header: Option<PathBuf>,
        /// How many times each stage runs (alternating: read, json_syntax, audit).
        #[arg(long, default_value_t = 5)]
        runs: usize,
    },
}

#[derive(Subcommand)]
enum ReachCommand {
    /// Capsules enclosing every link for every configuration in each joint box.
    ///
    /// Input: {"robot": "fr3", "boxes": [{"q_lo": [...], "q_hi": [...]}], "tracking_error": 0.0}
    /// (rad, m). Without --input: the built-in example (a ±0.01 rad box around the FR3 ready pose,
    /// examples/robot.json).
    Robot {
        /// Input JSON file (default: built-in example).
        #[arg(long, value_name = "FILE")]
        input: Option<PathBuf>,
    },
    /// Capsules enclosing every body part over each time interval after a measurement.
    ///
    /// Input: {"human": "default", "model": "combined"|"pos"|"vel"|"acc", "measurement": {"time": t,
    /// "positions": [[x,y,z], ...], "velocities": [[x,y,z], ...]}, "intervals": [[t_a, t_b], ...]}
    /// (m, m/s, s; absolute times). Without --input: the built-in example (default human in front
    /// of the robot, three intervals, examples/human.json).
    Human {
        /// Input JSON file (default: built-in example).
        #[arg(long, value_name = "FILE")]
        input: Option<PathBuf>,
    },
    /// A zonotope (plus radius) containing a dynamic object over each time interval after a
    /// measurement, with a bounding capsule.
    ///
    /// Input: {"object": "ball" | {"shape": {"sphere": {"radius": r}}, "max_acc": a, ...},
    /// "measurement": {"time": t, "position": [x,y,z], "velocity": [x,y,z]}, "intervals": [[t_a,
    /// t_b], ...]} (m, m/s, m/s², s; absolute times). Model: double integrator, accelerations in
    /// acc_bias + acc_generators + ball(max_acc), optional max_speed, measurement errors and delay
    /// (docs/cli.md). Without --input: the built-in example (the rolling ball,
    /// examples/object.json).
    Object {
        /// Input JSON file (default: built-in example).
        #[arg(long, value_name = "FILE")]
        input: Option<PathBuf>,
    },
}

#[derive(Subcommand)]
enum RobotCommand {
    /// Print a robot model as JSON (the format `--robot`/`"robot"` inputs accept): a built-in by
    /// name ("fr3"), or a URDF converted with its side file (`--urdf F [--side S]`). With both a
    /// name and `--urdf`, the URDF is printed and where it differs from the built-in (joint
    /// limits, joint count) is listed on stderr.
    ///
    /// Examples: `pacs robot show fr3`; `pacs robot show --urdf arm.urdf --side arm.toml`;
    /// `pacs robot show fr3 --urdf fr3.urdf --side fr3.toml` (differences on stderr).
    Show {
        /// Built-in model name (fr3).
        name: Option<String>,
        /// URDF file to convert.
        #[arg(long, value_name = "FILE")]
        urdf: Option<PathBuf>,
        /// Side file (JSON or TOML) with what the URDF lacks (capsules, acceleration/jerk limits).
        #[arg(long, value_name = "FILE", requires = "urdf")]
        side: Option<PathBuf>,
    },
    /// Fit capsules to a URDF's mesh collisions (STL, OBJ, COLLADA) and write them into a side
    /// file to review. Each capsule contains every vertex of its mesh (checked vertex by vertex,
    /// radius rounded outward), hence the mesh. Links that already have capsules in `--side`
    /// keep them; primitive collisions (box, cylinder, sphere) of a mesh link are kept as their
    /// containing capsules. Prints each fit with its tightness (convex hull volume / capsule
    /// volume) as JSON.
    ///
    /// `package://PKG/...` mesh paths are looked up under each `--package-path DIR` (DIR/PKG/...,
    /// or DIR/... when DIR is the package itself) and then under `ROS_PACKAGE_PATH`; other paths
    /// are relative to the URDF's directory.
    ///
    /// Example: `pacs robot capsules --urdf fr3.urdf --side fr3.toml --package-path ~/ws/src
    /// --out fr3_capsules.json`, then `pacs robot show --urdf fr3.urdf --side fr3_capsules.json`.
    Capsules {
        /// URDF file.
        #[arg(long, value_name = "FILE")]
        urdf: PathBuf,
        /// Side file to start from (JSON or TOML); its entries are kept.
        #[arg(long, value_name = "FILE")]
        side: Option<PathBuf>,
        /// Directory holding ROS packages (or a package itself); repeatable.
        #[arg(long = "package-path", value_name = "DIR")]
        package_path: Vec<PathBuf>,
        /// Write the side file here (JSON); without it the side file is part of the printed JSON.
        #[arg(long, value_name = "FILE")]
        out: Option<PathBuf>,
    },
}

#[derive(Subcommand)]
enum ShowCommand {
    /// Print the named built-in model (robot: "fr3"; human: "default"; object: "ball").
    Show {
        /// Model name.
        name: String,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Fk { input } => cli::fk::run(&input),
        Command::Reach(ReachCommand::Robot { input }) => cli::reach::run_robot(input.as_deref()),
        Command::Reach(ReachCommand::Human { input }) => cli::reach::run_human(input.as_deref()),
        Command::Reach(ReachCommand::Object { input }) => cli::reach::run_object(input.as_deref()),
        Command::Robot(RobotCommand::Show { name, urdf, side }) => {
            cli::show::robot(name.as_deref(), urdf.as_deref(), side.as_deref())
        }
        Command::Robot(RobotCommand::Capsules {
            urdf,
            side,
            package_path,
            out,
        }) => cli::capsules::run(&urdf, side.as_deref(), &package_path, out.as_deref()),
        Command::Human(ShowCommand::Show { name }) => cli::show::human(&name),
        Command::Object(ShowCommand::Show { name }) => cli::show::object(&name),
        Command::Trajectory { input, brake_at } => cli::trajectory::run(&input, brake_at),
        Command::Demo { out } => {
            use std::io::IsTerminal;
            cli::demo::run_demo(std::io::stderr().is_terminal(), &out)
        }
        Command::Bench(BenchCommand::Shield {
            steps,
            lead,
            in_loop,
        }) => {
            use std::io::IsTerminal;
            let delivery = if in_loop {
                pacs_baselines::bench::ChunkDelivery::InLoop
            } else {
                pacs_baselines::bench::ChunkDelivery::Worker { lead }
            };
            cli::bench::shield(steps, delivery, std::io::stderr().is_terminal())
        }
        Command::Bench(BenchCommand::Cbf { steps }) => cli::bench::cbf(steps),
        Command::Bench(BenchCommand::Audit { logs, header, runs }) => {
            use std::io::IsTerminal;
            let progress = std::io::stderr().is_terminal();
            cli::bench_audit::audit(&logs, header.as_deref(), runs, progress)
        }
        Command::Shield { input, out } => cli::shield::run(input.as_deref(), &out),
        Command::Audit(args) => return cli::audit::main(args),
        Command::Simulate(args) => cli::simulate::run(&args),
    };
    match result {
        Ok(value) => {
            let mut out = std::io::stdout().lock();
            if let Err(e) = serde_json::to_writer(&mut out, &value).and_then(|_| {
                use std::io::Write;
                writeln!(out).map_err(serde_json::Error::io)
            }) {
                eprintln!("pacs: cannot write output: {e}");
                return ExitCode::from(cli::EXIT_CANNOT_WRITE as u8);
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("pacs: error: {}", e.message());
            ExitCode::from(e.code() as u8)
        }
    }
}
