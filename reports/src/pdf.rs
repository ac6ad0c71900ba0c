//! `report.pdf`: the certification report drawn directly as PDF 1.4 (A4 portrait, the standard
//! Helvetica and Courier fonts, vector plots), with no dependency: what an assessor prints and
//! signs. The same content as `report.html`: provenance, settings, summary, per log the models
//! with the SHA-256 of their parameters, the separation and energy plots and the violations,
//! then the assumptions and the checks with the tests backing them.

use crate::svg::{fmt_tick, ticks};
use crate::{ReportInput, TOOL_VERSION, definitions};
use pacs_audit::verdict::SeriesPoint;
use std::fmt::Write;

mod sections;

const PAGE_W: f64 = 595.0;
const PAGE_H: f64 = 842.0;
const MARGIN: f64 = 48.0;
const TEXT_W: f64 = PAGE_W - 2.0 * MARGIN;

/// A plotted line: (time, value) points, stroke colour (PDF `RG` operands), dash pattern.
type Line<'a> = (Vec<(f64, Option<f64>)>, &'a str, &'a str);

#[derive(Clone, Copy, PartialEq)]
enum Font {
    Regular,
    Bold,
    Mono,
}

impl Font {
    fn name(self) -> &'static str {
        match self {
            Font::Regular => "F1",
            Font::Bold => "F2",
            Font::Mono => "F3",
        }
    }
}

/// Helvetica advance widths (1/1000 em) of the printable ASCII characters 32..=126 (the font's
/// published metrics).
const HELVETICA: [u16; 95] = [
    278, 278, 355, 556, 556, 889, 667, 191, 333, 333, 389, 584, 278, 333, 278, 278, 556, 556, 556,
    556, 556, 556, 556, 556, 556, 556, 278, 278, 584, 584, 584, 556, 1015, 667, 667, 722, 722, 667,
    611, 778, 722, 278, 500, 667, 556, 833, 722, 778, 667, 778, 722, 667, 611, 722, 667, 944, 667,
    667, 611, 278, 278, 278, 469, 556, 333, 556, 556, 500, 556, 556, 278, 556, 556, 222, 222, 500,
    222, 833, 556, 556, 556, 556, 333, 500, 278, 556, 500, 722, 500, 500, 500, 334, 260, 334, 584,
];

/// The WinAnsi bytes of `s` (PDF standard fonts): Latin-1 as is, typographic dashes and quotes
/// mapped, other symbols spelled out.
fn win_ansi(s: &str) -> Vec<u8> {
    let mut out = Vec::with_capacity(s.len());
    for c in s.chars() {
        match c {
            ' '..='~' => out.push(c as u8),
            '\u{a0}'..='\u{ff}' => out.push(c as u32 as u8),
            '–' => out.push(0x96),
            '—' => out.push(0x97),
            '‘' => out.push(0x91),
            '’' => out.push(0x92),
            '“' => out.push(0x93),
            '”' => out.push(0x94),
            '•' => out.push(0x95),
            '…' => out.push(0x85),
            '≤' => out.extend_from_slice(b"<="),
            '≥' => out.extend_from_slice(b">="),
            '⁴' => out.push(b'4'),
            '∧' => out.extend_from_slice(b"and"),
            '→' => out.extend_from_slice(b"->"),
            '\n' | '\t' => out.push(b' '),
            _ => out.push(b'?'),
        }
    }
    out
}

fn char_width(b: u8, font: Font) -> f64 {
    let w = match font {
        Font::Mono => 600.0,
        _ => match b {
            32..=126 => HELVETICA[(b - 32) as usize] as f64,
            _ => 556.0,
        },
    };
    if font == Font::Bold { w * 1.06 } else { w }
}

fn text_width(s: &str, size: f64, font: Font) -> f64 {
    win_ansi(s)
        .iter()
        .map(|&b| char_width(b, font))
        .sum::<f64>()
        * size
        / 1000.0
}

/// Split `s` into lines no wider than `width` (pt), at spaces, or anywhere inside a word longer
/// than a line (hashes, paths).
fn wrap(s: &str, size: f64, font: Font, width: f64) -> Vec<String> {
    let mut lines = Vec::new();
    let mut cur = String::new();
    for word in s.split(' ') {
        let candidate = if cur.is_empty() {
            word.to_string()
        } else {
            format!("{cur} {word}")
        };
        if text_width(&candidate, size, font) <= width {
            cur = candidate;
            continue;
        }
        if !cur.is_empty() {
            lines.push(std::mem::take(&mut cur));
        }
        // A word wider than the line: break it by characters.
        let mut piece = String::new();
        for ch in word.chars() {
            piece.push(ch);
            if text_width(&piece, size, font) > width {
                piece.pop();
                lines.push(std::mem::take(&mut piece));
                piece.push(ch);
            }
        }
        cur = piece;
    }
    lines.push(cur);
    lines
}

/// Pages of content streams being laid out top to bottom.
struct Doc {
    pages: Vec<String>,
    y: f64,
}

impl Doc {
    fn new() -> Self {
        let mut d = Self {
            pages: Vec::new(),
            y: 0.0,
        };
        d.new_page();
        d
    }

    fn new_page(&mut self) {
        self.pages.push(String::new());
        self.y = PAGE_H - MARGIN;
    }

    fn out(&mut self) -> &mut String {
        self.pages.last_mut().expect("a page")
    }

    /// Make room for `h` pt, starting a new page if needed.
    fn need(&mut self, h: f64) {
        if self.y - h < MARGIN {
            self.new_page();
        }
    }

    fn put_text(&mut self, x: f64, y: f64, s: &str, size: f64, font: Font, rgb: [f64; 3]) {
        let bytes = win_ansi(s);
        let mut esc = String::new();
        for b in bytes {
            match b {
                b'(' | b')' | b'\\' => {
                    esc.push('\\');
                    esc.push(b as char);
                }
                32..=126 => esc.push(b as char),
                _ => {
                    let _ = write!(esc, "\\{b:03o}");
                }
            }
        }
        let _ = writeln!(
            self.out(),
            "BT {:.3} {:.3} {:.3} rg /{} {size:.1} Tf {x:.2} {y:.2} Td ({esc}) Tj ET",
            rgb[0],
            rgb[1],
            rgb[2],
            font.name()
        );
    }

    /// A paragraph, wrapped to the text width.
    fn para(&mut self, s: &str, size: f64, font: Font) {
        for line in wrap(s, size, font, TEXT_W) {
            self.need(size * 1.3);
            self.y -= size * 1.3;
            let y = self.y;
            self.put_text(MARGIN, y, &line, size, font, [0.0; 3]);
        }
    }

    fn heading(&mut self, s: &str, size: f64) {
        self.need(size * 3.0);
        self.y -= size * 0.8;
        self.para(s, size, Font::Bold);
        self.y -= size * 0.3;
    }

    fn gap(&mut self, h: f64) {
        self.y -= h;
    }

    /// A table: column widths as fractions of the text width; cells wrap; the header repeats on
    /// a new page.
    fn table(&mut self, header: &[&str], widths: &[f64], rows: &[Vec<(String, Font)>], size: f64) {
        let w: Vec<f64> = widths.iter().map(|f| f * TEXT_W).collect();
        let lh = size * 1.25;
        let layout = |cells: &[(String, Font)]| -> (Vec<Vec<String>>, f64) {
            let lines: Vec<Vec<String>> = cells
                .iter()
                .zip(&w)
                .map(|((t, f), cw)| wrap(t, size, *f, cw - 4.0))
                .collect();
            let n = lines.iter().map(Vec::len).max().unwrap_or(1) as f64;
            (lines, n * lh + 3.0)
        };
        let head: Vec<(String, Font)> =
            header.iter().map(|h| (h.to_string(), Font::Bold)).collect();
        let draw_row = |d: &mut Doc, cells: &[(String, Font)], shade: bool| {
            let (lines, h) = layout(cells);
            let top = d.y;
            if shade {
                let _ = writeln!(
                    d.out(),
                    "0.92 0.92 0.92 rg {:.2} {:.2} {:.2} {:.2} re f",
                    MARGIN,
                    top - h,
                    TEXT_W,
                    h
                );
            }
            let mut x = MARGIN;
            for (k, cell) in lines.iter().enumerate() {
                for (i, line) in cell.iter().enumerate() {
                    let y = top - lh * (i as f64 + 1.0) + 1.0;
                    d.put_text(x + 2.0, y, line, size, cells[k].1, [0.0; 3]);
                }
                x += w[k];
            }
            let _ = writeln!(
                d.out(),
                "0.6 0.6 0.6 RG 0.4 w {:.2} {:.2} m {:.2} {:.2} l S",
                MARGIN,
                top - h,
                MARGIN + TEXT_W,
                top - h
            );
            d.y = top - h;
        };
        self.gap(4.0);
        self.need(layout(&head).1 + layout(rows.first().map_or(&head[..], |r| &r[..])).1);
        draw_row(self, &head, true);
        for r in rows {
            let (_, h) = layout(r);
            if self.y - h < MARGIN {
                self.new_page();
                draw_row(self, &head, true);
            }
            draw_row(self, r, false);
        }
        self.gap(6.0);
    }

    /// A plot of the series: the kinetic energy and its threshold if `energy`, else the separation.
    fn plot(&mut self, s: &[SeriesPoint], energy: bool) {
        let (pw, ph) = (TEXT_W, 150.0);
        self.need(ph + 30.0);
        let top = self.y - 14.0;
        let title = if energy {
            "Kinetic energy: nominal (blue), bound at possible PFL contact (orange), threshold (red, dashed)"
        } else {
            "Separation figure (m; <= 0: contact possible); dotted grey: outside reach, ball distance only"
        };
        self.put_text(MARGIN, top + 3.0, title, 8.5, Font::Bold, [0.0; 3]);
        let (l, r, b, t) = (MARGIN + 38.0, MARGIN + pw, top - ph, top - 6.0);
        let ((x0, x1), (y0, y1)) = plot_ranges(s, energy);
        let px = |x: f64| l + (x - x0) / (x1 - x0).max(1e-12) * (r - l);
        let py = |v: f64| b + (v.clamp(y0, y1) - y0) / (y1 - y0).max(1e-12) * (t - b);
        let o = self.out();
        // Shading: at rest (green), inconclusive (grey), violation (red).
        for p in s {
            let c = if p.violation {
                "0.98 0.75 0.75"
            } else if p.inconclusive {
                "0.85 0.85 0.85"
            } else if p.at_rest {
                "0.86 0.95 0.86"
            } else {
                continue;
            };
            let (a, z) = (px(p.t), px(p.t_end.min(x1)));
            let _ = writeln!(
                o,
                "{c} rg {a:.2} {b:.2} {:.2} {:.2} re f",
                (z - a).max(0.5),
                t - b
            );
        }
        let _ = writeln!(
            o,
            "0 0 0 RG 0.6 w {l:.2} {b:.2} {:.2} {:.2} re S",
            r - l,
            t - b
        );
        let mut labels = Vec::new();
        let (ys, ystep) = ticks(y0, y1);
        for v in ys {
            let y = py(v);
            let g = if v == 0.0 { "0.45" } else { "0.85" };
            let _ = writeln!(o, "{g} {g} {g} RG 0.4 w {l:.2} {y:.2} m {r:.2} {y:.2} l S");
            labels.push((l - 3.0, y - 2.5, fmt_tick(v, ystep), true));
        }
        let (xs, xstep) = ticks(x0, x1);
        for x in xs {
            let xx = px(x);
            let _ = writeln!(
                o,
                "0 0 0 RG 0.4 w {xx:.2} {b:.2} m {xx:.2} {:.2} l S",
                b - 3.0
            );
            labels.push((xx, b - 11.0, fmt_tick(x, xstep), false));
        }
        let series = plot_lines(s, energy);
        for (pts, rgb, dash) in series {
            let mut pen = false;
            let _ = write!(o, "{rgb} RG 1 w {dash} d ");
            for (x, v) in pts {
                match v {
                    Some(v) if v.is_finite() => {
                        let _ = write!(
                            o,
                            "{:.2} {:.2} {} ",
                            px(x),
                            py(v),
                            if pen { "l" } else { "m" }
                        );
                        pen = true;
                    }
                    _ => pen = false,
                }
            }
            let _ = writeln!(o, "S [] 0 d");
        }
        for (x, y, txt, right) in labels {
            let w = text_width(&txt, 7.0, Font::Regular);
            let xx = if right { x - w } else { x - w / 2.0 };
            self.put_text(xx, y, &txt, 7.0, Font::Regular, [0.2; 3]);
        }
        self.put_text(r - 40.0, b - 20.0, "time (s)", 7.0, Font::Regular, [0.2; 3]);
        self.y = b - 26.0;
    }

    /// The PDF file: catalog, page tree, fonts, pages and their content streams.
    fn finish(self) -> Vec<u8> {
        let n = self.pages.len();
        // Objects: 1 catalog, 2 pages, 3-5 fonts, then per page: page, content.
        let mut objs: Vec<Vec<u8>> = Vec::new();
        let kids: Vec<String> = (0..n).map(|i| format!("{} 0 R", 6 + 2 * i)).collect();
        objs.push(b"<< /Type /Catalog /Pages 2 0 R >>".to_vec());
        objs.push(format!("<< /Type /Pages /Kids [{}] /Count {n} >>", kids.join(" ")).into_bytes());
        for base in ["Helvetica", "Helvetica-Bold", "Courier"] {
            objs.push(
                format!(
                    "<< /Type /Font /Subtype /Type1 /BaseFont /{base} /Encoding /WinAnsiEncoding >>"
                )
                .into_bytes(),
            );
        }
        for (i, content) in self.pages.iter().enumerate() {
            let footer = format!(
                "BT 0.4 0.4 0.4 rg /F1 7 Tf {MARGIN:.2} 24 Td (pacs audit certification report - page {} of {n}) Tj ET\n",
                i + 1
            );
            let stream = format!("{content}{footer}");
            objs.push(
                format!(
                    "<< /Type /Page /Parent 2 0 R /MediaBox [0 0 {PAGE_W} {PAGE_H}] /Resources << /Font << /F1 3 0 R /F2 4 0 R /F3 5 0 R >> >> /Contents {} 0 R >>",
                    7 + 2 * i
                )
                .into_bytes(),
            );
            let mut c = format!("<< /Length {} >>\nstream\n", stream.len()).into_bytes();
            c.extend_from_slice(stream.as_bytes());
            c.extend_from_slice(b"\nendstream");
            objs.push(c);
        }
        objs.push(
            format!(
                "<< /Title (pacs audit certification report) /Producer (pacs {TOOL_VERSION}) >>"
            )
            .into_bytes(),
        );
        let info = objs.len();
        let mut out = b"%PDF-1.4\n%\xe2\xe3\xcf\xd3\n".to_vec();
        let mut offsets = Vec::with_capacity(objs.len());
        for (i, o) in objs.iter().enumerate() {
            offsets.push(out.len());
            out.extend_from_slice(format!("{} 0 obj\n", i + 1).as_bytes());
            out.extend_from_slice(o);
            out.extend_from_slice(b"\nendobj\n");
        }
        let xref = out.len();
        let mut x = format!("xref\n0 {}\n0000000000 65535 f \n", objs.len() + 1);
        for off in offsets {
            let _ = writeln!(x, "{off:010} 00000 n ");
        }
        let _ = write!(
            x,
            "trailer\n<< /Size {} /Root 1 0 R /Info {info} 0 R >>\nstartxref\n{xref}\n%%EOF\n",
            objs.len() + 1
        );
        out.extend_from_slice(x.as_bytes());
        out
    }
}

/// The plotted time range (s) and value range (m or J) of the series: the values and 0 (for the
/// separation, the top within 0.1..3 m and the bottom at least -1 m), padded by 5 % of the range
/// (below only if the bottom is negative).
fn plot_ranges(s: &[SeriesPoint], energy: bool) -> ((f64, f64), (f64, f64)) {
    let (x0, x1) = match (s.first(), s.last()) {
        (Some(a), Some(z)) if z.t_end > a.t => (a.t, z.t_end),
        (Some(a), _) => (a.t, a.t + 1.0),
        _ => (0.0, 1.0),
    };
    let vals: Vec<f64> = s
        .iter()
        .flat_map(|p| {
            if energy {
                vec![p.energy_nominal, p.energy_bound, p.threshold]
            } else {
                vec![p.min_separation, p.far_separation]
            }
        })
        .flatten()
        .filter(|v| v.is_finite())
        .collect();
    let (mut y0, mut y1) = (
        vals.iter().copied().fold(0.0f64, f64::min),
        vals.iter().copied().fold(0.0f64, f64::max),
    );
    if !energy {
        y1 = y1.clamp(0.1, 3.0);
        y0 = y0.max(-1.0);
    } else {
        y1 = y1.max(1e-3);
    }
    let pad = 0.05 * (y1 - y0);
    if y0 < 0.0 {
        y0 -= pad;
    }
    y1 += pad;
    ((x0, x1), (y0, y1))
}

/// The plotted lines at the middle of each bucket: the nominal energy, its bound and the
/// threshold (dashed) if `energy`, else the far-range bound (dotted) and the separation.
fn plot_lines(s: &[SeriesPoint], energy: bool) -> Vec<Line<'static>> {
    if energy {
        vec![
            (
                s.iter()
                    .map(|p| (0.5 * (p.t + p.t_end), p.energy_nominal))
                    .collect(),
                "0.08 0.40 0.75",
                "[] 0",
            ),
            (
                s.iter()
                    .map(|p| (0.5 * (p.t + p.t_end), p.energy_bound))
                    .collect(),
                "0.94 0.42 0.0",
                "[] 0",
            ),
            (
                s.iter()
                    .map(|p| (0.5 * (p.t + p.t_end), p.threshold))
                    .collect(),
                "0.72 0.11 0.11",
                "[4 2] 0",
            ),
        ]
    } else {
        vec![
            (
                s.iter()
                    .map(|p| (0.5 * (p.t + p.t_end), p.far_separation))
                    .collect(),
                "0.46 0.46 0.46",
                "[1.5 2] 0",
            ),
            (
                s.iter()
                    .map(|p| (0.5 * (p.t + p.t_end), p.min_separation))
                    .collect(),
                "0.08 0.40 0.75",
                "[] 0",
            ),
        ]
    }
}

/// The PDF report.
pub fn report(input: &ReportInput) -> Vec<u8> {
    let mut d = Doc::new();
    let defs = definitions();
    sections::front_matter(&mut d, input);
    sections::summary_table(&mut d, input, &defs);
    sections::evidence_table(&mut d, input.runs);
    if let Some(note) = crate::skipped_note(&input.skipped) {
        d.para(&note, 8.0, Font::Regular);
    }
    if input.runs.len() > 1 {
        sections::aggregate_table(&mut d, input.runs);
    }
    for r in input.runs {
        sections::run_section(&mut d, r, &defs);
    }
    sections::assumptions_section(&mut d, input.runs);
    sections::check_backing_table(&mut d);
    d.finish()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrapping_respects_the_width_and_keeps_every_character() {
        let s = "a b c 0123456789abcdef0123456789abcdef0123456789abcdef0123456789abcdef end";
        let lines = wrap(s, 8.0, Font::Mono, 100.0);
        for l in &lines {
            assert!(text_width(l, 8.0, Font::Mono) <= 100.0 + 1e-9, "{l}");
        }
        assert_eq!(lines.join("").replace(' ', ""), s.replace(' ', ""));
    }

    #[test]
    fn win_ansi_maps_the_report_symbols() {
        assert_eq!(win_ansi("a–b ≤ 2 m²"), b"a\x96b <= 2 m\xb2".to_vec());
    }
}
