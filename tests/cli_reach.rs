//! End-to-end tests of the CLI contract: `pacs fk`, `pacs reach robot|human`, `pacs robot|human show`.

use serde_json::{Value, json};
use std::io::Write;
use std::process::{Command, Output};

fn pacs(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pacs"))
        .args(args)
        .output()
        .expect("run pacs")
}

fn with_input(sub: &[&str], input: &Value) -> Output {
    let mut f = tempfile_path();
    f.write_all(input.to_string().as_bytes()).unwrap();
    let path = f.path.clone();
    let mut args: Vec<&str> = sub.to_vec();
    args.push("--input");
    args.push(&path);
    pacs(&args)
}

struct TempFile {
    path: String,
    file: std::fs::File,
}
impl Write for TempFile {
    fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
        self.file.write(b)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.file.flush()
    }
}
impl Drop for TempFile {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}
fn tempfile_path() -> TempFile {
    use std::sync::atomic::{AtomicUsize, Ordering};
    static N: AtomicUsize = AtomicUsize::new(0);
    let path = std::env::temp_dir()
        .join(format!(
            "pacs-cli-test-{}-{}.json",
            std::process::id(),
            N.fetch_add(1, Ordering::SeqCst)
        ))
        .to_string_lossy()
        .into_owned();
    let file = std::fs::File::create(&path).unwrap();
    TempFile { path, file }
}

fn ok_json(out: Output) -> Value {
    assert!(
        out.status.success(),
        "exit {:?}, stderr: {}",
        out.status.code(),
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("stdout is JSON")
}

fn invalid(out: Output, needle: &str) {
    assert_eq!(
        out.status.code(),
        Some(3),
        "stderr: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains(needle),
        "stderr `{err}` should mention `{needle}`"
    );
    assert!(!err.contains("panicked"), "{err}");
}

use std::f64::consts::{FRAC_PI_2, FRAC_PI_4};
const Q_READY: [f64; 7] = [
    0.0,
    -FRAC_PI_4,
    0.0,
    -3.0 * FRAC_PI_4,
    0.0,
    FRAC_PI_2,
    FRAC_PI_4,
];

#[test]
fn fk_reports_flange_at_reference_position() {
    let v = ok_json(with_input(
        &["fk"],
        &json!({"robot": "fr3", "q": [Q_READY]}),
    ));
    let links = &v["configurations"][0]["links"];
    let link7 = links
        .as_array()
        .unwrap()
        .iter()
        .find(|l| l["name"] == "fr3_link7")
        .unwrap();
    // link7's first capsule runs along its z axis (pointing down at q_ready) from z=-0.06 to 0.08:
    // the flange (z = 0.107 in link7) is at (0.3069, 0, 0.5903) per the reference.
    let p1 = link7["capsules"][0]["p1"].as_array().unwrap();
    let x = p1[0].as_f64().unwrap();
    let z = p1[2].as_f64().unwrap();
    assert!((x - 0.3069).abs() < 1e-4, "{x}");
    assert!((z - (0.5903 + 0.107 + 0.06)).abs() < 1e-4, "{z}");
    for l in links.as_array().unwrap() {
        for c in l["capsules"].as_array().unwrap() {
            assert!(c["radius"].as_f64().unwrap() > 0.0);
            assert_eq!(c["p1"].as_array().unwrap().len(), 3);
        }
    }
}

#[test]
fn reach_robot_contains_fk_of_box_corners() {
    let lo: Vec<f64> = Q_READY.iter().map(|q| q - 0.05).collect();
    let hi: Vec<f64> = Q_READY.iter().map(|q| q + 0.05).collect();
    let v = ok_json(with_input(
        &["reach", "robot"],
        &json!({"robot": "fr3", "boxes": [{"q_lo": lo, "q_hi": hi}], "tracking_error": 0.01}),
    ));
    let occ = &v["boxes"][0]["links"];
    let corner: Vec<f64> = (0..7)
        .map(|i| if i % 2 == 0 { lo[i] } else { hi[i] })
        .collect();
    let fk = ok_json(with_input(&["fk"], &json!({"robot": "fr3", "q": [corner]})));
    let pt = |v: &Value| -> [f64; 3] {
        [
            v[0].as_f64().unwrap(),
            v[1].as_f64().unwrap(),
            v[2].as_f64().unwrap(),
        ]
    };
    for (l, lf) in occ
        .as_array()
        .unwrap()
        .iter()
        .zip(fk["configurations"][0]["links"].as_array().unwrap())
    {
        assert_eq!(l["name"], lf["name"]);
        for (c, cf) in l["capsules"]
            .as_array()
            .unwrap()
            .iter()
            .zip(lf["capsules"].as_array().unwrap())
        {
            // Both endpoints of the FK capsule (with its radius and the tracking error) lie within
            // the occupancy capsule's radius of its axis: check endpoint distances to the axis.
            let (a, b, r) = (pt(&c["p1"]), pt(&c["p2"]), c["radius"].as_f64().unwrap());
            for e in [pt(&cf["p1"]), pt(&cf["p2"])] {
                let d = seg_dist(e, a, b);
                assert!(
                    d + cf["radius"].as_f64().unwrap() + 0.01 <= r + 1e-12,
                    "{} {d} vs {r}",
                    l["name"]
                );
            }
        }
    }
}

fn seg_dist(p: [f64; 3], a: [f64; 3], b: [f64; 3]) -> f64 {
    let ab = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let ap = [p[0] - a[0], p[1] - a[1], p[2] - a[2]];
    let l2 = ab.iter().map(|x| x * x).sum::<f64>();
    let t = if l2 > 0.0 {
        (ap.iter().zip(&ab).map(|(x, y)| x * y).sum::<f64>() / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (0..3)
        .map(|i| (ap[i] - t * ab[i]).powi(2))
        .sum::<f64>()
        .sqrt()
}

#[test]
fn reach_human_default_vel_hand_computed() {
    // vel model, default human (e_pos 0, v_max 2), interval [0, 0.1] after a measurement at 0:
    // every keypoint ball has radius 0.2; the head (ball, thickness 0.434) -> 0.2 + 0.217.
    let positions: Vec<[f64; 3]> = (0..9).map(|k| [1.0, 0.1 * k as f64, 1.0]).collect();
    let v = ok_json(with_input(
        &["reach", "human"],
        &json!({"human": "default", "model": "vel", "measurement": {"time": 0.0, "positions": positions}, "intervals": [[0.0, 0.1]]}),
    ));
    let parts = v["intervals"][0]["body_parts"].as_array().unwrap();
    assert_eq!(parts.len(), 8);
    let head = parts.iter().find(|p| p["name"] == "head").unwrap();
    let r = head["radius"].as_f64().unwrap();
    assert!((0.417..0.417 + 1e-12).contains(&r), "{r}");
    assert_eq!(v["intervals"][0]["t"], json!([0.0, 0.1]));
}

#[test]
fn reach_human_accepts_inline_model() {
    let human = json!({"keypoints": ["a", "b"], "v_max": [1.0, 1.0], "a_max": [5.0, 5.0],
        "body_parts": [{"name": "stick", "from": "a", "to": "b", "thickness": 0.1}],
        "measurement_error_pos": 0.01, "measurement_error_vel": 0.0, "delay": 0.02});
    let v = ok_json(with_input(
        &["reach", "human"],
        &json!({"human": human, "model": "vel", "measurement": {"time": 1.0, "positions": [[0,0,0],[1,0,0]]}, "intervals": [[1.0, 1.08]]}),
    ));
    // r = 0.01 + 1.0 * (0.08 + 0.02) + 0.05 = 0.16
    let r = v["intervals"][0]["body_parts"][0]["radius"]
        .as_f64()
        .unwrap();
    assert!((r - 0.16).abs() < 1e-12, "{r}");
}

#[test]
fn show_prints_loadable_models() {
    let robot = ok_json(pacs(&["robot", "show", "fr3"]));
    assert_eq!(robot["joints"].as_array().unwrap().len(), 7);
    // The printed robot is accepted back as an inline model.
    let v = ok_json(with_input(
        &["fk"],
        &json!({"robot": robot, "q": [Q_READY]}),
    ));
    assert!(v["configurations"][0]["links"].as_array().unwrap().len() >= 8);
    let human = ok_json(pacs(&["human", "show", "default"]));
    assert_eq!(human["keypoints"].as_array().unwrap().len(), 9);
    let positions: Vec<[f64; 3]> = (0..9).map(|_| [0.0, 0.0, 0.0]).collect();
    ok_json(with_input(
        &["reach", "human"],
        &json!({"human": human, "model": "pos", "measurement": {"time": 0.0, "positions": positions}, "intervals": [[0.0, 0.1]]}),
    ));
}

#[test]
fn invalid_inputs_exit_3_with_a_message() {
    invalid(
        with_input(&["fk"], &json!({"robot": "fr3", "q": [[0.0, 1.0]]})),
        "q[0]",
    );
    invalid(
        with_input(&["fk"], &json!({"robot": "ur5", "q": []})),
        "ur5",
    );
    invalid(with_input(&["fk"], &json!({"robot": "fr3"})), "q");
    invalid(
        with_input(
            &["reach", "robot"],
            &json!({"robot": "fr3", "boxes": [{"q_lo": Q_READY, "q_hi": [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]}]}),
        ),
        "q_lo <= q_hi",
    );
    invalid(
        with_input(
            &["reach", "robot"],
            &json!({"robot": "fr3", "boxes": [], "tracking_error": -1.0}),
        ),
        "tracking_error",
    );
    let positions: Vec<[f64; 3]> = (0..8).map(|_| [0.0, 0.0, 0.0]).collect();
    invalid(
        with_input(
            &["reach", "human"],
            &json!({"human": "default", "model": "vel", "measurement": {"time": 0.0, "positions": positions}, "intervals": [[0.0, 0.1]]}),
        ),
        "expected 9 keypoints",
    );
    let positions: Vec<[f64; 3]> = (0..9).map(|_| [0.0, 0.0, 0.0]).collect();
    invalid(
        with_input(
            &["reach", "human"],
            &json!({"human": "default", "model": "fast", "measurement": {"time": 0.0, "positions": positions}, "intervals": [[0.0, 0.1]]}),
        ),
        "fast",
    );
    invalid(
        with_input(
            &["reach", "human"],
            &json!({"human": "default", "model": "vel", "measurement": {"time": 1.0, "positions": positions}, "intervals": [[0.0, 0.1]]}),
        ),
        "before the measured state",
    );
    let bad_human = json!({"keypoints": ["a"], "v_max": [-1.0], "a_max": [5.0],
        "body_parts": [{"name": "s", "from": "a", "to": "a", "thickness": 0.1}]});
    invalid(
        with_input(
            &["reach", "human"],
            &json!({"human": bad_human, "model": "vel", "measurement": {"time": 0.0, "positions": [[0,0,0]]}, "intervals": [[0.0, 0.1]]}),
        ),
        "v_max[0]",
    );
    // Not JSON at all.
    let mut f = tempfile_path();
    f.write_all(b"{not json").unwrap();
    invalid(pacs(&["fk", "--input", &f.path.clone()]), "invalid input");
    invalid(
        pacs(&["fk", "--input", "/nonexistent/file.json"]),
        "cannot read",
    );
}

#[test]
fn fk_accepts_a_urdf_robot() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/models/tests/data");
    let urdf = json!({"urdf": format!("{dir}/fr3.urdf"), "side": format!("{dir}/fr3_side.toml")});
    let a = ok_json(with_input(&["fk"], &json!({"robot": urdf, "q": [Q_READY]})));
    let b = ok_json(with_input(
        &["fk"],
        &json!({"robot": "fr3", "q": [Q_READY]}),
    ));
    let caps = |v: &Value| -> Vec<f64> {
        v["configurations"][0]["links"]
            .as_array()
            .unwrap()
            .iter()
            .flat_map(|l| l["capsules"].as_array().unwrap().clone())
            .flat_map(|c| {
                let mut x: Vec<f64> = c["p1"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|v| v.as_f64().unwrap())
                    .collect();
                x.extend(
                    c["p2"]
                        .as_array()
                        .unwrap()
                        .iter()
                        .map(|v| v.as_f64().unwrap()),
                );
                x.push(c["radius"].as_f64().unwrap());
                x
            })
            .collect()
    };
    let (ca, cb) = (caps(&a), caps(&b));
    assert_eq!(ca.len(), cb.len());
    for (x, y) in ca.iter().zip(&cb) {
        assert!((x - y).abs() < 1e-12, "{x} vs {y}");
    }
    invalid(
        with_input(
            &["fk"],
            &json!({"robot": {"urdf": "/nonexistent.urdf"}, "q": [Q_READY]}),
        ),
        "nonexistent",
    );
}

#[test]
fn builtin_examples_run_without_input() {
    let v = ok_json(pacs(&["reach", "human"]));
    assert_eq!(v["intervals"].as_array().unwrap().len(), 3);
    // Occupancies grow with the interval's end: the torso's radius increases.
    let r = |i: usize| {
        v["intervals"][i]["body_parts"][6]["radius"]
            .as_f64()
            .unwrap()
    };
    assert!(r(0) < r(1) && r(1) < r(2));
    let v = ok_json(pacs(&["reach", "robot"]));
    assert_eq!(v["boxes"][0]["links"].as_array().unwrap().len(), 10);
}

/// A bound that overflows is an input error (exit 3, naming the field and value),
/// never `null` where a number is promised.
#[test]
fn overflowing_bounds_are_input_errors_not_null() {
    let dir = std::env::temp_dir().join(format!("pacs-reach-overflow-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let robot = dir.join("robot.json");
    std::fs::write(
        &robot,
        r#"{"robot":"fr3","boxes":[{"q_lo":[0,0,0,-2,0,1,0],"q_hi":[0.1,0.1,0.1,-1.9,0.1,1.1,0.1]}],"tracking_error":1.7976931348623157e308}"#,
    )
    .unwrap();
    let human = dir.join("human.json");
    std::fs::write(
        &human,
        r#"{"human":"default","measurement":{"time":0.0,"positions":[[0.8,0.25,1.35],[0.9,0.3,1.1],[0.75,0.3,0.95],[0.8,-0.25,1.35],[0.75,-0.3,1.1],[0.6,-0.2,1.0],[0.8,0.0,1.45],[0.85,0.0,0.95],[0.8,0.0,1.6]]},"intervals":[[1,1e308]]}"#,
    )
    .unwrap();
    for (what, file, field) in [
        ("robot", &robot, "tracking_error 1.7976931348623157e308"),
        ("human", &human, "intervals[0]: body part `lUpperArm`"),
    ] {
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_pacs"))
            .args(["reach", what, "--input"])
            .arg(file)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(3), "{what}: {err}");
        assert!(
            err.contains(field) && err.contains("overflows"),
            "{what}: {err}"
        );
        assert!(!String::from_utf8_lossy(&o.stdout).contains("null"));
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A robot whose offsets overflow (finite in the file, `inf` after summing) would make `pacs fk`
/// print `null`. Every command that loads a robot refuses it: exit 3 naming the field.
#[test]
fn astronomical_robot_is_an_input_error_not_null() {
    let mut spec =
        serde_json::to_value(pacs_models::RobotModel::builtin("fr3").unwrap().spec()).unwrap();
    spec["joints"][1]["origin"]["xyz"] = json!([1.7e308, 0.0, 0.0]);
    spec["joints"][2]["origin"]["xyz"] = json!([1.7e308, 0.0, 0.0]);
    let cases: [(&[&str], Value); 2] = [
        (&["fk"], json!({"robot": spec, "q": [Q_READY]})),
        (
            &["reach", "robot"],
            json!({"robot": spec, "boxes": [{"q_lo": Q_READY, "q_hi": Q_READY}]}),
        ),
    ];
    for (sub, input) in cases {
        let o = with_input(sub, &input);
        assert!(o.stdout.is_empty(), "{sub:?}: {:?}", o.stdout);
        invalid(o, "robot: invalid value for `joints[1].origin.xyz`");
    }
}

/// A URDF link whose collision geometry is a mesh (no side-file capsules) would be
/// invisible to every check; every command that loads the robot refuses it, naming the links.
#[test]
fn mesh_only_urdf_links_are_refused_by_every_command() {
    let data = concat!(env!("CARGO_MANIFEST_DIR"), "/models/tests/data");
    let urdf = std::fs::read_to_string(format!("{data}/planar2.urdf"))
        .unwrap()
        .replace(
            "<box size=\"0.2 0.1 0.4\"/>",
            "<mesh filename=\"package://planar2/fore.stl\"/>",
        )
        .replace(
            "<cylinder radius=\"0.05\" length=\"1.0\"/>",
            "<mesh filename=\"package://planar2/upper.stl\"/>",
        );
    let dir = std::env::temp_dir().join(format!("pacs-cli-mesh-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("planar2_mesh.urdf");
    std::fs::write(&path, urdf).unwrap();
    let robot = json!({"urdf": path, "side": format!("{data}/planar2_side.json")});
    let cases: [(&[&str], Value); 3] = [
        (&["fk"], json!({"robot": robot, "q": [[0.0, 0.0]]})),
        (
            &["reach", "robot"],
            json!({"robot": robot, "boxes": [{"q_lo": [0.0, 0.0], "q_hi": [0.1, 0.1]}]}),
        ),
        (
            &["trajectory"],
            json!({"robot": robot, "state": {"q": [0.0, 0.0]}, "chunk": {"actions": [[0.1, 0.1]], "execute": 1}}),
        ),
    ];
    for (sub, input) in cases {
        let o = with_input(sub, &input);
        let err = String::from_utf8_lossy(&o.stderr).to_string();
        invalid(
            o,
            "links with mesh collision geometry and no capsules: `upper`, `fore`",
        );
        assert!(err.contains("planar2_mesh.urdf"), "{sub:?}: {err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `pacs reach object`: the built-in example, an inline object (hand-computed: constant velocity,
/// no errors, so the centre sweeps p + [0, 1]·v), the printed ball accepted back, and bad input
/// naming the field (exit 3).
#[test]
fn reach_object_example_inline_and_errors() {
    let v = ok_json(pacs(&["reach", "object"]));
    let iv = v["intervals"].as_array().unwrap();
    assert_eq!(iv.len(), 3);
    let r = |i: usize| iv[i]["zonotope"]["radius"].as_f64().unwrap();
    assert!(
        r(0) < r(1) && r(1) < r(2),
        "radii grow with the interval's end"
    );
    assert!(iv[0]["speed_set"]["radius"].as_f64().unwrap() > 0.04);
    for i in iv {
        for k in ["p1", "p2"] {
            assert_eq!(i["bounding_capsule"][k].as_array().unwrap().len(), 3);
        }
    }
    let obj = json!({"shape": {"capsule": {"half_axis": [0.0, 0.0, 0.1], "radius": 0.02}}, "max_acc": 0.0});
    let v = ok_json(with_input(
        &["reach", "object"],
        &json!({"object": obj, "measurement": {"time": 0.0, "position": [1.0, 2.0, 3.0], "velocity": [1.0, 0.0, 0.0]}, "intervals": [[0.0, 1.0]]}),
    ));
    let z = &v["intervals"][0]["zonotope"];
    let c: Vec<f64> = serde_json::from_value(z["centre"].clone()).unwrap();
    assert!(
        (c[0] - 1.5).abs() < 1e-15 && c[1] == 2.0 && c[2] == 3.0,
        "{c:?}"
    );
    let g: Vec<[f64; 3]> = serde_json::from_value(z["generators"].clone()).unwrap();
    assert!((g[0][0] - 0.5).abs() < 1e-15, "{g:?}");
    assert_eq!(
        g[2],
        [0.0, 0.0, 0.1],
        "the capsule's half axis is a generator"
    );
    assert!((z["radius"].as_f64().unwrap() - 0.02).abs() < 1e-15);
    assert!(v["intervals"][0].get("speed_set").is_none());
    // The printed built-in is accepted back.
    let ball = ok_json(pacs(&["object", "show", "ball"]));
    assert_eq!(ball["shape"]["sphere"]["radius"], 0.04);
    ok_json(with_input(
        &["reach", "object"],
        &json!({"object": ball, "measurement": {"time": 0.0, "position": [0.0, 0.0, 0.0]}, "intervals": [[0.0, 0.1]]}),
    ));
    // Bad input: named fields, exit 3.
    let m = json!({"time": 0.0, "position": [0.0, 0.0, 0.0], "velocity": [0.0, 0.0, 0.0]});
    invalid(
        with_input(
            &["reach", "object"],
            &json!({"object": {"shape": {"sphere": {"radius": 0.1}}}, "measurement": m, "intervals": [[0.0, 0.1]]}),
        ),
        "missing field `max_acc`",
    );
    invalid(
        with_input(
            &["reach", "object"],
            &json!({"object": {"shape": {"sphere": {"radius": -0.1}}, "max_acc": 1.0}, "measurement": m, "intervals": [[0.0, 0.1]]}),
        ),
        "shape.sphere.radius",
    );
    invalid(
        with_input(
            &["reach", "object"],
            &json!({"object": {"shape": {"cube": {}}, "max_acc": 1.0}, "measurement": m, "intervals": [[0.0, 0.1]]}),
        ),
        "unknown variant `cube`",
    );
    invalid(
        with_input(
            &["reach", "object"],
            &json!({"object": "rock", "measurement": m, "intervals": [[0.0, 0.1]]}),
        ),
        "unknown built-in object `rock`",
    );
    invalid(
        with_input(
            &["reach", "object"],
            &json!({"object": "ball", "measurement": m, "intervals": [[-1.0, 0.1]]}),
        ),
        "intervals[0]",
    );
    invalid(
        with_input(
            &["reach", "object"],
            &json!({"object": {"shape": {"sphere": {"radius": 0.1}}, "max_acc": 1.0}, "measurement": {"time": 0.0, "position": [0.0, 0.0, 0.0]}, "intervals": [[0.0, 0.1]]}),
        ),
        "no velocity",
    );
    invalid(pacs(&["object", "show", "rock"]), "built-in: ball");
}

/// An inline robot or human with a missing or unknown field names it; no
/// "untagged enum" message reaches the user.
#[test]
fn inline_models_name_the_faulty_field() {
    let out = pacs(&["robot", "show", "fr3"]);
    let mut robot: Value = ok_json(out);
    robot.as_object_mut().unwrap().remove("joints");
    let o = with_input(&["fk"], &json!({"robot": robot, "q": [Q_READY]}));
    invalid(o, "missing field `joints`");
    let o = with_input(
        &["fk"],
        &json!({"robot": {"urdf": "arm.urdf", "sidefile": "x"}, "q": [Q_READY]}),
    );
    invalid(o, "unknown field `sidefile`");
    let mut human: Value = ok_json(pacs(&["human", "show", "default"]));
    human.as_object_mut().unwrap().remove("body_parts");
    let o = with_input(
        &["reach", "human"],
        &json!({"human": human, "measurement": {"time": 0.0, "positions": []}, "intervals": []}),
    );
    invalid(o, "missing field `body_parts`");
    let o = with_input(&["fk"], &json!({"robot": 3, "q": [Q_READY]}));
    invalid(o, "expected a built-in model name");
}
