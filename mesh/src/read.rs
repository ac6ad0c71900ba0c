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
    let doc = read_dae(path, s)?;
    check_up_axis(path, doc.up_axis.as_deref())?;
    let mut out = doc.scene_vertices(path)?;
    for p in &mut out {
        *p = Point3::from(p.coords * doc.unit);
    }
    Ok(out)
}

fn unsupported(path: &Path, what: String) -> MeshError {
    MeshError::Unsupported {
        path: path.to_path_buf(),
        what,
    }
}

/// What a COLLADA document says about its vertices, in file units.
struct Dae {
    /// Metres per file unit (`<unit meter>`, 1 if absent).
    unit: f64,
    up_axis: Option<String>,
    /// float_array id -> values.
    arrays: HashMap<String, Vec<f64>>,
    /// source id -> float_array id (`!stride N` for an accessor that is not 3 components).
    source_array: HashMap<String, String>,
    /// geometry id -> its POSITION source ids.
    geometry_positions: HashMap<String, Vec<String>>,
    /// Instanced geometry ids with their node transforms accumulated from the scene root.
    instances: Vec<(String, Matrix4<f64>)>,
}

/// A pass over a COLLADA document's XML: what it has read so far and where it is.
struct DaeReader<'p> {
    path: &'p Path,
    doc: Dae,
    /// Element stack (local names).
    stack: Vec<String>,
    cur_source: Option<String>,
    cur_array: Option<String>,
    cur_geometry: Option<String>,
    in_vertices: bool,
    /// Scene nodes: a stack of accumulated transforms.
    nodes: Vec<Node>,
    in_scene: bool,
    /// The transform or `up_axis` element whose text comes next.
    pending_text_for: Option<String>,
}

/// Read a COLLADA document's units, up axis, geometries and scene in one pass over its XML.
fn read_dae(path: &Path, s: &str) -> Result<Dae, MeshError> {
    let mut rd = Reader::from_str(s);
    rd.config_mut().trim_text(true);
    let mut st = DaeReader {
        path,
        doc: Dae {
            unit: 1.0,
            up_axis: None,
            arrays: HashMap::new(),
            source_array: HashMap::new(),
            geometry_positions: HashMap::new(),
            instances: Vec::new(),
        },
        stack: Vec::new(),
        cur_source: None,
        cur_array: None,
        cur_geometry: None,
        in_vertices: false,
        nodes: Vec::new(),
        in_scene: false,
        pending_text_for: None,
    };
    loop {
        let ev = rd.read_event().map_err(|e| {
            parse_err(
                path,
                format!("XML error at byte {}: {e}", rd.error_position()),
            )
        })?;
        match ev {
            Event::Start(ref e) | Event::Empty(ref e) => {
                st.start(e, matches!(ev, Event::Empty(_)))?;
            }
            Event::Text(t) => {
                let txt = t
                    .decode()
                    .map_err(|e| parse_err(path, format!("XML text: {e}")))?
                    .into_owned();
                st.text(&txt)?;
            }
            Event::End(e) => {
                let name = String::from_utf8_lossy(e.local_name().as_ref()).into_owned();
                st.end(&name);
            }
            Event::Eof => break,
            _ => {}
        }
    }
    Ok(st.doc)
}

impl DaeReader<'_> {
    /// An element opens (or is self-closing, `empty`: it opens nothing).
    fn start(
        &mut self,
        e: &quick_xml::events::BytesStart<'_>,
        empty: bool,
    ) -> Result<(), MeshError> {
        let path = self.path;
        let name = String::from_utf8_lossy(e.local_name().as_ref()).into_owned();
        // A self-closing element has no content and no end event: it opens nothing.
        let opens = !empty;
        let in_scene = self.in_scene;
        match name.as_str() {
            "unit" => {
                if let Some(m) = attr(e, b"meter") {
                    self.doc.unit = m.parse().map_err(|_| {
                        parse_err(path, format!("<unit meter=\"{m}\"> is not a number"))
                    })?;
                    if !(self.doc.unit.is_finite() && self.doc.unit > 0.0) {
                        return Err(parse_err(path, format!("<unit meter=\"{m}\">")));
                    }
                }
            }
            "geometry" if opens => self.cur_geometry = attr(e, b"id"),
            "source" if opens => self.cur_source = attr(e, b"id"),
            "float_array" if opens => self.cur_array = attr(e, b"id"),
            "accessor" => {
                if let (Some(src), Some(a)) = (&self.cur_source, attr(e, b"source")) {
                    let stride = attr(e, b"stride").unwrap_or_else(|| "1".into());
                    if stride != "3" {
                        // Only 3-component accessors are positions we read.
                        self.doc
                            .source_array
                            .insert(src.clone(), format!("!stride {stride}"));
                    } else {
                        self.doc
                            .source_array
                            .insert(src.clone(), a.trim_start_matches('#').to_string());
                    }
                }
            }
            "vertices" if opens => self.in_vertices = true,
            "input" if self.in_vertices => {
                if attr(e, b"semantic").as_deref() == Some("POSITION")
                    && let (Some(g), Some(src)) = (&self.cur_geometry, attr(e, b"source"))
                {
                    self.doc
                        .geometry_positions
                        .entry(g.clone())
                        .or_default()
                        .push(src.trim_start_matches('#').to_string());
                }
            }
            "visual_scene" if opens => {
                self.in_scene = true;
                self.nodes.clear();
                self.nodes.push(Node {
                    transform: Matrix4::identity(),
                });
            }
            "node" if in_scene && opens => {
                let parent = self
                    .nodes
                    .last()
                    .map_or(Matrix4::identity(), |n| n.transform);
                self.nodes.push(Node { transform: parent });
            }
            "instance_geometry" if in_scene => {
                let url = attr(e, b"url").unwrap_or_default();
                let t = self
                    .nodes
                    .last()
                    .map_or(Matrix4::identity(), |n| n.transform);
                self.doc
                    .instances
                    .push((url.trim_start_matches('#').to_string(), t));
            }
            "instance_node" if in_scene => {
                return Err(unsupported(
                    path,
                    "<instance_node> (node references)".into(),
                ));
            }
            "instance_controller" if in_scene => {
                return Err(unsupported(
                    path,
                    "<instance_controller> (skinned or morphed meshes)".into(),
                ));
            }
            "skew" | "lookat" if in_scene => {
                return Err(unsupported(path, format!("<{name}> node transforms")));
            }
            "matrix" | "translate" | "rotate" | "scale" if in_scene && opens => {
                self.pending_text_for = Some(name.clone());
            }
            "up_axis" if opens => self.pending_text_for = Some(name.clone()),
            _ => {}
        }
        if opens {
            self.stack.push(name);
        }
        Ok(())
    }

    /// Text inside the innermost open element: a float array's values, the up axis, or a node
    /// transform applied to the innermost node.
    fn text(&mut self, txt: &str) -> Result<(), MeshError> {
        let path = self.path;
        let top = self.stack.last().map(String::as_str).unwrap_or("");
        if top == "float_array" {
            if let Some(id) = &self.cur_array {
                self.doc.arrays.insert(
                    id.clone(),
                    floats(path, &format!("float_array `{id}`"), txt)?,
                );
            }
        } else if let Some(kind) = self.pending_text_for.take() {
            if kind == "up_axis" {
                self.doc.up_axis = Some(txt.trim().to_string());
            } else {
                let v = floats(path, &format!("<{kind}>"), txt)?;
                let m = node_transform(path, &kind, &v)?;
                if let Some(n) = self.nodes.last_mut() {
                    n.transform *= m;
                }
            }
        }
        Ok(())
    }

    /// The element `name` closes.
    fn end(&mut self, name: &str) {
        match name {
            "geometry" => self.cur_geometry = None,
            "source" => self.cur_source = None,
            "float_array" => self.cur_array = None,
            "vertices" => self.in_vertices = false,
            "node" if self.in_scene => {
                self.nodes.pop();
            }
            "visual_scene" => self.in_scene = false,
            _ => {}
        }
        self.pending_text_for = None;
        self.stack.pop();
    }
}

/// Only `Z_UP` is read: refuse other up axes and a missing one (COLLADA's default is `Y_UP`).
fn check_up_axis(path: &Path, up_axis: Option<&str>) -> Result<(), MeshError> {
    match up_axis {
        Some("Z_UP") => Ok(()),
        Some(a) => Err(unsupported(
            path,
            format!(
                "<up_axis>{a}</up_axis> (only Z_UP is read: tools disagree on how to rotate other axes; export with Z up or as STL)"
            ),
        )),
        None => Err(unsupported(
            path,
            "no <up_axis> (COLLADA's default is Y_UP, which tools rotate differently; export with <up_axis>Z_UP</up_axis> or as STL)".into(),
        )),
    }
}

impl Dae {
    /// The vertices (file units) of the instanced geometries through their node transforms;
    /// with no instance, every geometry in its own frame, by id.
    fn scene_vertices(&self, path: &Path) -> Result<Vec<Point3<f64>>, MeshError> {
        let mut out = Vec::new();
        if self.instances.is_empty() {
            // No scene: every geometry in its own frame.
            let mut ids: Vec<&String> = self.geometry_positions.keys().collect();
            ids.sort();
            for g in ids {
                out.extend(self.positions(path, g)?);
            }
        } else {
            for (g, t) in &self.instances {
                if !self.geometry_positions.contains_key(g) {
                    return Err(parse_err(
                        path,
                        format!("instance_geometry `#{g}` not found"),
                    ));
                }
                for p in self.positions(path, g)? {
                    out.push(Point3::from_homogeneous(t * p.to_homogeneous()).ok_or_else(
                        || parse_err(path, format!("node transform of `#{g}` is not affine")),
                    )?);
                }
            }
        }
        Ok(out)
    }

    /// The POSITION vertices (file units) of geometry `g`, in its own frame.
    fn positions(&self, path: &Path, g: &str) -> Result<Vec<Point3<f64>>, MeshError> {
        let mut out = Vec::new();
        for src in self.geometry_positions.get(g).into_iter().flatten() {
            let arr = self.source_array.get(src).ok_or_else(|| {
                parse_err(
                    path,
                    format!("geometry `{g}`: POSITION source `{src}` not found"),
                )
            })?;
            if let Some(stride) = arr.strip_prefix("!stride ") {
                return Err(unsupported(
                    path,
                    format!("geometry `{g}`: POSITION source `{src}` with stride {stride}"),
                ));
            }
            let v = self.arrays.get(arr.as_str()).ok_or_else(|| {
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
    }
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
