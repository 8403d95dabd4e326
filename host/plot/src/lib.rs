//! Every chart triquint draws, in one style, on plotters' SVG backend.
//!
//! - [`Chart`]: lines against an axis (joint profiles, simulation traces):
//!   round-number ticks, units in the axis labels, a legend above the plot,
//!   limits dashed and labelled, knots dotted and labelled.
//! - [`Path3d`]: a 3-D path with labelled via points, alone or with its top
//!   (x–y) and front (x–z) views at true scale.
//! - [`Figure`]: panels in a grid under one title.
//!
//! Text is measured with the embedded DejaVu Sans (fonts/LICENSE-DejaVu.txt),
//! so charts lay out the same on a machine without fontconfig or fonts; the
//! SVG names the same font, then `sans-serif`.
//!
//! ```
//! use triquint_plot::{Chart, Line};
//! let svg = Chart::new("Joint velocity")
//!     .x_label("time (s)")
//!     .y_label("velocity (m/s)")
//!     .line(Line::joint(0, "joint 1", vec![(0.0, 0.0), (1.0, 0.2), (2.0, 0.0)]))
//!     .limit(0.5, "+0.5 m/s")
//!     .knot(1.0, "P2")
//!     .to_svg()
//!     .unwrap();
//! assert!(svg.contains("joint 1"));
//! ```

mod path3d;
pub mod ticks;

use std::sync::OnceLock;

use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

pub use path3d::Path3d;
use ticks::Axis;

/// Font family as written into the SVG (and the name the font is registered under).
const FAMILY: &str = "DejaVu Sans, sans-serif";
static FONT_DATA: &[u8] = include_bytes!("../fonts/DejaVuSans.ttf");

/// Colour of joint 1, 2, 3 in every chart.
pub const JOINT_COLOURS: [RGBColor; 3] = [
    RGBColor(0x1f, 0x77, 0xb4),
    RGBColor(0xff, 0x7f, 0x0e),
    RGBColor(0x2c, 0xa0, 0x2c),
];
/// Limits (dashed).
pub const LIMIT_COLOUR: RGBColor = RGBColor(0xc0, 0x10, 0x10);
/// Knots (dotted).
pub const KNOT_COLOUR: RGBColor = RGBColor(0x70, 0x70, 0x70);
/// Secondary lines (e.g. the feedforward against the total).
pub const DARK: RGBColor = RGBColor(0x30, 0x30, 0x30);
const GRID: RGBColor = RGBColor(0xe4, 0xe4, 0xe4);
const NOTE: RGBColor = RGBColor(0x50, 0x50, 0x50);

/// Why a chart could not be drawn.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PlotError {
    /// The font compiled into the crate did not register.
    #[error("drawing a chart: the embedded font is not a font")]
    Font,
    /// plotters' drawing area or SVG backend failed: its message (its
    /// error type is generic over the backend).
    #[error("drawing a chart: {0}")]
    Backend(String),
}

fn err(e: impl std::fmt::Display) -> PlotError {
    PlotError::Backend(e.to_string())
}

/// Registers the embedded font once (plotters keeps a global table).
fn font_ready() -> Result<(), PlotError> {
    static DONE: OnceLock<bool> = OnceLock::new();
    let ok = *DONE.get_or_init(|| {
        plotters::style::register_font(FAMILY, FontStyle::Normal, FONT_DATA).is_ok()
    });
    if ok { Ok(()) } else { Err(PlotError::Font) }
}

/// Text of `px` pixels in the chart font (plotters writes size / 1.24 into the SVG).
fn font(px: f64) -> TextStyle<'static> {
    (FAMILY, px * 1.24).into_font().color(&BLACK)
}

/// Titles: bold where the viewer has the bold face (measured as regular,
/// which only centred titles use).
fn bold(px: f64) -> TextStyle<'static> {
    (FAMILY, px * 1.24, FontStyle::Bold)
        .into_font()
        .color(&BLACK)
}

/// Width of `text` in pixels as drawn at `px`.
fn text_width<DB: DrawingBackend>(area: &DrawingArea<DB, Shift>, text: &str, px: f64) -> f64 {
    // plotters measures at the nominal size and draws at size / 1.24, and
    // ab_glyph's scale is the line height (ascent − descent = 1.164 em in
    // DejaVu Sans), not the em that SVG's font-size is.
    area.estimate_text_size(text, &font(px))
        .map(|(w, _)| w as f64 / 1.24 * 1.164)
        .unwrap_or(0.6 * px * text.chars().count() as f64)
}

type Area<'a> = DrawingArea<SVGBackend<'a>, Shift>;

/// A data line as plotters drew it, at whole pixels (its SVG backend rounds
/// every point, which makes a smooth curve a staircase), with the exact
/// coordinates to put in its place.
struct ExactLine {
    /// The opacity it was drawn with, which marks its polyline.
    mark: String,
    /// Its real opacity.
    opacity: String,
    /// `x,y x,y …` in pixels, to 0.01.
    points: String,
}

/// Draws into a fresh SVG document of `w` × `h` pixels.
fn svg_document(
    w: u32,
    h: u32,
    draw: impl FnOnce(&Area) -> Result<Vec<ExactLine>, PlotError>,
) -> Result<String, PlotError> {
    font_ready()?;
    let mut out = String::new();
    let exact;
    {
        let root = SVGBackend::with_string(&mut out, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        exact = draw(&root)?;
        root.present().map_err(err)?;
    }
    Ok(with_exact_lines(&out, &exact))
}

/// `svg` with each marked polyline, in drawing order, given its exact
/// points and real opacity.
fn with_exact_lines(svg: &str, lines: &[ExactLine]) -> String {
    let mut out = String::with_capacity(svg.len() + svg.len() / 2);
    let mut rest = svg;
    for l in lines {
        let key = format!("opacity=\"{}\"", l.mark);
        let Some(at) = rest.find(&key) else { break };
        let Some(start) = rest[at..].find("points=\"").map(|i| at + i + 8) else {
            break;
        };
        let Some(end) = rest[start..].find('"').map(|i| start + i) else {
            break;
        };
        out.push_str(&rest[..at]);
        out.push_str(&format!("opacity=\"{}\"", l.opacity));
        out.push_str(&rest[at + key.len()..start]);
        out.push_str(&l.points);
        rest = &rest[end..];
    }
    out.push_str(rest);
    out
}

/// How a line is drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Stroke {
    /// The main data (2 px).
    Solid,
    /// Thin (1 px), drawn over others.
    Thin,
    /// Wide and light (6 px), drawn under the others: a reference that a
    /// measured line should cover.
    Wide,
    /// Dashed 1 px, for a second quantity in the same colour.
    Dashed,
}

/// One line of a chart.
#[derive(Clone, Debug)]
pub struct Line {
    pub name: String,
    pub colour: RGBColor,
    pub stroke: Stroke,
    pub points: Vec<(f64, f64)>,
}

impl Line {
    pub fn new(name: impl Into<String>, colour: RGBColor, points: Vec<(f64, f64)>) -> Self {
        Self {
            name: name.into(),
            colour,
            stroke: Stroke::Solid,
            points,
        }
    }
    /// A solid line in joint `j`'s colour (0-based; others wrap).
    pub fn joint(j: usize, name: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Self::new(name, JOINT_COLOURS[j % 3], points)
    }
    pub fn stroke(mut self, stroke: Stroke) -> Self {
        self.stroke = stroke;
        self
    }
    fn style(&self) -> ShapeStyle {
        match self.stroke {
            Stroke::Solid => self.colour.stroke_width(2),
            Stroke::Thin | Stroke::Dashed => self.colour.stroke_width(1),
            Stroke::Wide => self.colour.mix(0.3).stroke_width(6),
        }
    }
    fn finite(&self) -> impl Iterator<Item = (f64, f64)> + Clone + '_ {
        self.points
            .iter()
            .copied()
            .filter(|(x, y)| x.is_finite() && y.is_finite())
    }
}

/// Labelled points (via points in a projection).
#[derive(Clone, Debug)]
pub struct Markers {
    pub name: String,
    pub points: Vec<(f64, f64)>,
    pub labels: Vec<String>,
}

/// A line chart: lines, dashed limits, dotted knots, a legend and notes.
#[derive(Clone, Debug)]
pub struct Chart {
    title: String,
    notes: Vec<String>,
    x_label: String,
    y_label: String,
    lines: Vec<Line>,
    markers: Vec<Markers>,
    limits: Vec<(f64, String)>,
    knots: Vec<(f64, String)>,
    /// The legend's name for the vertical markers.
    knots_name: String,
    equal_aspect: bool,
    x_range: Option<(f64, f64)>,
    size: (u32, u32),
}

impl Chart {
    pub fn new(title: impl Into<String>) -> Self {
        Self {
            title: title.into(),
            notes: Vec::new(),
            x_label: String::new(),
            y_label: String::new(),
            lines: Vec::new(),
            markers: Vec::new(),
            limits: Vec::new(),
            knots: Vec::new(),
            knots_name: "knot".into(),
            equal_aspect: false,
            x_range: None,
            size: (900, 480),
        }
    }
    /// Axis label, with its unit, e.g. "time (s)".
    pub fn x_label(mut self, label: impl Into<String>) -> Self {
        self.x_label = label.into();
        self
    }
    pub fn y_label(mut self, label: impl Into<String>) -> Self {
        self.y_label = label.into();
        self
    }
    /// A line of smaller text under the title.
    pub fn note(mut self, note: impl Into<String>) -> Self {
        self.notes.push(note.into());
        self
    }
    pub fn line(mut self, line: Line) -> Self {
        self.lines.push(line);
        self
    }
    pub fn markers(mut self, m: Markers) -> Self {
        self.markers.push(m);
        self
    }
    /// A dashed horizontal limit at `y`, labelled at its right end.
    pub fn limit(mut self, y: f64, label: impl Into<String>) -> Self {
        self.limits.push((y, label.into()));
        self
    }
    /// A dotted vertical marker at `x` (a knot), labelled above the plot.
    pub fn knot(mut self, x: f64, label: impl Into<String>) -> Self {
        self.knots.push((x, label.into()));
        self
    }
    /// The legend's name for the [`Chart::knot`] markers ("knot" unless
    /// they mark something else, such as a resonance).
    pub fn knots_name(mut self, name: impl Into<String>) -> Self {
        self.knots_name = name.into();
        self
    }
    /// Same scale on both axes (projections of a path).
    pub fn equal_aspect(mut self, on: bool) -> Self {
        self.equal_aspect = on;
        self
    }
    /// The x range instead of the data's (e.g. the whole run for every trace).
    pub fn x_range(mut self, lo: f64, hi: f64) -> Self {
        self.x_range = Some((lo, hi));
        self
    }
    /// Size in pixels as a document of its own (default 900 × 480).
    pub fn size(mut self, w: u32, h: u32) -> Self {
        self.size = (w, h);
        self
    }
    pub fn title(&self) -> &str {
        &self.title
    }

    /// The chart as a complete SVG document.
    pub fn to_svg(&self) -> Result<String, PlotError> {
        svg_document(self.size.0, self.size.1, |root| self.draw(root))
    }

    fn legend(&self) -> Vec<LegendEntry> {
        let mut out: Vec<LegendEntry> = self
            .lines
            .iter()
            .filter(|l| !l.name.is_empty())
            .map(|l| LegendEntry {
                name: l.name.clone(),
                colour: l.colour,
                kind: match l.stroke {
                    Stroke::Wide => LegendKind::Wide,
                    Stroke::Dashed => LegendKind::Dashed,
                    _ => LegendKind::Line,
                },
            })
            .collect();
        out.extend(self.markers.iter().map(|m| LegendEntry {
            name: m.name.clone(),
            colour: DARK,
            kind: LegendKind::Dot,
        }));
        if !self.limits.is_empty() {
            out.push(LegendEntry {
                name: "limit".into(),
                colour: LIMIT_COLOUR,
                kind: LegendKind::Dashed,
            });
        }
        if !self.knots.is_empty() {
            out.push(LegendEntry {
                name: self.knots_name.clone(),
                colour: KNOT_COLOUR,
                kind: LegendKind::Dotted,
            });
        }
        out
    }

    /// Data range: every finite point, the limits and the knots.
    fn ranges(&self) -> ((f64, f64), (f64, f64)) {
        let mut xs = (f64::INFINITY, f64::NEG_INFINITY);
        let mut ys = (f64::INFINITY, f64::NEG_INFINITY);
        let add = |r: &mut (f64, f64), v: f64| {
            if v.is_finite() {
                r.0 = r.0.min(v);
                r.1 = r.1.max(v);
            }
        };
        for l in &self.lines {
            for (x, y) in l.finite() {
                add(&mut xs, x);
                add(&mut ys, y);
            }
        }
        for m in &self.markers {
            for &(x, y) in &m.points {
                if x.is_finite() && y.is_finite() {
                    add(&mut xs, x);
                    add(&mut ys, y);
                }
            }
        }
        for (y, _) in &self.limits {
            add(&mut ys, *y);
        }
        for (x, _) in &self.knots {
            add(&mut xs, *x);
        }
        if let Some((lo, hi)) = self.x_range
            && lo.is_finite()
            && hi.is_finite()
            && lo < hi
        {
            xs = (lo, hi);
        }
        (xs, ys)
    }

    fn draw(&self, area: &Area) -> Result<Vec<ExactLine>, PlotError> {
        let (w, h) = area.dim_in_pixel();
        let (w, h) = (w as f64, h as f64);
        let mut y = header(area, &self.title, &self.notes, &self.legend(), 62.0)?;
        let knot_rows = if self.knots.is_empty() { 0.0 } else { 30.0 };
        y += knot_rows;
        let ((x0, x1), (y0, y1)) = self.ranges();
        let time_like = self.x_range.is_some() || !self.knots.is_empty();
        let mut xa = Axis::new(x0, x1, ((w / 110.0) as usize).max(3), !time_like);
        let pad = 0.04 * (y1 - y0).abs();
        let mut ya = Axis::new(y0 - pad, y1 + pad, ((h / 70.0) as usize).max(3), true);
        let tick_w = ya
            .ticks
            .iter()
            .map(|&v| text_width(area, &ya.label(v), 12.0))
            .fold(0.0, f64::max);
        let y_area = (tick_w + 34.0).ceil();
        let (x_area, right, top) = (46.0, 24.0, 6.0);
        if self.equal_aspect {
            // Widen the axis whose units per pixel are fewer, about its centre.
            let pw = (w - y_area - right - 12.0).max(10.0);
            let ph = (h - y - x_area - top).max(10.0);
            let (sx, sy) = ((xa.hi - xa.lo) / pw, (ya.hi - ya.lo) / ph);
            let s = sx.max(sy);
            let grow = |a: &Axis, px: f64| {
                let c = 0.5 * (a.lo + a.hi);
                Axis::new(
                    c - 0.5 * s * px,
                    c + 0.5 * s * px,
                    (px / 90.0) as usize + 2,
                    false,
                )
            };
            xa = grow(&xa, pw);
            ya = grow(&ya, ph);
        }
        let (_, body) = area.split_vertically(y);
        let mut chart = ChartBuilder::on(&body)
            .margin_top(top)
            .margin_right(right)
            .margin_left(12)
            .x_label_area_size(x_area)
            .y_label_area_size(y_area)
            .build_cartesian_2d(xa.clone(), ya.clone())
            .map_err(err)?;
        chart
            .configure_mesh()
            .bold_line_style(GRID)
            .light_line_style(TRANSPARENT)
            .axis_style(BLACK.stroke_width(1))
            .label_style(font(12.0))
            .axis_desc_style(font(13.5))
            .x_desc(self.x_label.as_str())
            .y_desc(self.y_label.as_str())
            .draw()
            .map_err(err)?;

        // The zero line of a signed quantity, darker than the grid.
        if ya.lo < 0.0 && ya.hi > 0.0 {
            chart
                .draw_series(LineSeries::new(
                    [(xa.lo, 0.0), (xa.hi, 0.0)],
                    RGBColor(0xa0, 0xa0, 0xa0).stroke_width(1),
                ))
                .map_err(err)?;
        }
        // Knots under the data, then the lines (wide ones first), then limits.
        for (x, _) in &self.knots {
            if x.is_finite() {
                chart
                    .draw_series(DashedLineSeries::new(
                        [(*x, ya.lo), (*x, ya.hi)],
                        2,
                        3,
                        KNOT_COLOUR.stroke_width(1),
                    ))
                    .map_err(err)?;
            }
        }
        let mut exact = Vec::new();
        let mut order: Vec<&Line> = self.lines.iter().collect();
        order.sort_by_key(|l| match l.stroke {
            Stroke::Wide => 0,
            Stroke::Solid => 1,
            _ => 2,
        });
        for l in order {
            if l.stroke == Stroke::Dashed {
                chart
                    .draw_series(DashedLineSeries::new(l.finite(), 5, 3, l.style()))
                    .map_err(err)?;
            } else {
                // Exact pixel positions: the axes map linearly between the
                // plot area's corners ([`Axis`], rounded only there).
                let (a, b) = (
                    chart.backend_coord(&(xa.lo, ya.lo)),
                    chart.backend_coord(&(xa.hi, ya.hi)),
                );
                let px = |(x, y): (f64, f64)| {
                    (
                        a.0 as f64 + (x - xa.lo) / (xa.hi - xa.lo) * (b.0 - a.0) as f64,
                        a.1 as f64 + (y - ya.lo) / (ya.hi - ya.lo) * (b.1 - a.1) as f64,
                    )
                };
                let inside = |(x, y): (f64, f64)| {
                    (f64::from(a.0.min(b.0)) - 1.0..=f64::from(a.0.max(b.0)) + 1.0).contains(&x)
                        && (f64::from(a.1.min(b.1)) - 1.0..=f64::from(a.1.max(b.1)) + 1.0)
                            .contains(&y)
                };
                // Points closer than half a pixel add nothing visible.
                let pts: Vec<(f64, f64)> = l.finite().collect();
                let n = pts.len();
                let mut last: Option<(f64, f64)> = None;
                let thin: Vec<((f64, f64), (f64, f64))> = pts
                    .iter()
                    .enumerate()
                    .filter_map(|(k, &p)| {
                        let q = px(p);
                        let keep = k + 1 == n
                            || last.is_none_or(|r| (q.0 - r.0).abs() + (q.1 - r.1).abs() >= 0.5);
                        keep.then(|| {
                            last = Some(q);
                            (p, q)
                        })
                    })
                    .collect();
                let mut style = l.style();
                // Lines that leave the plot area stay as plotters clips them.
                if thin.iter().all(|(_, q)| inside(*q)) {
                    let opacity = style.color.3;
                    let mark = opacity - 1e-9;
                    style.color.3 = mark;
                    exact.push(ExactLine {
                        mark: format!("{mark}"),
                        opacity: format!("{opacity}"),
                        points: thin
                            .iter()
                            .map(|(_, q)| format!("{:.2},{:.2}", q.0, q.1))
                            .collect::<Vec<_>>()
                            .join(" "),
                    });
                }
                chart
                    .draw_series(LineSeries::new(thin.iter().map(|(p, _)| *p), style))
                    .map_err(err)?;
            }
        }
        for m in &self.markers {
            let finite: Vec<(f64, f64)> = m
                .points
                .iter()
                .copied()
                .filter(|(x, y)| x.is_finite() && y.is_finite())
                .collect();
            let n = finite.len().max(1) as f64;
            let c = finite
                .iter()
                .fold((0.0, 0.0), |a, p| (a.0 + p.0 / n, a.1 + p.1 / n));
            // Pixels per unit, so "outward" is measured on the screen.
            let (sx, sy) = {
                let (pw, ph) = chart.plotting_area().dim_in_pixel();
                (pw as f64 / (xa.hi - xa.lo), ph as f64 / (ya.hi - ya.lo))
            };
            // Markers along a line: "outward" would put labels on the line,
            // so they all go to its side instead.
            let (sxx, syy, sxy) = finite.iter().fold((0.0, 0.0, 0.0), |a, p| {
                let (dx, dy) = ((p.0 - c.0) * sx, (p.1 - c.1) * sy);
                (a.0 + dx * dx, a.1 + dy * dy, a.2 + dx * dy)
            });
            let tr = sxx + syy;
            let det = sxx * syy - sxy * sxy;
            let minor = 0.5 * tr - (0.25 * tr * tr - det).max(0.0).sqrt();
            let side = if tr > 0.0 && minor < 0.02 * tr {
                // Normal of the principal axis, pointing up.
                let angle = 0.5 * (2.0 * sxy).atan2(sxx - syy);
                let (nx, ny) = (-angle.sin(), angle.cos());
                Some(if ny < 0.0 { (-nx, -ny) } else { (nx, ny) })
            } else {
                None
            };
            for (k, &(px, py)) in m.points.iter().enumerate() {
                if !(px.is_finite() && py.is_finite()) {
                    continue;
                }
                let label = m.labels.get(k).cloned().unwrap_or_default();
                let (offset, pos) = outward(side.unwrap_or(((px - c.0) * sx, (py - c.1) * sy)));
                chart
                    .draw_series(std::iter::once(
                        EmptyElement::at((px, py))
                            + Circle::new((0, 0), 4, DARK.filled())
                            + Text::new(label, offset, font(12.0).pos(pos)),
                    ))
                    .map_err(err)?;
            }
        }
        for (v, label) in &self.limits {
            if !v.is_finite() {
                continue;
            }
            chart
                .draw_series(DashedLineSeries::new(
                    [(xa.lo, *v), (xa.hi, *v)],
                    8,
                    5,
                    LIMIT_COLOUR.stroke_width(2),
                ))
                .map_err(err)?;
            // Above a positive limit, below a negative one: inside the plot.
            let (dy, vpos) = if *v >= 0.0 {
                (-3, VPos::Bottom)
            } else {
                (3, VPos::Top)
            };
            let style = font(12.0)
                .color(&LIMIT_COLOUR)
                .pos(Pos::new(HPos::Right, vpos));
            chart
                .draw_series(std::iter::once(
                    EmptyElement::at((xa.hi, *v)) + Text::new(label.clone(), (-6, dy), style),
                ))
                .map_err(err)?;
        }

        // Knot labels above the plot, in two rows where they would touch.
        let base = area.get_base_pixel();
        let mut row_end = [f64::NEG_INFINITY; 2];
        for (x, label) in &self.knots {
            if !x.is_finite() || label.is_empty() {
                continue;
            }
            let (px, py) = chart.backend_coord(&(*x, ya.hi));
            let lw = text_width(area, label, 11.5);
            let cx = (px - base.0) as f64;
            let row = if cx - lw / 2.0 > row_end[0] + 3.0 {
                0
            } else if cx - lw / 2.0 > row_end[1] + 3.0 {
                1
            } else {
                0
            };
            row_end[row] = cx + lw / 2.0;
            let ty = (py - base.1) as f64 - 4.0 - 14.0 * row as f64;
            area.draw(&Text::new(
                label.clone(),
                (cx as i32, ty as i32),
                font(11.5)
                    .color(&KNOT_COLOUR)
                    .pos(Pos::new(HPos::Center, VPos::Bottom)),
            ))
            .map_err(err)?;
        }
        Ok(exact)
    }
}

/// Offset and anchor of a marker's label placed away from the markers'
/// centre, `d` pixels from it (screen y down is handled here: `d.1` is up).
fn outward(d: (f64, f64)) -> ((i32, i32), Pos) {
    let len = d.0.hypot(d.1);
    let (ux, uy) = if len > 1e-9 {
        (d.0 / len, d.1 / len)
    } else {
        (0.6, 0.8)
    };
    let h = if ux > 0.35 {
        HPos::Left
    } else if ux < -0.35 {
        HPos::Right
    } else {
        HPos::Center
    };
    let v = if uy > 0.35 {
        VPos::Bottom
    } else if uy < -0.35 {
        VPos::Top
    } else {
        VPos::Center
    };
    let r = 8.0;
    (((r * ux) as i32, (-r * uy) as i32), Pos::new(h, v))
}

#[derive(Clone, Copy, Debug)]
enum LegendKind {
    Line,
    Wide,
    Dashed,
    Dotted,
    Dot,
}

#[derive(Clone, Debug)]
struct LegendEntry {
    name: String,
    colour: RGBColor,
    kind: LegendKind,
}

/// Title, notes and legend at the top of `area`, from `left` pixels; returns
/// the height used.
fn header(
    area: &Area,
    title: &str,
    notes: &[String],
    legend: &[LegendEntry],
    left: f64,
) -> Result<f64, PlotError> {
    let (w, _) = area.dim_in_pixel();
    let w = w as f64;
    let centre = Pos::new(HPos::Center, VPos::Top);
    let mut y = 14.0;
    area.draw(&Text::new(
        title.to_string(),
        ((w / 2.0) as i32, y as i32),
        bold(16.0).pos(centre),
    ))
    .map_err(err)?;
    y += 24.0;
    for n in notes {
        area.draw(&Text::new(
            n.clone(),
            ((w / 2.0) as i32, y as i32),
            font(12.0).color(&NOTE).pos(centre),
        ))
        .map_err(err)?;
        y += 16.0;
    }
    if legend.is_empty() {
        return Ok(y + 2.0);
    }
    y += 4.0;
    let mut x = left;
    let row_h = 18.0;
    for e in legend {
        let tw = text_width(area, &e.name, 12.5);
        let item = 30.0 + tw + 18.0;
        if x + item > w - 10.0 && x > left {
            x = left;
            y += row_h;
        }
        let ly = (y + 7.0) as i32;
        let (x0, x1) = (x as i32, (x + 24.0) as i32);
        match e.kind {
            LegendKind::Line => area.draw(&PathElement::new(
                vec![(x0, ly), (x1, ly)],
                e.colour.stroke_width(2),
            )),
            LegendKind::Wide => area.draw(&PathElement::new(
                vec![(x0, ly), (x1, ly)],
                e.colour.mix(0.3).stroke_width(6),
            )),
            LegendKind::Dashed => area.draw(&DashedPathElement::new(
                vec![(x0, ly), (x1, ly)],
                6,
                3,
                e.colour.stroke_width(2),
            )),
            LegendKind::Dotted => area.draw(&DashedPathElement::new(
                vec![(x0, ly), (x1, ly)],
                2,
                3,
                e.colour.stroke_width(1),
            )),
            LegendKind::Dot => area.draw(&Circle::new((x0 + 12, ly), 4, e.colour.filled())),
        }
        .map_err(err)?;
        area.draw(&Text::new(
            e.name.clone(),
            (x1 + 6, ly),
            font(12.5).pos(Pos::new(HPos::Left, VPos::Center)),
        ))
        .map_err(err)?;
        x += item;
    }
    Ok(y + row_h + 2.0)
}

/// One panel of a [`Figure`].
#[derive(Clone, Debug)]
pub enum Panel {
    Chart(Chart),
    Path(Path3d),
}

impl From<Chart> for Panel {
    fn from(c: Chart) -> Self {
        Panel::Chart(c)
    }
}

impl From<Path3d> for Panel {
    fn from(p: Path3d) -> Self {
        Panel::Path(p)
    }
}

impl Panel {
    fn draw(&self, area: &Area) -> Result<Vec<ExactLine>, PlotError> {
        match self {
            Panel::Chart(c) => c.draw(area),
            Panel::Path(p) => p.draw(area),
        }
    }
}

/// Panels in a grid of `columns`, each `cell` pixels, under one title.
#[derive(Clone, Debug)]
pub struct Figure {
    title: String,
    columns: usize,
    cell: (u32, u32),
    panels: Vec<Panel>,
}

impl Figure {
    pub fn new(title: impl Into<String>, columns: usize, cell: (u32, u32)) -> Self {
        Self {
            title: title.into(),
            columns: columns.max(1),
            cell,
            panels: Vec::new(),
        }
    }
    pub fn panel(mut self, p: impl Into<Panel>) -> Self {
        self.panels.push(p.into());
        self
    }
    pub fn panels(&self) -> &[Panel] {
        &self.panels
    }

    pub fn to_svg(&self) -> Result<String, PlotError> {
        let cols = self.columns.min(self.panels.len().max(1));
        let rows = self.panels.len().div_ceil(cols).max(1);
        let title_h = 40;
        let w = self.cell.0 * cols as u32;
        let h = self.cell.1 * rows as u32 + title_h;
        svg_document(w, h, |root| {
            root.draw(&Text::new(
                self.title.clone(),
                ((w / 2) as i32, 10),
                bold(19.0).pos(Pos::new(HPos::Center, VPos::Top)),
            ))
            .map_err(err)?;
            let (_, grid) = root.split_vertically(title_h);
            let cells = grid.split_evenly((rows, cols));
            let mut exact = Vec::new();
            for (p, cell) in self.panels.iter().zip(cells.iter()) {
                exact.extend(p.draw(cell)?);
            }
            Ok(exact)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample_chart() -> Chart {
        let pts: Vec<(f64, f64)> = (0..50)
            .map(|k| (k as f64 * 0.1, (k as f64).sin()))
            .collect();
        Chart::new("Joint <velocity> & more")
            .x_label("time (s)")
            .y_label("velocity (m/s)")
            .line(Line::joint(0, "joint 1", pts.clone()))
            .line(Line::joint(1, "joint 2", vec![(0.0, f64::NAN), (1.0, 0.5)]))
            .limit(1.2, "+1.2 m/s")
            .limit(-1.2, "−1.2 m/s")
            .knot(0.0, "P1")
            .knot(2.0, "P2")
    }

    #[test]
    fn chart_escapes_text_and_draws_every_part() {
        let svg = sample_chart().to_svg().unwrap();
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        assert!(svg.contains("Joint &lt;velocity&gt; &amp; more"));
        for text in [
            "joint 1", "joint 2", "limit", "knot", "P1", "P2", "+1.2 m/s", "time (s)",
        ] {
            assert!(svg.contains(&format!("{text}\n</text>")), "{text}");
        }
        assert!(svg.contains(FAMILY));
        assert!(!svg.contains("NaN"));
    }

    /// The `points` of every polyline drawn in `colour`.
    fn polylines<'a>(svg: &'a str, colour: &str) -> Vec<&'a str> {
        svg.split("<polyline")
            .skip(1)
            .filter(|p| p.contains(&format!("stroke=\"{colour}\"")))
            .map(|p| {
                p.split("points=\"")
                    .nth(1)
                    .unwrap()
                    .split('"')
                    .next()
                    .unwrap()
            })
            .collect()
    }

    #[test]
    fn data_lines_keep_their_exact_pixels() {
        // A smooth curve at whole pixels is a staircase.
        let pts: Vec<(f64, f64)> = (0..=400)
            .map(|k| (k as f64 * 0.01, (k as f64 * 0.01).sin()))
            .collect();
        let chart = Chart::new("sine").line(Line::joint(0, "joint 1", pts.clone()));
        let svg = chart.to_svg().unwrap();
        let blue = polylines(&svg, "#1F77B4");
        let data = blue.iter().max_by_key(|p| p.len()).unwrap();
        let fractional = data
            .split_whitespace()
            .filter(|xy| xy.split(',').any(|v| !v.ends_with(".00")))
            .count();
        assert!(fractional > 100, "{data}");
        // Its real opacity, not the mark it was found by.
        assert!(!svg.contains("0.999999999"), "a mark was left");
        let wide = Chart::new("wide")
            .line(Line::joint(0, "joint 1", pts).stroke(Stroke::Wide))
            .to_svg()
            .unwrap();
        assert!(wide.contains("opacity=\"0.3\""), "{wide}");
        assert!(!wide.contains("0.299999"));
        // A line that leaves the plot (its x range cut) stays as plotters
        // clips it, at whole pixels.
        let cut = Chart::new("cut")
            .line(Line::joint(
                0,
                "joint 1",
                (0..=400).map(|k| (k as f64 * 0.01, 1.0)).collect(),
            ))
            .x_range(1.0, 2.0)
            .to_svg()
            .unwrap();
        let long = polylines(&cut, "#1F77B4")
            .into_iter()
            .max_by_key(|p| p.len())
            .unwrap();
        assert!(!long.contains('.'), "{long}");
    }

    #[test]
    fn bad_input_draws_an_empty_chart() {
        for pts in [vec![], vec![(f64::NAN, f64::INFINITY)], vec![(1.0, 1.0)]] {
            let svg = Chart::new("empty")
                .line(Line::joint(7, "x", pts))
                .limit(f64::NAN, "nan")
                .knot(f64::INFINITY, "inf")
                .x_range(f64::NAN, 0.0)
                .equal_aspect(true)
                .to_svg()
                .unwrap();
            assert!(svg.trim_end().ends_with("</svg>"));
        }
    }

    #[test]
    fn figure_holds_every_panel() {
        let fig = Figure::new("overview", 2, (500, 360))
            .panel(sample_chart())
            .panel(sample_chart())
            .panel(Path3d::new("path").unit("mm").path(
                "platform",
                &[[0.0, 0.0, 0.0], [10.0, 5.0, 2.0], [20.0, 0.0, 4.0]],
            ));
        let svg = fig.to_svg().unwrap();
        assert!(svg.contains("width=\"1000\" height=\"760\""));
        assert_eq!(svg.matches("Joint &lt;velocity&gt;").count(), 2);
        assert!(svg.contains("platform"));
    }
}
