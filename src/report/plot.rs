//! Plot models rendered to SVG strings with plotters (SVG backend only, no font files).
//!
//! Text without fonts: plotters is built without its `ttf`/`ab_glyph` features, so it sizes
//! text with a fixed estimate (an em of `size / 1.24²` and 0.7 em per character) and writes
//! every label as an SVG `<text>` element with `font-family="sans-serif"` and
//! `font-size = size / 1.24`; the viewer's own sans-serif font draws it. Label areas here are
//! sized with margin to spare for that estimate. Font sizes are chosen so that a 960 px wide
//! plot printed across a page gives tick labels of about 8 pt and titles of about 13 pt.
//!
//! Bad data never panics: non-finite points (and, on a log axis, points with y ≤ 0) are
//! skipped, breaking the line there; a plot with nothing left to draw is an error.
//! The output is deterministic: the same model gives byte-identical SVG.

use std::ops::Range;

use plotters::coord::combinators::LogCoord;
use plotters::coord::ranged1d::{DefaultFormatting, KeyPointHint, ValueFormatter};
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// Default plot size in px (width, height).
pub const DEFAULT_SIZE: (u32, u32) = (960, 600);

/// Line colours: the Okabe–Ito colour-blind-safe palette without its yellow (too pale on white),
/// plus grey. Source: Okabe & Ito (2008), "Color Universal Design".
const PALETTE: [RGBColor; 8] = [
    RGBColor(0, 114, 178),   // blue
    RGBColor(213, 94, 0),    // vermillion
    RGBColor(0, 158, 115),   // bluish green
    RGBColor(204, 121, 167), // reddish purple
    RGBColor(230, 159, 0),   // orange
    RGBColor(86, 180, 233),  // sky blue
    RGBColor(0, 0, 0),       // black
    RGBColor(120, 120, 120), // grey
];

const FONT: &str = "sans-serif";
/// Plotters font sizes (the SVG font-size is these / 1.24).
const TITLE_SIZE: f64 = 30.0;
const DESC_SIZE: f64 = 24.0;
const TICK_SIZE: f64 = 19.0;
const LEGEND_SIZE: f64 = 19.0;

/// Why a plot could not be drawn.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PlotError {
    /// Nothing finite (and positive, on a log axis) to draw.
    #[error("plot '{0}': no finite data to draw")]
    NoData(String),
    /// The model is inconsistent (e.g. a bar chart whose values do not match its categories).
    #[error("plot '{title}': {message}")]
    Invalid {
        /// Plot title.
        title: String,
        /// What is wrong.
        message: String,
    },
    /// The drawing backend failed.
    #[error("plot '{title}': drawing failed: {message}")]
    Draw {
        /// Plot title.
        title: String,
        /// Backend message.
        message: String,
    },
}

/// One named line of (x, y) points, in the units of the plot's axis labels.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend entry.
    pub name: String,
    /// Points in drawing order; non-finite ones break the line.
    pub points: Vec<(f64, f64)>,
    /// Draw against the secondary (right) y axis.
    pub secondary: bool,
}

impl Series {
    /// A series on the primary axis.
    pub fn new(name: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Series {
            name: name.into(),
            points,
            secondary: false,
        }
    }
    /// Move this series to the secondary (right) y axis.
    pub fn on_secondary(mut self) -> Self {
        self.secondary = true;
        self
    }
}

/// A line plot: several series, a legend, labelled axes (put units in the labels, e.g.
/// `"time (s)"`), optionally log axes, a depth axis increasing downward, and a linear
/// secondary y axis.
///
/// The legend goes in the corner of the plotting area that covers the fewest data points; if
/// every corner covers some, a linear primary y axis is extended upward (downward on a depth
/// axis) until the legend fits beside the data, and otherwise the legend is drawn outside,
/// right of the plot. A title too
/// long for the width is set smaller and, if need be, on two lines.
#[derive(Debug, Clone, PartialEq)]
pub struct LinePlot {
    /// Title above the plot.
    pub title: String,
    /// x-axis label with unit.
    pub x_label: String,
    /// Primary y-axis label with unit.
    pub y_label: String,
    /// The lines. With more than six, each also gets a marker shape; beyond seven, dashes.
    pub series: Vec<Series>,
    /// Logarithmic primary y axis (points with y ≤ 0 are skipped).
    pub log_y: bool,
    /// Logarithmic x axis (points with x ≤ 0 are skipped; no secondary axis).
    pub log_x: bool,
    /// The primary y axis increases downward (depth); linear axes only.
    pub y_down: bool,
    /// Every series gets its own dash pattern and marker shape, for curves that lie on top of
    /// each other (colour alone does not tell them apart).
    pub distinct: bool,
    /// Secondary (right) y-axis label with unit; required if any series is secondary.
    pub secondary_y_label: Option<String>,
    /// Size in px (width, height).
    pub size: (u32, u32),
}

impl LinePlot {
    /// An empty plot of [`DEFAULT_SIZE`] with the given title and axis labels.
    pub fn new(
        title: impl Into<String>,
        x_label: impl Into<String>,
        y_label: impl Into<String>,
    ) -> Self {
        LinePlot {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            series: Vec::new(),
            log_y: false,
            log_x: false,
            y_down: false,
            distinct: false,
            secondary_y_label: None,
            size: DEFAULT_SIZE,
        }
    }

    /// Add a series (builder style).
    pub fn with(mut self, s: Series) -> Self {
        self.series.push(s);
        self
    }

    /// Render to an SVG document.
    pub fn to_svg(&self) -> Result<String, PlotError> {
        let n = self.series.len();
        let invalid = |m: &str| PlotError::Invalid {
            title: self.title.clone(),
            message: m.into(),
        };
        let has_secondary = self.series.iter().any(|s| s.secondary);
        if has_secondary && self.secondary_y_label.is_none() {
            return Err(invalid(
                "a series is on the secondary axis but `secondary_y_label` is not set",
            ));
        }
        if self.log_x && has_secondary {
            return Err(invalid("a log x axis takes no secondary y axis"));
        }
        if self.y_down && self.log_y {
            return Err(invalid("a downward y axis must be linear"));
        }
        // a downward axis is drawn as −y and labelled +y
        let sign = |s: &Series| {
            if self.y_down && !s.secondary {
                -1.0
            } else {
                1.0
            }
        };
        let runs: Vec<Vec<Vec<(f64, f64)>>> = self
            .series
            .iter()
            .map(|s| {
                let k = sign(s);
                let pts: Vec<(f64, f64)> = s.points.iter().map(|&(x, y)| (x, k * y)).collect();
                finite_runs(&pts, self.log_y && !s.secondary, self.log_x)
            })
            .collect();
        let all = |secondary: bool| {
            self.series
                .iter()
                .zip(&runs)
                .filter(move |(s, _)| s.secondary == secondary)
                .flat_map(|(_, r)| r.iter().flatten().copied())
        };
        let x = bounds(all(false).chain(all(true)).map(|p| p.0))
            .ok_or_else(|| PlotError::NoData(self.title.clone()))?;
        let y = bounds(all(false).map(|p| p.1));
        let y2 = bounds(all(true).map(|p| p.1));
        let xr = if self.log_x {
            let (a, b) = decades(x);
            a..b
        } else {
            pad_linear(x, false)
        };
        let (w, h) = self.size;
        let draw_err = |e: String| PlotError::Draw {
            title: self.title.clone(),
            message: e,
        };
        let mut svg = String::new();
        {
            let root = SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area();
            root.fill(&WHITE).map_err(|e| draw_err(e.to_string()))?;
            let (below, title_h) =
                title_area(&root, &self.title).map_err(|e| draw_err(e.to_string()))?;
            let styles: Vec<LineLook> = (0..n).map(|i| LineLook::of(i, n, self.distinct)).collect();
            let y2r = has_secondary.then(|| pad_linear(y2.unwrap_or((0.0, 1.0)), true));
            let (lo, hi) = y.map(decades).unwrap_or((1.0, 10.0));
            let mut yr = pad_linear(y.unwrap_or((0.0, 1.0)), true);
            // Data in fractions of the plotting area, to keep the legend off the lines.
            let frac = |v: f64, r: &Range<f64>, log: bool| {
                if log {
                    (v.log10() - r.start.log10()) / (r.end.log10() - r.start.log10())
                } else {
                    (v - r.start) / (r.end - r.start)
                }
            };
            let fractions = |yr: &Range<f64>| {
                let mut pts = Vec::new();
                for (s, rs) in self.series.iter().zip(&runs) {
                    for run in rs {
                        let f: Vec<(f64, f64)> = run
                            .iter()
                            .map(|&(xv, yv)| {
                                let fy = match &y2r {
                                    Some(r2) if s.secondary => frac(yv, r2, false),
                                    _ if self.log_y => frac(yv, &(lo..hi), true),
                                    _ => frac(yv, yr, false),
                                };
                                (frac(xv, &xr, self.log_x), fy)
                            })
                            .collect();
                        densify(&f, &mut pts);
                    }
                }
                pts
            };
            let right_labels = if has_secondary { 110.0 } else { 0.0 };
            let plot_w = w as f64 - 36.0 - 110.0 - right_labels;
            let plot_h = h as f64 - title_h as f64 - 36.0 - 70.0;
            let (bw, bh) = legend_box_px(self.series.iter().map(|s| {
                if s.secondary {
                    s.name.chars().count() + " (right axis)".len()
                } else {
                    s.name.chars().count()
                }
            }));
            let (fw, fh) = (bw / plot_w.max(1.0), bh / plot_h.max(1.0));
            let (mut corner, covered) = Corner::emptiest(&fractions(&yr), fw, fh);
            let mut legend = LegendPlace::Inside(corner);
            if covered > 0 {
                if !self.log_y && !has_secondary && fh < 0.45 {
                    // room above the data (below it on a depth axis, not above the surface)
                    yr = room_for_legend(yr, fh, self.y_down);
                    corner = Corner::emptiest(&fractions(&yr), fw, fh).0;
                    legend = LegendPlace::Inside(corner);
                } else {
                    legend = LegendPlace::Right((right_labels + 14.0) as i32);
                }
            }
            let mut b = ChartBuilder::on(&below);
            b.margin(18)
                .margin_top(6)
                .x_label_area_size(70)
                .y_label_area_size(110)
                .right_y_label_area_size(right_labels as u32);
            if let LegendPlace::Right(_) = legend {
                b.margin_right(18 + bw as u32 + 14);
            }
            let lines = LinesToDraw {
                plot: self,
                runs: &runs,
                styles: &styles,
                y2: y2r,
                legend,
            };
            match (self.log_x, self.log_y) {
                (false, false) => {
                    let chart = b
                        .build_cartesian_2d(xr.clone(), yr)
                        .map_err(|e| draw_err(e.to_string()))?;
                    lines.draw(chart, xr).map_err(draw_err)?;
                }
                (false, true) => {
                    let chart = b
                        .build_cartesian_2d(xr.clone(), log_axis(lo..hi))
                        .map_err(|e| draw_err(e.to_string()))?;
                    lines.draw(chart, xr).map_err(draw_err)?;
                }
                (true, false) => {
                    let chart = b
                        .build_cartesian_2d(log_axis(xr.clone()), yr)
                        .map_err(|e| draw_err(e.to_string()))?;
                    lines.draw(chart, xr).map_err(draw_err)?;
                }
                (true, true) => {
                    let chart = b
                        .build_cartesian_2d(log_axis(xr.clone()), log_axis(lo..hi))
                        .map_err(|e| draw_err(e.to_string()))?;
                    lines.draw(chart, xr).map_err(draw_err)?;
                }
            }
            root.present().map_err(|e| draw_err(e.to_string()))?;
        }
        Ok(svg)
    }
}

/// Where the legend goes: a corner of the plotting area, or right of it (px beyond its
/// right edge).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum LegendPlace {
    Inside(Corner),
    Right(i32),
}

/// A drawing error of backend `DB`.
type AreaError<DB> = plotters::drawing::DrawingAreaErrorKind<<DB as DrawingBackend>::ErrorType>;

/// Width in px of `chars` characters of a sans-serif font drawn at plotters size `size`:
/// 0.62 of the SVG font-size (`size / 1.24`) per character, a little wider than the average
/// character of DejaVu Sans or Helvetica so that a title estimated to fit does fit.
fn text_px(chars: usize, size: f64) -> f64 {
    0.62 * size / 1.24 * chars as f64
}

/// Draw `title` centred at the top of `root`: at [`TITLE_SIZE`] if it fits the width, else
/// smaller (down to 0.8 of it), else wrapped onto two lines (a third and more are cut with
/// `…`). Returns the area below the title and the title's height in px.
pub(crate) fn title_area<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
) -> Result<(DrawingArea<DB, Shift>, u32), AreaError<DB>> {
    let (w, _) = root.dim_in_pixel();
    let avail = w as f64 - 2.0 * 18.0;
    let chars = title.chars().count();
    let fit = avail / text_px(1, TITLE_SIZE);
    let (size, lines) = if chars as f64 <= fit {
        (TITLE_SIZE, vec![title.to_string()])
    } else if chars as f64 <= avail / text_px(1, 0.8 * TITLE_SIZE) {
        (
            (avail / chars as f64 / text_px(1, 1.0)).floor(),
            vec![title.to_string()],
        )
    } else {
        let size = 0.8 * TITLE_SIZE;
        let per_line = (avail / text_px(1, size)).floor() as usize;
        let mut lines = wrap(title, per_line.max(8));
        if lines.len() > 2 {
            lines.truncate(2);
            let mut last: Vec<char> = lines[1].chars().collect();
            last.truncate(per_line.saturating_sub(1));
            lines[1] = last.into_iter().collect::<String>() + "…";
        }
        (size, lines)
    };
    let line_h = (size / 1.24 * 1.25).ceil() as i32;
    let style = TextStyle::from((FONT, size).into_font())
        .pos(Pos::new(HPos::Center, VPos::Top))
        .color(&BLACK);
    for (k, line) in lines.iter().enumerate() {
        root.draw(&Text::new(
            line.clone(),
            (w as i32 / 2, 12 + k as i32 * line_h),
            style.clone(),
        ))?;
    }
    let height = (12 + lines.len() as i32 * line_h + 6) as u32;
    let (_, below) = root.split_vertically(height);
    Ok((below, height))
}

/// A plot that has nothing to draw, as an SVG of [`DEFAULT_SIZE`]: its title and, in the middle,
/// why (e.g. a run in which no bubble ever formed). Written where a figure is promised, so that
/// a degenerate but valid run still gives every file, each saying what it holds.
pub fn message_svg(title: &str, message: &str) -> Result<String, PlotError> {
    let draw_err = |e: String| PlotError::Draw {
        title: title.to_string(),
        message: e,
    };
    let (w, h) = DEFAULT_SIZE;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| draw_err(e.to_string()))?;
        let (below, _) = title_area(&root, title).map_err(|e| draw_err(e.to_string()))?;
        let (bw, bh) = below.dim_in_pixel();
        let per_line = ((bw as f64 - 72.0) / text_px(1, DESC_SIZE)).floor() as usize;
        let lines = wrap(message, per_line.max(8));
        let line_h = (DESC_SIZE / 1.24 * 1.25).ceil() as i32;
        let top = bh as i32 / 2 - line_h * lines.len() as i32 / 2;
        let style = TextStyle::from((FONT, DESC_SIZE).into_font())
            .pos(Pos::new(HPos::Center, VPos::Top))
            .color(&BLACK);
        for (k, line) in lines.iter().enumerate() {
            below
                .draw(&Text::new(
                    line.clone(),
                    (bw as i32 / 2, top + k as i32 * line_h),
                    style.clone(),
                ))
                .map_err(|e| draw_err(e.to_string()))?;
        }
        root.present().map_err(|e| draw_err(e.to_string()))?;
    }
    Ok(svg)
}

impl LinePlot {
    /// [`LinePlot::to_svg`], or, when there is nothing finite to draw, [`message_svg`] with the
    /// plot's title and `message` (why it is empty).
    pub fn to_svg_or_message(&self, message: &str) -> Result<String, PlotError> {
        match self.to_svg() {
            Err(PlotError::NoData(_)) => message_svg(&self.title, message),
            r => r,
        }
    }
}

/// How one series looks: colour, dash pattern, marker.
#[derive(Debug, Clone, Copy)]
struct LineLook {
    color: RGBColor,
    /// 0 solid, 1 dashed, 2 dotted, 3 long dashes.
    dash: usize,
    /// Marker shape index, if markers are used.
    marker: Option<usize>,
}

impl LineLook {
    /// The look of series `i` of `n`; `distinct`: every series its own dash pattern and
    /// marker shape (filled circle, triangle, square, diamond, then hollow ones).
    fn of(i: usize, n: usize, distinct: bool) -> Self {
        if distinct {
            return LineLook {
                color: PALETTE[i % 7],
                dash: i % 4,
                marker: Some((2 * i) % 8 + (i / 4) % 2),
            };
        }
        LineLook {
            color: PALETTE[i % 7],
            dash: (i / 7) % 3,
            marker: if n > 6 { Some(i % 8) } else { None },
        }
    }
    fn style(&self) -> ShapeStyle {
        ShapeStyle {
            color: self.color.to_rgba(),
            filled: false,
            stroke_width: 2,
        }
    }
}

/// Marker shapes 0..8: filled/hollow circle, triangle, square, diamond, as one composed
/// element centred on `$c` (a macro because plotters does not export the composed type).
/// The shapes not wanted are transparent: the SVG backend writes nothing for them.
macro_rules! marker {
    ($c:expr, $k:expr, $color:expr) => {{
        let k: Option<usize> = $k;
        let shape = k.map(|k| (k / 2) % 4);
        let filled = k.is_some_and(|k| k % 2 == 0);
        let color: RGBColor = $color;
        let st = |which: usize| ShapeStyle {
            color: if shape == Some(which) {
                color.to_rgba()
            } else {
                TRANSPARENT
            },
            filled,
            stroke_width: 2,
        };
        EmptyElement::at($c)
            + Circle::new((0, 0), 5, st(0))
            + TriangleMarker::new((0, 0), 6, st(1))
            + Rectangle::new([(-4, -4), (4, 4)], st(2))
            + Polygon::new(vec![(0, -6), (6, 0), (0, 6), (-6, 0)], st(3))
    }};
}

/// Marker positions of one series: about ten, shifted per series so that they do not coincide.
fn marker_points(runs: &[Vec<(f64, f64)>], look: LineLook, index: usize) -> Vec<(f64, f64)> {
    if look.marker.is_none() {
        return Vec::new();
    }
    let pts: Vec<(f64, f64)> = runs.iter().flatten().copied().collect();
    if pts.is_empty() {
        return Vec::new();
    }
    let step = (pts.len() / 10).max(1);
    let offset = (index * step / 7) % step;
    pts.into_iter().skip(offset).step_by(step).collect()
}

/// Dash and gap lengths in px for a look (solid: one dash longer than any plot).
fn dash_pattern(dash: usize) -> (i32, i32) {
    match dash {
        0 => (1_000_000, 1),
        1 => (10, 6),
        2 => (3, 4),
        _ => (20, 6),
    }
}

/// Legend glyph for a look: a short line, dashed as drawn, and the marker.
macro_rules! legend_glyph {
    ($c:expr, $look:expr) => {{
        let look: LineLook = $look;
        let (d, g) = dash_pattern(look.dash);
        EmptyElement::at($c)
            + DashedPathElement::new(vec![(0, 0), (24, 0)], d.min(1000), g, look.style())
            + marker!((12, 0), look.marker, look.color)
    }};
}

type Line<C> = DashedPathElement<std::vec::IntoIter<C>, i32>;

/// The line elements of one series (one per run of drawable points).
fn series_lines(runs: &[Vec<(f64, f64)>], look: LineLook) -> Vec<Line<(f64, f64)>> {
    let (d, g) = dash_pattern(look.dash);
    runs.iter()
        .map(|run| DashedPathElement::new(run.clone(), d, g, look.style()))
        .collect()
}

/// Everything needed to draw the lines once the chart's coordinates exist.
struct LinesToDraw<'p> {
    plot: &'p LinePlot,
    runs: &'p [Vec<Vec<(f64, f64)>>],
    styles: &'p [LineLook],
    y2: Option<Range<f64>>,
    legend: LegendPlace,
}

/// A corner of the plotting area for the legend.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Corner {
    UpperRight,
    UpperLeft,
    LowerRight,
    LowerLeft,
}

impl Corner {
    pub(crate) fn position(self) -> SeriesLabelPosition {
        match self {
            Corner::UpperRight => SeriesLabelPosition::UpperRight,
            Corner::UpperLeft => SeriesLabelPosition::UpperLeft,
            Corner::LowerRight => SeriesLabelPosition::LowerRight,
            Corner::LowerLeft => SeriesLabelPosition::LowerLeft,
        }
    }

    /// The corner whose legend box (`bw` × `bh`, fractions of the plotting area) covers the
    /// fewest data points, and how many it covers; `pts` are in fractions of the plotting area
    /// (y up). Ties go to the upper right, then upper left, lower right, lower left.
    fn emptiest(pts: &[(f64, f64)], bw: f64, bh: f64) -> (Corner, usize) {
        let (bw, bh) = (bw.min(1.0), bh.min(1.0));
        [
            (Corner::UpperRight, 1.0 - bw, 1.0 - bh),
            (Corner::UpperLeft, 0.0, 1.0 - bh),
            (Corner::LowerRight, 1.0 - bw, 0.0),
            (Corner::LowerLeft, 0.0, 0.0),
        ]
        .into_iter()
        .map(|(c, x0, y0)| {
            let n = pts
                .iter()
                .filter(|(x, y)| *x >= x0 && *x <= x0 + bw && *y >= y0 && *y <= y0 + bh)
                .count();
            (n, c)
        })
        .fold(None::<(usize, Corner)>, |best, (n, c)| match best {
            Some((bn, _)) if bn <= n => best,
            _ => Some((n, c)),
        })
        .map(|(n, c)| (c, n))
        .unwrap_or((Corner::UpperRight, 0))
    }
}

/// The y range `yr` extended (upward, or downward on a depth axis) so that the data fill
/// 1 − `fh` − 2 % of the height and a legend `fh` of the plotting area high fits beside them.
pub(crate) fn room_for_legend(yr: Range<f64>, fh: f64, down: bool) -> Range<f64> {
    let span = (yr.end - yr.start) / (1.0 - fh - 0.02);
    if down {
        yr.end - span..yr.end
    } else {
        yr.start..yr.start + span
    }
}

/// A legend's corner for data `pts(yr)` (fractions of a plotting area of `plot` px, for the
/// y range `yr`) and a legend box of `legend` px: the corner that covers the fewest points;
/// when every corner covers some and the legend is under 45 % of the height, the y range is
/// extended upward first ([`room_for_legend`]). Returns the corner, the y range and how many
/// points the legend still covers.
pub(crate) fn place_legend(
    yr: Range<f64>,
    plot: (f64, f64),
    legend: (f64, f64),
    pts: impl Fn(&Range<f64>) -> Vec<(f64, f64)>,
) -> (Corner, Range<f64>, usize) {
    let (fw, fh) = (legend.0 / plot.0.max(1.0), legend.1 / plot.1.max(1.0));
    let (corner, covered) = Corner::emptiest(&pts(&yr), fw, fh);
    if covered == 0 || fh >= 0.45 {
        return (corner, yr, covered);
    }
    let yr = room_for_legend(yr, fh, false);
    let (corner, covered) = Corner::emptiest(&pts(&yr), fw, fh);
    (corner, yr, covered)
}

/// Legend box size in px for labels of `lengths` characters, by the same font-less estimate
/// plotters uses (0.7 em per character, em = size / 1.24²), with the glyph and margins.
pub(crate) fn legend_box_px(lengths: impl Iterator<Item = usize>) -> (f64, f64) {
    let mut n = 0usize;
    let mut chars = 0usize;
    for l in lengths {
        n += 1;
        chars = chars.max(l);
    }
    let em = LEGEND_SIZE / 1.24 / 1.24;
    (
        30.0 + 0.7 * em * chars as f64 + 30.0,
        n as f64 * (LEGEND_SIZE / 1.24 + 8.0) + 25.0,
    )
}

/// Points of a polyline in plot fractions, with extra points so that no gap exceeds 0.02.
pub(crate) fn densify(run: &[(f64, f64)], out: &mut Vec<(f64, f64)>) {
    for w in run.windows(2) {
        let (a, b) = (w[0], w[1]);
        let d = ((b.0 - a.0).abs()).max((b.1 - a.1).abs());
        let k = ((d / 0.02).ceil() as usize).clamp(1, 200);
        for j in 0..k {
            let f = j as f64 / k as f64;
            out.push((a.0 + f * (b.0 - a.0), a.1 + f * (b.1 - a.1)));
        }
    }
    if let Some(l) = run.last() {
        out.push(*l);
    }
}

impl LinesToDraw<'_> {
    fn draw<'a, DB, X, Y>(
        &self,
        mut chart: ChartContext<'a, DB, Cartesian2d<X, Y>>,
        xr: Range<f64>,
    ) -> Result<(), String>
    where
        DB: DrawingBackend + 'a,
        X: Ranged<ValueType = f64> + ValueFormatter<f64>,
        Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
    {
        let e = |e: plotters::drawing::DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
        let Some(y2) = self.y2.clone() else {
            self.mesh(&mut chart).map_err(e)?;
            for (i, s) in self.plot.series.iter().enumerate() {
                let look = self.styles[i];
                chart
                    .draw_series(series_lines(&self.runs[i], look))
                    .map_err(e)?
                    .label(s.name.as_str())
                    .legend(move |c| legend_glyph!(c, look));
                chart
                    .draw_series(
                        marker_points(&self.runs[i], look, i)
                            .into_iter()
                            .map(|p| marker!(p, look.marker, look.color)),
                    )
                    .map_err(e)?;
            }
            return legend(&mut chart, self.legend).map_err(e);
        };
        // The secondary coordinates take over the right label area, so they must exist
        // before the primary mesh is drawn (or it would label the right axis too).
        let span2 = y2.end - y2.start;
        let tick = move |v: &f64| fmt_tick_in(*v, span2);
        let mut dual = chart.set_secondary_coord(xr, y2);
        self.mesh(&mut dual).map_err(e)?;
        dual.configure_secondary_axes()
            .y_desc(self.plot.secondary_y_label.as_deref().unwrap_or(""))
            .y_label_formatter(&tick)
            .axis_desc_style((FONT, DESC_SIZE))
            .label_style((FONT, TICK_SIZE))
            .draw()
            .map_err(e)?;
        for (i, s) in self.plot.series.iter().enumerate() {
            let look = self.styles[i];
            let lines = series_lines(&self.runs[i], look);
            let markers = marker_points(&self.runs[i], look, i)
                .into_iter()
                .map(|p| marker!(p, look.marker, look.color));
            if s.secondary {
                dual.draw_secondary_series(markers).map_err(e)?;
            } else {
                dual.draw_series(markers).map_err(e)?;
            }
            let anno = if s.secondary {
                dual.draw_secondary_series(lines).map_err(e)?
            } else {
                dual.draw_series(lines).map_err(e)?
            };
            let name = if s.secondary {
                format!("{} (right axis)", s.name)
            } else {
                s.name.clone()
            };
            anno.label(name).legend(move |c| legend_glyph!(c, look));
        }
        legend(&mut dual, self.legend).map_err(e)
    }
}

impl LinesToDraw<'_> {
    fn mesh<'a, DB, X, Y>(
        &self,
        chart: &mut ChartContext<'a, DB, Cartesian2d<X, Y>>,
    ) -> Result<(), plotters::drawing::DrawingAreaErrorKind<DB::ErrorType>>
    where
        DB: DrawingBackend + 'a,
        X: Ranged<ValueType = f64> + ValueFormatter<f64>,
        Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
    {
        let (xs, ys) = (chart.x_range(), chart.y_range());
        let (xspan, yspan) = (xs.end - xs.start, ys.end - ys.start);
        let tick = |v: &f64| fmt_tick_in(*v, xspan);
        // a downward axis holds −y: label it +y
        let down = self.plot.y_down;
        let ytick = move |v: &f64| fmt_tick_in(if down { -*v } else { *v }, yspan);
        chart
            .configure_mesh()
            .x_desc(self.plot.x_label.as_str())
            .y_desc(self.plot.y_label.as_str())
            .x_label_formatter(&tick)
            .y_label_formatter(&ytick)
            .axis_desc_style((FONT, DESC_SIZE))
            .label_style((FONT, TICK_SIZE))
            .light_line_style(RGBColor(235, 235, 235))
            .bold_line_style(RGBColor(205, 205, 205))
            .draw()
    }
}

fn legend<'a, DB: DrawingBackend + 'a, CT: CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    place: LegendPlace,
) -> Result<(), plotters::drawing::DrawingAreaErrorKind<DB::ErrorType>> {
    let position = match place {
        LegendPlace::Inside(c) => c.position(),
        LegendPlace::Right(dx) => {
            let (w, _) = chart.plotting_area().dim_in_pixel();
            SeriesLabelPosition::Coordinate(w as i32 + dx, 0)
        }
    };
    chart
        .configure_series_labels()
        .position(position)
        .label_font((FONT, LEGEND_SIZE))
        .background_style(WHITE.mix(0.85))
        .border_style(RGBColor(120, 120, 120))
        .legend_area_size(30)
        .draw()
}

/// Split points into runs of drawable points (finite; y > 0 when `positive_y`, x > 0 when
/// `positive_x`).
fn finite_runs(points: &[(f64, f64)], positive_y: bool, positive_x: bool) -> Vec<Vec<(f64, f64)>> {
    let mut runs = Vec::new();
    let mut cur = Vec::new();
    for &(x, y) in points {
        if x.is_finite() && y.is_finite() && (!positive_y || y > 0.0) && (!positive_x || x > 0.0) {
            cur.push((x, y));
        } else if !cur.is_empty() {
            runs.push(std::mem::take(&mut cur));
        }
    }
    if !cur.is_empty() {
        runs.push(cur);
    }
    runs
}

/// (min, max) of an iterator of finite values, or None if empty.
fn bounds(it: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    it.fold(None, |acc, v| match acc {
        None => Some((v, v)),
        Some((a, b)) => Some((a.min(v), b.max(v))),
    })
}

/// A linear axis range: degenerate ranges widened; `pad` adds 5 % either side (not below 0
/// when the data are all ≥ 0, not above 0 when they are all ≤ 0).
fn pad_linear((lo, hi): (f64, f64), pad: bool) -> Range<f64> {
    let span = hi - lo;
    if span <= 0.0 || !span.is_finite() {
        let d = if lo == 0.0 { 1.0 } else { lo.abs() * 0.1 };
        return (lo - d)..(hi + d);
    }
    if !pad {
        return lo..hi;
    }
    let p = 0.05 * span;
    let l = if lo >= 0.0 && lo - p < 0.0 {
        0.0
    } else {
        lo - p
    };
    let u = if hi <= 0.0 && hi + p > 0.0 {
        0.0
    } else {
        hi + p
    };
    l..u
}

/// Whole decades enclosing positive (lo, hi), widened by 10⁻¹² so that plotters' log axis
/// (which labels 10^ceil(log10(start)), and log10(0.1) = −0.99999999999999989) labels the
/// first decade too.
fn decades((lo, hi): (f64, f64)) -> (f64, f64) {
    let a = 10f64.powf(lo.log10().floor());
    let mut b = 10f64.powf(hi.log10().ceil());
    if b <= a {
        b = a * 10.0;
    }
    (a * (1.0 - 1e-12), b * (1.0 + 1e-12))
}

/// [`fmt_tick`] on an axis spanning `span`: a tick within 10⁻⁹ of the span from 0 is the
/// axis's zero missed by the tick steps' rounding (e.g. −2.22e-16 where the steps cross 0),
/// labelled 0.
pub fn fmt_tick_in(v: f64, span: f64) -> String {
    if v.abs() <= 1e-9 * span.abs() {
        return "0".into();
    }
    fmt_tick(v)
}

/// A short tick label: up to four significant digits, exponent form outside 1e-3..1e5.
pub fn fmt_tick(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let a = v.abs();
    if !(1e-3..1e5).contains(&a) {
        let s = format!("{v:.3e}");
        let (m, e) = s.split_once('e').unwrap_or((&s, "0"));
        let m = m.trim_end_matches('0').trim_end_matches('.');
        return format!("{m}e{e}");
    }
    let digits = (4 - 1 - a.log10().floor() as i32).max(0) as usize;
    let s = format!("{v:.digits$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// Grouped bar chart: for each category (x axis), one bar per group (colour, legend), e.g.
/// criteria (categories) × schedules (groups). Non-finite values leave their bar out.
#[derive(Debug, Clone, PartialEq)]
pub struct BarChart {
    /// Title above the chart.
    pub title: String,
    /// x-axis label (what the categories are).
    pub x_label: String,
    /// y-axis label with unit.
    pub y_label: String,
    /// Category names along the x axis.
    pub categories: Vec<String>,
    /// Group names (legend).
    pub groups: Vec<String>,
    /// `values[category][group]`, in the y-axis unit.
    pub values: Vec<Vec<f64>>,
    /// A horizontal reference line (value, legend label), e.g. a limit of 1 when values are
    /// value/limit ratios.
    pub reference: Option<(f64, String)>,
    /// Size in px (width, height).
    pub size: (u32, u32),
}

/// A [`BarChart`] whose bars carry intervals, drawn as error bars (e.g. Sobol' indices with
/// their bootstrap 95 % intervals).
#[derive(Debug, Clone, PartialEq)]
pub struct IntervalBars {
    /// The bars (`chart.values` are the point estimates).
    pub chart: BarChart,
    /// `intervals[category][group]` = (lower, upper), in the y-axis unit; a non-finite end
    /// leaves that bar without its error bar.
    pub intervals: Vec<Vec<(f64, f64)>>,
}

impl IntervalBars {
    /// Render to an SVG document.
    pub fn to_svg(&self) -> Result<String, PlotError> {
        self.svg(false)
    }

    /// Render to an SVG document with a logarithmic y axis ([`BarChart::to_log_svg`]); an
    /// interval's lower end at or below the axis bottom is drawn from the bottom.
    pub fn to_log_svg(&self) -> Result<String, PlotError> {
        self.svg(true)
    }

    fn svg(&self, log: bool) -> Result<String, PlotError> {
        let shape_ok = self.intervals.len() == self.chart.values.len()
            && self
                .intervals
                .iter()
                .zip(&self.chart.values)
                .all(|(i, v)| i.len() == v.len());
        if !shape_ok {
            return Err(PlotError::Invalid {
                title: self.chart.title.clone(),
                message: "the intervals do not match the bars".into(),
            });
        }
        self.chart.svg(Some(&self.intervals), log)
    }
}

impl BarChart {
    /// Render to an SVG document.
    pub fn to_svg(&self) -> Result<String, PlotError> {
        self.svg(None, false)
    }

    /// Render to an SVG document with a logarithmic y axis, for sizes that span decades (e.g.
    /// |sensitivities| of 1e-4 beside 1): every bar rises from the axis bottom to its value.
    /// A value of exactly 0 has no place on a log axis: its bar is replaced by a "0" written
    /// on the axis bottom at its place. A negative value is refused (plot its size).
    pub fn to_log_svg(&self) -> Result<String, PlotError> {
        self.svg(None, true)
    }

    fn svg(&self, intervals: Option<&[Vec<(f64, f64)>]>, log: bool) -> Result<String, PlotError> {
        let invalid = |m: String| PlotError::Invalid {
            title: self.title.clone(),
            message: m,
        };
        if self.values.len() != self.categories.len() {
            return Err(invalid(format!(
                "{} value rows for {} categories",
                self.values.len(),
                self.categories.len()
            )));
        }
        if let Some((i, r)) = self
            .values
            .iter()
            .enumerate()
            .find(|(_, r)| r.len() != self.groups.len())
        {
            return Err(invalid(format!(
                "category '{}' has {} values for {} groups",
                self.categories[i],
                r.len(),
                self.groups.len()
            )));
        }
        let mut ys: Vec<f64> = self
            .values
            .iter()
            .flatten()
            .copied()
            .filter(|v| v.is_finite())
            .collect();
        if ys.is_empty() {
            return Err(PlotError::NoData(self.title.clone()));
        }
        if let Some((r, _)) = self.reference.as_ref().filter(|r| r.0.is_finite()) {
            ys.push(*r);
        }
        for iv in intervals.into_iter().flatten().flatten() {
            ys.extend([iv.0, iv.1].into_iter().filter(|v| v.is_finite()));
        }
        let yr = if log {
            // a bar's value must have a size; an interval may reach below 0 (drawn from the
            // axis bottom)
            if self.values.iter().flatten().any(|v| *v < 0.0) {
                return Err(invalid(
                    "a log axis cannot show a negative value: plot its size".into(),
                ));
            }
            let (lo, hi) = bounds(ys.iter().copied().filter(|v| *v > 0.0))
                .ok_or_else(|| PlotError::NoData(self.title.clone()))?;
            // a decade more below where the smallest bar would be under half a decade tall
            let (a, b) = decades((lo / 3.0, hi));
            a..b
        } else {
            ys.push(0.0);
            let (lo, hi) = bounds(ys.into_iter()).expect("non-empty");
            pad_linear((lo, hi), true)
        };
        let nc = self.categories.len();
        let ng = self.groups.len();
        let draw_err = |e: String| PlotError::Draw {
            title: self.title.clone(),
            message: e,
        };
        let (w, h) = self.size;
        let mut svg = String::new();
        {
            let root = SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area();
            root.fill(&WHITE).map_err(|e| draw_err(e.to_string()))?;
            self.draw(&root, nc, ng, yr, intervals, log)
                .map_err(|e| draw_err(format!("{e:?}")))?;
            root.present().map_err(|e| draw_err(e.to_string()))?;
        }
        Ok(svg)
    }

    /// Place the legend and draw the chart on a linear or (`log`) logarithmic y axis `yr`.
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        nc: usize,
        ng: usize,
        yr: Range<f64>,
        intervals: Option<&[Vec<(f64, f64)>]>,
        log: bool,
    ) -> Result<(), plotters::drawing::DrawingAreaErrorKind<DB::ErrorType>> {
        let (below, _) = title_area(root, &self.title)?;
        // The legend's corner, from the bars in fractions of the plotting area (each bar
        // sampled across its width, so that no corner hides a bar's edge), and room above the
        // bars when every corner covers some: the plotting area as the chart below lays it out.
        // On a log axis the placement works on log10 of the values, where the axis is linear.
        let to_axis = |v: f64| if log { v.log10() } else { v };
        let width = 0.8 / ng.max(1) as f64;
        let (aw, ah) = below.dim_in_pixel();
        let plot = (
            aw as f64 - 2.0 * 18.0 - 110.0,
            ah as f64 - 6.0 - 18.0 - 90.0,
        );
        let names = self
            .groups
            .iter()
            .map(String::as_str)
            .chain(self.reference.iter().map(|r| r.1.as_str()));
        let legend = legend_box_px(names.map(|n| n.chars().count()));
        let bars_in = |ar: &Range<f64>| {
            let y0 = if log {
                ar.start
            } else {
                ar.start.max(0.0).min(ar.end)
            };
            let fy = |v: f64| (v - ar.start) / (ar.end - ar.start);
            let drawn = |v: &f64| v.is_finite() && (!log || *v > 0.0);
            let mut pts = Vec::new();
            for (c, row) in self.values.iter().enumerate() {
                for (g, v) in row.iter().enumerate().filter(|(_, v)| drawn(v)) {
                    let v = to_axis(*v);
                    let left = c as f64 + 0.1 + g as f64 * width;
                    for k in 0..=4 {
                        let x = (left + width * 0.92 * k as f64 / 4.0) / nc as f64;
                        densify(&[(x, fy(y0)), (x, fy(v))], &mut pts);
                    }
                    densify(
                        &[
                            (left / nc as f64, fy(v)),
                            ((left + width * 0.92) / nc as f64, fy(v)),
                        ],
                        &mut pts,
                    );
                    if let Some((a, b)) = bar_interval(intervals, c, g) {
                        let x = (left + width * 0.46) / nc as f64;
                        let (a, b) = (to_axis(a.max(0.0)).max(ar.start), to_axis(b));
                        densify(&[(x, fy(a)), (x, fy(b))], &mut pts);
                    }
                }
            }
            if let Some((r, _)) = self
                .reference
                .as_ref()
                .filter(|r| r.0.is_finite() && (!log || r.0 > 0.0))
            {
                densify(&[(0.0, fy(to_axis(*r))), (1.0, fy(to_axis(*r)))], &mut pts);
            }
            pts
        };
        let ar = to_axis(yr.start)..to_axis(yr.end);
        let (corner, ar, _) = place_legend(ar, plot, legend, bars_in);
        let mut b = ChartBuilder::on(&below);
        b.margin(18)
            .margin_top(6)
            .x_label_area_size(90)
            .y_label_area_size(110);
        if log {
            let yr = 10f64.powf(ar.start)..10f64.powf(ar.end);
            let chart = b.build_cartesian_2d(0.0..nc as f64, log_axis(yr.clone()))?;
            self.draw_on(root, chart, yr.start, intervals, corner, true)
        } else {
            let y0 = ar.start.max(0.0).min(ar.end);
            let chart = b.build_cartesian_2d(0.0..nc as f64, ar)?;
            self.draw_on(root, chart, y0, intervals, corner, false)
        }
    }

    /// Draw the mesh, bars (from `y0`), error bars, reference line, category names and legend
    /// on `chart`, whatever its y axis (`log`: logarithmic).
    fn draw_on<'a, DB, Y>(
        &self,
        root: &DrawingArea<DB, Shift>,
        mut chart: ChartContext<'a, DB, Cartesian2d<RangedCoordf64, Y>>,
        y0: f64,
        intervals: Option<&[Vec<(f64, f64)>]>,
        corner: Corner,
        log: bool,
    ) -> Result<(), plotters::drawing::DrawingAreaErrorKind<DB::ErrorType>>
    where
        DB: DrawingBackend + 'a,
        Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
    {
        let (nc, ng) = (self.categories.len(), self.groups.len());
        let width = 0.8 / ng.max(1) as f64;
        let yr = chart.y_range();
        // a bar with a place on the axis (a log axis has none for 0)
        let drawn = |v: f64| v.is_finite() && (!log || v > 0.0);
        let tick = |v: &f64| fmt_tick_in(*v, yr.end - yr.start);
        chart
            .configure_mesh()
            .disable_x_mesh()
            .x_labels(0)
            .x_desc(self.x_label.as_str())
            .y_desc(self.y_label.as_str())
            .y_label_formatter(&tick)
            .axis_desc_style((FONT, DESC_SIZE))
            .label_style((FONT, TICK_SIZE))
            .light_line_style(RGBColor(235, 235, 235))
            .bold_line_style(RGBColor(205, 205, 205))
            .draw()?;
        for g in 0..ng {
            let color = PALETTE[g % PALETTE.len()];
            let bars: Vec<Rectangle<(f64, f64)>> = (0..nc)
                .filter(|&c| drawn(self.values[c][g]))
                .map(|c| {
                    let x = c as f64 + 0.1 + g as f64 * width;
                    Rectangle::new(
                        [(x, y0), (x + width * 0.92, self.values[c][g])],
                        color.filled(),
                    )
                })
                .collect();
            chart
                .draw_series(bars)?
                .label(self.groups[g].as_str())
                .legend(move |(x, y)| {
                    Rectangle::new([(x, y - 7), (x + 16, y + 7)], color.filled())
                });
        }
        if log {
            // a value of exactly 0: a "0" on the axis bottom where its bar would stand
            let style = TextStyle::from((FONT, TICK_SIZE).into_font())
                .pos(Pos::new(HPos::Center, VPos::Bottom))
                .color(&BLACK);
            let zeros: Vec<_> = (0..nc)
                .flat_map(|c| (0..ng).map(move |g| (c, g)))
                .filter(|&(c, g)| self.values[c][g] == 0.0)
                .map(|(c, g)| {
                    let x = c as f64 + 0.1 + g as f64 * width + width * 0.46;
                    Text::new("0", (x, y0), style.clone())
                })
                .collect();
            chart.draw_series(zeros)?;
        }
        if intervals.is_some() {
            let black = ShapeStyle {
                color: BLACK.to_rgba(),
                filled: true,
                stroke_width: 2,
            };
            let bars: Vec<_> = (0..nc)
                .flat_map(|c| (0..ng).map(move |g| (c, g)))
                .filter(|&(c, g)| drawn(self.values[c][g]))
                .filter_map(|(c, g)| {
                    let (a, b) = bar_interval(intervals, c, g)?;
                    let x = c as f64 + 0.1 + g as f64 * width + width * 0.46;
                    Some(ErrorBar::new_vertical(
                        x,
                        a.max(y0),
                        self.values[c][g],
                        b,
                        black,
                        10,
                    ))
                })
                .collect();
            chart.draw_series(bars)?;
        }
        if let Some((r, name)) = self.reference.as_ref().filter(|r| drawn(r.0)) {
            let st = ShapeStyle {
                color: BLACK.to_rgba(),
                filled: false,
                stroke_width: 2,
            };
            chart
                .draw_series(std::iter::once(DashedPathElement::new(
                    vec![(0.0, *r), (nc as f64, *r)],
                    10,
                    6,
                    st,
                )))?
                .label(name.as_str())
                .legend(move |(x, y)| {
                    EmptyElement::at((x, y))
                        + PathElement::new(vec![(0, 0), (9, 0)], st)
                        + PathElement::new(vec![(15, 0), (24, 0)], st)
                });
        }
        // Category names under their group of bars, on the root area (outside the plot).
        let style = TextStyle::from((FONT, TICK_SIZE).into_font())
            .pos(Pos::new(HPos::Center, VPos::Top))
            .color(&BLACK);
        let bottom = chart.backend_coord(&(0.0, yr.start));
        let slot_px = (chart.backend_coord(&(1.0, yr.start)).0
            - chart.backend_coord(&(0.0, yr.start)).0)
            .max(1) as usize;
        // The font-less width estimate: 0.7 em per character, em = size / 1.24².
        let char_px = 0.7 * TICK_SIZE / 1.24 / 1.24;
        let max_chars = ((slot_px as f64 / char_px) as usize).max(4);
        for (c, name) in self.categories.iter().enumerate() {
            let (px, _) = chart.backend_coord(&(c as f64 + 0.5, yr.start));
            for (k, line) in wrap(name, max_chars).iter().take(3).enumerate() {
                root.draw(&Text::new(
                    line.clone(),
                    (px, bottom.1 + 8 + k as i32 * (TICK_SIZE as i32)),
                    style.clone(),
                ))?;
            }
        }
        chart
            .configure_series_labels()
            .position(corner.position())
            .label_font((FONT, LEGEND_SIZE))
            .background_style(WHITE.mix(0.85))
            .border_style(RGBColor(120, 120, 120))
            .draw()?;
        Ok(())
    }
}

/// Bar (`c`, `g`)'s interval, where it has a finite one.
fn bar_interval(intervals: Option<&[Vec<(f64, f64)>]>, c: usize, g: usize) -> Option<(f64, f64)> {
    intervals
        .and_then(|iv| iv.get(c)?.get(g).copied())
        .filter(|(a, b)| a.is_finite() && b.is_finite())
}

/// A logarithmic axis whose ticks read distinctly. plotters' own log axis gives the next decade
/// twice where it fits in the range (its last light tick of a decade, v·(1 + 10·9/10), is the
/// next bold tick 10v: two "10" labels at one place, reports/paper/fig2a/fig2a-ratio-mu1.svg),
/// and two ticks could also round to one label; [`distinct_ticks`] keeps the first of each.
struct LogAxis {
    inner: LogCoord<f64>,
    span: f64,
}

/// A [`LogAxis`] over `r` (positive).
fn log_axis(r: Range<f64>) -> LogAxis {
    LogAxis {
        span: r.end - r.start,
        inner: r.log_scale().into(),
    }
}

impl Ranged for LogAxis {
    type FormatOption = DefaultFormatting;
    type ValueType = f64;
    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        self.inner.map(value, limit)
    }
    fn key_points<H: KeyPointHint>(&self, hint: H) -> Vec<f64> {
        distinct_ticks(self.inner.key_points(hint), self.span)
    }
    fn range(&self) -> Range<f64> {
        self.inner.range()
    }
}

/// `ticks` without those whose label (as the axis of `span` writes it, [`fmt_tick_in`])
/// repeats an earlier tick's.
fn distinct_ticks(ticks: Vec<f64>, span: f64) -> Vec<f64> {
    let mut seen = std::collections::HashSet::new();
    ticks
        .into_iter()
        .filter(|t| seen.insert(fmt_tick_in(*t, span)))
        .collect()
}

/// Wrap text at spaces (or hard-break long words) into lines of at most `n` characters.
fn wrap(s: &str, n: usize) -> Vec<String> {
    let mut lines = Vec::new();
    let mut cur = String::new();
    for word in s.split_whitespace() {
        let mut word: Vec<char> = word.chars().collect();
        while word.len() > n {
            if !cur.is_empty() {
                lines.push(std::mem::take(&mut cur));
            }
            lines.push(word[..n].iter().collect());
            word.drain(..n);
        }
        let word: String = word.into_iter().collect();
        if cur.is_empty() {
            cur = word;
        } else if cur.chars().count() + 1 + word.chars().count() <= n {
            cur.push(' ');
            cur.push_str(&word);
        } else {
            lines.push(std::mem::replace(&mut cur, word));
        }
    }
    if !cur.is_empty() {
        lines.push(cur);
    }
    lines
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// The `<rect>`s of an SVG as (x, y, width, height, attributes).
    pub(crate) fn svg_rects(svg: &str) -> Vec<(f64, f64, f64, f64, String)> {
        let num = |tag: &str, key: &str| -> f64 {
            let k = format!(" {key}=\"");
            let i = tag.find(&k).map(|i| i + k.len()).unwrap_or(0);
            tag[i..]
                .split('"')
                .next()
                .unwrap_or("")
                .parse()
                .unwrap_or(f64::NAN)
        };
        svg.split("<rect")
            .skip(1)
            .map(|r| {
                let tag = r.split('>').next().unwrap_or("");
                let (x, y) = (num(tag, "x"), num(tag, "y"));
                (x, y, num(tag, "width"), num(tag, "height"), tag.to_string())
            })
            .collect()
    }

    /// The legend's box: the translucent white background plotters draws under it.
    pub(crate) fn legend_box(svg: &str) -> (f64, f64, f64, f64) {
        let r = svg_rects(svg)
            .into_iter()
            .find(|r| r.4.contains("opacity=\"0.85\""))
            .expect("a legend box");
        (r.0, r.1, r.2, r.3)
    }

    /// A bar chart whose tall bars stand at both ends (every corner of the plotting area
    /// holds part of a bar): the legend goes above them, over no bar (the review's
    /// demo/criteria.svg had the legend over the GF 100/100 bar, session 29).
    #[test]
    fn a_bar_charts_legend_covers_no_bar() {
        let chart = BarChart {
            title: "t".into(),
            x_label: "criterion".into(),
            y_label: "value / limit".into(),
            categories: vec!["a".into(), "b".into(), "c".into()],
            groups: vec!["GF 30/85".into(), "GF 50/80".into(), "VPM-B +2".into()],
            values: vec![
                vec![1.5, 1.4, 1.55],
                vec![0.2, 0.3, 0.25],
                vec![1.5, 1.45, 1.3],
            ],
            reference: Some((1.0, "limit".into())),
            size: DEFAULT_SIZE,
        };
        let svg = chart.to_svg().unwrap();
        let (lx, ly, lw, lh) = legend_box(&svg);
        let bars: Vec<_> = svg_rects(&svg)
            .into_iter()
            .filter(|r| r.4.contains("stroke=\"none\"") && r.4.contains("opacity=\"1\""))
            .filter(|r| r.2 < 100.0) // the bars, not the background
            .filter(|r| !(r.0 >= lx && r.0 + r.2 <= lx + lw && r.1 >= ly && r.1 + r.3 <= ly + lh))
            .collect(); // (and not the legend's own swatches)
        assert_eq!(bars.len(), 9, "{bars:?}");
        for (x, y, w, h, _) in bars {
            let apart = x + w <= lx || lx + lw <= x || y + h <= ly || ly + lh <= y;
            assert!(
                apart,
                "bar at ({x}, {y}) {w}×{h} under the legend ({lx}, {ly}) {lw}×{lh}"
            );
        }
    }

    /// Interval bars: one error bar per bar with a finite interval, the y axis reaching the
    /// highest upper end, the wrong shape refused.
    #[test]
    fn interval_bars_draw_their_intervals() {
        let chart = BarChart {
            title: "Sobol' indices".into(),
            x_label: "parameter".into(),
            y_label: "index".into(),
            categories: vec!["μ (Pa)".into(), "D factor".into()],
            groups: vec!["S1".into(), "ST".into()],
            values: vec![vec![0.8, 1.2], vec![0.01, 0.03]],
            reference: None,
            size: DEFAULT_SIZE,
        };
        let bars = IntervalBars {
            chart: chart.clone(),
            intervals: vec![
                vec![(0.5, 1.1), (0.7, 2.1)],
                vec![(0.0, 0.02), (f64::NAN, 0.05)],
            ],
        };
        let svg = bars.to_svg().unwrap();
        // plotters draws an error bar as three 2-px black lines (the stem and two caps)
        let lines: Vec<&str> = svg
            .split("<line")
            .skip(1)
            .filter(|l| l.contains("stroke=\"#000000\" stroke-width=\"2\""))
            .collect();
        assert_eq!(lines.len(), 9, "three finite intervals: {lines:?}");
        // the highest cap (2.1) lies inside the plotting area, below the title
        let top = lines
            .iter()
            .filter_map(|l| {
                let i = l.find(" y1=\"")? + 5;
                l[i..].split('"').next()?.parse::<f64>().ok()
            })
            .fold(f64::INFINITY, f64::min);
        assert!(top > 40.0 && top < 600.0, "top cap at y = {top}");
        let wrong = IntervalBars {
            chart,
            intervals: vec![vec![(0.0, 1.0)]],
        };
        assert!(wrong.to_svg().is_err());
    }

    #[test]
    fn a_tick_at_the_axis_zero_reads_0() {
        // a tick step's rounding misses 0 by 2.2e-16 on an axis spanning 1.6
        assert_eq!(fmt_tick_in(-2.220446049250313e-16, 1.6), "0");
        assert_eq!(fmt_tick_in(0.2, 1.6), "0.2");
        // a small value on an axis of small values keeps its digits
        assert_eq!(fmt_tick_in(2e-15, 1e-14), "2e-15");
    }

    /// The labels of a log axis's ticks over `r`, as the axes here write them, for several
    /// tick budgets (plotters asks with the mesh's label count and with its light lines').
    fn log_labels(r: Range<f64>) -> Vec<Vec<String>> {
        let axis = log_axis(r.clone());
        [3usize, 5, 10, 20, 50]
            .iter()
            .map(|n| {
                axis.key_points(*n)
                    .iter()
                    .map(|v| fmt_tick_in(*v, r.end - r.start))
                    .collect()
            })
            .collect()
    }

    /// No log axis writes one label twice: plotters' own gives the next decade twice over a
    /// decade (its light tick 1·(1 + 9) and the bold 10: fig2a-ratio-mu1.svg had two "10"
    /// at one place); the axes here keep the first of each label. Ranges as given and
    /// widened to whole decades, as the line plots draw them.
    #[test]
    fn a_log_axis_writes_no_label_twice() {
        // the cause, in plotters itself
        let raw: LogCoord<f64> = (1.0..10.0 * (1.0 + 1e-12)).log_scale().into();
        let tens = raw
            .key_points(10usize)
            .iter()
            .filter(|v| fmt_tick(**v) == "10")
            .count();
        assert_eq!(
            tens, 2,
            "plotters no longer repeats the decade: simplify LogAxis"
        );
        for (lo, hi) in [
            (8.0, 12.0),
            (9.99, 10.01),
            (1.0, 1000.0),
            (1.0, 10.0),
            (0.2, 7e5),
        ] {
            let (a, b) = decades((lo, hi));
            for r in [lo..hi, a..b] {
                for labels in log_labels(r.clone()) {
                    let mut seen = std::collections::HashSet::new();
                    for l in &labels {
                        assert!(seen.insert(l.clone()), "{r:?}: '{l}' twice in {labels:?}");
                    }
                }
            }
        }
        // and the decade itself is kept
        let labels = log_labels(decades((1.2, 9.0)).0..decades((1.2, 9.0)).1);
        assert!(labels[2].contains(&"10".to_string()), "{labels:?}");
    }

    /// The rendered plot: a log y axis over one decade (fig2a's ratio panels) writes "10" once.
    #[test]
    fn a_log_plot_writes_its_top_decade_once() {
        let mut p = LinePlot::new("ratio", "R0 (m)", "R_B/R0");
        p.log_x = true;
        p.log_y = true;
        let svg = p
            .with(Series::new("a", vec![(1e-7, 1.2), (1e-3, 4.6)]))
            .to_svg()
            .unwrap();
        let texts: Vec<&str> = svg
            .split("<text")
            .skip(1)
            .map(|t| {
                t.split('>')
                    .nth(1)
                    .unwrap_or("")
                    .split('<')
                    .next()
                    .unwrap_or("")
                    .trim()
            })
            .collect();
        assert_eq!(texts.iter().filter(|t| **t == "10").count(), 1, "{texts:?}");
    }

    /// A log bar chart shows values five decades apart, each bar at least half a decade above
    /// the axis bottom (the smallest, 1.1e-3, just above a decade's 1e-3, gets one more), and
    /// writes "0" for a value of exactly 0 (no bar); a negative value is refused.
    #[test]
    fn a_log_bar_chart_shows_every_size() {
        let chart = BarChart {
            title: "sensitivities".into(),
            x_label: "parameter".into(),
            y_label: "|normalised sensitivity| (log)".into(),
            categories: vec!["γ".into(), "L_N2".into(), "μ".into(), "D".into()],
            groups: vec!["R_max".into(), "t_max".into()],
            values: vec![
                vec![3.56e-4, 0.0],
                vec![0.00198, 0.0011],
                vec![1.41, 0.287],
                vec![0.0165, 0.294],
            ],
            reference: None,
            size: (960, 480),
        };
        let svg = chart.to_log_svg().unwrap();
        let bars: Vec<_> = svg_rects(&svg)
            .into_iter()
            .filter(|r| r.4.contains("stroke=\"none\"") && r.4.contains("opacity=\"1\""))
            .filter(|r| r.2 < 100.0 && r.2 > 20.0)
            .collect();
        // seven bars (the 0 has none), the smallest still tens of px tall
        assert_eq!(bars.len(), 7, "{bars:?}");
        let shortest = bars.iter().map(|b| b.3).fold(f64::INFINITY, f64::min);
        assert!(shortest > 20.0, "shortest bar {shortest} px");
        let zeros = svg
            .split("<text")
            .skip(1)
            .filter(|t| t.split('>').nth(1).unwrap_or("").split('<').next() == Some("\n0\n"))
            .count();
        assert_eq!(zeros, 1, "one value of 0, one mark");
        let mut neg = chart.clone();
        neg.values[0][0] = -3.56e-4;
        assert!(matches!(neg.to_log_svg(), Err(PlotError::Invalid { .. })));
    }

    #[test]
    fn tick_labels_are_short() {
        assert_eq!(fmt_tick(0.0), "0");
        assert_eq!(fmt_tick(1.5), "1.5");
        assert_eq!(fmt_tick(250.0), "250");
        assert_eq!(fmt_tick(12345.0), "12345");
        assert_eq!(fmt_tick(2e-9), "2e-9");
        assert_eq!(fmt_tick(1.25e6), "1.25e6");
        assert_eq!(fmt_tick(-0.5), "-0.5");
    }

    #[test]
    fn runs_split_at_bad_points() {
        let r = finite_runs(
            &[
                (0.0, 1.0),
                (1.0, f64::NAN),
                (2.0, 2.0),
                (3.0, -1.0),
                (4.0, 3.0),
            ],
            true,
            false,
        );
        assert_eq!(
            r,
            vec![vec![(0.0, 1.0)], vec![(2.0, 2.0)], vec![(4.0, 3.0)]]
        );
    }

    #[test]
    fn wraps_long_names() {
        assert_eq!(wrap("peak total volume", 10), vec!["peak total", "volume"]);
        assert_eq!(wrap("abcdefghijkl", 5), vec!["abcde", "fghij", "kl"]);
    }
}
