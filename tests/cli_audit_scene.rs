//! `pacs audit LOG --scene out.mcap`: the Foxglove replay, read back with the `mcap` crate —
//! schemas, topics, message counts, and the decoded scene content (capsules as cylinders and
//! spheres, red robot and markers where the audit found violations).

use foxglove::Decode;
use foxglove::schemas::SceneUpdate;
use std::collections::BTreeMap;
use std::path::Path;
use std::process::Command;

fn pacs(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_pacs"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("run pacs")
}

/// Per topic: (schema name, schema encoding, message encoding, messages).
type Topics = BTreeMap<String, (String, String, String, Vec<Vec<u8>>)>;

/// The scene file's topics and the log times of the robot frames.
fn read_scene(path: &Path) -> (Topics, Vec<u64>) {
    let bytes = std::fs::read(path).unwrap();
    let mut topics: Topics = BTreeMap::new();
    let mut times = Vec::new();
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        let schema = m
            .channel
            .schema
            .as_ref()
            .expect("every channel has a schema");
        let e = topics.entry(m.channel.topic.clone()).or_insert_with(|| {
            (
                schema.name.clone(),
                schema.encoding.clone(),
                m.channel.message_encoding.clone(),
                Vec::new(),
            )
        });
        e.3.push(m.data.to_vec());
        if m.channel.topic == "/pacs/robot" {
            times.push(m.log_time);
        }
    }
    (topics, times)
}

#[test]
fn a_violating_log_replays_with_markers_and_metrics() {
    let dir = std::env::temp_dir().join(format!("pacs-scene-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("close.mcap");
    let o = pacs(&[
        "audit",
        "examples/logs/close_sorting.jsonl",
        "--json",
        "--scene",
        scene.to_str().unwrap(),
    ]);
    assert_eq!(
        o.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let run: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let n_violations = run["runs"][0]["violations"].as_array().unwrap().len();
    assert!(n_violations > 0);
    let (topics, times) = read_scene(&scene);
    for t in [
        "/pacs/robot",
        "/pacs/human",
        "/pacs/human_occupancy",
        "/pacs/robot_occupancy",
        "/pacs/violations",
    ] {
        let (name, enc, msg_enc, msgs) = &topics[t];
        assert_eq!(name, "foxglove.SceneUpdate", "{t}");
        assert_eq!(enc, "protobuf", "{t}");
        assert_eq!(msg_enc, "protobuf", "{t}");
        assert!(!msgs.is_empty(), "{t}");
    }
    // 1 s of log at 50 frames per second.
    let frames = topics["/pacs/robot"].3.len();
    assert!((50..=52).contains(&frames), "{frames} frames");
    assert!(
        times.windows(2).all(|w| w[1] >= w[0] + 19_000_000),
        "frames 20 ms apart"
    );
    // One marker per violation interval.
    assert_eq!(topics["/pacs/violations"].3.len(), n_violations);
    // The robot: the FR3's capsules at the first frame — blue — and red while violating.
    let mut reds = 0;
    for data in &topics["/pacs/robot"].3 {
        let u = SceneUpdate::decode(&data[..]).unwrap();
        let e = &u.entities[0];
        assert_eq!(e.frame_id, "world");
        assert!(e.cylinders.len() >= 8 && e.spheres.len() >= 2 * e.cylinders.len() - 4);
        let c = e.cylinders[0].color.unwrap();
        reds += (c.r > 0.5) as usize;
    }
    assert!(reds > 0 && reds < frames, "{reds} red frames of {frames}");
    // Human capsules: one per body part of the default model.
    let h = SceneUpdate::decode(&topics["/pacs/human"].3[0][..]).unwrap();
    assert!(h.entities[0].cylinders.len() + h.entities[0].spheres.len() >= 8);
    let m = SceneUpdate::decode(&topics["/pacs/violations"].3[0][..]).unwrap();
    assert!(
        m.entities[0].texts[0].text.contains("on fr3_"),
        "{}",
        m.entities[0].texts[0].text
    );
    // Metrics: JSON with our schema, one message per plot bucket of the audit.
    let (name, enc, msg_enc, msgs) = &topics["/pacs/metrics"];
    assert_eq!(
        (name.as_str(), enc.as_str(), msg_enc.as_str()),
        ("pacs.Metrics", "jsonschema", "json")
    );
    let first: serde_json::Value = serde_json::from_slice(&msgs[0]).unwrap();
    assert!(first["min_separation_m"].is_number(), "{first}");
    let violating = msgs
        .iter()
        .filter(|b| serde_json::from_slice::<serde_json::Value>(b).unwrap()["violation"] == true)
        .count();
    assert!(violating > 0);
    // The CLI's guards: one log only; an unwritable scene exits 74.
    let o = pacs(&[
        "audit",
        "examples/logs/close_sorting.jsonl",
        "examples/logs/clean_sorting.jsonl",
        "--scene",
        scene.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(3));
    let o = pacs(&[
        "audit",
        "examples/logs/clean_sorting.jsonl",
        "--scene",
        "/dev/null/x.mcap",
    ]);
    assert_eq!(
        o.status.code(),
        Some(74),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    // A clean run: no markers, the robot never red.
    let clean = dir.join("clean.mcap");
    let o = pacs(&[
        "audit",
        "examples/logs/clean_sorting.jsonl",
        "--scene",
        clean.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0));
    let (topics, _) = read_scene(&clean);
    assert!(!topics.contains_key("/pacs/violations"));
    std::fs::remove_dir_all(&dir).ok();
}

/// A log of two people replays both: `/pacs/human` draws every person's body parts (twice the
/// capsules of one person) and `/pacs/human_occupancy` every person's occupancy.
#[test]
fn every_person_of_a_log_is_replayed() {
    use pacs_log::{Header, LogWriter, ModelRef, PersonEntry};
    let dir = std::env::temp_dir().join(format!("pacs-scene-people-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let write = |ids: &[&str]| {
        let people = ids
            .iter()
            .map(|id| PersonEntry {
                id: id.to_string(),
                human: ModelRef::Name("default".into()),
            })
            .collect();
        let mut w = LogWriter::new(Vec::new());
        w.write_header(&Header::with_people(
            ModelRef::Name("fr3".into()),
            people,
            ModelRef::Name("ssm".into()),
        ))
        .unwrap();
        let q = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785];
        for i in 0..=100 {
            let t = i as f64 * 1e-3;
            if i == 0 {
                for (k, id) in ids.iter().enumerate() {
                    let kp = pacs_testkit::keypoints_in_a_row(2.5 + k as f64);
                    w.write_person(t, t, Some(id), &kp).unwrap();
                }
            }
            w.write_robot(t, &q, Some(&[0.0; 7])).unwrap();
        }
        w.write_event(0.1, pacs_log::END_EVENT).unwrap();
        let path = dir.join(format!("{}.jsonl", ids.join("-")));
        std::fs::write(&path, w.finish().unwrap()).unwrap();
        path
    };
    let capsules = |log: &Path| {
        let scene = log.with_extension("mcap");
        let o = pacs(&[
            "audit",
            log.to_str().unwrap(),
            "--scene",
            scene.to_str().unwrap(),
        ]);
        assert_eq!(
            o.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&o.stdout)
        );
        let (topics, _) = read_scene(&scene);
        let count = |t: &str| {
            let u = SceneUpdate::decode(&topics[t].3[0][..]).unwrap();
            u.entities[0].cylinders.len() + u.entities[0].spheres.len()
        };
        (count("/pacs/human"), count("/pacs/human_occupancy"))
    };
    let one = capsules(&write(&["operator"]));
    let two = capsules(&write(&["operator", "visitor"]));
    assert!(one.0 > 0 && one.1 > 0);
    assert_eq!(two, (2 * one.0, 2 * one.1));
    let _ = std::fs::remove_dir_all(&dir);
}
