//! The dive-profile figure of `plan --plot`: depth against runtime (depth increasing
//! downward) with the ceiling, over a tissue heat map, one row per compartment (fastest at
//! the top), coloured by the fraction of the M-value gradient each compartment is at — the
//! two panels of DecoTengu's `dt-plot` and Subsurface's planner in one SVG.
//!
//! Nothing here knows about algorithms: callers pass the samples (time, depth, ceiling, one
//! value per compartment). Same input, byte-identical SVG; non-finite samples are an error.

use plotters::element::DashedPathElement;
use plotters::prelude::*;

use super::plot::{fmt_tick, title_area, PlotError};

const FONT: &str = "sans-serif";

/// One sample of the figure.
#[derive(Debug, Clone, PartialEq)]
pub struct ProfileSample {
    /// Runtime, min.
    pub time_min: f64,
    /// Depth, m.
    pub depth_m: f64,
    /// Ceiling, m.
    pub ceiling_m: f64,
    /// One value per compartment: fraction of the M-value gradient (negative: on-gassing).
    pub rows: Vec<f64>,
}

/// The figure's labels.
#[derive(Debug, Clone)]
pub struct ProfileFigure {
    /// Title.
    pub title: String,
    /// Label of the ceiling line, e.g. `ceiling (ZH-L16C, GF 85 %)`.
    pub ceiling_label: String,
    /// Label of the heat map's rows, e.g. `ZH-L16C compartment`.
    pub rows_label: String,
    /// Samples in time order.
    pub samples: Vec<ProfileSample>,
}

/// Heat-map colour of a gradient fraction `g`: blues for on-gassing (darker the more
/// undersaturated, saturating at −1), green → yellow → red from 0 to the M-value (1), purple
/// beyond it.
pub fn heat_colour(g: f64) -> RGBColor {
    let lerp = |a: (f64, f64, f64), b: (f64, f64, f64), t: f64| {
        let t = t.clamp(0.0, 1.0);
        RGBColor(
            (a.0 + (b.0 - a.0) * t).round() as u8,
            (a.1 + (b.1 - a.1) * t).round() as u8,
            (a.2 + (b.2 - a.2) * t).round() as u8,
        )
    };
    if g < 0.0 {
        lerp((198.0, 219.0, 239.0), (8.0, 48.0, 107.0), -g)
    } else if g <= 0.5 {
        lerp((161.0, 217.0, 155.0), (254.0, 224.0, 139.0), g / 0.5)
    } else if g <= 1.0 {
        lerp((254.0, 224.0, 139.0), (215.0, 48.0, 39.0), (g - 0.5) / 0.5)
    } else {
        RGBColor(118, 42, 131)
    }
}

impl ProfileFigure {
    /// Render to an SVG string (960 × 760 px).
    pub fn to_svg(&self) -> Result<String, PlotError> {
        let err = |m: String| PlotError::Draw {
            title: self.title.clone(),
            message: m,
        };
        let s = &self.samples;
        let nrows = s.first().map_or(0, |x| x.rows.len());
        if s.len() < 2 || nrows == 0 {
            return Err(PlotError::NoData(self.title.clone()));
        }
        if s.iter().any(|x| {
            !(x.time_min.is_finite() && x.depth_m.is_finite() && x.ceiling_m.is_finite())
                || x.rows.len() != nrows
                || x.rows.iter().any(|v| !v.is_finite())
        }) {
            return Err(PlotError::Invalid {
                title: self.title.clone(),
                message: "a sample is not finite or has the wrong number of rows".into(),
            });
        }
        let t_end = s.last().unwrap().time_min.max(1e-9);
        let d_max = s
            .iter()
            .map(|x| x.depth_m.max(x.ceiling_m))
            .fold(0.0, f64::max)
            .max(1.0)
            * 1.08;
        let mut svg = String::new();
        {
            let root = SVGBackend::with_string(&mut svg, (960, 760)).into_drawing_area();
            root.fill(&WHITE).map_err(|e| err(e.to_string()))?;
            // a long title (a dive log's name) is set smaller or on two lines, never clipped
            let (root, _) = title_area(&root, &self.title).map_err(|e| err(e.to_string()))?;
            let (top, bottom) = root.split_vertically(420);
            let tick = |v: &f64| fmt_tick(*v);
            let depth_tick = |v: &f64| fmt_tick(-*v);
            // upper panel: depth downward as negative y, labelled positive
            let mut c = ChartBuilder::on(&top)
                .margin(14)
                .x_label_area_size(50)
                .y_label_area_size(90)
                .build_cartesian_2d(0.0..t_end, -d_max..0.0)
                .map_err(|e| err(e.to_string()))?;
            c.configure_mesh()
                .y_desc("depth, m")
                .x_label_formatter(&tick)
                .y_label_formatter(&depth_tick)
                .axis_desc_style((FONT, 24.0))
                .label_style((FONT, 19.0))
                .light_line_style(RGBColor(235, 235, 235))
                .bold_line_style(RGBColor(205, 205, 205))
                .draw()
                .map_err(|e| err(e.to_string()))?;
            let blue = RGBColor(0, 114, 178);
            let red = RGBColor(213, 94, 0);
            c.draw_series(LineSeries::new(
                s.iter().map(|x| (x.time_min, -x.depth_m)),
                blue.stroke_width(3),
            ))
            .map_err(|e| err(e.to_string()))?
            .label("depth")
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 24, y)], blue.stroke_width(3))
            });
            c.draw_series(s.windows(2).map(|w| {
                DashedPathElement::new(
                    vec![
                        (w[0].time_min, -w[0].ceiling_m),
                        (w[1].time_min, -w[1].ceiling_m),
                    ],
                    6,
                    4,
                    red.stroke_width(2),
                )
            }))
            .map_err(|e| err(e.to_string()))?
            .label(self.ceiling_label.as_str())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], red.stroke_width(2)));
            c.configure_series_labels()
                .position(SeriesLabelPosition::LowerRight)
                .label_font((FONT, 19.0))
                .background_style(WHITE.mix(0.85))
                .border_style(RGBColor(160, 160, 160))
                .draw()
                .map_err(|e| err(e.to_string()))?;
            // lower panel: heat map, compartment 1 at the top
            let n = nrows as f64;
            let mut h = ChartBuilder::on(&bottom)
                .margin(14)
                .x_label_area_size(64)
                .y_label_area_size(90)
                .build_cartesian_2d(0.0..t_end, 0.0..n)
                .map_err(|e| err(e.to_string()))?;
            let row_tick = |v: &f64| {
                let r = nrows as f64 - v.floor();
                if (1.0..=n).contains(&r) && (r as usize == 1 || (r as usize).is_multiple_of(4)) {
                    format!("{}", r as usize)
                } else {
                    String::new()
                }
            };
            h.configure_mesh()
                .disable_mesh()
                .x_desc(
                    "runtime, min   (blue: on-gassing; green→red: 0→100 % of the M-value gradient; purple: beyond)",
                )
                .y_desc(self.rows_label.as_str())
                .y_labels(nrows + 1)
                .x_label_formatter(&tick)
                .y_label_formatter(&row_tick)
                .axis_desc_style((FONT, 24.0))
                .label_style((FONT, 19.0))
                .draw()
                .map_err(|e| err(e.to_string()))?;
            h.draw_series(s.windows(2).flat_map(|w| {
                (0..nrows).map(move |r| {
                    let y0 = n - 1.0 - r as f64;
                    Rectangle::new(
                        [(w[0].time_min, y0), (w[1].time_min, y0 + 1.0)],
                        heat_colour(w[1].rows[r]).filled(),
                    )
                })
            }))
            .map_err(|e| err(e.to_string()))?;
            root.present().map_err(|e| err(e.to_string()))?;
        }
        Ok(svg)
    }
}
