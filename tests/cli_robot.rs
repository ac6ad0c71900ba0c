//! `pacs robot show` (built-in, URDF, URDF against a built-in) and `pacs robot capsules` (mesh
//! collisions fitted into a side file the loader then accepts).

use std::path::Path;
use std::process::{Command, Output};

fn pacs(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pacs"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env_remove("ROS_PACKAGE_PATH")
        .output()
        .expect("run pacs")
}

fn ok_json(o: Output) -> serde_json::Value {
    assert!(
        o.status.success(),
        "exit {:?}: {}",
        o.status.code(),
        String::from_utf8_lossy(&o.stderr)
    );
    serde_json::from_slice(&o.stdout).expect("JSON on stdout")
}

/// A closed square tube (binary STL) along z from 0 to `len`, half-width `w`.
fn write_tube_stl(path: &Path, w: f64, len: f64) {
    let c = |x: f64, y: f64, z: f64| [x, y, z];
    let corners = [c(-w, -w, 0.0), c(w, -w, 0.0), c(w, w, 0.0), c(-w, w, 0.0)];
    let mut tris = Vec::new();
    for k in 0..4 {
        let (a, b) = (corners[k], corners[(k + 1) % 4]);
        let (a2, b2) = ([a[0], a[1], len], [b[0], b[1], len]);
        tris.push([a, b, b2]);
        tris.push([a, b2, a2]);
    }
    let mut bytes = vec![0u8; 80];
    bytes.extend_from_slice(&(tris.len() as u32).to_le_bytes());
    for t in &tris {
        bytes.extend_from_slice(&[0u8; 12]);
        for v in t {
            for x in v {
                bytes.extend_from_slice(&(*x as f32).to_le_bytes());
            }
        }
        bytes.extend_from_slice(&[0u8; 2]);
    }
    std::fs::write(path, bytes).unwrap();
}

#[test]
fn capsules_are_fitted_to_meshes_and_the_side_file_loads() {
    let dir = std::env::temp_dir().join(format!("pacs-cli-robot-{}", std::process::id()));
    let pkg = dir.join("ws").join("arm_description").join("meshes");
    std::fs::create_dir_all(&pkg).unwrap();
    write_tube_stl(&pkg.join("upper.stl"), 0.04, 0.3);
    let urdf = dir.join("arm.urdf");
    std::fs::write(
        &urdf,
        r#"<robot name="arm">
  <link name="base"/>
  <link name="upper"><inertial><mass value="2"/><inertia ixx="0.02" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.01"/></inertial>
    <collision><geometry><mesh filename="package://arm_description/meshes/upper.stl"/></geometry></collision></link>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="upper"/><axis xyz="0 1 0"/>
    <limit lower="-2" upper="2" velocity="2" effort="10"/></joint>
</robot>"#,
    )
    .unwrap();
    let side = dir.join("arm.toml");
    std::fs::write(&side, "a_max = 8.0\nj_max = 4000.0\n").unwrap();
    let (u, s) = (urdf.to_str().unwrap(), side.to_str().unwrap());
    // Without the fitted capsules the mesh link is refused (exit 3, naming it).
    let o = pacs(&["robot", "show", "--urdf", u, "--side", s]);
    assert_eq!(o.status.code(), Some(3));
    assert!(String::from_utf8_lossy(&o.stderr).contains("upper"));
    // Without a package path the package cannot be found (exit 3, naming the mesh).
    let o = pacs(&["robot", "capsules", "--urdf", u, "--side", s]);
    assert_eq!(o.status.code(), Some(3));
    assert!(String::from_utf8_lossy(&o.stderr).contains("arm_description"));
    let out = dir.join("arm_capsules.json");
    let ws = dir.join("ws");
    let report = ok_json(pacs(&[
        "robot",
        "capsules",
        "--urdf",
        u,
        "--side",
        s,
        "--package-path",
        ws.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]));
    let fits = report["fits"].as_array().unwrap();
    assert_eq!(fits.len(), 1);
    assert_eq!(report["loads"], true);
    assert_eq!(report["missing"], serde_json::json!([]));
    assert_eq!(fits[0]["link"], "upper");
    assert_eq!(fits[0]["vertices"], 24);
    // A square tube of half-width 4 cm: its corners are 4√2 cm from the axis.
    let r = fits[0]["radius_m"].as_f64().unwrap();
    assert!((0.04 * 2f64.sqrt() - 1e-6..0.07).contains(&r), "radius {r}");
    let t = fits[0]["tightness"].as_f64().unwrap();
    assert!(t > 0.3 && t <= 1.0, "tightness {t}");
    // The written side file keeps the user's entries and loads.
    let written: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(written["a_max"], 8.0);
    assert_eq!(
        written["links"]["upper"]["capsules"]
            .as_array()
            .unwrap()
            .len(),
        1
    );
    let spec = ok_json(pacs(&[
        "robot",
        "show",
        "--urdf",
        u,
        "--side",
        out.to_str().unwrap(),
    ]));
    assert_eq!(spec["name"], "arm");
    // Without the user's limits the side file is written, and the keys still missing are named
    // with the reason (the URDF gives no acceleration or jerk limit) on stdout and stderr.
    let bare = dir.join("bare.toml");
    std::fs::write(&bare, "").unwrap();
    let out2 = dir.join("bare_capsules.json");
    let o = pacs(&[
        "robot",
        "capsules",
        "--urdf",
        u,
        "--side",
        bare.to_str().unwrap(),
        "--package-path",
        ws.to_str().unwrap(),
        "--out",
        out2.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr).to_string();
    let report = ok_json(o);
    assert_eq!(report["loads"], false);
    let keys: Vec<&str> = report["missing"]
        .as_array()
        .unwrap()
        .iter()
        .map(|g| g["key"].as_str().unwrap())
        .collect();
    assert_eq!(keys, ["a_max", "j_max"]);
    assert!(
        stderr.starts_with(&format!(
            "{}: `pacs robot show` needs 2 more keys there:\n  a_max: no acceleration limit for joint shoulder: URDF before 1.2 has none",
            out2.display()
        )),
        "{stderr}"
    );
    // ... and `robot show` refuses that file with the first of them.
    let o = pacs(&[
        "robot",
        "show",
        "--urdf",
        u,
        "--side",
        out2.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(3));
    assert!(String::from_utf8_lossy(&o.stderr).contains("a_max"));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_urdf_named_with_a_built_in_lists_its_differences() {
    let dir = std::env::temp_dir().join(format!("pacs-cli-robot-diff-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("models/tests/data/fr3.urdf"),
    )
    .unwrap()
    .replacen(
        r#"lower="-2.7437" upper="2.7437""#,
        r#"lower="-2.3093" upper="2.3093""#,
        1,
    );
    let urdf = dir.join("fr3_public_limits.urdf");
    std::fs::write(&urdf, text).unwrap();
    let o = pacs(&[
        "robot",
        "show",
        "fr3",
        "--urdf",
        urdf.to_str().unwrap(),
        "--side",
        "models/tests/data/fr3_side.toml",
    ]);
    assert!(o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("2 differences"), "{err}");
    assert!(
        err.contains(
            "joints[0] (fr3_joint1).q_min: -2.3093 rad in the URDF, -2.7437 rad in the built-in"
        ),
        "{err}"
    );
    // The spec printed is the URDF's.
    let spec: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(spec["joints"][0]["limits"]["q_min"], -2.3093);
    // The unmodified URDF: the same limits.
    let o = pacs(&[
        "robot",
        "show",
        "fr3",
        "--urdf",
        "models/tests/data/fr3.urdf",
        "--side",
        "models/tests/data/fr3_side.toml",
    ]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("the same joint limits"));
    // Neither a name nor a URDF: exit 3 with what to give.
    let o = pacs(&["robot", "show"]);
    assert_eq!(o.status.code(), Some(3));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--urdf FILE"));
    std::fs::remove_dir_all(&dir).ok();
}

/// `{urdf, side}` robots everywhere, paths relative to the file that names them: a log header, an
/// audit config and a CLI input, each read from a working directory elsewhere.
#[test]
fn urdf_robots_in_headers_configs_and_inputs_resolve_against_their_file() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = std::env::temp_dir().join(format!("pacs-cli-robot-ref-{}", std::process::id()));
    let sub = dir.join("run");
    std::fs::create_dir_all(sub.join("model")).unwrap();
    for f in ["fr3.urdf", "fr3_side.toml"] {
        std::fs::copy(
            root.join("models/tests/data").join(f),
            sub.join("model").join(f),
        )
        .unwrap();
    }
    let urdf_ref = r#"{"urdf": "model/fr3.urdf", "side": "model/fr3_side.toml"}"#;
    // A log whose header names the URDF robot relative to the log.
    let log = std::fs::read_to_string(root.join("examples/logs/clean_sorting.jsonl"))
        .unwrap()
        .replacen(r#""robot": "fr3""#, &format!(r#""robot": {urdf_ref}"#), 1);
    std::fs::write(sub.join("run.jsonl"), log).unwrap();
    let run = |args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_pacs"))
            .args(args)
            .current_dir(&dir) // not the log's directory
            .output()
            .unwrap()
    };
    let o = run(&["audit", "run/run.jsonl", "--out", "report"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        matches!(o.status.code(), Some(0..=2)),
        "exit {:?}: {err}",
        o.status.code()
    );
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("report/report.json")).unwrap())
            .unwrap();
    // The URDF names its robot `fr3` (the bad path below shows the URDF is what is read); its
    // model is not the built-in FR3's, and the report says so under that name.
    assert_eq!(
        report["runs"][0]["models"]["robot"], "fr3 (custom spec, not the built-in fr3)",
        "{report}"
    );
    // A wrong relative path names the resolved file.
    let bad = std::fs::read_to_string(sub.join("run.jsonl"))
        .unwrap()
        .replacen("model/fr3.urdf", "model/nope.urdf", 1);
    std::fs::write(sub.join("bad.jsonl"), bad).unwrap();
    let o = run(&["audit", "run/bad.jsonl"]);
    assert_eq!(o.status.code(), Some(3));
    assert!(String::from_utf8_lossy(&o.stderr).contains("nope.urdf"));
    // An audit config overriding the robot, relative to the config file.
    std::fs::write(
        sub.join("audit.toml"),
        "robot = { urdf = \"model/fr3.urdf\", side = \"model/fr3_side.toml\" }\n",
    )
    .unwrap();
    let o = run(&[
        "audit",
        "--config",
        "run/audit.toml",
        &root
            .join("examples/logs/clean_sorting.jsonl")
            .display()
            .to_string(),
    ]);
    assert!(
        matches!(o.status.code(), Some(0..=2)),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    // The config's robot is read, relative to the config file: a wrong path is named.
    std::fs::write(
        sub.join("audit_bad.toml"),
        "robot = { urdf = \"model/nope.urdf\" }\n",
    )
    .unwrap();
    let o = run(&[
        "audit",
        "--config",
        "run/audit_bad.toml",
        &root
            .join("examples/logs/clean_sorting.jsonl")
            .display()
            .to_string(),
    ]);
    assert_eq!(o.status.code(), Some(3));
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("run/model/nope.urdf"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    // An MCAP recording whose embedded header names the URDF relative to the MCAP file.
    {
        use pacs_log::RecordReader;
        use pacs_log::mcap::{McapConfig, McapLogWriter};
        let mut reader = pacs_log::jsonl::JsonlReader::new(
            "run.jsonl",
            std::io::BufReader::new(std::fs::File::open(sub.join("run.jsonl")).unwrap()),
        )
        .unwrap();
        let mut header = reader.header().clone();
        header.robot = serde_json::from_str(urdf_ref).unwrap();
        let joints: Vec<String> = (1..=7).map(|i| format!("fr3_joint{i}")).collect();
        let joints: Vec<&str> = joints.iter().map(String::as_str).collect();
        let mut w = McapLogWriter::new(
            std::io::Cursor::new(Vec::new()),
            mcap::WriteOptions::new(),
            &header,
            &McapConfig::default(),
            &joints,
        )
        .unwrap();
        while let Some(rec) = reader.next_record().unwrap() {
            w.write_record(&rec).unwrap();
        }
        std::fs::write(sub.join("run.mcap"), w.finish().unwrap().into_inner()).unwrap();
    }
    let o = run(&["audit", "run/run.mcap"]);
    assert!(
        matches!(o.status.code(), Some(0..=2)),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    // A CLI input (fk) naming the URDF relative to the input file.
    std::fs::write(
        sub.join("fk.json"),
        format!(r#"{{"robot": {urdf_ref}, "q": [[0.0, -0.785398, 0.0, -2.356194, 0.0, 1.570796, 0.785398]]}}"#),
    )
    .unwrap();
    let o = run(&["fk", "--input", "run/fk.json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // An unknown field beside urdf is named.
    std::fs::write(
        sub.join("fk_bad.json"),
        r#"{"robot": {"urdf": "model/fr3.urdf", "sidefile": "x"}, "q": [[0,0,0,0,0,0,0]]}"#,
    )
    .unwrap();
    let o = run(&["fk", "--input", "run/fk_bad.json"]);
    assert_eq!(o.status.code(), Some(3));
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("sidefile"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// An inline robot (as in an input file or a log header) whose moving link has mass and no
/// capsules is refused with exit 3, naming the link; marked `"frame": true` too (its centre of mass
/// lies outside the other links' capsules); without mass it is accepted.
#[test]
fn an_inline_robot_with_an_uncovered_moving_link_is_refused() {
    let mut spec = ok_json(pacs(&["robot", "show", "fr3"]));
    let links = spec["links"].as_array_mut().unwrap();
    let l4 = links.iter_mut().find(|l| l["name"] == "fr3_link4").unwrap();
    l4["capsules"] = serde_json::json!([]);
    let dir = std::env::temp_dir().join(format!("pacs-cli-uncovered-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let input = dir.join("fk.json");
    let write = |spec: &serde_json::Value| {
        std::fs::write(
            &input,
            serde_json::json!({"robot": spec, "q": [[0.0, -0.78, 0.0, -2.36, 0.0, 1.57, 0.78]]})
                .to_string(),
        )
        .unwrap()
    };
    write(&spec);
    let o = pacs(&["fk", "--input", input.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(3));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains(
            "robot `fr3`: moving links with mass and no capsules: `fr3_link4` (2.6155955791 kg)"
        ),
        "{stderr}"
    );
    let links = spec["links"].as_array_mut().unwrap();
    let l4 = links.iter_mut().find(|l| l["name"] == "fr3_link4").unwrap();
    l4["frame"] = serde_json::json!(true);
    write(&spec);
    // Marked, its mass still lies outside every capsule of its joint: refused all the same.
    let o = pacs(&["fk", "--input", input.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(3));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains("(`fr3_link4`): `frame: true` states that the link has no body outside"),
        "{stderr}"
    );
    // A massless frame (a tool point) is accepted.
    let links = spec["links"].as_array_mut().unwrap();
    let l4 = links.iter_mut().find(|l| l["name"] == "fr3_link4").unwrap();
    l4.as_object_mut().unwrap().remove("inertial");
    write(&spec);
    ok_json(pacs(&["fk", "--input", input.to_str().unwrap()]));
    std::fs::remove_dir_all(&dir).ok();
}
