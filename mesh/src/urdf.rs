//! Capsules for a URDF's mesh collisions, written as side-file entries the user reviews
//! (`pacs robot capsules`).
//!
//! For every link with at least one `<collision><geometry><mesh>` and no capsules of its own in
//! the given side file: each mesh is resolved ([`crate::read::resolve`]), read, scaled by the
//! mesh's `scale`, placed by the collision `origin` in the link frame, and fitted
//! ([`crate::fit_capsule`]); the link's primitive collisions (boxes, cylinders, spheres) keep their
//! containing capsules. The side file's capsules replace the link's URDF collision geometry, so the
//! entry lists both. Every capsule contains every vertex of its mesh in the link frame (see
//! [`crate::fit`] for the guarantee and its margin).

use crate::error::MeshError;
use crate::fit::{FittedCapsule, fit_capsule};
use crate::read::{read_mesh, resolve};
use nalgebra::Point3;
use pacs_models::robot::PoseSpec;
use pacs_models::shape::CapsuleSpec;
use pacs_models::urdf::{SideFile, collision_capsules};
use std::path::{Path, PathBuf};

/// One fitted mesh collision.
#[derive(Debug, Clone)]
pub struct MeshFit {
    /// URDF link name.
    pub link: String,
    /// Index of the `<collision>` element in the link.
    pub collision: usize,
    /// The mesh file read.
    pub mesh: PathBuf,
    /// The capsule in the link frame.
    pub capsule: FittedCapsule,
}

/// Fit capsules to every mesh collision of the URDF at `urdf_path` whose link has no capsules
/// in `side`; returns `side` with those links' capsules added, and the fits (for the tightness
/// report). Mesh paths: `package://` under `package_paths`, others relative to the URDF's
/// directory.
pub fn fit_urdf_meshes(
    urdf_path: &Path,
    side: &SideFile,
    package_paths: &[PathBuf],
) -> Result<(SideFile, Vec<MeshFit>), MeshError> {
    let text = std::fs::read_to_string(urdf_path).map_err(|source| MeshError::Io {
        path: urdf_path.to_path_buf(),
        source,
    })?;
    let robot = urdf_rs::read_from_string(&text).map_err(|e| MeshError::Parse {
        path: urdf_path.to_path_buf(),
        what: format!("URDF: {e}"),
    })?;
    let base = urdf_path.parent().unwrap_or(Path::new("."));
    let mut out = side.clone();
    let mut fits = Vec::new();
    for link in &robot.links {
        let has_mesh = link
            .collision
            .iter()
            .any(|c| matches!(c.geometry, urdf_rs::Geometry::Mesh { .. }));
        let own = side
            .links
            .get(&link.name)
            .is_some_and(|l| l.capsules.is_some() || l.frame == Some(true));
        if !has_mesh || own {
            continue;
        }
        let mut caps: Vec<CapsuleSpec> = collision_capsules(link)?;
        for (ci, c) in link.collision.iter().enumerate() {
            let urdf_rs::Geometry::Mesh { filename, scale } = &c.geometry else {
                continue;
            };
            let field = format!("link `{}` collision[{ci}]", link.name);
            let path = resolve(filename, base, package_paths).map_err(|e| MeshError::Resolve {
                what: format!("{field}: {e}"),
            })?;
            let s = scale.as_ref().map_or([1.0; 3], |v| [v[0], v[1], v[2]]);
            if !s.iter().all(|x| x.is_finite()) {
                return Err(MeshError::Parse {
                    path: urdf_path.to_path_buf(),
                    what: format!("{field}: mesh scale {s:?} is not finite"),
                });
            }
            let pose = PoseSpec {
                xyz: *c.origin.xyz,
                rpy: *c.origin.rpy,
            };
            if !pose.xyz.iter().chain(&pose.rpy).all(|x| x.is_finite()) {
                return Err(MeshError::Parse {
                    path: urdf_path.to_path_buf(),
                    what: format!("{field}: origin is not finite"),
                });
            }
            let iso = pose.to_isometry();
            let pts: Vec<Point3<f64>> = read_mesh(&path)?
                .into_iter()
                .map(|p| iso * Point3::new(p.x * s[0], p.y * s[1], p.z * s[2]))
                .collect();
            let fit = fit_capsule(&pts, &path.display().to_string())?;
            caps.push(CapsuleSpec {
                p1: fit.p1.coords.into(),
                p2: fit.p2.coords.into(),
                radius: fit.radius,
            });
            fits.push(MeshFit {
                link: link.name.clone(),
                collision: ci,
                mesh: path,
                capsule: fit,
            });
        }
        let entry = out.links.entry(link.name.clone()).or_default();
        entry.capsules = Some(caps);
    }
    Ok((out, fits))
}
