//! SVG plots of rollouts: tool paths seen from above, and the true separation over time.

use super::Rollout;
use crate::task::{TaskKind, scenario, tool_point};
use std::fmt::Write as _;

/// The method labels of `rollouts`, in first-seen order.
fn methods_in<'a>(rollouts: &[&'a Rollout]) -> Vec<&'a str> {
    let mut methods: Vec<&str> = Vec::new();
    for r in rollouts {
        if !methods.contains(&r.method.as_str()) {
            methods.push(&r.method);
        }
    }
    methods
}

fn color(speed: f64, v_max: f64) -> String {
    // Light (slow) to dark blue (fast).
    let u = (speed / v_max).clamp(0.0, 1.0);
    let lerp = |a: f64, b: f64| (a + u * (b - a)).round() as u8;
    format!(
        "#{:02x}{:02x}{:02x}",
        lerp(198.0, 8.0),
        lerp(219.0, 48.0),
        lerp(239.0, 107.0)
    )
}

/// Top view (x–y, m) of the tool paths of `rollouts` (one task) coloured by speed, with the
/// demonstrations' region (tool paths of the task's demonstrations, ±2 cm) shaded grey: one
/// panel per method. Needs rollouts recorded with `record_every > 0`.
pub fn svg_paths(task: TaskKind, rollouts: &[&Rollout]) -> String {
    let scn = scenario(task, 0, true);
    let demo_tool: Vec<Vec<[f64; 3]>> = scn
        .policy
        .demos()
        .iter()
        .map(|d| d.iter().map(|q| tool_point(&scn.robot, q)).collect())
        .collect();
    let methods = methods_in(rollouts);
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    let pts = demo_tool.iter().flatten().chain(
        rollouts
            .iter()
            .flat_map(|r| r.episode.samples.iter().map(|s| &s.tool)),
    );
    for p in pts {
        x0 = x0.min(p[0]);
        x1 = x1.max(p[0]);
        y0 = y0.min(p[1]);
        y1 = y1.max(p[1]);
    }
    let pad = 0.05;
    let (x0, x1, y0, y1) = (x0 - pad, x1 + pad, y0 - pad, y1 + pad);
    // Colour scale: 0 to the 95th percentile of the recorded tool speeds (robust to spikes).
    let mut speeds: Vec<f64> = rollouts
        .iter()
        .flat_map(|r| r.episode.samples.iter().map(|s| s.tool_speed))
        .collect();
    speeds.sort_by(f64::total_cmp);
    let v_max = speeds
        .get(speeds.len() * 95 / 100)
        .copied()
        .unwrap_or(0.1)
        .max(0.05);
    let panel = 320.0;
    let scale = panel / (x1 - x0).max(y1 - y0);
    let w = panel * methods.len().max(1) as f64 + 20.0;
    let h = panel + 74.0;
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w:.0}\" height=\"{h:.0}\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n<text x=\"10\" y=\"16\">{}: tool paths seen from above (robot base at the origin, x up the page, y to the left)</text>\n<text x=\"10\" y=\"32\">colour: tool speed 0–{v_max:.2} m/s (light to dark blue); grey band: the demonstrations ±2 cm</text>\n",
        task.name()
    );
    for (mi, m) in methods.iter().enumerate() {
        let ox = 10.0 + mi as f64 * panel;
        let oy = 44.0;
        // Screen: x axis to the right = world −y (robot's left on the left), down = world −x.
        let map = |p: &[f64; 3]| (ox + (y1 - p[1]) * scale, oy + (x1 - p[0]) * scale);
        let _ = writeln!(
            s,
            "<g><rect x=\"{ox:.1}\" y=\"{oy:.1}\" width=\"{panel:.0}\" height=\"{panel:.0}\" fill=\"none\" stroke=\"#999\"/><text x=\"{:.1}\" y=\"{:.1}\">{m}</text>",
            ox + 6.0,
            oy + 16.0
        );
        for d in &demo_tool {
            let pts: Vec<String> = d
                .iter()
                .map(|p| {
                    let (a, b) = map(p);
                    format!("{a:.1},{b:.1}")
                })
                .collect();
            let _ = writeln!(
                s,
                "<polyline points=\"{}\" fill=\"none\" stroke=\"#bbbbbb\" stroke-opacity=\"0.5\" stroke-width=\"{:.1}\" stroke-linecap=\"round\" stroke-linejoin=\"round\"/>",
                pts.join(" "),
                0.04 * scale
            );
        }
        for r in rollouts.iter().filter(|r| r.method == *m) {
            for w2 in r.episode.samples.windows(2) {
                let (a, b) = (map(&w2[0].tool), map(&w2[1].tool));
                let _ = writeln!(
                    s,
                    "<line x1=\"{:.1}\" y1=\"{:.1}\" x2=\"{:.1}\" y2=\"{:.1}\" stroke=\"{}\" stroke-width=\"2\" stroke-linecap=\"round\"/>",
                    a.0,
                    a.1,
                    b.0,
                    b.1,
                    color(w2[1].tool_speed, v_max)
                );
            }
        }
        s.push_str("</g>\n");
    }
    let _ = writeln!(
        s,
        "<text x=\"10\" y=\"{:.0}\">scale: 10 cm = {:.0} px</text>\n</svg>",
        h - 10.0,
        0.1 * scale
    );
    s
}

/// True minimum separation (m) between the moving robot and the human over time, one line per
/// rollout, coloured by method; contact (≤ 0) shaded red.
pub fn svg_separation(task: TaskKind, rollouts: &[&Rollout]) -> String {
    const PALETTE: [&str; 9] = [
        "#d62728", "#1f77b4", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2", "#17becf",
        "#7f7f7f",
    ];
    let methods = methods_in(rollouts);
    let t_max = rollouts
        .iter()
        .flat_map(|r| r.episode.samples.last().map(|s| s.t))
        .fold(1.0, f64::max);
    let d_max = 1.0;
    let d_min = -0.1;
    let (w, h, l, top, pw, ph) = (760.0, 360.0, 50.0, 30.0, 680.0, 280.0);
    let x = |t: f64| l + t / t_max * pw;
    let y = |d: f64| top + (d_max - d.clamp(d_min, d_max)) / (d_max - d_min) * ph;
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n<text x=\"10\" y=\"18\">{}: true separation robot–human (m, clipped to [−0.1, 1]) over time (s)</text>\n<rect x=\"{l}\" y=\"{:.1}\" width=\"{pw}\" height=\"{:.1}\" fill=\"#f4cccc\"/>\n<rect x=\"{l}\" y=\"{top}\" width=\"{pw}\" height=\"{ph}\" fill=\"none\" stroke=\"#999\"/>\n",
        task.name(),
        y(0.0),
        y(d_min) - y(0.0)
    );
    for k in 0..=5 {
        let d = k as f64 * 0.2;
        let _ = writeln!(
            s,
            "<text x=\"{:.0}\" y=\"{:.1}\" text-anchor=\"end\">{d:.1}</text>",
            l - 4.0,
            y(d) + 4.0
        );
    }
    let steps = (t_max / 2.0).ceil() as usize;
    for k in 0..=steps {
        let t = k as f64 * 2.0;
        let _ = writeln!(
            s,
            "<text x=\"{:.1}\" y=\"{:.0}\" text-anchor=\"middle\">{t:.0}</text>",
            x(t),
            top + ph + 16.0
        );
    }
    for (mi, m) in methods.iter().enumerate() {
        let c = PALETTE[mi % PALETTE.len()];
        for r in rollouts.iter().filter(|r| r.method == *m) {
            let pts: Vec<String> = r
                .episode
                .samples
                .iter()
                .filter(|s| s.separation.is_finite())
                .map(|s| format!("{:.1},{:.1}", x(s.t), y(s.separation)))
                .collect();
            let _ = writeln!(
                s,
                "<polyline points=\"{}\" fill=\"none\" stroke=\"{c}\" stroke-opacity=\"0.6\" stroke-width=\"1.2\"/>",
                pts.join(" ")
            );
        }
        let _ = writeln!(
            s,
            "<rect x=\"{:.0}\" y=\"{:.0}\" width=\"12\" height=\"3\" fill=\"{c}\"/><text x=\"{:.0}\" y=\"{:.0}\">{m}</text>",
            l + 10.0 + mi as f64 * 90.0,
            h - 22.0,
            l + 26.0 + mi as f64 * 90.0,
            h - 16.0
        );
    }
    s.push_str("</svg>\n");
    s
}
