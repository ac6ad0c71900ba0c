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
        },
        series: (0..10)
            .map(|i| SeriesPoint {
                t: i as f64 * 0.01,
                t_end: (i + 1) as f64 * 0.01,
                min_separation: Some(0.1 * i as f64),
                energy_nominal: Some(0.01 * i as f64),
                energy_bound: (i > 5).then_some(0.02 * i as f64),
                threshold: (i > 5).then_some(0.1),
                violation: i == 7,
                inconclusive: i == 2,
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
    assert!((m - 0.5).abs() < 1e-15 && (s - 0.5f64.sqrt()).abs() < 1e-15);
    // Violation fraction {0.1, 0.3}: mean 0.2, sample std sqrt(0.02).
    let (m, s) = rows[1].safety_violation;
    assert!((m - 0.2).abs() < 1e-15 && (s - 0.02f64.sqrt()).abs() < 1e-12);
    assert_eq!(rows[1].safe_success, Some((0.0, 0.0)));
}

#[test]
fn plots_and_documents() {
    let runs = vec![
        run("a.jsonl", "pacs", Some(true), 0.0, Verdict::Pass),
        run("b.jsonl", "none", None, 0.1, Verdict::Fail),
    ];
    let sep = svg::separation_plot(&runs[0].series);
    assert!(sep.starts_with("<svg") && sep.ends_with("</svg>"));
    assert_eq!(sep.matches("class=\"violation\"").count(), 1);
    assert_eq!(sep.matches("class=\"inconclusive\"").count(), 1);
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
    };
    let j = report_json(&input);
    assert_eq!(j["verdict"], "fail");
    assert_eq!(j["runs"][1]["sha256"], "11".repeat(32));
    assert_eq!(j["aggregate"].as_array().unwrap().len(), 2);
    // Issue 11: the `pos` model's extremity-length assumption, and its fallback, are listed.
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
    assert!(h.contains("Safety Viol.") && h.contains("FAIL"));
    let md = markdown::report(&input);
    assert!(
        md.contains("| handover | act | pacs | 1 | 100.0 ± 0.0 % | 100.0 ± 0.0 % | 0.0 ± 0.0 % |"),
        "{md}"
    );
}
