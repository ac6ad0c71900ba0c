//! `pacs robot capsules`: capsules fitted to a URDF's collision meshes, written as a side file.

use super::{CliError, read_file};
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

/// Fit, write the side file (or embed it), and report each fit with its tightness.
pub fn run(
    urdf: &Path,
    side: Option<&Path>,
    package_paths: &[PathBuf],
    out: Option<&Path>,
) -> Result<Value, CliError> {
    let side_file = match side {
        Some(p) => pacs_models::urdf::SideFile::parse(&read_file(p)?)
            .map_err(|e| CliError::Input(format!("{}: {e}", p.display())))?,
        None => Default::default(),
    };
    let mut paths = package_paths.to_vec();
    if let Some(env) = std::env::var_os("ROS_PACKAGE_PATH") {
        paths.extend(std::env::split_paths(&env));
    }
    let (fitted, fits) = pacs_mesh::urdf::fit_urdf_meshes(urdf, &side_file, &paths)
        .map_err(|e| CliError::Input(e.to_string()))?;
    let side_json = serde_json::to_value(&fitted).map_err(|e| CliError::Internal(e.to_string()))?;
    // What the written side file still lacks for `pacs robot show --urdf … --side …` to accept it.
    let gaps = pacs_models::urdf::side_file_gaps(&read_file(urdf)?, &fitted)
        .map_err(|e| CliError::Input(format!("{}: {e}", urdf.display())))?;
    if let Some(o) = out {
        if let Some(dir) = o.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir)
                .map_err(|e| CliError::Output(format!("cannot create {}: {e}", dir.display())))?;
        }
        let text = serde_json::to_string_pretty(&side_json)
            .map_err(|e| CliError::Internal(e.to_string()))?;
        std::fs::write(o, text + "\n")
            .map_err(|e| CliError::Output(format!("cannot write {}: {e}", o.display())))?;
    }
    let rows: Vec<Value> = fits
        .iter()
        .map(|f| {
            let c = &f.capsule;
            json!({
                "link": f.link,
                "collision": f.collision,
                "mesh": f.mesh.display().to_string(),
                "vertices": c.vertices,
                "p1": [c.p1.x, c.p1.y, c.p1.z],
                "p2": [c.p2.x, c.p2.y, c.p2.z],
                "radius_m": c.radius,
                "length_m": (c.p2 - c.p1).norm(),
                "max_vertex_distance_m": c.max_distance,
                "hull_volume_m3": c.hull_volume,
                "capsule_volume_m3": c.capsule_volume,
                "tightness": c.tightness(),
            })
        })
        .collect();
    let t: Vec<f64> = fits.iter().map(|f| f.capsule.tightness()).collect();
    let mut report = json!({
        "urdf": urdf.display().to_string(),
        "fits": rows,
        "tightness": {
            "min": t.iter().copied().fold(f64::INFINITY, f64::min).min(1.0),
            "mean": if t.is_empty() { 0.0 } else { t.iter().sum::<f64>() / t.len() as f64 },
        },
    });
    report["loads"] = json!(gaps.is_empty());
    report["missing"] = json!(gaps);
    let written = match out {
        Some(o) => {
            report["side_file"] = json!(o.display().to_string());
            o.display().to_string()
        }
        None => {
            report["side"] = side_json;
            "the side file (`side` below)".to_string()
        }
    };
    if !gaps.is_empty() {
        eprintln!(
            "{written}: `pacs robot show` needs {} more key{} there:",
            gaps.len(),
            if gaps.len() == 1 { "" } else { "s" }
        );
        for g in &gaps {
            eprintln!("  {}: {}", g.key, g.why);
        }
    }
    Ok(report)
}
