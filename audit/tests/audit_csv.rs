//! The CSV form gives exactly the JSON Lines result; bad CSV input is rejected with its line.

mod audit_common;

use audit_common::*;
use pacs_audit::{AuditConfig, Verdict};
use pacs_log::{Location, LogError, csv::CsvReader};
use serde_json::Value;

/// Convert a JSON Lines log to the CSV form (written here, independently of the reader).
fn to_csv(jsonl: &str) -> String {
    let mut out = String::new();
    for (i, line) in jsonl.lines().enumerate() {
        if i == 0 {
            out.push_str(&format!("#{line}\n"));
            continue;
        }
        let v: Value = serde_json::from_str(line).unwrap();
        let t = v["t"].as_f64().unwrap();
        let nums = |a: &Value| -> Vec<String> {
            a.as_array()
                .unwrap()
                .iter()
                .map(|x| format!("{:?}", x.as_f64().unwrap()))
                .collect()
        };
        match v["type"].as_str().unwrap() {
            "robot" => {
                let mut cells = nums(&v["q"]);
                let n = cells.len();
                if v.get("dq").is_some() {
                    cells.extend(nums(&v["dq"]));
                }
                out.push_str(&format!("robot,{t:?},{n},{}\n", cells.join(",")));
            }
            "human" => {
                let p: Vec<String> = v["positions"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .flat_map(nums)
                    .collect();
                out.push_str(&format!(
                    "human,{t:?},{:?},{}\n",
                    v["t_meas"].as_f64().unwrap(),
                    p.join(",")
                ));
            }
            "event" => out.push_str(&format!("event,{t:?},{}\n", v["name"].as_str().unwrap())),
            other => panic!("{other}"),
        }
    }
    out
}

fn run_csv(text: &str) -> Result<pacs_audit::RunResult, LogError> {
    let mut r = CsvReader::new("test.csv", std::io::Cursor::new(text.as_bytes()))?;
    pacs_audit::audit_reader(&mut r, &AuditConfig::default())
}

#[test]
fn csv_and_jsonl_give_the_same_result() {
    let mut log = Log::new(ssm());
    let near = standing(0.45, 0.0);
    for i in 0..=300 {
        let t = i as f64 * 1e-3;
        if i % 30 == 0 {
            log.human(t, &near);
        }
        let mut q = Q_READY;
        q[0] = 0.5 * t;
        log.robot(
            t,
            &q,
            if i % 2 == 0 {
                Some(&[0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
            } else {
                None
            },
        );
    }
    log.w.write_event(0.3, "success").unwrap();
    let text = log.text();
    let a = run(&text, &AuditConfig::default()).unwrap();
    let mut b = run_csv(&to_csv(&text)).unwrap();
    assert_eq!(a.verdict, Verdict::Fail, "the scenario has violations");
    b.log = a.log.clone();
    assert_eq!(a, b);
}

fn expect(text: &str, line: u64, what: &str) {
    let e = run_csv(text).expect_err("must be rejected");
    let msg = e.to_string();
    assert!(
        matches!(e, LogError::Input { location, .. } if location == Location::Line(line)),
        "{msg}"
    );
    assert!(msg.contains(what), "`{msg}` should mention `{what}`");
}

const H: &str = r#"#{"type":"header","format":"pacs-log","version":1,"robot":"fr3","human":"default","constraints":"ssm"}"#;

#[test]
fn bad_csv_input_is_rejected_with_its_line() {
    let human = "human,0,0,2,0,1,2,0,1,2,0,1,2,0,1,2,0,1,2,0,1,2,0,1,2,0,1,2,0,1";
    let ok = "robot,0,7,0,-0.785,0,-2.356,0,1.571,0.785";
    expect(
        &format!("{H}\n{human}\nrobot,0,7,NaN,-0.785,0,-2.356,0,1.571,0.785\n"),
        3,
        "not finite",
    );
    expect(
        &format!("{H}\n{human}\nrobot,0,7,inf,-0.785,0,-2.356,0,1.571,0.785\n"),
        3,
        "not finite",
    );
    expect(
        &format!("{H}\n{human}\nrobot,0,7,x,-0.785,0,-2.356,0,1.571,0.785\n"),
        3,
        "not a number",
    );
    expect(
        &format!("{H}\n{human}\nrobot,0,7,0,0,0\n"),
        3,
        "expected 7, 14 or 21",
    );
    expect(
        &format!("{H}\n{human}\nrobot,0,6,0,0,0,0,0,0\n"),
        3,
        "expected 7 joint positions",
    );
    expect(
        &format!("{H}\n{human}\n{ok}\nrobot,-1,7,0,-0.785,0,-2.356,0,1.571,0.785\n"),
        4,
        "backwards",
    );
    expect(&format!("{H}\nhuman,0,0,1,2\n"), 2, "multiple of 3");
    expect(&format!("{H}\nlidar,0\n"), 2, "unknown record type `lidar`");
    // An event row is `event,t,name`: a cell after the name is an error, not an `end` event.
    expect(
        &format!("{H}\n{human}\n{ok}\nevent,0,end,x\n"),
        4,
        "cell after `name`: `x`",
    );
    expect(&format!("{H}\n{human}\n{ok}"), 3, "truncated");
    let e = run_csv(&format!("{human}\n")).unwrap_err();
    assert!(e.to_string().contains("missing header"));
}

/// Object rows: `object,t,t_meas,id,x,y,z[,vx,vy,vz]`. A ball resting on the flange
/// under `no_contact` fails; malformed rows name the problem and the line.
#[test]
fn object_rows_are_audited() {
    let h = r#"#{"type":"header","format":"pacs-log","version":1,"robot":"fr3","human":"default","constraints":"ssm","objects":[{"id":"b1","object":"ball","contact":"no_contact"}]}"#;
    let robot = pacs_models::RobotModel::builtin("fr3").unwrap();
    let f = robot.capsules_world(&Q_READY).last().unwrap().1.p2();
    let kp: Vec<String> = standing(2.5, 0.0)
        .iter()
        .flat_map(|p| p.iter().map(|x| x.to_string()))
        .collect();
    let q: Vec<String> = Q_READY.iter().map(|x| x.to_string()).collect();
    let mut text = format!("{h}\n");
    for k in 0..=50 {
        let t = k as f64 * 1e-3;
        if k % 10 == 0 {
            text += &format!("human,{t},{t},{}\n", kp.join(","));
            text += &format!("object,{t},{t},b1,{},{},{},0,0,0\n", f.x, f.y, f.z);
        }
        text += &format!("robot,{t},7,{}\n", q.join(","));
    }
    let r = run_csv(&text).unwrap();
    assert_eq!(r.verdict, Verdict::Fail);
    assert_eq!(r.violations[0].body_part, "object `b1`");
    expect(
        &format!("{h}\nobject,0,0,b1,1,2\n"),
        2,
        "expected 3 (position) or 6",
    );
    expect(&format!("{h}\nobject,0,0,b1,1,2,nan\n"), 2, "position[2]");
    expect(&format!("{h}\nobject,0,0\n"), 2, "missing column `id`");
}
