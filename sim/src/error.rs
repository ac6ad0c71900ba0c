//! [`SimError`]: why an episode could not run (not why it failed: a failed or unsafe episode is
//! a result).

use thiserror::Error;

/// Errors of running an episode.
#[derive(Debug, Error)]
pub enum SimError {
    /// The filter refused a model, the start or an input.
    #[error(transparent)]
    Filter(#[from] pacs_shield::shield::ShieldError),
    /// The measurement inbox refused a frame (or the filter refused a delivered one).
    #[error(transparent)]
    Delivery(#[from] pacs_shield::session::InboxError),
    /// A model of the scene is invalid (e.g. constraints that do not resolve for the person).
    #[error(transparent)]
    Model(#[from] pacs_models::ModelError),
    /// Writing the episode's log failed.
    #[error("log: {0}")]
    Log(#[from] pacs_log::WriteError),
    /// The ground-truth audit refused an input.
    #[error("ground-truth audit: {0}")]
    Audit(#[from] pacs_audit::AuditError),
}
