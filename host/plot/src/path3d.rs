//! A 3-D path (z up, true scale) with labelled via points, optionally with
//! its top and front views.

use plotters::prelude::*;

use crate::ticks::Axis;
use crate::{
    Area, Chart, DARK, ExactLine, KNOT_COLOUR, LegendEntry, LegendKind, Line, Markers, PlotError,
    err, font, header, svg_document,
};

/// Colour of the platform path (not a joint's).
const PATH_COLOUR: RGBColor = RGBColor(0x6a, 0x3d, 0x9a);
const SHADOW: RGBColor = RGBColor(0xbb, 0xbb, 0xbb);

/// A 3-D path with labelled markers, seen from the (+x, −y, +z) side, with
/// its shadow on the floor of the box and drop lines from the markers.
#[derive(Clone, Debug)]
pub struct Path3d {
    title: String,
    notes: Vec<String>,
    unit: String,
    paths: Vec<(String, Vec<[f64; 3]>)>,
    markers: Vec<(String, Vec<[f64; 3]>, Vec<String>)>,
    projections: bool,
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
        }
    }
    /// Unit of all three coordinates, shown in the axis labels (e.g. "mm").
    pub fn unit(mut self, unit: impl Into<String>) -> Self {
        self.unit = unit.into();
        self
    }
    pub fn note(mut self, note: impl Into<String>) -> Self {
        self.notes.push(note.into());
        self
    }
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
    /// Adds the top (x–y) and front (x–z) views beside the 3-D view.
    pub fn projections(mut self, on: bool) -> Self {
        self.projections = on;
        self
    }

    pub fn to_svg(&self) -> Result<String, PlotError> {
        let (w, h) = if self.projections {
            (1280, 760)
        } else {
            (760, 640)
        };
        svg_document(w, h, |root| self.draw(root))
    }

    fn axis_label(&self, axis: &str) -> String {
        if self.unit.is_empty() {
            axis.to_string()
        } else {
            format!("{axis} ({})", self.unit)
        }
    }

    fn finite(points: &[[f64; 3]]) -> impl Iterator<Item = [f64; 3]> + Clone + '_ {
        points
            .iter()
            .copied()
            .filter(|p| p.iter().all(|v| v.is_finite()))
    }

    /// The view onto axes `a`, `b` (0 = x, 1 = y, 2 = z) as a chart.
    pub fn projection(&self, title: &str, a: usize, b: usize) -> Chart {
        let names = ["x", "y", "z"];
        let mut chart = Chart::new(title)
            .x_label(self.axis_label(names[a]))
            .y_label(self.axis_label(names[b]))
            .equal_aspect(true);
        for (name, pts) in &self.paths {
            let pts = Self::finite(pts).map(|p| (p[a], p[b])).collect();
            chart = chart.line(Line::new(name.clone(), PATH_COLOUR, pts));
        }
        for (name, pts, labels) in &self.markers {
            chart = chart.markers(Markers {
                name: name.clone(),
                points: pts.iter().map(|p| (p[a], p[b])).collect(),
                labels: merge_labels(pts, labels, a, b),
            });
        }
        chart
    }

    /// Every view's lines at exact (sub-pixel) positions: the 3-D view's
    /// projection is affine, so its exact points follow from plotters'
    /// matrix; the two views are charts.
    pub(crate) fn draw(&self, area: &Area) -> Result<Vec<ExactLine>, PlotError> {
        if !self.projections {
            return self.draw_iso(area);
        }
        let (w, _) = area.dim_in_pixel();
        let (left, right) = area.split_horizontally((w as f64 * 0.56) as u32);
        let mut exact = self.draw_iso(&left)?;
        let (top, front) = {
            let (_, h) = right.dim_in_pixel();
            right.split_vertically(h / 2)
        };
        exact.extend(self.projection("Top view (x–y)", 0, 1).draw(&top)?);
        exact.extend(self.projection("Front view (x–z)", 0, 2).draw(&front)?);
        Ok(exact)
    }

    fn draw_iso(&self, area: &Area) -> Result<Vec<ExactLine>, PlotError> {
        let mut legend: Vec<LegendEntry> = self
            .paths
            .iter()
            .map(|(n, _)| LegendEntry {
                name: n.clone(),
                colour: PATH_COLOUR,
                kind: LegendKind::Line,
            })
            .collect();
        legend.extend(self.markers.iter().map(|(n, _, _)| LegendEntry {
            name: n.clone(),
            colour: DARK,
            kind: LegendKind::Dot,
        }));
        legend.push(LegendEntry {
            name: "shadow on the floor".into(),
            colour: SHADOW,
            kind: LegendKind::Line,
        });
        let y = header(area, &self.title, &self.notes, &legend, 40.0)?;
        let (_, body) = area.split_vertically(y);

        // A cube around the data: the same scale on all three axes.
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        let all = self
            .paths
            .iter()
            .map(|(_, p)| p)
            .chain(self.markers.iter().map(|(_, p, _)| p));
        for pts in all {
            for p in Self::finite(pts) {
                for i in 0..3 {
                    lo[i] = lo[i].min(p[i]);
                    hi[i] = hi[i].max(p[i]);
                }
            }
        }
        if lo[0] > hi[0] {
            (lo, hi) = ([0.0; 3], [1.0; 3]);
        }
        let span = (0..3)
            .map(|i| hi[i] - lo[i])
            .fold(0.0, f64::max)
            .max(1e-9 * lo.iter().chain(&hi).fold(0.0f64, |m, v| m.max(v.abs())))
            .max(1e-12);
        let half = 0.55 * span;
        let axes: Vec<Axis> = (0..3)
            .map(|i| {
                let c = 0.5 * (lo[i] + hi[i]);
                let mut a = Axis::new(c - half, c + half, 5, false);
                // x and y meet at the front corner (their high ends): no
                // tick there, where the two labels would print over each other.
                let front = if i < 2 { 0.12 } else { 0.03 };
                a.ticks
                    .retain(|t| (t - a.lo) > 0.03 * span && (a.hi - t) > front * span);
                a
            })
            .collect();
        let (ax, ay, az) = (&axes[0], &axes[1], &axes[2]);
        // plotters' 3-D y is up: draw (x, z, y).
        let mut chart = ChartBuilder::on(&body)
            .margin(10)
            .margin_left(56)
            .margin_bottom(24)
            .build_cartesian_3d(ax.clone(), az.clone(), ay.clone())
            .map_err(err)?;
        chart.with_projection(|mut p| {
            p.yaw = 0.6;
            p.pitch = 0.35;
            p.scale = 0.84;
            p.into_matrix()
        });
        let fx = |v: &f64| ax.label(*v);
        let fz = |v: &f64| az.label(*v);
        let fy = |v: &f64| ay.label(*v);
        chart
            .configure_axes()
            .label_style(font(11.5))
            .bold_grid_style(RGBColor(0xdd, 0xdd, 0xdd))
            .light_grid_style(TRANSPARENT)
            .max_light_lines(0)
            .axis_panel_style(RGBColor(0xf6, 0xf6, 0xf6))
            .x_formatter(&fx)
            .y_formatter(&fz)
            .z_formatter(&fy)
            .draw()
            .map_err(err)?;
        // Axis names beyond the labelled edges.
        let names = [
            (
                self.axis_label("x"),
                (0.5 * (ax.lo + ax.hi), az.lo, ay.hi + 0.3 * (ay.hi - ay.lo)),
            ),
            (
                self.axis_label("y"),
                (ax.hi + 0.3 * (ax.hi - ax.lo), az.lo, 0.5 * (ay.lo + ay.hi)),
            ),
            (
                self.axis_label("z"),
                (ax.lo, az.hi + 0.06 * (az.hi - az.lo), ay.hi),
            ),
        ];
        for (name, at) in names {
            chart
                .draw_series(std::iter::once(Text::new(
                    name,
                    at,
                    font(13.5).pos(plotters::style::text_anchor::Pos::new(
                        plotters::style::text_anchor::HPos::Center,
                        plotters::style::text_anchor::VPos::Center,
                    )),
                )))
                .map_err(err)?;
        }
        // plotters rounds each axis to a whole pixel and then projects
        // (an affine map, `translate`), truncating: the same map unrounded.
        let (size, m) = {
            let spec = chart.as_coord_spec();
            (
                spec.map_3d(&ax.hi, &az.hi, &ay.hi),
                *spec.projection().as_ref(),
            )
        };
        let exact_px = |(x, z, y): (f64, f64, f64)| {
            let v = [
                (x - ax.lo) / (ax.hi - ax.lo) * f64::from(size.0),
                (z - az.lo) / (az.hi - az.lo) * f64::from(size.1),
                (y - ay.lo) / (ay.hi - ay.lo) * f64::from(size.2),
            ];
            let row = |r: &[f64; 4]| r[0] * v[0] + r[1] * v[1] + r[2] * v[2] + r[3];
            (row(&m[0]), row(&m[1]))
        };
        let mut exact = Vec::new();
        let mut exact_line = |pts: Vec<(f64, f64, f64)>, colour: RGBColor| {
            // A mark just under the real opacity finds the polyline again.
            let mark = 1.0 - 1e-9;
            exact.push(ExactLine {
                mark: format!("{mark}"),
                opacity: "1".into(),
                points: pts
                    .iter()
                    .map(|p| {
                        let q = exact_px(*p);
                        format!("{:.2},{:.2}", q.0, q.1)
                    })
                    .collect::<Vec<_>>()
                    .join(" "),
            });
            (pts, colour.mix(mark).stroke_width(2))
        };
        for (_, pts) in &self.paths {
            let (pts, style) = exact_line(
                Self::finite(pts).map(|p| (p[0], az.lo, p[1])).collect(),
                SHADOW,
            );
            chart
                .draw_series(LineSeries::new(pts, style))
                .map_err(err)?;
        }
        for (_, pts, _) in &self.markers {
            for p in Self::finite(pts) {
                chart
                    .draw_series(DashedLineSeries::new(
                        [(p[0], az.lo, p[1]), (p[0], p[2], p[1])],
                        2,
                        3,
                        KNOT_COLOUR.stroke_width(1),
                    ))
                    .map_err(err)?;
            }
        }
        for (_, pts) in &self.paths {
            let (pts, style) = exact_line(
                Self::finite(pts).map(|p| (p[0], p[2], p[1])).collect(),
                PATH_COLOUR,
            );
            chart
                .draw_series(LineSeries::new(pts, style))
                .map_err(err)?;
        }
        for (_, pts, labels) in &self.markers {
            for (k, p) in pts.iter().enumerate() {
                if !p.iter().all(|v| v.is_finite()) {
                    continue;
                }
                let label = labels.get(k).cloned().unwrap_or_default();
                chart
                    .draw_series(std::iter::once(
                        EmptyElement::at((p[0], p[2], p[1]))
                            + Circle::new((0, 0), 4, DARK.filled())
                            + Text::new(label, (6, -16), font(12.0)),
                    ))
                    .map_err(err)?;
            }
        }
        Ok(exact)
    }
}

/// Labels of points that coincide in the (a, b) view joined into one
/// ("P2, P9"), so they do not print over each other.
fn merge_labels(pts: &[[f64; 3]], labels: &[String], a: usize, b: usize) -> Vec<String> {
    let mut out: Vec<String> = (0..pts.len())
        .map(|k| labels.get(k).cloned().unwrap_or_default())
        .collect();
    for k in 0..pts.len() {
        if out[k].is_empty() {
            continue;
        }
        for m in 0..k {
            let close =
                (pts[k][a] - pts[m][a]).abs() < 1e-6 && (pts[k][b] - pts[m][b]).abs() < 1e-6;
            if close && !out[m].is_empty() {
                let joined = format!("{}, {}", out[m], out[k]);
                out[m] = joined;
                out[k].clear();
                break;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coinciding_labels_merge_in_a_view() {
        let pts = [[0.0, 0.0, 0.0], [1.0, 0.0, 5.0], [0.0, 0.0, 9.0]];
        let labels: Vec<String> = ["P1", "P2", "P3"].map(String::from).to_vec();
        // Top view: P1 and P3 are one point.
        assert_eq!(merge_labels(&pts, &labels, 0, 1), ["P1, P3", "P2", ""]);
        assert_eq!(merge_labels(&pts, &labels, 0, 2), ["P1", "P2", "P3"]);
    }

    #[test]
    fn the_3d_path_is_drawn_at_exact_pixels_where_plotters_puts_it() {
        let pts: Vec<[f64; 3]> = (0..=300)
            .map(|k| {
                let a = k as f64 * 0.05;
                [80.0 * a.cos(), 80.0 * a.sin(), 560.0 + 8.0 * a]
            })
            .collect();
        let ends = [pts[0], pts[300]];
        let svg = Path3d::new("helix")
            .path("platform path", &pts)
            .markers("via points", &ends, &["P1".into(), "P2".into()])
            .to_svg()
            .unwrap();
        // The data lines, not the legend's samples: the shadow, then the path.
        let lines: Vec<Vec<(f64, f64)>> = svg
            .split("<polyline")
            .skip(1)
            .filter(|p| p.contains("stroke=\"#6A3D9A\"") || p.contains("stroke=\"#BBBBBB\""))
            .map(|p| -> Vec<(f64, f64)> {
                let pts = p
                    .split("points=\"")
                    .nth(1)
                    .unwrap()
                    .split('"')
                    .next()
                    .unwrap();
                pts.split_whitespace()
                    .map(|xy| {
                        let (x, y) = xy.split_once(',').unwrap();
                        (x.parse().unwrap(), y.parse().unwrap())
                    })
                    .collect()
            })
            .filter(|l| l.len() > 200)
            .collect();
        assert_eq!(lines.len(), 2, "the path and its shadow");
        for l in &lines {
            let fractional = l
                .iter()
                .filter(|(x, y)| x.fract() != 0.0 || y.fract() != 0.0);
            assert!(fractional.count() > 200, "{l:?}");
        }
        assert!(!svg.contains("0.999999999"), "a mark was left");
        // The path starts and ends at the markers plotters placed (whole
        // pixels, truncated): within a pixel of them.
        let circles: Vec<(f64, f64)> = svg
            .split("<circle")
            .skip(1)
            .map(|c| {
                let attr = |n: &str| -> f64 {
                    c.split(&format!("{n}=\""))
                        .nth(1)
                        .unwrap()
                        .split('"')
                        .next()
                        .unwrap()
                        .parse()
                        .unwrap()
                };
                (attr("cx"), attr("cy"))
            })
            .collect();
        let path = &lines[1];
        // The markers are drawn last (after the legend's dot).
        let markers = &circles[circles.len() - 2..];
        for (end, c) in [path[0], *path.last().unwrap()].iter().zip(markers) {
            assert!(
                (end.0 - c.0).abs() <= 1.0 && (end.1 - c.1).abs() <= 1.0,
                "{end:?} vs marker {c:?}"
            );
        }
    }

    #[test]
    fn path_with_views_draws_three_panels() {
        let pts: Vec<[f64; 3]> = (0..20)
            .map(|k| [k as f64, (k as f64 * 0.3).sin() * 5.0, 300.0 + k as f64])
            .collect();
        let svg = Path3d::new("path")
            .unit("mm")
            .path("platform path", &pts)
            .markers(
                "via points",
                &[pts[0], pts[19]],
                &["P1".into(), "P2".into()],
            )
            .projections(true)
            .to_svg()
            .unwrap();
        for t in [
            "Top view (x–y)",
            "Front view (x–z)",
            "x (mm)",
            "z (mm)",
            "P1",
            "P2",
        ] {
            assert!(svg.contains(t), "{t}");
        }
    }
}
