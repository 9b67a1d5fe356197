//! Measured points with error bars against simulated lines (the fit and discover reports):
//! plotters' SVG backend, the same fonts, palette and conventions as [`super::plot`]
//! (no font files, deterministic output, non-finite values skipped, nothing to draw an error).

use super::plot::{densify, fmt_tick_in, legend_box_px, place_legend, title_area, PlotError};
use plotters::element::DashedPathElement;
use plotters::prelude::*;

const FONT: &str = "sans-serif";
const COLORS: [RGBColor; 4] = [
    RGBColor(213, 94, 0),  // vermillion (first line)
    RGBColor(0, 114, 178), // blue (second line)
    RGBColor(0, 158, 115), // bluish green
    RGBColor(204, 121, 167),
];

/// A measured-vs-simulated overlay.
#[derive(Debug, Clone, PartialEq)]
pub struct Overlay {
    /// Title.
    pub title: String,
    /// x label with unit.
    pub x_label: String,
    /// y label with unit.
    pub y_label: String,
    /// Legend of the points.
    pub points_label: String,
    /// Measured points (x, y, error half-width; 0 for none).
    pub points: Vec<(f64, f64, f64)>,
    /// Simulated lines (legend, points); the first solid, the next dashed.
    pub lines: Vec<(String, Vec<(f64, f64)>)>,
}

impl Overlay {
    /// Render to SVG (960 × 600 px).
    pub fn to_svg(&self) -> Result<String, PlotError> {
        let pts: Vec<(f64, f64, f64)> = self
            .points
            .iter()
            .copied()
            .filter(|(x, y, e)| x.is_finite() && y.is_finite() && e.is_finite())
            .collect();
        let lines: Vec<(String, Vec<(f64, f64)>)> = self
            .lines
            .iter()
            .map(|(n, l)| {
                (
                    n.clone(),
                    l.iter()
                        .copied()
                        .filter(|(x, y)| x.is_finite() && y.is_finite())
                        .collect(),
                )
            })
            .collect();
        let xs = pts
            .iter()
            .map(|p| p.0)
            .chain(lines.iter().flat_map(|l| l.1.iter().map(|p| p.0)));
        let ys = pts
            .iter()
            .flat_map(|p| [p.1 - p.2, p.1 + p.2])
            .chain(lines.iter().flat_map(|l| l.1.iter().map(|p| p.1)));
        let bound = |it: &mut dyn Iterator<Item = f64>| {
            it.fold(None, |acc: Option<(f64, f64)>, v| {
                Some(acc.map_or((v, v), |(a, b)| (a.min(v), b.max(v))))
            })
        };
        let (x0, x1) =
            bound(&mut xs.into_iter()).ok_or_else(|| PlotError::NoData(self.title.clone()))?;
        let (y0, y1) =
            bound(&mut ys.into_iter()).ok_or_else(|| PlotError::NoData(self.title.clone()))?;
        let pad = |a: f64, b: f64| {
            let d = if b > a {
                0.05 * (b - a)
            } else {
                a.abs().max(1e-12) * 0.05
            };
            (a - d)..(b + d)
        };
        let draw_err = |e: String| PlotError::Draw {
            title: self.title.clone(),
            message: e,
        };
        let mut svg = String::new();
        {
            let root = SVGBackend::with_string(&mut svg, (960, 600)).into_drawing_area();
            root.fill(&WHITE).map_err(|e| draw_err(e.to_string()))?;
            let (below, _) = title_area(&root, &self.title).map_err(|e| draw_err(e.to_string()))?;
            // The legend in the corner that hides the fewest lines, points and error bars
            // (fractions of the plotting area as the chart below lays it out), with room made
            // above the data when every corner hides some
            let (xr, yr) = (pad(x0, x1), pad(y0, y1));
            let (aw, ah) = below.dim_in_pixel();
            let plot = (
                aw as f64 - 2.0 * 18.0 - 110.0,
                ah as f64 - 2.0 * 18.0 - 70.0,
            );
            let names = lines
                .iter()
                .map(|l| l.0.chars().count())
                .chain(std::iter::once(self.points_label.chars().count()));
            let legend = legend_box_px(names);
            let data_in = |yr: &std::ops::Range<f64>| {
                let f = |x: f64, y: f64| {
                    (
                        (x - xr.start) / (xr.end - xr.start),
                        (y - yr.start) / (yr.end - yr.start),
                    )
                };
                let mut out = Vec::new();
                for (_, l) in &lines {
                    let run: Vec<(f64, f64)> = l.iter().map(|&(x, y)| f(x, y)).collect();
                    densify(&run, &mut out);
                }
                for &(x, y, e) in &pts {
                    densify(&[f(x, y - e), f(x, y + e)], &mut out);
                }
                out
            };
            let (corner, yr, _) = place_legend(yr, plot, legend, data_in);
            let mut chart = ChartBuilder::on(&below)
                .margin(18)
                .x_label_area_size(70)
                .y_label_area_size(110)
                .build_cartesian_2d(xr.clone(), yr.clone())
                .map_err(|e| draw_err(e.to_string()))?;
            let xtick = |v: &f64| fmt_tick_in(*v, xr.end - xr.start);
            let ytick = |v: &f64| fmt_tick_in(*v, yr.end - yr.start);
            chart
                .configure_mesh()
                .x_desc(self.x_label.as_str())
                .y_desc(self.y_label.as_str())
                .x_label_formatter(&xtick)
                .y_label_formatter(&ytick)
                .axis_desc_style((FONT, 24))
                .label_style((FONT, 19))
                .light_line_style(RGBColor(235, 235, 235))
                .bold_line_style(RGBColor(205, 205, 205))
                .draw()
                .map_err(|e| draw_err(e.to_string()))?;
            for (i, (name, l)) in lines.iter().enumerate() {
                let c = COLORS[i % COLORS.len()];
                let style = ShapeStyle {
                    color: c.to_rgba(),
                    filled: false,
                    stroke_width: 2,
                };
                if i == 0 {
                    chart
                        .draw_series(LineSeries::new(l.iter().copied(), style))
                        .map_err(|e| draw_err(e.to_string()))?
                        .label(name.as_str())
                        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], style));
                } else {
                    chart
                        .draw_series(std::iter::once(DashedPathElement::new(
                            l.iter().copied(),
                            8,
                            5,
                            style,
                        )))
                        .map_err(|e| draw_err(e.to_string()))?
                        .label(name.as_str())
                        .legend(move |(x, y)| {
                            DashedPathElement::new(vec![(x, y), (x + 24, y)], 8, 5, style)
                        });
                }
            }
            let black = ShapeStyle {
                color: BLACK.to_rgba(),
                filled: true,
                stroke_width: 1,
            };
            chart
                .draw_series(
                    pts.iter()
                        .filter(|p| p.2 > 0.0)
                        .map(|&(x, y, e)| ErrorBar::new_vertical(x, y - e, y, y + e, black, 6)),
                )
                .map_err(|e| draw_err(e.to_string()))?;
            chart
                .draw_series(pts.iter().map(|&(x, y, _)| Circle::new((x, y), 3, black)))
                .map_err(|e| draw_err(e.to_string()))?
                .label(self.points_label.as_str())
                .legend(move |(x, y)| Circle::new((x + 10, y), 3, black));
            chart
                .configure_series_labels()
                .position(corner.position())
                .label_font((FONT, 19))
                .background_style(WHITE.mix(0.85))
                .border_style(RGBColor(120, 120, 120))
                .draw()
                .map_err(|e| draw_err(e.to_string()))?;
            root.present().map_err(|e| draw_err(e.to_string()))?;
        }
        Ok(svg)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::plot::tests::legend_box;

    /// Points and a line that fill every corner (a decaying oscillation): the legend covers no
    /// point, no error bar and no stretch of the line (the review's discover overlays and the
    /// Fig. 5 panel had the legend, fixed in the lower right, over data; session 29).
    #[test]
    fn the_legend_covers_no_data() {
        let f =
            |t: f64| 150.0 + 40.0 * (-t / 400.0).exp() * (t / 30.0 * std::f64::consts::PI).cos();
        let o = Overlay {
            title: "osc-150: bubble 0".into(),
            x_label: "time (s)".into(),
            y_label: "radius (µm)".into(),
            points_label: "measured (± 2 sd)".into(),
            points: (0..=60)
                .map(|i| (10.0 * i as f64, f(10.0 * i as f64), 4.0))
                .collect(),
            lines: vec![
                (
                    "baseline".into(),
                    (0..=600).map(|t| (t as f64, f(t as f64) + 3.0)).collect(),
                ),
                (
                    "fitted".into(),
                    (0..=600).map(|t| (t as f64, f(t as f64))).collect(),
                ),
            ],
        };
        let svg = o.to_svg().unwrap();
        let (lx, ly, lw, lh) = legend_box(&svg);
        let inside = |x: f64, y: f64| x > lx && x < lx + lw && y > ly && y < ly + lh;
        // the points' circles and the lines' vertices, in px
        let mut drawn = 0;
        for c in svg.split("<circle").skip(1) {
            let tag = c.split('>').next().unwrap();
            let get = |k: &str| -> f64 {
                let key = format!(" {k}=\"");
                let i = tag.find(&key).unwrap() + key.len();
                tag[i..].split('"').next().unwrap().parse().unwrap()
            };
            let (cx, cy) = (get("cx"), get("cy"));
            // the legend's own glyph sits inside its box
            if inside(cx, cy) && !(cx < lx + 40.0) {
                panic!("a point at ({cx}, {cy}) under the legend ({lx}, {ly}) {lw}×{lh}");
            }
            drawn += 1;
        }
        assert!(drawn > 60, "{drawn} circles");
        for p in svg.split("<polyline").skip(1) {
            let tag = p.split('>').next().unwrap();
            let i = tag.find(" points=\"").unwrap() + " points=\"".len();
            let pts: Vec<(f64, f64)> = tag[i..]
                .split('"')
                .next()
                .unwrap()
                .split_whitespace()
                .map(|q| {
                    let (a, b) = q.split_once(',').unwrap();
                    (a.parse().unwrap(), b.parse().unwrap())
                })
                .collect();
            // lines and error bars, sampled along each segment (the legend's own glyphs sit
            // in its left 45 px)
            for w in pts.windows(2) {
                for k in 0..=10 {
                    let t = k as f64 / 10.0;
                    let (x, y) = (
                        w[0].0 + t * (w[1].0 - w[0].0),
                        w[0].1 + t * (w[1].1 - w[0].1),
                    );
                    assert!(
                        !inside(x, y) || x < lx + 45.0,
                        "a line or error bar at ({x}, {y}) under the legend ({lx}, {ly}) {lw}×{lh}"
                    );
                }
            }
        }
    }

    #[test]
    fn draws_points_bars_and_lines() {
        let o = Overlay {
            title: "t".into(),
            x_label: "time (s)".into(),
            y_label: "radius (µm)".into(),
            points_label: "measured".into(),
            points: vec![(0.0, 1.0, 0.1), (1.0, 2.0, 0.1), (2.0, f64::NAN, 0.1)],
            lines: vec![
                ("baseline".into(), vec![(0.0, 1.0), (2.0, 3.0)]),
                ("fitted".into(), vec![(0.0, 1.1), (2.0, 2.9)]),
            ],
        };
        let svg = o.to_svg().unwrap();
        assert!(svg.starts_with("<svg") && svg.contains("measured"));
        assert!(svg.contains("fitted") && svg.contains("baseline"));
        let empty = Overlay {
            points: vec![],
            lines: vec![],
            ..o
        };
        assert!(empty.to_svg().is_err());
    }
}
