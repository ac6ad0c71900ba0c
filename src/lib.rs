//! pacs: path-consistent safety filtering for action-chunking robot policies.
//!
//! One crate per job, each re-exported here under its job's name (`pacs::audit`, `pacs::shield`,
//! …), and the types a robotics engineer reaches for first at the root:
//!
//! ```no_run
//! use pacs::{AuditConfig, RobotModel, Verdict};
//! let fr3 = RobotModel::builtin("fr3").unwrap();
//! let run = pacs::audit::audit_file("run.jsonl".as_ref(), &AuditConfig::default()).unwrap();
//! assert_eq!(fr3.dof(), 7);
//! assert!(run.verdict == Verdict::Pass);
//! ```
//!
//! The shield between a policy and a robot, every safety step:
//!
//! ```
//! use pacs::motion::chunk::ActionKind;
//! use pacs::models::{default_human, fr3};
//! use pacs::{Chunk, ConstraintSpec, RobotModel, Shield};
//! let sorting = ConstraintSpec::builtin("sorting")?;
//! let mut shield = Shield::builder(RobotModel::builtin("fr3")?)
//!     .person(default_human(), &sorting)
//!     .build()?;
//! shield.start(0.0, &fr3::Q_READY)?;
//! let actions = vec![vec![0.01; 7]; 4]; // joint-position deltas (rad)
//! let chunk = Chunk { kind: ActionKind::Delta, actions, execute: 2, gripper: None };
//! shield.set_chunk(&chunk)?;
//! let cmd = shield.step(0.0, None)?; // no measurement of the person yet: the arm holds still
//! assert!(!cmd.diag.verified && cmd.dq().iter().all(|v| *v == 0.0));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
pub use pacs_audit as audit;
pub use pacs_baselines as baselines;
pub use pacs_log as log;
pub use pacs_mesh as mesh;
pub use pacs_models as models;
pub use pacs_motion as motion;
pub use pacs_reach as reach;
pub use pacs_replay as replay;
pub use pacs_reports as reports;
pub use pacs_shield as shield;
pub use pacs_sim as sim;
pub use pacs_verify as verify;

pub use pacs_audit::{AuditConfig, Auditor, RunResult, Verdict};
pub use pacs_log::{Header, LogError};
pub use pacs_models::{Capsule, ConstraintSpec, HumanModel, ObjectModel, RobotModel};
pub use pacs_motion::chunk::Chunk;
pub use pacs_shield::{
    Command, ReplanPolicy, Session, SessionError, Shield, ShieldBuilder, ShieldConfig, ShieldError,
};
