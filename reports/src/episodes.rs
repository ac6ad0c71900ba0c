//! Violation episodes: the audit's violation intervals (often a few ms each, one per body part
//! and link) merged into what an assessor reads as one event — the same person or object, link
//! and constraint, with gaps of at most [`EPISODE_GAP_S`] between the intervals.

use pacs_audit::{ConstraintKind, Violation};
use serde::Serialize;

/// Intervals of one person or object, link and constraint less than this far apart (s) are one
/// episode.
pub const EPISODE_GAP_S: f64 = 0.1;

/// One violation episode.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Episode {
    /// `person` or `object `ID``.
    pub who: String,
    /// The body parts (person) or the object involved, in order of first violation.
    pub body_parts: Vec<String>,
    /// Robot link name.
    pub link: String,
    /// SSM, PFL or no-contact.
    pub constraint: ConstraintKind,
    /// Start of the first interval (s).
    pub t_start: f64,
    /// End of the last interval (s).
    pub t_end: f64,
    /// Time covered by the merged intervals (s; their union, so at most `t_end - t_start`).
    pub violating_s: f64,
    /// Number of violation intervals merged (the rows of report.json and violations.csv).
    pub intervals: usize,
    /// Smallest signed separation (m) of the logged robot and the measured person or object
    /// over the episode (negative: overlap as logged; `NaN` if none was computed).
    pub worst_separation_m: f64,
    /// Largest energy upper bound (J) (PFL; `NaN` otherwise, written as 0 in JSON, as an SSM
    /// violation's `energy`: never `null`).
    #[serde(serialize_with = "zero_unless_finite")]
    pub worst_energy_j: f64,
    /// Smallest threshold (J) that applied (PFL; `NaN` otherwise, written as 0 in JSON, as an SSM
    /// violation's `threshold`).
    #[serde(serialize_with = "zero_unless_finite")]
    pub threshold_j: f64,
    /// The constrained (clamping) threshold applied somewhere.
    pub clamped: bool,
    /// Some interval is certain (the logged robot and the measured person themselves violate).
    pub certain: bool,
}

/// An SSM episode's energy and threshold (not computed: `NaN`) as JSON writes them: 0, as the
/// violation rows do, never `null`.
fn zero_unless_finite<S: serde::Serializer>(x: &f64, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_f64(if x.is_finite() { *x } else { 0.0 })
}

/// Who a violation belongs to: objects are named `object `ID``; body parts belong to the person
/// the violation names (a v2 log's person id, as `person `ID``), or to `person` (a v1 log's one
/// person).
fn who(v: &Violation) -> String {
    if v.body_part.starts_with("object `") {
        v.body_part.clone()
    } else {
        match &v.person {
            Some(id) => format!("person `{id}`"),
            None => "person".into(),
        }
    }
}

/// Merge violation intervals into episodes, ordered by start time (then who, link).
pub fn episodes(violations: &[Violation]) -> Vec<Episode> {
    let mut sorted: Vec<&Violation> = violations.iter().collect();
    sorted.sort_by(|a, b| a.t_start.total_cmp(&b.t_start));
    let mut out: Vec<Episode> = Vec::new();
    // Per key, the index in `out` of its latest episode.
    let mut open: Vec<((String, String, ConstraintKind), usize)> = Vec::new();
    for v in sorted {
        let key = (who(v), v.link.clone(), v.constraint);
        let pfl = v.constraint == ConstraintKind::Pfl;
        let energy = if pfl { v.energy } else { f64::NAN };
        let threshold = if pfl { v.threshold } else { f64::NAN };
        let slot = open.iter().position(|(k, _)| *k == key);
        if let Some(i) = slot.map(|s| open[s].1)
            && v.t_start - out[i].t_end <= EPISODE_GAP_S
        {
            let e = &mut out[i];
            // Union length: only the part beyond what is covered so far (sorted by start).
            e.violating_s += (v.t_end - v.t_start.max(e.t_end)).max(0.0);
            e.t_end = e.t_end.max(v.t_end);
            e.intervals += 1;
            if !e.body_parts.contains(&v.body_part) {
                e.body_parts.push(v.body_part.clone());
            }
            e.worst_separation_m = e.worst_separation_m.min(v.min_separation);
            e.worst_energy_j = e.worst_energy_j.max(energy);
            e.threshold_j = e.threshold_j.min(threshold);
            e.clamped |= v.constrained;
            e.certain |= v.certain;
            continue;
        }
        out.push(Episode {
            who: key.0.clone(),
            body_parts: vec![v.body_part.clone()],
            link: v.link.clone(),
            constraint: v.constraint,
            t_start: v.t_start,
            t_end: v.t_end,
            violating_s: v.t_end - v.t_start,
            intervals: 1,
            worst_separation_m: v.min_separation,
            worst_energy_j: energy,
            threshold_j: threshold,
            clamped: v.constrained,
            certain: v.certain,
        });
        match slot {
            Some(s) => open[s].1 = out.len() - 1,
            None => open.push((key, out.len() - 1)),
        }
    }
    out
}

/// The column heads of [`episode_cells`] (HTML, PDF and Markdown print the same).
pub const EPISODE_COLUMNS: [&str; 10] = [
    "from (s)",
    "to (s)",
    "who (body parts)",
    "link",
    "constraint",
    "violating (s) / intervals",
    "worst separation (m)",
    "worst energy bound (J)",
    "threshold (J)",
    "certain",
];

/// An episode as report cells ([`EPISODE_COLUMNS`]): energies only for PFL (`-` otherwise).
pub fn episode_cells(e: &Episode) -> [String; 10] {
    let num = |x: f64| {
        if x.is_finite() {
            format!("{x:.4}")
        } else {
            "-".into()
        }
    };
    [
        format!("{:.4}", e.t_start),
        format!("{:.4}", e.t_end),
        if e.who.starts_with("person") {
            format!("{} ({})", e.who, e.body_parts.join(", "))
        } else {
            e.who.clone()
        },
        e.link.clone(),
        crate::constraint_name(e.constraint),
        format!("{:.4} / {}", e.violating_s, e.intervals),
        num(e.worst_separation_m),
        num(e.worst_energy_j),
        if e.threshold_j.is_finite() {
            format!(
                "{:.4}{}",
                e.threshold_j,
                if e.clamped { " (clamped)" } else { "" }
            )
        } else {
            "-".into()
        },
        if e.certain { "yes" } else { "possible" }.into(),
    ]
}

/// The violation intervals of the runs as CSV (`violations.csv` beside report.json): one row per
/// interval, the log first; separations in m, energies in J (empty: not computed).
pub fn violations_csv(runs: &[pacs_audit::RunResult]) -> String {
    let mut s = String::from(
        "log,t_start_s,t_end_s,constraint,person,body_part,link,min_separation_m,energy_j,threshold_j,clamped,certain,spans\n",
    );
    let q = |x: &str| {
        if x.contains([',', '"', '\n']) {
            format!("\"{}\"", x.replace('"', "\"\""))
        } else {
            x.to_string()
        }
    };
    let num = |x: f64| {
        if x.is_finite() {
            format!("{x}")
        } else {
            String::new()
        }
    };
    for r in runs {
        for v in &r.violations {
            let pfl = v.constraint == ConstraintKind::Pfl;
            s.push_str(&format!(
                "{},{},{},{},{},{},{},{},{},{},{},{},{}\n",
                q(&r.log),
                v.t_start,
                v.t_end,
                v.constraint.label(),
                q(v.person.as_deref().unwrap_or("")),
                q(&v.body_part),
                q(&v.link),
                num(v.min_separation),
                if pfl { num(v.energy) } else { String::new() },
                if pfl { num(v.threshold) } else { String::new() },
                v.constrained,
                v.certain,
                v.spans
            ));
        }
    }
    s
}
