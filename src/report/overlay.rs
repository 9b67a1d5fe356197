//! Measured points with error bars against simulated lines (the fit and discover reports):
//! plotters' SVG backend, the same fonts, palette and conventions as [`super::plot`]
//! (no font files, deterministic output, non-finite values skipped, nothing to draw an error).

use super::plot::{fmt_tick, PlotError};
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
            let mut chart = ChartBuilder::on(&root)
                .caption(&self.title, (FONT, 30))
                .margin(18)
                .x_label_area_size(70)
                .y_label_area_size(110)
                .build_cartesian_2d(pad(x0, x1), pad(y0, y1))
                .map_err(|e| draw_err(e.to_string()))?;
            let tick = |v: &f64| fmt_tick(*v);
            chart
                .configure_mesh()
                .x_desc(self.x_label.as_str())
                .y_desc(self.y_label.as_str())
                .x_label_formatter(&tick)
                .y_label_formatter(&tick)
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
                .position(SeriesLabelPosition::LowerRight)
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
