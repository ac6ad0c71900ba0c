//! pacs: path-consistent safety filtering for action-chunking robot policies.
pub use pacs_audit as audit;
pub use pacs_log as log;
pub use pacs_models as models;
pub use pacs_motion as motion;
pub use pacs_reach as reach;
pub use pacs_shield as shield;
pub use pacs_verify as verify;
