//! Report building blocks: hashing (FIPS 180-2 test vector), aggregate statistics (computed by
//! hand here), plots and documents.

use pacs_audit::verdict::{Metrics, ModelNames, RunResult, SeriesPoint, Verdict};
use pacs_reports::{InputFile, ReportInput, aggregate, html, markdown, report_json, svg};

fn run(name: &str, filter: &str, success: Option<bool>, viol: f64, verdict: Verdict) -> RunResult {
    let mut meta = serde_json::Map::new();
    meta.insert("task".into(), "handover".into());
    meta.insert("policy".into(), "act".into());
    meta.insert("filter".into(), filter.into());
    RunResult {
        log: name.into(),
        verdict,
        violations: vec![],
        inconclusive: vec![],
        metrics: Metrics {
            samples: 100,
            human_records: 3,
            duration: 0.099,
            violation_fraction: viol,
            violating_samples: (viol * 100.0) as u64,
            certain_violating_samples: 0,
            inconclusive_duration: 0.0,
            min_separation: Some(0.2),
            success,
            safe_success: success.map(|s| s && verdict == Verdict::Pass),
        },
        evidence: pacs_audit::Evidence {
            t_start: 0.0,
            t_end: 0.099,
            completeness: pacs_audit::Completeness::Complete,
        },
        people: vec!["human".into()],
        meta,
        models: ModelNames {
            robot: "fr3".into(),
            human: "default".into(),
            constraints: "handover".into(),
            robot_v_max: vec![],
            robot_a_max: vec![],
            human_v_max: vec![],
            human_measurement_error_pos: 0.0,
            human_delay: 0.0,
            environment_shapes: 0,
            people: Vec::new(),
            specs: serde_json::json!({"robot": {"name": "fr3", "dof": 7}, "human": {"name": "default"}}),
        },
        series: (0..10)
            .map(|i| SeriesPoint {
                t: i as f64 * 0.01,
                t_end: (i + 1) as f64 * 0.01,
                min_separation: Some(0.1 * i as f64 - 0.25),
                far_separation: None,
                energy_nominal: Some(0.01 * i as f64),
                energy_bound: (i > 5).then_some(0.02 * i as f64),
                threshold: (i > 5).then_some(0.1),
                violation: i == 7,
                inconclusive: i == 2,
                at_rest: i == 0,
            })
            .collect(),
    }
}

#[test]
fn sha256_matches_the_fips_test_vector() {
    let p = std::env::temp_dir().join(format!("pacs-reports-abc-{}", std::process::id()));
    std::fs::write(&p, b"abc").unwrap();
    let h = InputFile::hash(&p).unwrap();
    assert_eq!(
        h.sha256,
        "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
    );
    assert_eq!(h.bytes, 3);
    let _ = std::fs::remove_file(&p);
}

#[test]
fn aggregate_groups_by_meta_with_mean_and_sample_std() {
    let runs = vec![
        run("a", "pacs", Some(true), 0.0, Verdict::Pass),
        run("b", "pacs", Some(false), 0.0, Verdict::Pass),
        run("c", "none", Some(true), 0.1, Verdict::Fail),
        run("d", "none", Some(true), 0.3, Verdict::Fail),
    ];
    let rows = aggregate::aggregate(&runs);
    assert_eq!(rows.len(), 2);
    assert_eq!((rows[0].filter.as_str(), rows[0].runs), ("pacs", 2));
    // Success {1, 0}: mean 0.5, sample std sqrt(0.5).
    let (m, s) = rows[0].success.unwrap();
    assert!((m - 0.5).abs() < 1e-15 && (s.unwrap() - 0.5f64.sqrt()).abs() < 1e-15);
    // Violation fraction {0.1, 0.3}: mean 0.2, sample std sqrt(0.02).
    let (m, s) = rows[1].safety_violation.unwrap();
    assert!((m - 0.2).abs() < 1e-15 && (s.unwrap() - 0.02f64.sqrt()).abs() < 1e-12);
    assert_eq!(rows[1].safe_success, Some((0.0, Some(0.0))));
    // One log: no spread to measure, n/a rather than ± 0.0.
    let one = aggregate::aggregate(&runs[..1]);
    assert_eq!(one[0].success, Some((1.0, None)));
    assert_eq!(aggregate::pct(one[0].success), "100.0 % ± n/a");
    assert_eq!(aggregate::pct(rows[0].success), "50.0 ± 70.7 %");
    // Python shield logs say `pacs-shield (python)` whatever the mode: the mode in their
    // `shield_config` keeps PACS and OFF apart.
    let mut py = vec![
        run("p", "pacs-shield (python)", Some(true), 0.0, Verdict::Pass),
        run("o", "pacs-shield (python)", Some(true), 0.2, Verdict::Fail),
        run("q", "pacs-shield (python)", Some(true), 0.0, Verdict::Pass),
    ];
    py[0]
        .meta
        .insert("shield_config".into(), serde_json::json!({}));
    py[1]
        .meta
        .insert("shield_config".into(), serde_json::json!({"mode": "off"}));
    py[2]
        .meta
        .insert("shield_config".into(), serde_json::json!({"mode": "pacs"}));
    let rows = aggregate::aggregate(&py);
    let f: Vec<(&str, usize)> = rows.iter().map(|r| (r.filter.as_str(), r.runs)).collect();
    assert_eq!(
        f,
        [
            ("pacs-shield (python), mode pacs", 2),
            ("pacs-shield (python), mode off", 1)
        ]
    );
}

#[test]
fn plots_and_documents() {
    let mut runs = vec![
        run("a.jsonl", "pacs", Some(true), 0.0, Verdict::Pass),
        run("b.jsonl", "none", None, 0.1, Verdict::Fail),
    ];
    // An inconclusive span about a person names the person in every document.
    runs[1]
        .inconclusive
        .push(pacs_audit::verdict::InconclusiveSpan {
            t_start: 0.01,
            t_end: 0.02,
            reason: pacs_audit::InconclusiveReason::NoHuman,
            spans: 10,
            person: Some("visitor".into()),
            object: None,
        });
    let sep = svg::separation_plot(&runs[0].series);
    assert!(sep.starts_with("<svg") && sep.ends_with("</svg>"));
    assert_eq!(sep.matches("class=\"violation\"").count(), 1);
    assert_eq!(sep.matches("class=\"inconclusive\"").count(), 1);
    assert_eq!(sep.matches("class=\"at-rest\"").count(), 1);
    // Negative separations are drawn (the zero line is inside the plot).
    assert!(sep.contains(">-0.2<"), "{sep}");
    // An SSM-like series (no threshold anywhere) has nothing to draw against.
    let mut ssm = runs[0].series.clone();
    for p in &mut ssm {
        p.threshold = None;
    }
    assert!(!svg::has_threshold(&ssm) && svg::has_threshold(&runs[0].series));
    assert!(!svg::energy_plot(&ssm).contains(">threshold<"));
    let en = svg::energy_plot(&runs[0].series);
    assert!(en.contains("class=\"threshold\"") && en.contains("class=\"energy-bound\""));
    let input = ReportInput {
        runs: &runs,
        logs: vec![
            InputFile {
                path: "a.jsonl".into(),
                sha256: "00".repeat(32),
                bytes: 1,
            },
            InputFile {
                path: "b.jsonl".into(),
                sha256: "11".repeat(32),
                bytes: 1,
            },
        ],
        config: None,
        settings: serde_json::json!({"max_gap": 0.1}),
        generated: pacs_reports::utc_now(),
        skipped: Vec::new(),
    };
    let j = report_json(&input);
    assert_eq!(j["verdict"], "fail");
    assert_eq!(j["runs"][1]["sha256"], "11".repeat(32));
    assert_eq!(j["aggregate"].as_array().unwrap().len(), 2);
    // The `pos` model's extremity-length assumption, and its fallback, are listed.
    let pos = "With human_model = pos: each extremity's keypoints stay within its length + \
               thickness/2 of its base keypoint; a measurement contradicting this by more than 2 \
               measurement_error_pos is not trusted (that extremity uses the speed-bounded \
               occupancy).";
    assert!(
        j["assumptions"]
            .as_array()
            .unwrap()
            .iter()
            .any(|a| a == pos),
        "{}",
        j["assumptions"]
    );
    assert!(markdown::report(&input).contains(pos));
    let h = html::report(&input);
    assert_eq!(h.matches("<svg").count(), 4);
    assert!(h.contains("n (logs)") && h.contains("FAIL") && h.contains("Generated 20"));
    // Settings as a table, not raw JSON; every model with the SHA-256 of its parameters.
    assert!(
        h.contains("<td><code>max_gap</code></td><td>0.1</td>"),
        "{h}"
    );
    let robot_hash = pacs_reports::model_sha256(&serde_json::json!({"name": "fr3", "dof": 7}));
    assert_eq!(
        j["runs"][0]["model_parameters"]["robot"]["sha256"],
        robot_hash
    );
    assert!(h.contains(&robot_hash));
    assert_eq!(robot_hash.len(), 64);
    // Defined once, printed with the tables.
    for k in ["separation_m", "violation_separation_m", "safe_success"] {
        assert!(j["definitions"][k].is_string(), "{k}");
    }
    assert!(j["generated_utc"].as_str().unwrap().ends_with('Z'));
    let md = markdown::report(&input);
    assert!(
        md.contains("| handover | act | pacs | 1 | 100.0 % ± n/a | 100.0 % ± n/a | 0.0 % ± n/a |"),
        "{md}"
    );
    assert!(md.contains("| `max_gap` | 0.1 |") && md.contains(&robot_hash));
    assert!(
        md.contains("- 0.0100–0.0200 s: no_human, person `visitor` (10 spans)"),
        "{md}"
    );
    assert!(
        h.contains("<li>0.0100–0.0200 s: no_human, person `visitor` (10 spans)</li>"),
        "{h}"
    );
    // The PDF: a well-formed file (header, objects, xref offsets that point at them, trailer).
    let pdf = pacs_reports::pdf::report(&input);
    assert!(pdf.starts_with(b"%PDF-1.4"));
    let text = String::from_utf8_lossy(&pdf);
    assert!(text.trim_end().ends_with("%%EOF"));
    // Offsets are in bytes: check them on the bytes.
    let tail = &pdf[pdf.len() - 64..];
    let tail = String::from_utf8_lossy(tail);
    let startxref: usize = tail
        .rsplit("startxref")
        .next()
        .unwrap()
        .split_whitespace()
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(pdf[startxref..].starts_with(b"xref"));
    let xref = String::from_utf8_lossy(&pdf[startxref..]).to_string();
    let count: usize = xref
        .lines()
        .nth(1)
        .unwrap()
        .split_whitespace()
        .nth(1)
        .unwrap()
        .parse()
        .unwrap();
    for (i, line) in xref.lines().skip(3).take(count - 1).enumerate() {
        let off: usize = line[..10].parse().unwrap();
        assert!(
            pdf[off..].starts_with(format!("{} 0 obj", i + 1).as_bytes()),
            "object {}",
            i + 1
        );
    }
    let pages = text.matches("/Type /Page ").count();
    assert!(pages >= 2, "{pages} pages");
    assert!(text.contains(&format!("/Count {pages}")));
    assert!(text.contains("(Generated 20"));
}

#[test]
fn utc_dates_are_gregorian() {
    assert_eq!(pacs_reports::utc(0), "1970-01-01T00:00:00Z");
    assert_eq!(pacs_reports::utc(951_782_400), "2000-02-29T00:00:00Z");
    assert_eq!(pacs_reports::utc(1_795_620_600), "2026-11-25T15:30:00Z");
    assert_eq!(pacs_reports::utc(4_107_542_399), "2100-02-28T23:59:59Z");
}

/// A run of several people: the report's model rows give each person's model, parameters and
/// hash (not the first person's for everyone).
#[test]
fn model_rows_name_every_persons_model() {
    let mut r = run("p.jsonl", "pacs", None, 0.0, Verdict::Pass);
    let spec = |delay: f64| serde_json::json!({"name": "default", "delay": delay});
    r.models.specs = serde_json::json!({
        "robot": {"name": "fr3"},
        "human": spec(0.0),
        "humans": {"A": spec(0.0), "B": spec(0.3)},
        "constraints": {"name": "ssm"},
    });
    r.models.people = ["A", "B"]
        .iter()
        .zip([0.0, 0.3])
        .map(|(id, d)| pacs_audit::PersonModel {
            id: id.to_string(),
            human: if *id == "B" {
                "delayed (custom spec)"
            } else {
                "default"
            }
            .into(),
            human_v_max: vec![2.0],
            human_measurement_error_pos: 0.01,
            human_delay: d,
        })
        .collect();
    let rows = pacs_reports::model_rows(&r);
    let heads: Vec<_> = rows.iter().map(|row| row[0].as_str()).collect();
    assert_eq!(heads, ["robot", "human `A`", "human `B`", "constraints"]);
    assert!(rows[2][2].contains("delay 0.3 s"), "{:?}", rows[2]);
    assert!(rows[1][2].contains("delay 0 s"), "{:?}", rows[1]);
    assert_eq!(rows[2][3], pacs_reports::model_sha256(&spec(0.3)));
    assert_ne!(rows[1][3], rows[2][3]);
}

/// Text from the logs (file names, `meta` values) cannot break report.md's tables: a `|` is
/// escaped and a newline shown as a space, so every table row keeps its cells and no line of a
/// log's text becomes a heading (a `meta.robot_id` with "\n## injected").
#[test]
fn log_text_cannot_break_the_markdown_tables() {
    let mut runs = vec![
        run("a|b.jsonl", "pa|cs", Some(true), 0.0, Verdict::Pass),
        run(
            "c\n## log.jsonl",
            "none\n## filter",
            None,
            0.1,
            Verdict::Fail,
        ),
    ];
    runs[0]
        .meta
        .insert("robot_id".into(), "arm\n## injected | x".into());
    runs[1].meta.insert("robot_id".into(), "arm|2".into());
    let input = ReportInput {
        runs: &runs,
        logs: ["a|b.jsonl", "c\n## log.jsonl"]
            .iter()
            .map(|p| InputFile {
                path: (*p).into(),
                sha256: "00".repeat(32),
                bytes: 1,
            })
            .collect(),
        config: None,
        settings: serde_json::json!({"max_gap": 0.1}),
        generated: pacs_reports::utc_now(),
        skipped: Vec::new(),
    };
    let md = markdown::report(&input);
    let headings: Vec<&str> = md.lines().filter(|l| l.starts_with('#')).collect();
    assert!(
        headings
            .iter()
            .all(|h| !h.contains("injected") && !h.starts_with("## filter")),
        "{headings:?}"
    );
    // Every row of a table has as many unescaped `|` as its header row.
    let unescaped = |l: &str| l.matches('|').count() - l.matches("\\|").count();
    let mut width = None;
    for line in md.lines() {
        if line.starts_with('|') {
            let w = unescaped(line);
            match width {
                None => width = Some(w),
                Some(h) => assert_eq!(w, h, "row {line:?}\n{md}"),
            }
        } else {
            width = None;
        }
    }
    assert!(
        md.contains("pa\\|cs") && md.contains("arm ## injected \\| x"),
        "{md}"
    );
}

/// An inconclusive log's violation fraction counts only what was checked: the aggregate's
/// safety violation is over the logs with a verdict, and says how many it left out ("n/a" when
/// every log is inconclusive) — never 0 % for time nobody checked.
#[test]
fn the_aggregate_violation_leaves_inconclusive_logs_out_and_says_so() {
    let runs = vec![
        run("a", "none", Some(true), 0.2, Verdict::Fail),
        run("b", "none", Some(true), 0.0, Verdict::Inconclusive),
    ];
    let rows = aggregate::aggregate(&runs);
    assert_eq!(
        (rows[0].safety_violation, rows[0].inconclusive),
        (Some((0.2, None)), 1)
    );
    assert_eq!(
        aggregate::violation_cell(&rows[0]),
        "20.0 % ± n/a (1 inconclusive left out)"
    );
    let rows = aggregate::aggregate(&runs[1..]);
    assert_eq!((rows[0].safety_violation, rows[0].inconclusive), (None, 1));
    assert_eq!(
        aggregate::violation_cell(&rows[0]),
        "n/a (1 inconclusive left out)"
    );
    let json = serde_json::to_value(&rows[0]).unwrap();
    assert!(json.get("safety_violation").is_none(), "{json}");
}
