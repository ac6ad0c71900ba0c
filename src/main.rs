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
    /// Reachable occupancies of the robot (joint boxes) or of a human (time intervals).
    #[command(subcommand)]
    Reach(ReachCommand),
    /// Print a built-in robot model as JSON (the format `--robot`/`"robot"` inputs accept).
    #[command(subcommand)]
    Robot(ShowCommand),
    /// Print a built-in human model as JSON (the format `"human"` inputs accept).
    #[command(subcommand)]
    Human(ShowCommand),
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
}

#[derive(Subcommand)]
enum ReachCommand {
    /// Capsules enclosing every link for every configuration in each joint box.
    ///
    /// Input: {"robot": "fr3", "boxes": [{"q_lo": [...], "q_hi": [...]}], "tracking_error": 0.0}.
    Robot {
        /// Input JSON file.
        #[arg(long, value_name = "FILE")]
        input: PathBuf,
    },
    /// Capsules enclosing every body part over each time interval after a measurement.
    ///
    /// Input: {"human": "default", "model": "combined"|"pos"|"vel"|"acc", "measurement": {"time": t,
    /// "positions": [[x,y,z], ...], "velocities": [[x,y,z], ...]}, "intervals": [[t_a, t_b], ...]}.
    Human {
        /// Input JSON file.
        #[arg(long, value_name = "FILE")]
        input: PathBuf,
    },
}

#[derive(Subcommand)]
enum ShowCommand {
    /// Print the named built-in model (robot: "fr3"; human: "default").
    Show {
        /// Model name.
        name: String,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Fk { input } => cli::fk::run(&input),
        Command::Reach(ReachCommand::Robot { input }) => cli::reach::run_robot(&input),
        Command::Reach(ReachCommand::Human { input }) => cli::reach::run_human(&input),
        Command::Robot(ShowCommand::Show { name }) => cli::show::robot(&name),
        Command::Human(ShowCommand::Show { name }) => cli::show::human(&name),
        Command::Trajectory { input, brake_at } => cli::trajectory::run(&input, brake_at),
        Command::Audit(args) => return cli::audit::main(args),
    };
    match result {
        Ok(value) => {
            let mut out = std::io::stdout().lock();
            if let Err(e) = serde_json::to_writer(&mut out, &value).and_then(|_| {
                use std::io::Write;
                writeln!(out).map_err(serde_json::Error::io)
            }) {
                eprintln!("pacs: cannot write output: {e}");
                return ExitCode::from(74);
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("pacs: error: {}", e.message());
            ExitCode::from(e.code() as u8)
        }
    }
}
