//! Mesh files into vertex lists (in the file's own frame, scaled to metres where the format
//! says its unit). Every vertex the file defines is returned, also ones no face uses: a capsule
//! around more points is still a capsule around the mesh.
//!
//! Formats, chosen by extension (case-insensitive):
//! - **STL** (`.stl`): binary (80-byte header, triangle count, 50 bytes per triangle) or ASCII
//!   (`vertex x y z` lines); a file whose size matches the binary layout is read as binary even
//!   if its header starts with `solid` (exporters do that).
//! - **OBJ** (`.obj`): `v x y z [w]` lines (a `w` ≠ 1 divides the position); `v x y z r g b [a]`
//!   lines (vertex colours) are positions with colours.
//! - **COLLADA** (`.dae`): the `POSITION` sources of every geometry instanced in the visual scene,
//!   through the scene's node transforms (`matrix`, `translate`, `rotate`, `scale`), scaled by
//!   `<unit meter>`. Refused rather than guessed: an `up_axis` other than `Z_UP` (tools disagree on
//!   the rotation), `skew`/`lookat` transforms, `instance_node`, controllers (skinned meshes).

use crate::error::MeshError;
use nalgebra::{Matrix4, Point3, Rotation3, Unit, Vector3};
use quick_xml::Reader;
use quick_xml::events::Event;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Read the vertices (m, in the mesh file's frame) of an STL, OBJ or COLLADA file.
pub fn read_mesh(path: &Path) -> Result<Vec<Point3<f64>>, MeshError> {
    let bytes = std::fs::read(path).map_err(|source| MeshError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    let v = match ext.as_str() {
        "stl" => stl(path, &bytes)?,
        "obj" => obj(path, text(path, &bytes)?)?,
        "dae" => dae(path, text(path, &bytes)?)?,
        _ => {
            return Err(MeshError::Unsupported {
                path: path.to_path_buf(),
                what: format!(
                    "mesh format `.{ext}` (read: .stl, .obj, .dae; convert others to STL)"
                ),
            });
        }
    };
    if v.is_empty() {
        return Err(MeshError::Empty {
            path: path.to_path_buf(),
        });
    }
    if let Some(p) = v.iter().find(|p| !p.iter().all(|x| x.is_finite())) {
        return Err(MeshError::Parse {
            path: path.to_path_buf(),
            what: format!("a vertex is not finite: {:?}", p.coords.as_slice()),
        });
    }
    Ok(v)
}

fn text<'a>(path: &Path, bytes: &'a [u8]) -> Result<&'a str, MeshError> {
    std::str::from_utf8(bytes).map_err(|e| MeshError::Parse {
        path: path.to_path_buf(),
        what: format!("not UTF-8 text: {e}"),
    })
}

fn parse_err(path: &Path, what: String) -> MeshError {
    MeshError::Parse {
        path: path.to_path_buf(),
        what,
    }
}

/// STL, binary or ASCII.
pub fn stl(path: &Path, bytes: &[u8]) -> Result<Vec<Point3<f64>>, MeshError> {
    if bytes.len() >= 84 {
        let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
        if n.checked_mul(50).and_then(|b| b.checked_add(84)) == Some(bytes.len()) {
            let mut out = Vec::with_capacity(3 * n);
            for t in 0..n {
                let base = 84 + 50 * t + 12; // after the normal
                for k in 0..3 {
                    let f = |j: usize| {
                        let o = base + 12 * k + 4 * j;
                        f32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]])
                            as f64
                    };
                    out.push(Point3::new(f(0), f(1), f(2)));
                }
            }
            return Ok(out);
        }
    }
    let Ok(s) = std::str::from_utf8(bytes) else {
        return Err(parse_err(
            path,
            format!(
                "neither binary STL ({} bytes do not match 84 + 50 × the triangle count) nor ASCII STL (not text)",
                bytes.len()
            ),
        ));
    };
    if !s.trim_start().starts_with("solid") {
        return Err(parse_err(
            path,
            "neither binary STL (size does not match its triangle count) nor ASCII STL (no `solid`)"
                .into(),
        ));
    }
    let mut out = Vec::new();
    for (ln, line) in s.lines().enumerate() {
        let mut it = line.split_whitespace();
        if it.next() != Some("vertex") {
            continue;
        }
        out.push(three(path, ln + 1, &mut it, "vertex")?);
    }
    Ok(out)
}

fn three<'a>(
    path: &Path,
    line: usize,
    it: &mut impl Iterator<Item = &'a str>,
    what: &str,
) -> Result<Point3<f64>, MeshError> {
    let mut c = [0.0; 3];
    for (i, x) in c.iter_mut().enumerate() {
        let tok = it.next().ok_or_else(|| {
            parse_err(
                path,
                format!("line {line}: `{what}` needs 3 coordinates, has {i}"),
            )
        })?;
        *x = tok.parse().map_err(|_| {
            parse_err(
                path,
                format!("line {line}: `{what}` coordinate `{tok}` is not a number"),
            )
        })?;
    }
    Ok(Point3::from(c))
}

/// Wavefront OBJ vertices.
pub fn obj(path: &Path, s: &str) -> Result<Vec<Point3<f64>>, MeshError> {
    let mut out = Vec::new();
    for (ln, line) in s.lines().enumerate() {
        let mut it = line.split_whitespace();
        if it.next() != Some("v") {
            continue;
        }
        let p = three(path, ln + 1, &mut it, "v")?;
        // `v x y z`, `v x y z w` (homogeneous weight), or `v x y z r g b [a]` (vertex colours,
        // as MeshLab writes them: not a weight).
        let rest: Vec<&str> = it.collect();
        let w = match rest.len() {
            0 | 3 | 4 => 1.0,
            1 => rest[0].parse::<f64>().map_err(|_| {
                parse_err(
                    path,
                    format!("line {}: `v` weight `{}` is not a number", ln + 1, rest[0]),
                )
            })?,
            k => {
                return Err(parse_err(
                    path,
                    format!(
                        "line {}: `v` has {k} numbers after x y z (expected none, a weight, or an r g b [a] colour)",
                        ln + 1
                    ),
                ));
            }
        };
        if !(w.is_finite() && w != 0.0) {
            return Err(parse_err(path, format!("line {}: `v` weight {w}", ln + 1)));
        }
        out.push(Point3::from(p.coords / w));
    }
    Ok(out)
}

/// A scene node: its transform accumulated from the scene root.
#[derive(Debug, Default, Clone)]
struct Node {
    transform: Matrix4<f64>,
}

fn floats(path: &Path, what: &str, s: &str) -> Result<Vec<f64>, MeshError> {
    s.split_whitespace()
        .map(|t| {
            t.parse::<f64>()
                .map_err(|_| parse_err(path, format!("{what}: `{t}` is not a number")))
        })
        .collect()
}

fn attr(e: &quick_xml::events::BytesStart<'_>, name: &[u8]) -> Option<String> {
    e.attributes()
        .flatten()
        .find(|a| a.key.as_ref() == name)
        .map(|a| String::from_utf8_lossy(&a.value).into_owned())
}

/// COLLADA: positions of the instanced geometries through the node transforms, in metres.
pub fn dae(path: &Path, s: &str) -> Result<Vec<Point3<f64>>, MeshError> {
    let unsupported = |what: String| MeshError::Unsupported {
        path: path.to_path_buf(),
        what,
    };
    let mut rd = Reader::from_str(s);
    rd.config_mut().trim_text(true);
    // Element stack (local names).
    let mut stack: Vec<String> = Vec::new();
    let mut unit = 1.0f64;
    let mut up_axis: Option<String> = None;
    // float_array id -> values; source id -> float_array id; vertices id -> source id
    let mut arrays: HashMap<String, Vec<f64>> = HashMap::new();
    let mut source_array: HashMap<String, String> = HashMap::new();
    let mut cur_source: Option<String> = None;
    let mut cur_array: Option<String> = None;
    let mut geometry_positions: HashMap<String, Vec<String>> = HashMap::new();
    let mut cur_geometry: Option<String> = None;
    let mut in_vertices = false;
    // Scene nodes: a stack of accumulated transforms; instanced geometries with their transform.
    let mut nodes: Vec<Node> = Vec::new();
    let mut instances: Vec<(String, Matrix4<f64>)> = Vec::new();
    let mut in_scene = false;
    let mut pending_text_for: Option<String> = None;
    loop {
        let ev = rd.read_event().map_err(|e| {
            parse_err(
                path,
                format!("XML error at byte {}: {e}", rd.error_position()),
            )
        })?;
        match ev {
            Event::Start(ref e) | Event::Empty(ref e) => {
                let empty = matches!(ev, Event::Empty(_));
                let name = String::from_utf8_lossy(e.local_name().as_ref()).into_owned();
                // A self-closing element has no content and no end event: it opens nothing.
                let opens = !empty;
                match name.as_str() {
                    "unit" => {
                        if let Some(m) = attr(e, b"meter") {
                            unit = m.parse().map_err(|_| {
                                parse_err(path, format!("<unit meter=\"{m}\"> is not a number"))
                            })?;
                            if !(unit.is_finite() && unit > 0.0) {
                                return Err(parse_err(path, format!("<unit meter=\"{m}\">")));
                            }
                        }
                    }
                    "geometry" if opens => cur_geometry = attr(e, b"id"),
                    "source" if opens => cur_source = attr(e, b"id"),
                    "float_array" if opens => cur_array = attr(e, b"id"),
                    "accessor" => {
                        if let (Some(src), Some(a)) = (&cur_source, attr(e, b"source")) {
                            let stride = attr(e, b"stride").unwrap_or_else(|| "1".into());
                            if stride != "3" {
                                // Only 3-component accessors are positions we read.
                                source_array.insert(src.clone(), format!("!stride {stride}"));
                            } else {
                                source_array
                                    .insert(src.clone(), a.trim_start_matches('#').to_string());
                            }
                        }
                    }
                    "vertices" if opens => in_vertices = true,
                    "input" if in_vertices => {
                        if attr(e, b"semantic").as_deref() == Some("POSITION")
                            && let (Some(g), Some(src)) = (&cur_geometry, attr(e, b"source"))
                        {
                            geometry_positions
                                .entry(g.clone())
                                .or_default()
                                .push(src.trim_start_matches('#').to_string());
                        }
                    }
                    "visual_scene" if opens => {
                        in_scene = true;
                        nodes.clear();
                        nodes.push(Node {
                            transform: Matrix4::identity(),
                        });
                    }
                    "node" if in_scene && opens => {
                        let parent = nodes.last().map_or(Matrix4::identity(), |n| n.transform);
                        nodes.push(Node { transform: parent });
                    }
                    "instance_geometry" if in_scene => {
                        let url = attr(e, b"url").unwrap_or_default();
                        let t = nodes.last().map_or(Matrix4::identity(), |n| n.transform);
                        instances.push((url.trim_start_matches('#').to_string(), t));
                    }
                    "instance_node" if in_scene => {
                        return Err(unsupported("<instance_node> (node references)".into()));
                    }
                    "instance_controller" if in_scene => {
                        return Err(unsupported(
                            "<instance_controller> (skinned or morphed meshes)".into(),
                        ));
                    }
                    "skew" | "lookat" if in_scene => {
                        return Err(unsupported(format!("<{name}> node transforms")));
                    }
                    "matrix" | "translate" | "rotate" | "scale" if in_scene && opens => {
                        pending_text_for = Some(name.clone());
                    }
                    "up_axis" if opens => pending_text_for = Some(name.clone()),
                    _ => {}
                }
                if opens {
                    stack.push(name);
                }
            }
            Event::Text(t) => {
                let txt = t
                    .decode()
                    .map_err(|e| parse_err(path, format!("XML text: {e}")))?
                    .into_owned();
                let top = stack.last().map(String::as_str).unwrap_or("");
                if top == "float_array" {
                    if let Some(id) = &cur_array {
                        arrays.insert(
                            id.clone(),
                            floats(path, &format!("float_array `{id}`"), &txt)?,
                        );
                    }
                } else if let Some(kind) = pending_text_for.take() {
                    if kind == "up_axis" {
                        up_axis = Some(txt.trim().to_string());
                    } else {
                        let v = floats(path, &format!("<{kind}>"), &txt)?;
                        let m = node_transform(path, &kind, &v)?;
                        if let Some(n) = nodes.last_mut() {
                            n.transform *= m;
                        }
                    }
                }
            }
            Event::End(e) => {
                let name = String::from_utf8_lossy(e.local_name().as_ref()).into_owned();
                match name.as_str() {
                    "geometry" => cur_geometry = None,
                    "source" => cur_source = None,
                    "float_array" => cur_array = None,
                    "vertices" => in_vertices = false,
                    "node" if in_scene => {
                        nodes.pop();
                    }
                    "visual_scene" => in_scene = false,
                    _ => {}
                }
                pending_text_for = None;
                stack.pop();
            }
            Event::Eof => break,
            _ => {}
        }
    }
    match up_axis.as_deref() {
        Some("Z_UP") => {}
        Some(a) => {
            return Err(unsupported(format!(
                "<up_axis>{a}</up_axis> (only Z_UP is read: tools disagree on how to rotate other axes; export with Z up or as STL)"
            )));
        }
        None => {
            return Err(unsupported(
                "no <up_axis> (COLLADA's default is Y_UP, which tools rotate differently; export with <up_axis>Z_UP</up_axis> or as STL)".into(),
            ));
        }
    }
    let positions = |g: &str| -> Result<Vec<Point3<f64>>, MeshError> {
        let mut out = Vec::new();
        for src in geometry_positions.get(g).into_iter().flatten() {
            let arr = source_array.get(src).ok_or_else(|| {
                parse_err(
                    path,
                    format!("geometry `{g}`: POSITION source `{src}` not found"),
                )
            })?;
            if let Some(stride) = arr.strip_prefix("!stride ") {
                return Err(unsupported(format!(
                    "geometry `{g}`: POSITION source `{src}` with stride {stride}"
                )));
            }
            let v = arrays.get(arr.as_str()).ok_or_else(|| {
                parse_err(
                    path,
                    format!("geometry `{g}`: float_array `{arr}` not found"),
                )
            })?;
            if v.len() % 3 != 0 {
                return Err(parse_err(
                    path,
                    format!(
                        "float_array `{arr}`: {} values, not a multiple of 3",
                        v.len()
                    ),
                ));
            }
            out.extend(v.chunks_exact(3).map(|c| Point3::new(c[0], c[1], c[2])));
        }
        Ok(out)
    };
    let mut out = Vec::new();
    if instances.is_empty() {
        // No scene: every geometry in its own frame.
        let mut ids: Vec<&String> = geometry_positions.keys().collect();
        ids.sort();
        for g in ids {
            out.extend(positions(g)?);
        }
    } else {
        for (g, t) in &instances {
            if !geometry_positions.contains_key(g) {
                return Err(parse_err(
                    path,
                    format!("instance_geometry `#{g}` not found"),
                ));
            }
            for p in positions(g)? {
                out.push(
                    Point3::from_homogeneous(t * p.to_homogeneous()).ok_or_else(|| {
                        parse_err(path, format!("node transform of `#{g}` is not affine"))
                    })?,
                );
            }
        }
    }
    for p in &mut out {
        *p = Point3::from(p.coords * unit);
    }
    Ok(out)
}

/// One COLLADA node transform element as a 4×4 matrix.
fn node_transform(path: &Path, kind: &str, v: &[f64]) -> Result<Matrix4<f64>, MeshError> {
    let need = match kind {
        "matrix" => 16,
        "rotate" => 4,
        _ => 3,
    };
    if v.len() != need {
        return Err(parse_err(
            path,
            format!("<{kind}> needs {need} numbers, has {}", v.len()),
        ));
    }
    Ok(match kind {
        // Row-major in the file.
        "matrix" => Matrix4::from_row_slice(v),
        "translate" => Matrix4::new_translation(&Vector3::new(v[0], v[1], v[2])),
        "scale" => Matrix4::new_nonuniform_scaling(&Vector3::new(v[0], v[1], v[2])),
        _ => {
            let axis = Vector3::new(v[0], v[1], v[2]);
            if axis.norm() == 0.0 {
                return Err(parse_err(path, "<rotate> with a zero axis".into()));
            }
            Rotation3::from_axis_angle(&Unit::new_normalize(axis), v[3].to_radians())
                .to_homogeneous()
        }
    })
}

/// Where `filename` (a URDF `<mesh filename>`) lives: `package://PKG/REST` under a package path
/// (`P/PKG/REST`, or `P/REST` when `P` is the package directory itself), `file://ABS`, or a
/// path relative to `base` (the URDF's directory).
pub fn resolve(
    filename: &str,
    base: &Path,
    package_paths: &[PathBuf],
) -> Result<PathBuf, MeshError> {
    if let Some(rest) = filename.strip_prefix("package://") {
        let (pkg, sub) = rest.split_once('/').unwrap_or((rest, ""));
        let mut tried = Vec::new();
        for p in package_paths {
            for cand in [p.join(pkg).join(sub), p.join(sub)] {
                if cand == p.join(sub) && p.file_name().and_then(|n| n.to_str()) != Some(pkg) {
                    continue;
                }
                if cand.is_file() {
                    return Ok(cand);
                }
                tried.push(cand.display().to_string());
            }
        }
        // The package is there but the file is not: say that, not "package not found".
        let found: Vec<PathBuf> = package_paths
            .iter()
            .flat_map(|p| [p.join(pkg), p.clone()])
            .filter(|d| d.file_name().and_then(|n| n.to_str()) == Some(pkg) && d.is_dir())
            .collect();
        if let Some(dir) = found.first() {
            return Err(MeshError::Resolve {
                what: format!(
                    "mesh `{filename}`: package `{pkg}` is at {}, but it has no file `{sub}` (no {})",
                    dir.display(),
                    dir.join(sub).display()
                ),
            });
        }
        return Err(MeshError::Resolve {
            what: format!(
                "mesh `{filename}`: package `{pkg}` not found under the package paths [{}] (give --package-path DIR or set ROS_PACKAGE_PATH){}",
                package_paths
                    .iter()
                    .map(|p| p.display().to_string())
                    .collect::<Vec<_>>()
                    .join(", "),
                if tried.is_empty() {
                    String::new()
                } else {
                    format!("; tried {}", tried.join(", "))
                }
            ),
        });
    }
    let p = match filename.strip_prefix("file://") {
        Some(abs) => PathBuf::from(abs),
        None => base.join(filename),
    };
    if p.is_file() {
        Ok(p)
    } else {
        Err(MeshError::Resolve {
            what: format!("mesh `{filename}`: no file {}", p.display()),
        })
    }
}
