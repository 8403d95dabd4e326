//! Minimal, dependency-free SVG charts for plans and simulation results.
//!
//! - [`Chart`]: a line chart: several series with a legend, round-number axis
//!   ticks, axis labels with units, a title and notes, dashed horizontal limit
//!   lines and dotted vertical markers (knot times), optional equal aspect.
//! - [`Path3d`]: a 3-D path in isometric projection with labelled markers
//!   (via points), floor shadow and drop lines, optionally with x-y and x-z
//!   projection panels beside it.
//! - [`Figure`]: several panels (anything implementing [`Panel`]) in a grid.
//!
//! ```no_run
//! use triquint_host::svg::Chart;
//! Chart::new("Joint velocity")
//!     .x_label("time (s)")
//!     .y_label("velocity (m/s)")
//!     .series("joint 1", &[(0.0, 0.0), (1.0, 0.2), (2.0, 0.0)])
//!     .hline(0.5, "v max")
//!     .hline(-0.5, "")
//!     .vline(1.0, "P2")
//!     .write("velocity.svg")?;
//! # Ok::<(), std::io::Error>(())
//! ```

use std::fmt::Write as _;
use std::path::Path;

/// Series colours, in order (colour-blind-friendly enough, distinct in print).
pub const PALETTE: [&str; 8] = [
    "#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf",
];

const FONT: &str = "DejaVu Sans, Helvetica, Arial, sans-serif";
const LIMIT_COLOUR: &str = "#b22222";
const MARKER_COLOUR: &str = "#888888";

/// A rectangle in SVG user units (pixels), y down.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rect {
    pub x: f64,
    pub y: f64,
    pub w: f64,
    pub h: f64,
}

impl Rect {
    pub fn new(x: f64, y: f64, w: f64, h: f64) -> Self {
        Self { x, y, w, h }
    }
}

/// Something that draws itself into a rectangle of an SVG document.
pub trait Panel {
    /// Appends SVG elements drawing the panel inside `area`.
    fn render(&self, out: &mut String, area: Rect);
    /// Size (width, height) used when the panel is a document on its own.
    fn size(&self) -> (f64, f64);

    /// The panel as a complete SVG document.
    fn to_svg(&self) -> String {
        let (w, h) = self.size();
        let mut out = document_start(w, h);
        self.render(&mut out, Rect::new(0.0, 0.0, w, h));
        out.push_str("</svg>\n");
        out
    }
}

fn document_start(w: f64, h: f64) -> String {
    format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" \
         viewBox=\"0 0 {w} {h}\" font-family=\"{FONT}\">\n\
         <rect x=\"0\" y=\"0\" width=\"{w}\" height=\"{h}\" fill=\"white\"/>\n"
    )
}

/// Writes an SVG document (plain write; callers wanting atomic files write
/// [`Panel::to_svg`] themselves).
fn write_file(path: impl AsRef<Path>, svg: &str) -> std::io::Result<()> {
    std::fs::write(path, svg)
}

/// Escapes text for SVG content and attributes.
pub fn escape(text: &str) -> String {
    let mut s = String::with_capacity(text.len());
    for ch in text.chars() {
        match ch {
            '&' => s.push_str("&amp;"),
            '<' => s.push_str("&lt;"),
            '>' => s.push_str("&gt;"),
            '"' => s.push_str("&quot;"),
            _ => s.push(ch),
        }
    }
    s
}

/// Rough width of `text` at `size` px (for layout only).
fn text_width(text: &str, size: f64) -> f64 {
    text.chars().count() as f64 * size * 0.6
}

fn text(out: &mut String, x: f64, y: f64, size: f64, anchor: &str, extra: &str, content: &str) {
    let _ = writeln!(
        out,
        "<text x=\"{x:.1}\" y=\"{y:.1}\" font-size=\"{size}\" text-anchor=\"{anchor}\" {extra}>{}</text>",
        escape(content)
    );
}

/// Round tick step for a span: 1, 2 or 5 × 10^k, about `target` ticks.
pub fn nice_step(span: f64, target: usize) -> f64 {
    let raw = span.abs() / target.max(1) as f64;
    if !(raw.is_finite() && raw > 0.0) {
        return 1.0;
    }
    let mag = 10f64.powf(raw.log10().floor());
    let f = raw / mag;
    let nice = if f < 1.5 {
        1.0
    } else if f < 3.0 {
        2.0
    } else if f < 7.0 {
        5.0
    } else {
        10.0
    };
    nice * mag
}

/// Tick positions: multiples of `step` inside [lo, hi] (with rounding slack).
pub fn ticks(lo: f64, hi: f64, step: f64) -> Vec<f64> {
    let first = (lo / step - 1e-9).ceil() as i64;
    let last = (hi / step + 1e-9).floor() as i64;
    if last < first || last - first > 1000 {
        return Vec::new();
    }
    (first..=last).map(|k| k as f64 * step).collect()
}

/// A tick label with just enough decimals for `step`, a true minus sign and no "−0".
pub fn format_tick(value: f64, step: f64) -> String {
    let decimals = (-(step.abs().log10()) - 1e-9).ceil().clamp(0.0, 12.0) as usize;
    let s = format!("{value:.decimals$}");
    if s.trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        s.trim_start_matches('-').to_string()
    } else {
        s.replacen('-', "\u{2212}", 1)
    }
}

/// Range [lo, hi] of finite values, widened if empty or degenerate.
fn range_of(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if lo > hi {
        return (0.0, 1.0);
    }
    if hi - lo <= 1e-12 * hi.abs().max(lo.abs()).max(1e-300) {
        let pad = if lo == 0.0 { 1.0 } else { 0.1 * lo.abs() };
        return (lo - pad, hi + pad);
    }
    (lo, hi)
}

/// Mean of pixel positions ((0, 0) if none).
fn centroid(points: impl Iterator<Item = (f64, f64)>) -> (f64, f64) {
    let (mut sx, mut sy, mut n) = (0.0, 0.0, 0.0);
    for (x, y) in points.filter(|p| p.0.is_finite() && p.1.is_finite()) {
        sx += x;
        sy += y;
        n += 1.0;
    }
    if n == 0.0 {
        (0.0, 0.0)
    } else {
        (sx / n, sy / n)
    }
}

/// A marker label placed away from the markers' centroid, so labels of a
/// closed path sit outside it and labels of an open one spread apart; left
/// out if it would overprint a label already in `placed`.
fn label_outward(
    out: &mut String,
    p: (f64, f64),
    centre: (f64, f64),
    label: &str,
    placed: &mut Vec<Rect>,
) {
    let (dx, dy) = (p.0 - centre.0, p.1 - centre.1);
    let len = dx.hypot(dy);
    let (ux, uy) = if len > 1e-9 {
        (dx / len, dy / len)
    } else {
        (
            std::f64::consts::FRAC_1_SQRT_2,
            -std::f64::consts::FRAC_1_SQRT_2,
        )
    };
    let (x, y) = (p.0 + 9.0 * ux, p.1 + 9.0 * uy + 4.0 + 3.0 * uy);
    let anchor = if ux > 0.35 {
        "start"
    } else if ux < -0.35 {
        "end"
    } else {
        "middle"
    };
    let w = text_width(label, 11.0);
    let left = match anchor {
        "start" => x,
        "end" => x - w,
        _ => x - w / 2.0,
    };
    let rect = Rect::new(left, y - 10.0, w, 12.0);
    let overlaps = |r: &Rect| {
        rect.x < r.x + r.w && r.x < rect.x + rect.w && rect.y < r.y + r.h && r.y < rect.y + rect.h
    };
    if placed.iter().any(overlaps) {
        return;
    }
    placed.push(rect);
    text(out, x, y, 11.0, anchor, "fill=\"#222\"", label);
}

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Style {
    /// A polyline; non-finite points break it.
    Line,
    /// Circle markers only.
    Markers,
    /// A dashed polyline.
    Dashed,
}

/// One data series of a [`Chart`].
#[derive(Clone, Debug)]
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
    pub style: Style,
    /// None: the next palette colour.
    pub colour: Option<String>,
    /// Labels drawn next to markers (same length as `points`, or empty).
    pub labels: Vec<String>,
}

#[derive(Clone, Debug)]
struct Line {
    at: f64,
    label: String,
    colour: String,
}

/// A line chart. Build with the chainable methods, then [`Chart::write`] or
/// [`Panel::to_svg`].
#[derive(Clone, Debug)]
pub struct Chart {
    title: String,
    notes: Vec<String>,
    x_label: String,
    y_label: String,
    series: Vec<Series>,
    hlines: Vec<Line>,
    vlines: Vec<Line>,
    x_range: Option<(f64, f64)>,
    y_range: Option<(f64, f64)>,
    equal_aspect: bool,
    width: f64,
    height: f64,
}

impl Chart {
    pub fn new(title: impl Into<String>) -> Self {
        Self {
            title: title.into(),
            notes: Vec::new(),
            x_label: String::new(),
            y_label: String::new(),
            series: Vec::new(),
            hlines: Vec::new(),
            vlines: Vec::new(),
            x_range: None,
            y_range: None,
            equal_aspect: false,
            width: 900.0,
            height: 500.0,
        }
    }
    /// x-axis label, with its unit, e.g. "time (s)".
    pub fn x_label(mut self, label: impl Into<String>) -> Self {
        self.x_label = label.into();
        self
    }
    /// y-axis label, with its unit, e.g. "velocity (m/s)".
    pub fn y_label(mut self, label: impl Into<String>) -> Self {
        self.y_label = label.into();
        self
    }
    /// A line of smaller text under the title (may be called repeatedly).
    pub fn note(mut self, note: impl Into<String>) -> Self {
        self.notes.push(note.into());
        self
    }
    /// Document size in pixels (default 900 × 500).
    pub fn size(mut self, width: f64, height: f64) -> Self {
        self.width = width;
        self.height = height;
        self
    }
    /// A line series in the next palette colour.
    pub fn series(self, name: impl Into<String>, points: &[(f64, f64)]) -> Self {
        self.add_series(Series {
            name: name.into(),
            points: points.to_vec(),
            style: Style::Line,
            colour: None,
            labels: Vec::new(),
        })
    }
    /// A marker-only series; `labels` (possibly empty) are drawn beside the markers.
    pub fn markers(
        self,
        name: impl Into<String>,
        points: &[(f64, f64)],
        labels: &[String],
    ) -> Self {
        self.add_series(Series {
            name: name.into(),
            points: points.to_vec(),
            style: Style::Markers,
            colour: None,
            labels: labels.to_vec(),
        })
    }
    /// Any series, fully specified.
    pub fn add_series(mut self, series: Series) -> Self {
        self.series.push(series);
        self
    }
    /// A dashed horizontal line at `y` (a limit), labelled at its right end;
    /// it widens the y range to stay visible.
    pub fn hline(mut self, y: f64, label: impl Into<String>) -> Self {
        self.hlines.push(Line {
            at: y,
            label: label.into(),
            colour: LIMIT_COLOUR.into(),
        });
        self
    }
    /// A dotted vertical marker at `x` (e.g. a knot time), labelled above the plot.
    pub fn vline(mut self, x: f64, label: impl Into<String>) -> Self {
        self.vlines.push(Line {
            at: x,
            label: label.into(),
            colour: MARKER_COLOUR.into(),
        });
        self
    }
    /// Fixes the x range instead of fitting the data.
    pub fn x_range(mut self, lo: f64, hi: f64) -> Self {
        self.x_range = Some((lo, hi));
        self
    }
    /// Fixes the y range instead of fitting the data.
    pub fn y_range(mut self, lo: f64, hi: f64) -> Self {
        self.y_range = Some((lo, hi));
        self
    }
    /// Same scale on both axes (for paths in a plane).
    pub fn equal_aspect(mut self, on: bool) -> Self {
        self.equal_aspect = on;
        self
    }
    /// Writes the chart as an SVG file.
    pub fn write(&self, path: impl AsRef<Path>) -> std::io::Result<()> {
        write_file(path, &self.to_svg())
    }

    fn colour(&self, i: usize) -> String {
        self.series[i]
            .colour
            .clone()
            .unwrap_or_else(|| PALETTE[i % PALETTE.len()].to_string())
    }
}

/// Linear map from data to pixels.
#[derive(Clone, Copy)]
struct Axes {
    plot: Rect,
    x: (f64, f64),
    y: (f64, f64),
}

impl Axes {
    fn px(&self, x: f64) -> f64 {
        self.plot.x + (x - self.x.0) / (self.x.1 - self.x.0) * self.plot.w
    }
    fn py(&self, y: f64) -> f64 {
        self.plot.y + self.plot.h - (y - self.y.0) / (self.y.1 - self.y.0) * self.plot.h
    }
}

impl Panel for Chart {
    fn size(&self) -> (f64, f64) {
        (self.width, self.height)
    }

    fn render(&self, out: &mut String, area: Rect) {
        // Header: title, notes, legend (wrapping).
        let mut y = area.y + 24.0;
        text(
            out,
            area.x + area.w / 2.0,
            y,
            17.0,
            "middle",
            "font-weight=\"bold\"",
            &self.title,
        );
        for note in &self.notes {
            y += 17.0;
            text(
                out,
                area.x + area.w / 2.0,
                y,
                12.0,
                "middle",
                "fill=\"#444\"",
                note,
            );
        }
        let legend: Vec<usize> = (0..self.series.len())
            .filter(|&i| !self.series[i].name.is_empty())
            .collect();
        if !legend.is_empty() {
            let widths: Vec<f64> = legend
                .iter()
                .map(|&i| 34.0 + text_width(&self.series[i].name, 12.0) + 14.0)
                .collect();
            let mut rows: Vec<Vec<usize>> = vec![Vec::new()];
            let mut row_w = 0.0;
            for (k, w) in widths.iter().enumerate() {
                if row_w + w > area.w - 40.0 && !rows.last().unwrap().is_empty() {
                    rows.push(Vec::new());
                    row_w = 0.0;
                }
                rows.last_mut().unwrap().push(k);
                row_w += w;
            }
            for row in rows {
                y += 20.0;
                let total: f64 = row.iter().map(|&k| widths[k]).sum();
                let mut x = area.x + (area.w - total) / 2.0;
                for k in row {
                    let i = legend[k];
                    let colour = self.colour(i);
                    match self.series[i].style {
                        Style::Markers => {
                            let _ = writeln!(
                                out,
                                "<circle cx=\"{:.1}\" cy=\"{:.1}\" r=\"4\" fill=\"{colour}\" stroke=\"#222\" stroke-width=\"0.8\"/>",
                                x + 13.0,
                                y - 4.0
                            );
                        }
                        style => {
                            let dash = if style == Style::Dashed {
                                " stroke-dasharray=\"6,3\""
                            } else {
                                ""
                            };
                            let _ = writeln!(
                                out,
                                "<line x1=\"{:.1}\" y1=\"{:.1}\" x2=\"{:.1}\" y2=\"{:.1}\" stroke=\"{colour}\" stroke-width=\"2.5\"{dash}/>",
                                x,
                                y - 4.0,
                                x + 26.0,
                                y - 4.0
                            );
                        }
                    }
                    text(out, x + 32.0, y, 12.0, "start", "", &self.series[i].name);
                    x += widths[k];
                }
            }
        }
        let top = y + if self.vlines.iter().any(|l| !l.label.is_empty()) {
            26.0
        } else {
            14.0
        };
        let left = if self.y_label.is_empty() { 56.0 } else { 76.0 };
        let bottom = if self.x_label.is_empty() { 30.0 } else { 52.0 };
        let right = 24.0
            + self
                .hlines
                .iter()
                .map(|l| text_width(&l.label, 11.0))
                .fold(0.0, f64::max)
                .min(120.0);
        let plot = Rect::new(
            area.x + left,
            top,
            (area.w - left - right).max(40.0),
            (area.y + area.h - bottom - top).max(40.0),
        );

        // Ranges: x fits the data exactly (padded for equal aspect), y is padded
        // by 5 %; ticks fall inside.
        let xs = self
            .series
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.0))
            .chain(self.vlines.iter().map(|l| l.at));
        let ys = self
            .series
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.1))
            .chain(self.hlines.iter().map(|l| l.at));
        let mut xr = self.x_range.unwrap_or_else(|| {
            let (lo, hi) = range_of(xs);
            let pad = if self.equal_aspect {
                0.04 * (hi - lo)
            } else {
                0.0
            };
            (lo - pad, hi + pad)
        });
        let mut yr = self.y_range.unwrap_or_else(|| {
            let (lo, hi) = range_of(ys);
            let pad = 0.05 * (hi - lo);
            (lo - pad, hi + pad)
        });
        let x_target = ((plot.w / 90.0) as usize).clamp(2, 12);
        let y_target = ((plot.h / 55.0) as usize).clamp(2, 10);
        if self.equal_aspect {
            // Widen whichever axis has room so one unit is the same length on both.
            let sx = plot.w / (xr.1 - xr.0);
            let sy = plot.h / (yr.1 - yr.0);
            if sx > sy {
                let extra = plot.w / sy - (xr.1 - xr.0);
                xr = (xr.0 - extra / 2.0, xr.1 + extra / 2.0);
            } else {
                let extra = plot.h / sx - (yr.1 - yr.0);
                yr = (yr.0 - extra / 2.0, yr.1 + extra / 2.0);
            }
        }
        let ax = Axes { plot, x: xr, y: yr };

        // Grid, ticks and frame.
        let xstep = nice_step(xr.1 - xr.0, x_target);
        let ystep = nice_step(yr.1 - yr.0, y_target);
        let bottom_y = plot.y + plot.h;
        for t in ticks(xr.0, xr.1, xstep) {
            let px = ax.px(t);
            let _ = writeln!(
                out,
                "<line x1=\"{px:.1}\" y1=\"{:.1}\" x2=\"{px:.1}\" y2=\"{bottom_y:.1}\" stroke=\"#e4e4e4\"/>\
                 <line x1=\"{px:.1}\" y1=\"{bottom_y:.1}\" x2=\"{px:.1}\" y2=\"{:.1}\" stroke=\"#333\"/>",
                plot.y,
                bottom_y + 5.0
            );
            text(
                out,
                px,
                bottom_y + 19.0,
                12.0,
                "middle",
                "",
                &format_tick(t, xstep),
            );
        }
        for t in ticks(yr.0, yr.1, ystep) {
            let py = ax.py(t);
            let _ = writeln!(
                out,
                "<line x1=\"{:.1}\" y1=\"{py:.1}\" x2=\"{:.1}\" y2=\"{py:.1}\" stroke=\"#e4e4e4\"/>\
                 <line x1=\"{:.1}\" y1=\"{py:.1}\" x2=\"{:.1}\" y2=\"{py:.1}\" stroke=\"#333\"/>",
                plot.x,
                plot.x + plot.w,
                plot.x - 5.0,
                plot.x
            );
            text(
                out,
                plot.x - 8.0,
                py + 4.0,
                12.0,
                "end",
                "",
                &format_tick(t, ystep),
            );
        }
        if yr.0 < 0.0 && yr.1 > 0.0 {
            let py = ax.py(0.0);
            let _ = writeln!(
                out,
                "<line x1=\"{:.1}\" y1=\"{py:.1}\" x2=\"{:.1}\" y2=\"{py:.1}\" stroke=\"#999\" stroke-width=\"1\"/>",
                plot.x,
                plot.x + plot.w
            );
        }
        if !self.x_label.is_empty() {
            text(
                out,
                plot.x + plot.w / 2.0,
                bottom_y + 42.0,
                13.0,
                "middle",
                "",
                &self.x_label,
            );
        }
        if !self.y_label.is_empty() {
            let (lx, ly) = (area.x + 18.0, plot.y + plot.h / 2.0);
            text(
                out,
                lx,
                ly,
                13.0,
                "middle",
                &format!("transform=\"rotate(-90 {lx:.1} {ly:.1})\""),
                &self.y_label,
            );
        }

        // Vertical markers (labels above the frame; a label that would overlap
        // the previous one is left out), limit lines.
        let mut vlines: Vec<&Line> = self.vlines.iter().collect();
        vlines.sort_by(|a, b| a.at.total_cmp(&b.at));
        let mut label_right = f64::NEG_INFINITY;
        for l in vlines {
            if !(l.at >= xr.0 && l.at <= xr.1) {
                continue;
            }
            let px = ax.px(l.at);
            let _ = writeln!(
                out,
                "<line x1=\"{px:.1}\" y1=\"{:.1}\" x2=\"{px:.1}\" y2=\"{bottom_y:.1}\" stroke=\"{}\" stroke-width=\"1\" stroke-dasharray=\"2,3\"/>",
                plot.y, l.colour
            );
            let half = 0.5 * text_width(&l.label, 10.5);
            if !l.label.is_empty() && px - half > label_right + 3.0 {
                label_right = px + half;
                text(
                    out,
                    px,
                    plot.y - 6.0,
                    10.5,
                    "middle",
                    "fill=\"#555\"",
                    &l.label,
                );
            }
        }
        let clip = format!("clip{:.0}x{:.0}", area.x, area.y);
        let _ = writeln!(
            out,
            "<clipPath id=\"{clip}\"><rect x=\"{:.1}\" y=\"{:.1}\" width=\"{:.1}\" height=\"{:.1}\"/></clipPath>",
            plot.x, plot.y, plot.w, plot.h
        );
        let mut label_ys: Vec<f64> = Vec::new();
        let mut hlines: Vec<&Line> = self.hlines.iter().collect();
        hlines.sort_by(|a, b| b.at.total_cmp(&a.at));
        for l in hlines {
            if !(l.at >= yr.0 && l.at <= yr.1) {
                continue;
            }
            let py = ax.py(l.at);
            let _ = writeln!(
                out,
                "<line x1=\"{:.1}\" y1=\"{py:.1}\" x2=\"{:.1}\" y2=\"{py:.1}\" stroke=\"{}\" stroke-width=\"1.4\" stroke-dasharray=\"8,5\"/>",
                plot.x,
                plot.x + plot.w,
                l.colour
            );
            if !l.label.is_empty() {
                // Top to bottom; a label too close to the previous one moves down.
                let mut ly = py + 4.0;
                if let Some(&prev) = label_ys.last() {
                    ly = ly.max(prev + 13.0);
                }
                label_ys.push(ly);
                let fill = format!("fill=\"{}\"", l.colour);
                text(
                    out,
                    plot.x + plot.w + 4.0,
                    ly,
                    11.0,
                    "start",
                    &fill,
                    &l.label,
                );
            }
        }

        // Data: lines clipped to the plot, then markers (with labels) on top.
        let _ = writeln!(out, "<g clip-path=\"url(#{clip})\">");
        let mut order: Vec<usize> = (0..self.series.len()).collect();
        order.sort_by_key(|&i| self.series[i].style == Style::Markers);
        let mut clipped = true;
        for i in order {
            let s = &self.series[i];
            let colour = self.colour(i);
            if clipped && s.style == Style::Markers {
                out.push_str("</g>\n");
                clipped = false;
            }
            match s.style {
                Style::Markers => {
                    let centre = centroid(s.points.iter().map(|&(x, y)| (ax.px(x), ax.py(y))));
                    let mut placed = Vec::new();
                    for (k, &(x, y)) in s.points.iter().enumerate() {
                        let inside = x >= xr.0 && x <= xr.1 && y >= yr.0 && y <= yr.1;
                        if !inside {
                            continue;
                        }
                        let (px, py) = (ax.px(x), ax.py(y));
                        let _ = writeln!(
                            out,
                            "<circle cx=\"{px:.1}\" cy=\"{py:.1}\" r=\"4\" fill=\"{colour}\" stroke=\"#222\" stroke-width=\"0.8\"/>"
                        );
                        if let Some(label) = s.labels.get(k).filter(|l| !l.is_empty()) {
                            label_outward(out, (px, py), centre, label, &mut placed);
                        }
                    }
                }
                style => {
                    let mut d = String::new();
                    let mut pen_down = false;
                    for &(x, y) in &s.points {
                        if !(x.is_finite() && y.is_finite()) {
                            pen_down = false;
                            continue;
                        }
                        let _ = write!(
                            d,
                            "{}{:.2},{:.2} ",
                            if pen_down { "L" } else { "M" },
                            ax.px(x),
                            ax.py(y)
                        );
                        pen_down = true;
                    }
                    let dash = if style == Style::Dashed {
                        " stroke-dasharray=\"6,3\""
                    } else {
                        ""
                    };
                    let _ = writeln!(
                        out,
                        "<path d=\"{}\" fill=\"none\" stroke=\"{colour}\" stroke-width=\"1.8\" stroke-linejoin=\"round\"{dash}/>",
                        d.trim_end()
                    );
                }
            }
        }
        if clipped {
            out.push_str("</g>\n");
        }
        let _ = writeln!(
            out,
            "<rect x=\"{:.1}\" y=\"{:.1}\" width=\"{:.1}\" height=\"{:.1}\" fill=\"none\" stroke=\"#333\"/>",
            plot.x, plot.y, plot.w, plot.h
        );
    }
}

/// A 3-D path in isometric projection (z up, true scale on all axes), seen
/// from the (+x, +y, +z) octant, with labelled markers (via points), the
/// path's shadow on the floor of the bounding box and drop lines from the
/// markers; optionally with x-y and x-z projections beside it.
#[derive(Clone, Debug)]
pub struct Path3d {
    title: String,
    notes: Vec<String>,
    unit: String,
    paths: Vec<(String, Vec<[f64; 3]>)>,
    markers: Vec<(String, Vec<[f64; 3]>, Vec<String>)>,
    projections: bool,
    width: f64,
    height: f64,
}

impl Path3d {
    pub fn new(title: impl Into<String>) -> Self {
        Self {
            title: title.into(),
            notes: Vec::new(),
            unit: String::new(),
            paths: Vec::new(),
            markers: Vec::new(),
            projections: false,
            width: 760.0,
            height: 640.0,
        }
    }
    /// Unit of all three coordinates, shown in the axis labels (e.g. "mm").
    pub fn unit(mut self, unit: impl Into<String>) -> Self {
        self.unit = unit.into();
        self
    }
    /// A line of smaller text under the title.
    pub fn note(mut self, note: impl Into<String>) -> Self {
        self.notes.push(note.into());
        self
    }
    /// A polyline through 3-D points, in the next palette colour.
    pub fn path(mut self, name: impl Into<String>, points: &[[f64; 3]]) -> Self {
        self.paths.push((name.into(), points.to_vec()));
        self
    }
    /// Marked points with labels (labels may be empty).
    pub fn markers(
        mut self,
        name: impl Into<String>,
        points: &[[f64; 3]],
        labels: &[String],
    ) -> Self {
        self.markers
            .push((name.into(), points.to_vec(), labels.to_vec()));
        self
    }
    /// Adds x-y (top) and x-z (front) projection panels beside the 3-D view.
    pub fn projections(mut self, on: bool) -> Self {
        self.projections = on;
        self
    }
    /// Size of the 3-D view in pixels (default 760 × 640; projections add a column).
    pub fn size(mut self, width: f64, height: f64) -> Self {
        self.width = width;
        self.height = height;
        self
    }
    /// Writes the view as an SVG file.
    pub fn write(&self, path: impl AsRef<Path>) -> std::io::Result<()> {
        write_file(path, &self.to_svg())
    }

    fn axis_label(&self, axis: &str) -> String {
        if self.unit.is_empty() {
            axis.to_string()
        } else {
            format!("{axis} ({})", self.unit)
        }
    }

    /// A 2-D projection (axes a, b of x, y, z) as a chart.
    fn projection(&self, title: &str, a: usize, b: usize) -> Chart {
        let names = ["x", "y", "z"];
        let mut chart = Chart::new(title)
            .x_label(self.axis_label(names[a]))
            .y_label(self.axis_label(names[b]))
            .equal_aspect(true);
        for (i, (name, pts)) in self.paths.iter().enumerate() {
            chart = chart.add_series(Series {
                name: name.clone(),
                points: pts.iter().map(|p| (p[a], p[b])).collect(),
                style: Style::Line,
                colour: Some(PALETTE[i % PALETTE.len()].into()),
                labels: Vec::new(),
            });
        }
        for (i, (name, pts, labels)) in self.markers.iter().enumerate() {
            chart = chart.add_series(Series {
                name: name.clone(),
                points: pts.iter().map(|p| (p[a], p[b])).collect(),
                style: Style::Markers,
                colour: Some(PALETTE[(self.paths.len() + i) % PALETTE.len()].into()),
                labels: merge_labels(pts, labels, a, b),
            });
        }
        chart
    }

    /// The 3-D view alone, in `area`.
    fn render_iso(&self, out: &mut String, area: Rect) {
        let mut y = area.y + 24.0;
        text(
            out,
            area.x + area.w / 2.0,
            y,
            17.0,
            "middle",
            "font-weight=\"bold\"",
            &self.title,
        );
        for note in &self.notes {
            y += 17.0;
            text(
                out,
                area.x + area.w / 2.0,
                y,
                12.0,
                "middle",
                "fill=\"#444\"",
                note,
            );
        }
        // Legend.
        let mut items: Vec<(String, String, bool)> = Vec::new();
        for (i, (name, _)) in self.paths.iter().enumerate() {
            items.push((name.clone(), PALETTE[i % PALETTE.len()].into(), false));
        }
        for (i, (name, _, _)) in self.markers.iter().enumerate() {
            let colour = PALETTE[(self.paths.len() + i) % PALETTE.len()];
            items.push((name.clone(), colour.into(), true));
        }
        items.retain(|it| !it.0.is_empty());
        if !items.is_empty() {
            y += 20.0;
            let total: f64 = items.iter().map(|it| 48.0 + text_width(&it.0, 12.0)).sum();
            let mut x = area.x + (area.w - total) / 2.0;
            for (name, colour, marker) in &items {
                if *marker {
                    let _ = writeln!(
                        out,
                        "<circle cx=\"{:.1}\" cy=\"{:.1}\" r=\"4\" fill=\"{colour}\" stroke=\"#222\" stroke-width=\"0.8\"/>",
                        x + 13.0,
                        y - 4.0
                    );
                } else {
                    let _ = writeln!(
                        out,
                        "<line x1=\"{x:.1}\" y1=\"{:.1}\" x2=\"{:.1}\" y2=\"{:.1}\" stroke=\"{colour}\" stroke-width=\"2.5\"/>",
                        y - 4.0,
                        x + 26.0,
                        y - 4.0
                    );
                }
                text(out, x + 32.0, y, 12.0, "start", "", name);
                x += 48.0 + text_width(name, 12.0);
            }
        }

        // Bounding box: each axis widened to round ticks, and to at least a
        // quarter of the largest span so flat paths keep a visible box.
        let all: Vec<[f64; 3]> = self
            .paths
            .iter()
            .flat_map(|p| p.1.iter().copied())
            .chain(self.markers.iter().flat_map(|m| m.1.iter().copied()))
            .filter(|p| p.iter().all(|v| v.is_finite()))
            .collect();
        let mut lo = [0.0; 3];
        let mut hi = [0.0; 3];
        for k in 0..3 {
            (lo[k], hi[k]) = range_of(all.iter().map(|p| p[k]));
        }
        let biggest = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max);
        let mut steps = [1.0; 3];
        for k in 0..3 {
            let span = hi[k] - lo[k];
            if span < 0.25 * biggest {
                let c = 0.5 * (lo[k] + hi[k]);
                lo[k] = c - 0.125 * biggest;
                hi[k] = c + 0.125 * biggest;
            }
            steps[k] = nice_step(hi[k] - lo[k], 4);
            lo[k] = (lo[k] / steps[k]).floor() * steps[k];
            hi[k] = (hi[k] / steps[k]).ceil() * steps[k];
        }
        // Isometric: right = (y − x) cos 30°, up = z − (x + y) sin 30°.
        let (c30, s30) = (30f64.to_radians().cos(), 0.5);
        let proj = |p: [f64; 3]| -> (f64, f64) {
            let (x, y, z) = (p[0] - lo[0], p[1] - lo[1], p[2] - lo[2]);
            ((y - x) * c30, z - (x + y) * s30)
        };
        let corners: Vec<[f64; 3]> = (0..8)
            .map(|i| {
                [
                    if i & 1 == 0 { lo[0] } else { hi[0] },
                    if i & 2 == 0 { lo[1] } else { hi[1] },
                    if i & 4 == 0 { lo[2] } else { hi[2] },
                ]
            })
            .collect();
        let (mut umin, mut umax, mut vmin, mut vmax) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for &c in &corners {
            let (u, v) = proj(c);
            umin = umin.min(u);
            umax = umax.max(u);
            vmin = vmin.min(v);
            vmax = vmax.max(v);
        }
        let view = Rect::new(
            area.x + 90.0,
            y + 30.0,
            area.w - 180.0,
            area.y + area.h - y - 100.0,
        );
        let scale = (view.w / (umax - umin)).min(view.h / (vmax - vmin));
        let ox = view.x + (view.w - (umax - umin) * scale) / 2.0;
        let oy = view.y + (view.h - (vmax - vmin) * scale) / 2.0;
        let to_px = |p: [f64; 3]| -> (f64, f64) {
            let (u, v) = proj(p);
            (ox + (u - umin) * scale, oy + (vmax - v) * scale)
        };
        let seg = |out: &mut String, a: [f64; 3], b: [f64; 3], attrs: &str| {
            let (pa, pb) = (to_px(a), to_px(b));
            let _ = writeln!(
                out,
                "<line x1=\"{:.1}\" y1=\"{:.1}\" x2=\"{:.1}\" y2=\"{:.1}\" {attrs}/>",
                pa.0, pa.1, pb.0, pb.1
            );
        };
        // Floor grid and the three back walls' edges.
        for t in ticks(lo[0], hi[0], steps[0]) {
            seg(
                out,
                [t, lo[1], lo[2]],
                [t, hi[1], lo[2]],
                "stroke=\"#e4e4e4\"",
            );
        }
        for t in ticks(lo[1], hi[1], steps[1]) {
            seg(
                out,
                [lo[0], t, lo[2]],
                [hi[0], t, lo[2]],
                "stroke=\"#e4e4e4\"",
            );
        }
        for t in ticks(lo[2], hi[2], steps[2]) {
            seg(
                out,
                [lo[0], lo[1], t],
                [hi[0], lo[1], t],
                "stroke=\"#eeeeee\"",
            );
            seg(
                out,
                [lo[0], lo[1], t],
                [lo[0], hi[1], t],
                "stroke=\"#eeeeee\"",
            );
        }
        for i in 0..8usize {
            for bit in [1usize, 2, 4] {
                let j = i | bit;
                if j != i {
                    let back = corners[i][0] == lo[0] || corners[i][1] == lo[1];
                    let front_vertical = bit == 4 && i & 3 == 3;
                    let attrs = if front_vertical {
                        "stroke=\"#bbbbbb\" stroke-dasharray=\"4,3\""
                    } else if back {
                        "stroke=\"#999999\""
                    } else {
                        "stroke=\"#bbbbbb\""
                    };
                    seg(out, corners[i], corners[j], attrs);
                }
            }
        }
        // Tick labels: x along the bottom edge at y = hi, y along x = hi, z on
        // the left vertical edge (x = hi, y = lo); all offset outward.
        let offset = |p: [f64; 3], du: f64, dv: f64| {
            let (x, y) = to_px(p);
            (x + du, y + dv)
        };
        for t in ticks(lo[0], hi[0], steps[0]) {
            let (x, y) = offset([t, hi[1], lo[2]], 8.0, 16.0);
            seg(
                out,
                [t, hi[1], lo[2]],
                [t, hi[1] + 0.03 * (hi[1] - lo[1]), lo[2]],
                "stroke=\"#333\"",
            );
            text(out, x, y, 11.0, "start", "", &format_tick(t, steps[0]));
        }
        // (No y label at the front corner, where the x axis already has one.)
        for t in ticks(lo[1], hi[1] - 0.5 * steps[1], steps[1]) {
            let (x, y) = offset([hi[0], t, lo[2]], -8.0, 16.0);
            seg(
                out,
                [hi[0], t, lo[2]],
                [hi[0] + 0.03 * (hi[0] - lo[0]), t, lo[2]],
                "stroke=\"#333\"",
            );
            text(out, x, y, 11.0, "end", "", &format_tick(t, steps[1]));
        }
        for t in ticks(lo[2], hi[2], steps[2]) {
            let (x, y) = offset([hi[0], lo[1], t], -10.0, 4.0);
            text(out, x, y, 11.0, "end", "", &format_tick(t, steps[2]));
        }
        let mid = |k: usize| 0.5 * (lo[k] + hi[k]);
        let (x, y) = offset([mid(0), hi[1], lo[2]], 30.0, 44.0);
        text(
            out,
            x,
            y,
            13.0,
            "start",
            "font-weight=\"bold\"",
            &self.axis_label("x"),
        );
        let (x, y) = offset([hi[0], mid(1), lo[2]], -30.0, 44.0);
        text(
            out,
            x,
            y,
            13.0,
            "end",
            "font-weight=\"bold\"",
            &self.axis_label("y"),
        );
        let (x, y) = offset([hi[0], lo[1], hi[2]], 0.0, -14.0);
        text(
            out,
            x,
            y,
            13.0,
            "middle",
            "font-weight=\"bold\"",
            &self.axis_label("z"),
        );

        // Shadows on the floor, drop lines, paths, markers.
        let polyline = |pts: &[[f64; 3]], flat: bool| -> String {
            let mut d = String::new();
            let mut pen = false;
            for p in pts {
                if !p.iter().all(|v| v.is_finite()) {
                    pen = false;
                    continue;
                }
                let q = if flat { [p[0], p[1], lo[2]] } else { *p };
                let (x, y) = to_px(q);
                let _ = write!(d, "{}{x:.2},{y:.2} ", if pen { "L" } else { "M" });
                pen = true;
            }
            d.trim_end().to_string()
        };
        for (_, pts) in &self.paths {
            let _ = writeln!(
                out,
                "<path d=\"{}\" fill=\"none\" stroke=\"#c8c8c8\" stroke-width=\"1.5\"/>",
                polyline(pts, true)
            );
        }
        for (_, pts, _) in &self.markers {
            for p in pts.iter().filter(|p| p.iter().all(|v| v.is_finite())) {
                seg(
                    out,
                    *p,
                    [p[0], p[1], lo[2]],
                    "stroke=\"#aaaaaa\" stroke-dasharray=\"2,3\"",
                );
            }
        }
        for (i, (_, pts)) in self.paths.iter().enumerate() {
            let _ = writeln!(
                out,
                "<path d=\"{}\" fill=\"none\" stroke=\"{}\" stroke-width=\"2.2\" stroke-linejoin=\"round\"/>",
                polyline(pts, false),
                PALETTE[i % PALETTE.len()]
            );
        }
        for (i, (_, pts, labels)) in self.markers.iter().enumerate() {
            let colour = PALETTE[(self.paths.len() + i) % PALETTE.len()];
            let mut placed = Vec::new();
            let centre = centroid(
                pts.iter()
                    .filter(|p| p.iter().all(|v| v.is_finite()))
                    .map(|p| to_px(*p)),
            );
            for (k, p) in pts.iter().enumerate() {
                if !p.iter().all(|v| v.is_finite()) {
                    continue;
                }
                let (x, y) = to_px(*p);
                let _ = writeln!(
                    out,
                    "<circle cx=\"{x:.1}\" cy=\"{y:.1}\" r=\"4.5\" fill=\"{colour}\" stroke=\"#222\" stroke-width=\"0.8\"/>"
                );
                if let Some(label) = labels.get(k).filter(|l| !l.is_empty()) {
                    label_outward(out, (x, y), centre, label, &mut placed);
                }
            }
        }
    }
}

/// Labels of points that coincide in the (a, b) projection, joined on the
/// first of them ("P1, P2, P3"), so they do not overprint.
fn merge_labels(pts: &[[f64; 3]], labels: &[String], a: usize, b: usize) -> Vec<String> {
    let mut out: Vec<String> = labels.to_vec();
    let span = pts
        .iter()
        .flat_map(|p| [p[a].abs(), p[b].abs()])
        .fold(0.0, f64::max)
        .max(1e-300);
    for k in 0..out.len().min(pts.len()) {
        if out[k].is_empty() {
            continue;
        }
        for m in 0..k {
            let near = (pts[k][a] - pts[m][a]).abs() <= 1e-6 * span
                && (pts[k][b] - pts[m][b]).abs() <= 1e-6 * span;
            if near && !out[m].is_empty() {
                let moved = std::mem::take(&mut out[k]);
                out[m] = format!("{}, {moved}", out[m]);
                break;
            }
        }
    }
    out
}

impl Panel for Path3d {
    fn size(&self) -> (f64, f64) {
        if self.projections {
            (self.width + 0.75 * self.height, self.height)
        } else {
            (self.width, self.height)
        }
    }

    fn render(&self, out: &mut String, area: Rect) {
        if !self.projections {
            self.render_iso(out, area);
            return;
        }
        let side = area.w - self.width * area.w / self.size().0;
        let iso = Rect::new(area.x, area.y, area.w - side, area.h);
        self.render_iso(out, iso);
        let half = area.h / 2.0;
        self.projection("top view (x-y)", 0, 1)
            .render(out, Rect::new(area.x + iso.w, area.y, side, half));
        self.projection("front view (x-z)", 0, 2)
            .render(out, Rect::new(area.x + iso.w, area.y + half, side, half));
    }
}

/// Panels in a grid under a common title.
pub struct Figure {
    title: String,
    columns: usize,
    cell: (f64, f64),
    panels: Vec<Box<dyn Panel>>,
}

impl Figure {
    /// `columns` panels per row, each `cell_w` × `cell_h` pixels.
    pub fn new(title: impl Into<String>, columns: usize, cell_w: f64, cell_h: f64) -> Self {
        Self {
            title: title.into(),
            columns: columns.max(1),
            cell: (cell_w, cell_h),
            panels: Vec::new(),
        }
    }
    /// Appends a panel (row-major).
    pub fn panel(mut self, panel: impl Panel + 'static) -> Self {
        self.panels.push(Box::new(panel));
        self
    }
    /// Writes the figure as an SVG file.
    pub fn write(&self, path: impl AsRef<Path>) -> std::io::Result<()> {
        write_file(path, &self.to_svg())
    }
    fn header(&self) -> f64 {
        if self.title.is_empty() { 0.0 } else { 36.0 }
    }
}

impl Panel for Figure {
    fn size(&self) -> (f64, f64) {
        let rows = self.panels.len().div_ceil(self.columns).max(1);
        let cols = self.columns.min(self.panels.len()).max(1);
        (
            cols as f64 * self.cell.0,
            rows as f64 * self.cell.1 + self.header(),
        )
    }

    fn render(&self, out: &mut String, area: Rect) {
        if !self.title.is_empty() {
            text(
                out,
                area.x + area.w / 2.0,
                area.y + 26.0,
                20.0,
                "middle",
                "font-weight=\"bold\"",
                &self.title,
            );
        }
        let (w, h) = self.size();
        let (sx, sy) = (area.w / w, (area.h - self.header()) / (h - self.header()));
        for (i, p) in self.panels.iter().enumerate() {
            let (r, c) = (i / self.columns, i % self.columns);
            let cell = Rect::new(
                area.x + c as f64 * self.cell.0 * sx,
                area.y + self.header() + r as f64 * self.cell.1 * sy,
                self.cell.0 * sx,
                self.cell.1 * sy,
            );
            p.render(out, cell);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nice_steps_and_ticks() {
        assert_eq!(nice_step(10.0, 5), 2.0);
        assert_eq!(nice_step(1.0, 5), 0.2);
        assert_eq!(nice_step(4.767, 10), 0.5);
        assert_eq!(nice_step(0.0, 5), 1.0);
        assert_eq!(ticks(-0.1, 0.45, 0.1).len(), 6);
        assert_eq!(format_tick(-0.0, 0.1), "0.0");
        assert_eq!(format_tick(-0.25, 0.05), "\u{2212}0.25");
        assert_eq!(format_tick(600.0, 20.0), "600");
        assert_eq!(format_tick(0.30000000000000004, 0.1), "0.3");
    }

    #[test]
    fn chart_is_well_formed_and_escapes_text() {
        let svg = Chart::new("a < b & c")
            .x_label("time (s)")
            .y_label("v (m/s)")
            .series(
                "joint 1",
                &[(0.0, 0.0), (1.0, f64::NAN), (2.0, 1.0), (3.0, 0.5)],
            )
            .markers("pts", &[(1.0, 0.5)], &["P1".into()])
            .hline(1.2, "limit")
            .vline(1.5, "P2")
            .to_svg();
        assert!(svg.starts_with("<svg") && svg.ends_with("</svg>\n"));
        assert!(svg.contains("a &lt; b &amp; c"));
        assert!(!svg.contains("NaN") && !svg.contains("inf"));
        assert_eq!(svg.matches("<text").count(), svg.matches("</text>").count());
        // The broken series restarts with a move after the NaN.
        assert!(svg.matches(" M").count() + svg.matches("\"M").count() >= 2);
    }

    #[test]
    fn degenerate_data_renders() {
        let flat = Chart::new("flat")
            .series("zero", &[(0.0, 0.0), (1.0, 0.0)])
            .to_svg();
        assert!(!flat.contains("NaN"));
        let empty = Chart::new("empty").to_svg();
        assert!(!empty.contains("NaN"));
        let p = Path3d::new("planar")
            .unit("mm")
            .path("p", &[[0.0, 0.0, 1.0], [1.0, 1.0, 1.0]])
            .markers("v", &[[0.0, 0.0, 1.0]], &[])
            .projections(true)
            .to_svg();
        assert!(!p.contains("NaN") && !p.contains("inf"));
    }
}
