//! End-to-end tests of `pacs trajectory`.

use serde_json::{Value, json};
use std::process::Command;

fn run(input: &Value, brake_at: Option<f64>) -> (i32, Value, String) {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    (input.to_string(), brake_at.map(f64::to_bits)).hash(&mut h);
    let dir = pacs_testkit::ScratchDir::new("cli-traj", &h.finish().to_string());
    let path = dir.join("in.json");
    std::fs::write(&path, serde_json::to_string(input).unwrap()).unwrap();
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_pacs"));
    cmd.arg("trajectory").arg("--input").arg(&path);
    if let Some(t) = brake_at {
        cmd.arg("--brake-at").arg(t.to_string());
    }
    let out = cmd.output().unwrap();
    let stdout: Value = serde_json::from_slice(&out.stdout).unwrap_or(Value::Null);
    (
        out.status.code().unwrap_or(-1),
        stdout,
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn input(mode: &str) -> Value {
    json!({
        "robot": "fr3",
        "state": {"q": [0.0, -0.5, 0.0, -2.0, 0.0, 1.5, 0.8], "dq": [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], "ddq": [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]},
        "chunk": {"kind": "delta", "actions": [
            [0.01, 0.01, 0.0, 0.0, 0.0, 0.0, 0.0],
            [0.01, 0.012, 0.0, 0.0, 0.005, 0.0, 0.0],
            [0.01, 0.01, 0.0, -0.01, 0.0, 0.0, 0.0],
            [0.02, 0.01, 0.0, 0.0, 0.0, 0.0, 0.0]], "execute": 3},
        "limit_scale": 1.0, "mode": mode, "sample_dt": 0.002, "max_acc": 10.0, "max_jerk": 400.0
    })
}

fn vec(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

#[test]
fn chunk_output_passes_waypoints_and_ends_at_rest() {
    let (code, out, err) = run(&input("chunk"), None);
    assert_eq!(code, 0, "{err}");
    let t = out["duration"].as_f64().unwrap();
    let wt = vec(&out["waypoint_times"]);
    assert_eq!(wt.len(), 3);
    assert!((wt[2] - t).abs() < 1e-12);
    let samples = out["samples"].as_array().unwrap();
    assert!((samples[0]["t"].as_f64().unwrap()).abs() < 1e-15);
    let last = samples.last().unwrap();
    assert!((last["t"].as_f64().unwrap() - t).abs() < 1e-12);
    let q_end = vec(&last["q"]);
    let wp3 = vec(&out["waypoints"][3]);
    for i in 0..7 {
        assert!((q_end[i] - wp3[i]).abs() < 1e-9);
        assert!(vec(&last["dq"])[i].abs() < 1e-9);
    }
    for s in samples {
        for (i, a) in vec(&s["ddq"]).iter().enumerate() {
            assert!(a.abs() <= 10.0 * (1.0 + 1e-9), "joint {i}: {a}");
        }
    }
    assert!(out.get("failsafe").is_none());
}

#[test]
fn single_action_is_slower_and_stops_at_each_waypoint() {
    let (_, chunk, _) = run(&input("chunk"), None);
    let (code, single, err) = run(&input("single-action"), None);
    assert_eq!(code, 0, "{err}");
    assert!(single["duration"].as_f64().unwrap() > chunk["duration"].as_f64().unwrap());
}

#[test]
fn brake_at_adds_a_failsafe_that_ends_at_rest_on_the_path() {
    let (code, out, err) = run(&input("chunk"), Some(0.05));
    assert_eq!(code, 0, "{err}");
    let f = &out["failsafe"];
    assert_eq!(f["start_time"].as_f64().unwrap(), 0.05);
    let stop = f["stop_time"].as_f64().unwrap();
    assert!(stop > 0.05);
    let fs = f["samples"].as_array().unwrap();
    assert!((fs[0]["t"].as_f64().unwrap() - 0.05).abs() < 1e-15);
    let last = fs.last().unwrap();
    assert!((last["t"].as_f64().unwrap() - stop).abs() < 1e-12);
    for x in vec(&last["dq"]) {
        assert!(x.abs() < 1e-9);
    }
    let s: Vec<f64> = fs.iter().map(|x| x["s"].as_f64().unwrap()).collect();
    assert!(s.windows(2).all(|w| w[1] >= w[0] - 1e-12));
    assert!((s.last().unwrap() - f["s_stop"].as_f64().unwrap()).abs() < 1e-12);
    assert_eq!(vec(&f["distance_bound"]).len(), 7);
    // The shield's braking: within the FR3's limits at every sample, and every sample on the
    // intended path (its distance from the start within the reported bound).
    let robot = pacs_models::RobotModel::builtin("fr3").unwrap();
    let lim = robot.limits();
    let q0 = vec(&fs[0]["q"]);
    let bound = vec(&f["distance_bound"]);
    for x in fs {
        let (q, dq, ddq) = (vec(&x["q"]), vec(&x["dq"]), vec(&x["ddq"]));
        for i in 0..7 {
            assert!(
                dq[i].abs() <= lim.v_max()[i] * (1.0 + 1e-9),
                "dq[{i}] = {}",
                dq[i]
            );
            assert!(
                ddq[i].abs() <= lim.a_max()[i] * (1.0 + 1e-9),
                "ddq[{i}] = {}",
                ddq[i]
            );
            assert!(
                (q[i] - q0[i]).abs() <= bound[i],
                "joint {i} beyond its distance bound"
            );
        }
    }
    assert!(
        ["brake", "delayed-brake", "follow-to-end"].contains(&f["kind"].as_str().unwrap()),
        "{}",
        f["kind"]
    );
    assert!(f["delay"].as_f64().unwrap() >= 0.0);
}

#[test]
fn invalid_inputs_exit_with_code_3_and_a_message() {
    let mut bad_len = input("chunk");
    bad_len["state"]["q"] = json!([0.0, 1.0]);
    let mut bad_exec = input("chunk");
    bad_exec["chunk"]["execute"] = json!(9);
    let mut bad_scale = input("chunk");
    bad_scale["limit_scale"] = json!(0.0);
    let mut bad_dt = input("chunk");
    bad_dt["sample_dt"] = json!(-1.0);
    let mut outside = input("chunk");
    outside["chunk"]["actions"][0][0] = json!(10.0);
    let mut bad_mode = input("chunk");
    bad_mode["mode"] = json!("fast");
    let mut bad_robot = input("chunk");
    bad_robot["robot"] = json!("nonexistent");
    for (case, needle) in [
        (bad_len, "state.q"),
        (bad_exec, "execute"),
        (bad_scale, "limit_scale"),
        (bad_dt, "sample_dt"),
        (outside, "outside"),
        (bad_mode, "fast"),
        (bad_robot, "nonexistent"),
    ] {
        let (code, _, err) = run(&case, None);
        assert_eq!(code, 3, "{needle}: {err}");
        assert!(err.contains(needle), "stderr should name {needle}: {err}");
    }
    let (code, _, err) = run(&input("chunk"), Some(99.0));
    assert_eq!(code, 3);
    assert!(err.contains("--brake-at"));
}
