//! `pacs shield --input scene.json` end to end: the shipped example runs, writes one
//! command per safety step and a log `pacs audit` passes; the commands stay within the joint
//! limits, stop for the person and resume; a person in the way from the start keeps the arm at
//! rest; bad scenes exit 3 naming the field.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn pacs() -> Command {
    Command::new(env!("CARGO_BIN_EXE_pacs"))
}

fn dir(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("pacs-shield-{name}-{}", std::process::id()))
}

fn example() -> Value {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scene.json");
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

fn run_scene(name: &str, scene: &Value) -> (Output, PathBuf) {
    run_scene_text(name, &scene.to_string())
}

/// `pacs shield --input D/scene.json --out D/out` on the scene file `text` (D: a fresh
/// directory named after `name`).
fn run_scene_text(name: &str, text: &str) -> (Output, PathBuf) {
    let d = dir(name);
    std::fs::create_dir_all(&d).unwrap();
    let input = d.join("scene.json");
    std::fs::write(&input, text).unwrap();
    let out = pacs()
        .args(["shield", "--input"])
        .arg(&input)
        .arg("--out")
        .arg(d.join("out"))
        .output()
        .unwrap();
    (out, d)
}

fn commands(d: &Path) -> Vec<Value> {
    std::fs::read_to_string(d.join("out/commands.jsonl"))
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

#[test]
fn the_example_scene_runs_and_its_log_passes_the_audit() {
    let (out, d) = run_scene("example", &example());
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let summary: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(summary["steps"], 2400);
    assert_eq!(summary["chunks_accepted"], 6);
    let cmds = commands(&d);
    assert_eq!(cmds.len(), 2400);
    let robot = pacs_models::RobotModel::builtin("fr3").unwrap();
    let lim = robot.limits();
    let mut unverified = 0;
    let mut named = 0;
    for (k, c) in cmds.iter().enumerate() {
        let t = c["t"].as_f64().unwrap();
        assert!(
            (t - (k + 1) as f64 * 1e-3).abs() < 1e-9,
            "step {k}: t = {t}"
        );
        let q: Vec<f64> = serde_json::from_value(c["q"].clone()).unwrap();
        let dq: Vec<f64> = serde_json::from_value(c["dq"].clone()).unwrap();
        assert!(lim.contains(&q), "step {k}: {q:?} outside the limits");
        for (j, v) in dq.iter().enumerate() {
            assert!(
                v.abs() <= lim.v_max()[j] + 1e-9,
                "step {k}: joint {j} at {v}"
            );
        }
        unverified += (!c["verified"].as_bool().unwrap()) as usize;
        // The binding names what its indices stand for.
        let b = &c["binding"];
        if let Some(l) = b["link"].as_u64() {
            assert_eq!(
                b["link_name"],
                robot.links()[l as usize].name.as_str(),
                "{b}"
            );
        }
        if let Some(p) = b["body_part"].as_u64() {
            let human = pacs_models::HumanModel::builtin("default").unwrap();
            assert_eq!(
                b["body_part_name"],
                human.body_parts()[p as usize].name.as_str(),
                "{b}"
            );
            named += 1;
        }
        if b["kind"] == "object" {
            assert_eq!(b["object_id"], "ball", "{b}");
        }
    }
    assert!(named > 0, "some steps are bound by the person");
    // The header records the filter that ran (the configured mode; default PACS).
    let header = header_meta(&d);
    assert_eq!(header["filter"], "pacs");
    assert_eq!(header["tool"], "pacs shield");
    // The person walks up and the ball rolls past: some steps brake, most are verified.
    let frac = summary["verified_fraction"].as_f64().unwrap();
    assert!(frac > 0.5 && frac < 1.0, "verified fraction {frac}");
    assert!(unverified > 0);
    let a = pacs()
        .arg("audit")
        .arg(d.join("out/log.jsonl"))
        .output()
        .unwrap();
    assert_eq!(
        a.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&a.stdout)
    );
    std::fs::remove_dir_all(&d).ok();
}

/// `meta` of the header (first line) of `d/out/log.jsonl`.
fn header_meta(d: &Path) -> Value {
    let text = std::fs::read_to_string(d.join("out/log.jsonl")).unwrap();
    let first: Value = serde_json::from_str(text.lines().next().unwrap()).unwrap();
    first["meta"].clone()
}

/// `meta.filter` is the mode that ran, so reports never average PACS and OFF runs together
/// (it was `"pacs-shield"` whatever `config.mode` said).
#[test]
fn the_log_header_names_the_mode_that_ran() {
    for mode in ["off", "single-action"] {
        let mut scene = example();
        scene["config"]["mode"] = Value::from(mode);
        scene["duration"] = Value::from(0.05);
        let (out, d) = run_scene(&format!("mode-{mode}"), &scene);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert_eq!(header_meta(&d)["filter"], mode);
        std::fs::remove_dir_all(&d).ok();
    }
}

#[test]
fn the_built_in_example_is_the_shipped_file() {
    let d = dir("builtin");
    let out = pacs().args(["shield", "--out"]).arg(&d).output().unwrap();
    assert!(out.status.success());
    let summary: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(summary["scene"], "examples/scene.json");
    assert_eq!(summary["steps"], 2400);
    std::fs::remove_dir_all(&d).ok();
}

/// Inputs arriving after the last step never reach the shield: the summary lists them under
/// `not_delivered` (and a warning names the chunks) instead of leaving them out of every count.
#[test]
fn inputs_after_the_end_are_reported_not_delivered() {
    let mut scene = example();
    let full = example();
    let n_chunks = full["chunks"].as_array().unwrap().len();
    let n_humans = full["human_measurements"].as_array().unwrap().len();
    // Cut the run at 1.2 s: which inputs come later is counted from the file itself.
    let end = 1.2;
    scene["duration"] = serde_json::json!(end);
    let later = |key: &str| {
        full[key]
            .as_array()
            .unwrap()
            .iter()
            .enumerate()
            .filter(|(_, m)| {
                let t = m["received"].as_f64().unwrap_or(m["t"].as_f64().unwrap());
                t > end - 1e-3 + 1e-9
            })
            .map(|(i, _)| i)
            .collect::<Vec<_>>()
    };
    let late_chunks = later("chunks");
    let late_humans = later("human_measurements").len();
    let late_objects = later("object_measurements").len();
    assert!(!late_chunks.is_empty() && late_chunks.len() < n_chunks);
    assert!(late_humans > 0 && late_humans < n_humans);
    let (out, d) = run_scene("late", &scene);
    assert!(out.status.success());
    let summary: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(summary["steps"], 1200);
    assert_eq!(
        summary["not_delivered"]["chunks"],
        serde_json::json!(late_chunks)
    );
    assert_eq!(summary["not_delivered"]["human_measurements"], late_humans);
    assert_eq!(
        summary["not_delivered"]["object_measurements"],
        late_objects
    );
    assert_eq!(
        summary["chunks_accepted"].as_u64().unwrap() as usize
            + summary["chunks_rejected"].as_array().unwrap().len()
            + late_chunks.len(),
        n_chunks
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("never handed to the shield"), "{err}");
    // The full run delivers everything.
    let (out, d2) = run_scene("all", &full);
    let summary: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        summary["not_delivered"],
        serde_json::json!({"chunks": [], "human_measurements": 0, "object_measurements": 0})
    );
    std::fs::remove_dir_all(&d).ok();
    std::fs::remove_dir_all(&d2).ok();
}

/// A measurement that the others contradict — the right hand on the moving flange, stamped 1 ms
/// before a measurement of the person 1.3 m away that arrives in the same step — is not hidden
/// by the newer one: the runner logs every measurement it delivers, and the audit checks each
/// against the human model beside its neighbours in time, so the run cannot pass (a runner that
/// kept only the newest measurement of a step would write the unmodified run's log, which
/// passes). The unmodified run passes; a clock starting at 0.1 s (steps and stamps rounding
/// differently) passes too: no measurement is handed over before its stamp (one handed over
/// 1 ulp early would be ignored by the shield, and the audit would refuse the log, exit 3).
#[test]
fn a_contradicting_measurement_cannot_hide_behind_a_newer_one() {
    let robot = pacs_models::RobotModel::builtin("fr3").unwrap();
    let base = example();
    let (out, d0) = run_scene("contradiction-base", &base);
    assert!(out.status.success());
    // Where the flange is at 0.599 s in the unmodified run.
    let cmds = commands(&d0);
    let c = cmds
        .iter()
        .find(|c| (c["t"].as_f64().unwrap() - 0.599).abs() < 1e-9)
        .unwrap();
    let q: Vec<f64> = serde_json::from_value(c["q"].clone()).unwrap();
    let p = robot.capsules_world(&q).last().unwrap().1.p2();
    let mut scene = base.clone();
    let ms = scene["human_measurements"].as_array_mut().unwrap();
    let k = ms
        .iter()
        .position(|m| (m["t"].as_f64().unwrap() - 0.6).abs() < 1e-12)
        .unwrap();
    let mut hand = ms[k].clone();
    hand["t"] = serde_json::json!(0.599);
    hand["keypoints"][5] = serde_json::json!([p.x, p.y, p.z]);
    ms.insert(k, hand);
    let audit = |d: &Path| {
        pacs()
            .args(["audit", "--json"])
            .arg(d.join("out/log.jsonl"))
            .output()
            .unwrap()
    };
    let (out, d) = run_scene("contradiction", &scene);
    assert!(out.status.success());
    let a = audit(&d);
    let report: Value = serde_json::from_slice(&a.stdout).unwrap();
    let text = report.to_string();
    assert_ne!(a.status.code(), Some(0), "{text}");
    assert!(text.contains("human_exceeds_model"), "{text}");
    assert_eq!(audit(&d0).status.code(), Some(0));
    let mut late = base.clone();
    let shift = |v: &mut Value| *v = serde_json::json!(v.as_f64().unwrap() + 0.1);
    shift(&mut late["t0"]);
    for key in ["chunks", "human_measurements", "object_measurements"] {
        for m in late[key].as_array_mut().unwrap() {
            shift(&mut m["t"]);
            if m.get("received").is_some() {
                shift(&mut m["received"]);
            }
        }
    }
    let (out, d1) = run_scene("contradiction-t0", &late);
    assert!(out.status.success());
    let a = audit(&d1);
    assert_eq!(
        a.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&a.stdout)
    );
    for d in [d, d0, d1] {
        std::fs::remove_dir_all(&d).ok();
    }
}

#[test]
fn a_person_at_the_arm_from_the_start_keeps_it_at_rest() {
    let mut scene = example();
    // The hand on the flange at every measurement.
    let robot = pacs_models::RobotModel::builtin("fr3").unwrap();
    let start: Vec<f64> = serde_json::from_value(scene["start"].clone()).unwrap();
    let p = robot.capsules_world(&start).last().unwrap().1.p2();
    for m in scene["human_measurements"].as_array_mut().unwrap() {
        m["keypoints"][5] = serde_json::json!([p.x, p.y, p.z]);
    }
    let (out, d) = run_scene("blocked", &scene);
    assert!(out.status.success());
    for c in commands(&d) {
        assert_eq!(c["q"], scene["start"], "moved at t = {}", c["t"]);
        assert_eq!(c["verified"], false);
    }
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn bad_scenes_exit_3_naming_the_field() {
    type Edit = Box<dyn Fn(&mut Value)>;
    let cases: Vec<(&str, Edit, &str)> = vec![
        (
            "keypoints",
            Box::new(|s| {
                s["human_measurements"][7]["keypoints"]
                    .as_array_mut()
                    .unwrap()
                    .pop();
            }),
            "human_measurements[7].keypoints",
        ),
        (
            "action",
            Box::new(|s| s["chunks"][2]["actions"][5] = serde_json::json!([0.0, 0.0])),
            "chunks[2].actions[5]",
        ),
        (
            "object",
            Box::new(|s| s["object_measurements"][3]["id"] = "cup".into()),
            "object_measurements[3].id",
        ),
        (
            "received",
            Box::new(|s| s["human_measurements"][4]["received"] = serde_json::json!(-1.0)),
            "human_measurements[4].received",
        ),
        (
            "execute",
            Box::new(|s| s["chunks"][0]["execute"] = serde_json::json!(17)),
            "chunks[0].execute",
        ),
        (
            "mode",
            Box::new(|s| s["config"]["mode"] = "fast".into()),
            "config.mode",
        ),
        (
            "start",
            Box::new(|s| s["start"][3] = serde_json::json!(5.0)),
            "start[3] (joint `fr3_joint4`): 5 rad is outside the joint position limits [-3.0421, -0.1518] rad",
        ),
        (
            "unknown",
            Box::new(|s| s["chunk"] = serde_json::json!([])),
            "unknown field `chunk`",
        ),
        // A clock that cannot resolve the step: at 10¹³ s floats are 2 ms apart.
        (
            "huge t0",
            Box::new(|s| s["t0"] = serde_json::json!(1e13)),
            "too large to resolve the safety step",
        ),
        (
            "tiny step",
            Box::new(|s| s["config"]["safety_step"] = serde_json::json!(1e-9)),
            "safety_step",
        ),
        // A rest speed that would let SSM accept contact with a moving robot.
        (
            "rest speed",
            Box::new(|s| s["config"]["rest_speed"] = serde_json::json!(1.0)),
            "rest_speed",
        ),
        (
            "short run",
            Box::new(|s| s["duration"] = serde_json::json!(1e-4)),
            "shorter than one safety step",
        ),
    ];
    for (name, edit, want) in cases {
        let mut scene = example();
        edit(&mut scene);
        let (out, d) = run_scene(name, &scene);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(3), "{name}: {err}");
        assert!(err.contains(want), "{name}: {err}");
        assert!(!err.contains("panicked"), "{name}: {err}");
        std::fs::remove_dir_all(&d).ok();
    }
}

/// A scene with two people (`humans`): the shield takes both, the log lists both (format v2)
/// with every measurement's person, ends with the promised `end` event and passes the audit;
/// the same log cut at a line boundary (or without its end) exits 2, `incomplete_log`.
#[test]
fn two_people_are_logged_and_a_cut_log_is_never_a_pass() {
    let mut scene = example();
    let o = scene.as_object_mut().unwrap();
    o.remove("human");
    o.insert(
        "humans".into(),
        serde_json::json!([{"id": "operator", "human": "default"}, {"id": "visitor", "human": "default"}]),
    );
    // The visitor stands 3 m behind the robot, measured every 50 ms.
    let mut ms: Vec<Value> = o["human_measurements"].as_array().unwrap().clone();
    for m in &mut ms {
        m["id"] = "operator".into();
    }
    for k in 0..48 {
        let kp: Vec<[f64; 3]> = (0..9).map(|i| [-3.0, 0.1 * i as f64, 1.2]).collect();
        ms.push(serde_json::json!({"id": "visitor", "t": 0.05 * k as f64, "keypoints": kp}));
    }
    o.insert("human_measurements".into(), Value::Array(ms));
    let (out, d) = run_scene("two-people", &scene);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // A step bound by a person names that person (the operator walks up; the visitor is far).
    let by_person: Vec<Value> = commands(&d)
        .into_iter()
        .map(|c| c["binding"].clone())
        .filter(|b| b["kind"] == "ssm" || b["kind"] == "pfl")
        .collect();
    assert!(!by_person.is_empty());
    assert!(
        by_person.iter().all(|b| b["person"] == "operator"),
        "{by_person:?}"
    );
    let log = std::fs::read_to_string(d.join("out/log.jsonl")).unwrap();
    let lines: Vec<&str> = log.lines().collect();
    let header: Value = serde_json::from_str(lines[0]).unwrap();
    assert_eq!(header["version"], 2);
    assert_eq!(header["end_event"], true);
    assert_eq!(header["humans"][1]["id"], "visitor");
    assert!(lines.last().unwrap().contains("\"name\":\"end\""));
    let visitor = lines
        .iter()
        .filter(|l| l.contains("\"type\":\"human\"") && l.contains("\"id\":\"visitor\""))
        .count();
    assert_eq!(visitor, 48);
    let audit = |p: &Path| pacs().args(["audit", "--json"]).arg(p).output().unwrap();
    let a = audit(&d.join("out/log.jsonl"));
    assert_eq!(
        a.status.code(),
        Some(0),
        "{}{}",
        String::from_utf8_lossy(&a.stdout),
        String::from_utf8_lossy(&a.stderr)
    );
    for keep in [lines.len() * 3 / 10, lines.len() - 1] {
        let cut = d.join(format!("cut{keep}.jsonl"));
        let text: String = lines[..keep].iter().map(|l| format!("{l}\n")).collect();
        std::fs::write(&cut, text).unwrap();
        let a = audit(&cut);
        assert_eq!(a.status.code(), Some(2), "cut after {keep} lines");
        let s = String::from_utf8_lossy(&a.stdout);
        assert!(s.contains("incomplete_log"), "{s}");
    }
    // An undeclared person in the scene is refused, naming the field.
    assert_undeclared_person_refused(&scene);
    std::fs::remove_dir_all(&d).ok();
}

fn assert_undeclared_person_refused(scene: &Value) {
    let mut bad = scene.clone();
    bad["human_measurements"][0]["id"] = "stranger".into();
    let (out, d) = run_scene("undeclared-person", &bad);
    assert_eq!(out.status.code(), Some(3));
    let e = String::from_utf8_lossy(&out.stderr);
    // Found after the scene was parsed, the error still names the file.
    let file = d.join("scene.json").display().to_string();
    assert!(
        e.contains(&format!("{file}: human_measurements[0].id")) && e.contains("stranger"),
        "{e}"
    );
    std::fs::remove_dir_all(&d).ok();
}

/// A scene file that starts with a UTF-8 byte-order mark is told so (exit 3), naming the file.
#[test]
fn a_scene_with_a_byte_order_mark_is_named() {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scene.json");
    let text = std::fs::read_to_string(p).unwrap();
    let (out, d) = run_scene_text("bom", &format!("\u{feff}{text}"));
    let input = d.join("scene.json");
    assert_eq!(out.status.code(), Some(3));
    let e = String::from_utf8_lossy(&out.stderr);
    assert!(
        e.contains(&input.display().to_string()) && e.contains("byte order mark"),
        "{e}"
    );
    std::fs::remove_dir_all(&d).ok();
}

/// A number JSON cannot hold (`1e400`) or a `NaN` literal in a scene names the field,
/// not only the line and column.
#[test]
fn non_finite_numbers_in_a_scene_name_the_field() {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scene.json");
    let text = std::fs::read_to_string(p).unwrap();
    for (name, from, to, want) in [
        (
            "huge",
            "\"start\": [0.0, -0.785398,",
            "\"start\": [0.0, 1e400,",
            "invalid scene: start[1]: number out of range at line 9 column 22 (numbers must be finite: |x| ≤ 1.8e308)",
        ),
        (
            "nan",
            "{\"t\": 0.264, \"kind\": \"delta\", \"actions\": [[0.012,",
            "{\"t\": 0.264, \"kind\": \"delta\", \"actions\": [[NaN,",
            "invalid scene: chunks[1].actions[0][0]: expected value at line 14 column 48 (NaN and Infinity are not JSON: numbers must be finite)",
        ),
    ] {
        assert!(text.contains(from), "{name}");
        let d = dir(name);
        std::fs::create_dir_all(&d).unwrap();
        let input = d.join("scene.json");
        std::fs::write(&input, text.replacen(from, to, 1)).unwrap();
        let out = pacs()
            .args(["shield", "--input"])
            .arg(&input)
            .arg("--out")
            .arg(d.join("out"))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(3), "{name}: {err}");
        assert!(err.contains(want), "{name}: {err}");
        std::fs::remove_dir_all(&d).ok();
    }
}

/// `config.human_model = "acc"` in a scene is refused (exit 3), naming the file and the field:
/// a scene's person measurements carry positions only, so no step would ever be verified.
#[test]
fn a_scene_asking_for_the_acc_model_is_refused() {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scene.json");
    let mut scene: Value = serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap();
    scene["config"]["human_model"] = "acc".into();
    let (out, d) = run_scene("acc-model", &scene);
    assert_eq!(out.status.code(), Some(3));
    let e = String::from_utf8_lossy(&out.stderr);
    assert!(
        e.contains("scene.json: config.human_model: `acc` needs measured velocities"),
        "{e}"
    );
    std::fs::remove_dir_all(&d).ok();
}
