//! # pacs-mesh
//!
//! Capsules for robots whose URDF gives mesh collision geometry (most public robots):
//! - [`read`]: STL (binary and ASCII), Wavefront OBJ and COLLADA (`.dae`) files into vertices (m);
//! - [`fit`]: a capsule around a vertex set that **contains every vertex** (checked vertex by
//!   vertex after the fit, radius rounded outward), hence the vertices' convex hull, with its
//!   tightness (hull volume / capsule volume);
//! - [`urdf`]: every mesh collision of a URDF resolved (`package://` via package paths, relative
//!   paths against the URDF's directory), fitted, and written as side-file capsules the user can
//!   review (`pacs robot capsules`).
//!
//! Units: m, m³.

pub mod error;
pub mod fit;
pub mod read;
pub mod urdf;

pub use error::MeshError;
pub use fit::{FittedCapsule, fit_capsule};
pub use read::read_mesh;
