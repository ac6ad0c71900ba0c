//! Hand-written SVG plots (no dependencies): minimum separation and energy vs threshold over
//! time, with violation spans shaded red and inconclusive spans grey.

use pacs_audit::verdict::SeriesPoint;
use std::fmt::Write;

const W: f64 = 760.0;
const H: f64 = 220.0;
const ML: f64 = 60.0;
const MR: f64 = 15.0;
const MT: f64 = 32.0;
const MB: f64 = 35.0;

struct Frame {
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
}

impl Frame {
    fn x(&self, t: f64) -> f64 {
        ML + (t - self.x0) / (self.x1 - self.x0).max(1e-12) * (W - ML - MR)
    }
    fn y(&self, v: f64) -> f64 {
        let v = v.clamp(self.y0, self.y1);
        H - MB - (v - self.y0) / (self.y1 - self.y0).max(1e-12) * (H - MT - MB)
    }
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

fn axes(out: &mut String, f: &Frame, title: &str, ylabel: &str) {
    let _ = write!(
        out,
        r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 {W} {H}" width="100%" role="img" aria-label="{t}" font-family="sans-serif" font-size="11">"#,
        t = esc(title)
    );
    let _ = write!(
        out,
        r##"<rect x="{ML}" y="{MT}" width="{}" height="{}" fill="#fff" stroke="#444"/>"##,
        W - ML - MR,
        H - MT - MB
    );
    let (ys, ystep) = ticks(f.y0, f.y1);
    for v in ys {
        let y = f.y(v);
        let _ = write!(
            out,
            r##"<line x1="{ML}" x2="{}" y1="{y:.1}" y2="{y:.1}" stroke="{}"/><text x="{}" y="{:.1}" text-anchor="end">{}</text>"##,
            W - MR,
            if v == 0.0 { "#888" } else { "#ddd" },
            ML - 4.0,
            y + 4.0,
            fmt_tick(v, ystep)
        );
    }
    let (xs, xstep) = ticks(f.x0, f.x1);
    for t in xs {
        let x = f.x(t);
        let _ = write!(
            out,
            r##"<line x1="{x:.1}" x2="{x:.1}" y1="{}" y2="{}" stroke="#444"/><text x="{x:.1}" y="{}" text-anchor="middle">{}</text>"##,
            H - MB,
            H - MB + 4.0,
            H - MB + 15.0,
            fmt_tick(t, xstep)
        );
    }
    let _ = write!(
        out,
        r#"<text x="{}" y="{}" text-anchor="middle">time (s)</text><text x="12" y="{}" transform="rotate(-90 12 {})" text-anchor="middle">{}</text><text x="{ML}" y="13" font-weight="bold">{}</text>"#,
        (ML + W - MR) / 2.0,
        H - 4.0,
        H / 2.0,
        H / 2.0,
        esc(ylabel),
        esc(title)
    );
}

/// Tick values at a 1-2-5 step covering [lo, hi] (4 to 10 ticks) and the step.
pub fn ticks(lo: f64, hi: f64) -> (Vec<f64>, f64) {
    let range = (hi - lo).abs().max(1e-12);
    let raw = range / 5.0;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|m| m * mag)
        .find(|&st| range / st <= 8.0)
        .unwrap_or(10.0 * mag);
    let first = (lo / step).ceil();
    let mut out = Vec::new();
    let mut k = first;
    while k * step <= hi + 1e-9 * step && out.len() < 20 {
        // Snap -0 and rounding noise.
        let v = k * step;
        out.push(if v.abs() < 1e-12 * step { 0.0 } else { v });
        k += 1.0;
    }
    (out, step)
}

/// A tick label with as many decimals as the step needs.
pub fn fmt_tick(v: f64, step: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    if !(1e-4..1e4).contains(&step) {
        return format!("{v:.1e}");
    }
    let dec = (-step.log10().floor()).max(0.0) as usize;
    format!("{v:.dec$}")
}

fn shading(out: &mut String, f: &Frame, s: &[SeriesPoint]) {
    for p in s
        .iter()
        .filter(|p| p.at_rest && !p.violation && !p.inconclusive)
    {
        let (a, b) = (f.x(p.t), f.x(p.t_end.min(f.x1)));
        let _ = write!(
            out,
            r##"<rect class="at-rest" x="{a:.2}" y="{MT}" width="{:.2}" height="{}" fill="#66bb6a" fill-opacity="0.18"/>"##,
            (b - a).max(0.8),
            H - MT - MB
        );
    }
    for p in s {
        let colour = if p.violation {
            "#e53935"
        } else if p.inconclusive {
            "#9e9e9e"
        } else {
            continue;
        };
        let (a, b) = (f.x(p.t), f.x(p.t_end.min(f.x1)));
        let _ = write!(
            out,
            r#"<rect class="{}" x="{a:.2}" y="{MT}" width="{:.2}" height="{}" fill="{colour}" fill-opacity="0.3"/>"#,
            if p.violation {
                "violation"
            } else {
                "inconclusive"
            },
            (b - a).max(0.8),
            H - MT - MB
        );
    }
}

fn polyline(
    out: &mut String,
    f: &Frame,
    pts: impl Iterator<Item = (f64, Option<f64>)>,
    style: &str,
) {
    let mut d = String::new();
    let mut pen = false;
    for (t, v) in pts {
        match v {
            Some(v) if v.is_finite() => {
                let _ = write!(
                    d,
                    "{}{:.2},{:.2} ",
                    if pen { "L" } else { "M" },
                    f.x(t),
                    f.y(v)
                );
                pen = true;
            }
            _ => pen = false,
        }
    }
    if !d.is_empty() {
        let _ = write!(out, r#"<path d="{d}" fill="none" {style}/>"#);
    }
}

fn legend(out: &mut String, items: &[(&str, &str)]) {
    let mut x = W - MR - 10.0;
    for (label, colour) in items.iter().rev() {
        x -= 7.0 * label.len() as f64 + 22.0;
        let _ = write!(
            out,
            r#"<rect x="{x:.1}" y="18" width="12" height="8" fill="{colour}"/><text x="{:.1}" y="26">{}</text>"#,
            x + 15.0,
            esc(label)
        );
    }
}

/// Legend of the coarse separation (dotted grey): spans where everyone was outside the robot's
/// workspace ball, whose distance alone was computed (always > 0, far below the distance to
/// the arm).
pub const FAR_LABEL: &str = "outside reach (≥ ball distance)";

/// The separation figure over time (m; ≤ 0: contact possible), with at-rest, violation and
/// inconclusive spans shaded; where only the workspace ball was checked (everyone outside it),
/// the coarse figure is drawn dotted grey ([`FAR_LABEL`]), never as the separation.
pub fn separation_plot(s: &[SeriesPoint]) -> String {
    let (x0, x1) = span(s);
    let vals: Vec<f64> = s
        .iter()
        .flat_map(|p| [p.min_separation, p.far_separation])
        .flatten()
        .filter(|v| v.is_finite())
        .collect();
    let ymax = vals.iter().copied().fold(0.0f64, f64::max).clamp(0.1, 3.0);
    let ymin = vals.iter().copied().fold(0.0f64, f64::min).max(-1.0);
    let pad = 0.05 * (ymax - ymin);
    let f = Frame {
        x0,
        x1,
        y0: if ymin < 0.0 { ymin - pad } else { 0.0 },
        y1: ymax + pad,
    };
    let mut out = String::new();
    axes(
        &mut out,
        &f,
        "Separation figure (lower bound; ≤ 0: contact possible)",
        "m",
    );
    shading(&mut out, &f, s);
    polyline(
        &mut out,
        &f,
        s.iter().map(|p| (0.5 * (p.t + p.t_end), p.far_separation)),
        r##"class="far-separation" stroke="#757575" stroke-width="1.2" stroke-dasharray="2,3""##,
    );
    polyline(
        &mut out,
        &f,
        s.iter().map(|p| (0.5 * (p.t + p.t_end), p.min_separation)),
        r##"class="separation" stroke="#1565c0" stroke-width="1.5""##,
    );
    let mut items = vec![("separation", "#1565c0")];
    if s.iter().any(|p| p.far_separation.is_some()) {
        items.push((FAR_LABEL, "#757575"));
    }
    items.extend([
        ("at rest", "#66bb6a60"),
        ("violation", "#e5393580"),
        ("inconclusive", "#9e9e9e80"),
    ]);
    legend(&mut out, &items);
    out.push_str("</svg>");
    out
}

/// Whether any bucket has a PFL threshold (a possible PFL contact): only then does the energy
/// plot have a limit to show.
pub fn has_threshold(s: &[SeriesPoint]) -> bool {
    s.iter().any(|p| p.threshold.is_some_and(f64::is_finite))
}

/// Energy plot: nominal kinetic energy, energy upper bound at possible PFL contacts, and the
/// threshold (J), with shaded violation / inconclusive spans.
pub fn energy_plot(s: &[SeriesPoint]) -> String {
    let (x0, x1) = span(s);
    let ymax = s
        .iter()
        .flat_map(|p| [p.energy_nominal, p.energy_bound, p.threshold])
        .flatten()
        .filter(|v| v.is_finite())
        .fold(0.0f64, f64::max)
        .max(1e-3);
    let f = Frame {
        x0,
        x1,
        y0: 0.0,
        y1: ymax * 1.05,
    };
    let mut out = String::new();
    axes(&mut out, &f, "Kinetic energy vs PFL threshold", "J");
    shading(&mut out, &f, s);
    let mid = |p: &SeriesPoint| 0.5 * (p.t + p.t_end);
    polyline(
        &mut out,
        &f,
        s.iter().map(|p| (mid(p), p.energy_nominal)),
        r##"class="energy-nominal" stroke="#1565c0" stroke-width="1.2""##,
    );
    polyline(
        &mut out,
        &f,
        s.iter().map(|p| (mid(p), p.energy_bound)),
        r##"class="energy-bound" stroke="#ef6c00" stroke-width="1.5""##,
    );
    polyline(
        &mut out,
        &f,
        s.iter().map(|p| (mid(p), p.threshold)),
        r##"class="threshold" stroke="#b71c1c" stroke-width="1.5" stroke-dasharray="5,3""##,
    );
    let mut items = vec![
        ("nominal energy", "#1565c0"),
        ("energy bound at contact", "#ef6c00"),
    ];
    if has_threshold(s) {
        items.push(("threshold", "#b71c1c"));
    }
    items.push(("at rest", "#66bb6a60"));
    legend(&mut out, &items);
    out.push_str("</svg>");
    out
}

fn span(s: &[SeriesPoint]) -> (f64, f64) {
    match (s.first(), s.last()) {
        (Some(a), Some(b)) if b.t_end > a.t => (a.t, b.t_end),
        (Some(a), _) => (a.t, a.t + 1.0),
        _ => (0.0, 1.0),
    }
}
