//! What an assessor sees — violation intervals merged into episodes (the intervals in
//! report.json and violations.csv), PASS with contact explained, the same summary columns in
//! HTML, PDF and Markdown, the coarse far-range separation drawn apart, user-given model values
//! under the assumptions.

use pacs_audit::verdict::{Metrics, ModelNames, RunResult, SeriesPoint, Verdict};
use pacs_audit::{ConstraintKind, Violation};
use pacs_reports::episodes::{EPISODE_COLUMNS, Episode, episode_cells, episodes, violations_csv};
use pacs_reports::{InputFile, ReportInput, SUMMARY_COLUMNS, html, markdown, report_json, svg};

fn viol(t0: f64, t1: f64, kind: ConstraintKind, part: &str, link: &str, sep: f64) -> Violation {
    Violation {
        t_start: t0,
        t_end: t1,
        constraint: kind,
        person: None,
        body_part: part.into(),
        link: link.into(),
        min_separation: sep,
        energy: if kind == ConstraintKind::Pfl {
            3.0
        } else {
            0.0
        },
        threshold: if kind == ConstraintKind::Pfl {
            2.0
        } else {
            0.0
        },
        constrained: false,
        certain: sep < 0.0,
        spans: ((t1 - t0) / 0.001).round() as u64,
        first_span: 0,
    }
}

fn run(name: &str, verdict: Verdict, violations: Vec<Violation>, min_sep: f64) -> RunResult {
    RunResult {
        log: name.into(),
        verdict,
        violations,
        inconclusive: vec![],
        metrics: Metrics {
            samples: 1000,
            human_records: 30,
            duration: 0.999,
            violation_fraction: 0.0,
            violating_samples: 0,
            certain_violating_samples: 0,
            inconclusive_duration: 0.0,
            min_separation: Some(min_sep),
            success: Some(true),
            safe_success: Some(verdict == Verdict::Pass),
        },
        evidence: pacs_audit::Evidence::default(),
        people: vec!["human".into()],
        meta: serde_json::Map::new(),
        models: ModelNames {
            robot: "ur5e".into(),
            human: "default".into(),
            constraints: "sorting".into(),
            robot_v_max: vec![3.0],
            robot_a_max: vec![10.0],
            human_v_max: vec![],
            human_measurement_error_pos: 0.0,
            human_delay: 0.0,
            environment_shapes: 0,
            people: Vec::new(),
            specs: serde_json::json!({"robot": {"name": "ur5e", "user_values": [
                "a_max = 10 rad/s² for every joint", "j_max = 5000 rad/s³ for every joint"]}}),
        },
        // Far (workspace ball only) for the first half, then the arm's figure down to min_sep at rest.
        series: (0..10)
            .map(|i| {
                let far = i < 5;
                SeriesPoint {
                    t: i as f64 * 0.1,
                    t_end: (i + 1) as f64 * 0.1,
                    min_separation: (!far).then_some(min_sep + 0.1 * (9 - i) as f64),
                    far_separation: far.then_some(0.05 * (5 - i) as f64),
                    energy_nominal: Some(0.0),
                    energy_bound: None,
                    threshold: None,
                    violation: false,
                    inconclusive: false,
                    at_rest: i == 9,
                }
            })
            .collect(),
    }
}

fn input(runs: &[RunResult]) -> ReportInput<'_> {
    ReportInput {
        runs,
        logs: runs
            .iter()
            .map(|r| InputFile {
                path: r.log.clone(),
                sha256: "ab".repeat(32),
                bytes: 1,
            })
            .collect(),
        config: None,
        settings: serde_json::json!({}),
        generated: "2026-11-28T19:00:00Z".into(),
        skipped: Vec::new(),
    }
}

/// 1 ms intervals of one contact (two body parts, gaps of a few ms) are one episode; a later one
/// (0.5 s on), another link and an object are episodes of their own.
#[test]
fn intervals_merge_into_episodes() {
    use ConstraintKind::{NoContact, Pfl, Ssm};
    let mut v = Vec::new();
    for k in 0..55 {
        let t = 1.200 + 0.006 * k as f64;
        let part = if k % 2 == 0 {
            "right hand"
        } else {
            "right forearm"
        };
        v.push(viol(
            t,
            t + 0.001,
            Ssm,
            part,
            "link7",
            0.01 - 0.001 * k as f64,
        ));
    }
    v.push(viol(2.0, 2.1, Ssm, "right hand", "link7", 0.02));
    v.push(viol(1.3, 1.31, Ssm, "head", "link6", 0.03));
    v.push(viol(1.25, 1.26, NoContact, "object `ball`", "link7", -0.01));
    v.push(viol(3.0, 3.01, Pfl, "chest", "link5", 0.0));
    v.push(viol(3.05, 3.06, Pfl, "chest", "link5", -0.002));
    let e = episodes(&v);
    let rows: Vec<(String, &str, f64, f64, usize)> = e
        .iter()
        .map(|e| {
            (
                e.who.clone(),
                e.link.as_str(),
                e.t_start,
                e.t_end,
                e.intervals,
            )
        })
        .collect();
    assert_eq!(
        rows,
        vec![
            (
                "person".into(),
                "link7",
                1.2,
                1.2 + 0.006 * 54.0 + 0.001,
                55
            ),
            ("object `ball`".into(), "link7", 1.25, 1.26, 1),
            ("person".into(), "link6", 1.3, 1.31, 1),
            ("person".into(), "link7", 2.0, 2.1, 1),
            ("person".into(), "link5", 3.0, 3.06, 2),
        ]
    );
    let first: &Episode = &e[0];
    assert_eq!(first.body_parts, ["right hand", "right forearm"]);
    assert!(
        (first.violating_s - 0.055).abs() < 1e-9,
        "{}",
        first.violating_s
    );
    assert!((first.worst_separation_m - (0.01 - 0.054)).abs() < 1e-12);
    assert!(first.certain && first.worst_energy_j.is_nan());
    // In JSON an SSM episode's energy and threshold are 0 (as its violations'), never null.
    let j = serde_json::to_value(first).unwrap();
    assert_eq!(
        (j["worst_energy_j"].as_f64(), j["threshold_j"].as_f64()),
        (Some(0.0), Some(0.0))
    );
    assert_eq!(
        episode_cells(first),
        [
            "1.2000",
            "1.5250",
            "person (right hand, right forearm)",
            "link7",
            "SSM (no contact while moving)",
            "0.0550 / 55",
            "-0.0440",
            "-",
            "-",
            "yes",
        ]
    );
    // PFL: the worst energy bound and the threshold, union of the covered time.
    let pfl = &e[4];
    assert_eq!((pfl.worst_energy_j, pfl.threshold_j), (3.0, 2.0));
    assert!((pfl.violating_s - 0.02).abs() < 1e-12);
    assert_eq!(episode_cells(pfl)[7..9], ["3.0000", "2.0000"]);
    // Overlapping intervals count once in the covered time.
    let o = episodes(&[
        viol(0.0, 0.1, Ssm, "head", "l", 0.0),
        viol(0.05, 0.12, Ssm, "neck", "l", 0.0),
    ]);
    assert_eq!(o.len(), 1);
    assert!((o[0].violating_s - 0.12).abs() < 1e-12);
}

/// report.json keeps the intervals and adds the episodes; violations.csv beside it has one row
/// per interval; HTML, PDF and Markdown show the episodes, not the intervals.
#[test]
fn intervals_go_to_json_and_csv_episodes_to_the_documents() {
    let v: Vec<Violation> = (0..40)
        .map(|k| {
            let t = 0.5 + 0.002 * k as f64;
            viol(
                t,
                t + 0.001,
                ConstraintKind::Ssm,
                "right hand",
                "link7",
                -0.01,
            )
        })
        .collect();
    let runs = vec![run("off.jsonl", Verdict::Fail, v, -0.01)];
    let inp = input(&runs);
    let j = report_json(&inp);
    assert_eq!(j["runs"][0]["violations"].as_array().unwrap().len(), 40);
    assert_eq!(j["runs"][0]["episodes"].as_array().unwrap().len(), 1);
    assert_eq!(j["runs"][0]["episodes"][0]["intervals"], 40);
    let csv = violations_csv(&runs);
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines.len(), 41);
    assert_eq!(
        lines[0],
        "log,t_start_s,t_end_s,constraint,person,body_part,link,min_separation_m,energy_j,threshold_j,clamped,certain,spans"
    );
    assert_eq!(
        lines[1],
        "off.jsonl,0.5,0.501,SSM,,right hand,link7,-0.01,,,false,true,1"
    );
    let h = html::report(&inp);
    assert_eq!(
        h.matches("<td class=\"num\">0.5000</td>").count(),
        1,
        "one row"
    );
    assert!(h.contains("1 violation episode(s) from 40 violation interval(s)"));
    let md = markdown::report(&inp);
    assert!(md.contains(&format!("| {} |", EPISODE_COLUMNS.join(" | "))));
    assert_eq!(md.matches("| 0.5000 |").count(), 1);
    let dir = std::env::temp_dir().join(format!("pacs-reports-episodes-{}", std::process::id()));
    pacs_reports::write_reports(&dir, &inp).unwrap();
    assert_eq!(
        std::fs::read_to_string(dir.join("violations.csv")).unwrap(),
        csv
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// A PASS run with a separation ≤ 0 says why (contact while at rest is allowed under SSM);
/// a FAIL run or a positive separation does not.
#[test]
fn pass_with_contact_says_why() {
    let pass = run("pacs.jsonl", Verdict::Pass, vec![], -0.03);
    assert_eq!(
        pacs_reports::contact_note(&pass),
        Some("contact while at rest (SSM allows)")
    );
    let runs = vec![pass];
    let h = html::report(&input(&runs));
    assert!(h.contains("Passed with a separation figure ≤ 0: contact while at rest (SSM allows)."));
    assert!(h.contains("-0.0300: contact while at rest (SSM allows)"));
    let fail = run("off.jsonl", Verdict::Fail, vec![], -0.03);
    assert_eq!(pacs_reports::contact_note(&fail), None);
    let clear = run("far.jsonl", Verdict::Pass, vec![], 0.2);
    assert_eq!(pacs_reports::contact_note(&clear), None);
}

/// HTML, PDF and Markdown carry the same summary columns (success included), with the same cells.
#[test]
fn html_pdf_and_markdown_have_the_same_summary_columns() {
    let runs = vec![run("pacs.jsonl", Verdict::Pass, vec![], 0.2)];
    let inp = input(&runs);
    let h = html::report(&inp);
    let md = markdown::report(&inp);
    let pdf = String::from_utf8_lossy(&pacs_reports::pdf::report(&inp)).to_string();
    for head in SUMMARY_COLUMNS {
        let html_head = head.replace(" (1)", "¹").replace(" (2)", "²");
        assert!(
            h.contains(&format!(">{html_head}</th>")),
            "HTML lacks {head}"
        );
        assert!(md.contains(&format!(" {head} |")), "Markdown lacks {head}");
        // The PDF wraps heads into words: each word is drawn.
        for w in head.split_whitespace() {
            let w = w.replace('(', "\\(").replace(')', "\\)");
            assert!(pdf.contains(&w), "PDF lacks {w} of {head}");
        }
    }
    assert!(
        pdf.contains("(success) Tj"),
        "the success column in the PDF"
    );
    let cells = pacs_reports::summary_cells(&runs[0], &inp.logs[0]);
    assert_eq!(cells[8], "yes");
    assert_eq!(cells[9], "yes");
    assert_eq!(cells[7], "0");
}

/// Where only the workspace ball was checked the plot draws a dotted grey line, labelled, and
/// never as the separation; the separation line has only the arm's figures.
#[test]
fn the_far_range_bound_is_drawn_apart() {
    let r = run("pacs.jsonl", Verdict::Pass, vec![], 0.2);
    let sep = svg::separation_plot(&r.series);
    assert_eq!(sep.matches("class=\"far-separation\"").count(), 1);
    assert!(sep.contains(&format!(">{}<", svg::FAR_LABEL)));
    let path = |class: &str| {
        let i = sep.find(&format!("class=\"{class}\"")).unwrap();
        let d0 = sep[..i].rfind("d=\"").unwrap() + 3;
        sep[d0..d0 + sep[d0..].find('"').unwrap()].to_string()
    };
    // 5 far buckets, 5 of the arm: one point each in its own line.
    assert_eq!(path("far-separation").matches(['M', 'L']).count(), 5);
    assert_eq!(path("separation").matches(['M', 'L']).count(), 5);
    // Without far buckets no far line and no legend entry.
    let mut near = r.series.clone();
    for p in &mut near {
        p.far_separation = None;
    }
    let sep = svg::separation_plot(&near);
    assert!(!sep.contains("far-separation") && !sep.contains(svg::FAR_LABEL));
}

/// Model values from the side file (not the robot description) are listed under the assumptions.
#[test]
fn user_given_values_are_assumptions() {
    let runs = vec![run("pacs.jsonl", Verdict::Pass, vec![], 0.2)];
    let inp = input(&runs);
    let j = report_json(&inp);
    assert_eq!(
        j["user_values"],
        serde_json::json!([
            "robot `ur5e`: a_max = 10 rad/s² for every joint",
            "robot `ur5e`: j_max = 5000 rad/s³ for every joint"
        ])
    );
    let h = html::report(&inp);
    assert!(h.contains("<li>robot `ur5e`: a_max = 10 rad/s² for every joint</li>"));
    assert!(markdown::report(&inp).contains("- robot `ur5e`: j_max = 5000 rad/s³ for every joint"));
    let pdf = String::from_utf8_lossy(&pacs_reports::pdf::report(&inp)).to_string();
    assert!(pdf.contains("a_max = 10 rad/s"));
}

/// A v2 log of two people: the intervals of each person are their own episodes, named by the
/// person, even on one link at one time; the CSV carries the person of every interval.
#[test]
fn episodes_of_several_people_name_the_person() {
    let mut v = Vec::new();
    for (k, who) in ["operator", "visitor"].iter().enumerate() {
        for i in 0..3 {
            let t = 0.5 + i as f64 * 0.001;
            let mut x = viol(
                t,
                t + 0.001,
                ConstraintKind::Ssm,
                "right hand",
                "link7",
                -0.01,
            );
            x.person = Some(who.to_string());
            x.spans = 1 + k as u64;
            v.push(x);
        }
    }
    let e = episodes(&v);
    assert_eq!(e.len(), 2);
    let names: Vec<String> = e.iter().map(|e| episode_cells(e)[2].clone()).collect();
    assert!(
        names.contains(&"person `operator` (right hand)".to_string()),
        "{names:?}"
    );
    assert!(
        names.contains(&"person `visitor` (right hand)".to_string()),
        "{names:?}"
    );
    let runs = vec![run("two.jsonl", Verdict::Fail, v, -0.01)];
    let csv = violations_csv(&runs);
    assert!(
        csv.lines()
            .nth(1)
            .unwrap()
            .contains(",SSM,operator,right hand,")
    );
    assert_eq!(csv.lines().filter(|l| l.contains(",visitor,")).count(), 3);
}

/// Every document states what each log covers: its people, the audited span and whether it is
/// the whole run (an incomplete log says so in HTML, Markdown and PDF).
#[test]
fn every_document_states_the_evidence() {
    let mut r = run("cut.jsonl", Verdict::Inconclusive, vec![], 0.2);
    r.people = vec!["operator".into(), "visitor".into()];
    r.evidence = pacs_audit::Evidence {
        t_start: 0.0,
        t_end: 0.719,
        completeness: pacs_audit::Completeness::Incomplete,
    };
    let runs = vec![r];
    let inp = input(&runs);
    let h = html::report(&inp);
    let md = markdown::report(&inp);
    let pdf = String::from_utf8_lossy(&pacs_reports::pdf::report(&inp)).to_string();
    for doc in [&h, &md] {
        assert!(doc.contains("operator, visitor"), "{doc}");
        assert!(doc.contains("0.000 – 0.719"));
        assert!(doc.contains("INCOMPLETE (cut short: never a pass)"));
    }
    assert!(pdf.contains("(Evidence) Tj"));
    assert!(pdf.contains("(operator, visitor) Tj"));
    assert!(pdf.contains("INCOMPLETE"));
    let j = report_json(&inp);
    assert_eq!(j["runs"][0]["evidence"]["completeness"], "incomplete");
    assert_eq!(j["runs"][0]["people"][1], "visitor");
    // A log without robot samples states none (not a span of 0 s at 0 s); one whose writer
    // promised only its end says so.
    let mut r = runs[0].clone();
    r.metrics.samples = 0;
    r.evidence.completeness = pacs_audit::Completeness::EndOnly;
    let row = pacs_reports::evidence_row(&r);
    assert_eq!(row[2], "no robot samples");
    assert!(
        row[3].starts_with("end event reached; no start promised"),
        "{}",
        row[3]
    );
}

/// A PFL episode's figures merge over its intervals: the largest energy bound, the smallest
/// threshold, clamped if any interval was, certain if any was — whichever interval they come from.
#[test]
fn a_pfl_episode_keeps_its_worst_figures() {
    let pfl = |t: f64, energy: f64, threshold: f64, constrained: bool, sep: f64| Violation {
        energy,
        threshold,
        constrained,
        ..viol(t, t + 0.01, ConstraintKind::Pfl, "chest", "link5", sep)
    };
    let e = episodes(&[
        pfl(1.00, 3.0, 2.0, false, 0.01),
        pfl(1.02, 5.0, 2.0, false, 0.02),
        pfl(1.04, 4.0, 1.0, true, -0.001),
        pfl(1.06, 2.5, 2.0, false, 0.03),
    ]);
    assert_eq!(e.len(), 1);
    let ep = &e[0];
    assert_eq!(ep.intervals, 4);
    assert_eq!(ep.worst_energy_j, 5.0);
    assert_eq!(ep.threshold_j, 1.0);
    assert!(ep.clamped && ep.certain);
    assert_eq!(ep.worst_separation_m, -0.001);
    // The same intervals in another order merge to the same figures.
    let mut shuffled = vec![
        pfl(1.06, 2.5, 2.0, false, 0.03),
        pfl(1.04, 4.0, 1.0, true, -0.001),
        pfl(1.00, 3.0, 2.0, false, 0.01),
        pfl(1.02, 5.0, 2.0, false, 0.02),
    ];
    let again = episodes(&shuffled);
    assert_eq!(again, e);
    // Without the clamped interval: not clamped, the free threshold, not certain.
    shuffled.remove(1);
    let free = &episodes(&shuffled)[0];
    assert!(!free.clamped && !free.certain);
    assert_eq!((free.worst_energy_j, free.threshold_j), (5.0, 2.0));
}
