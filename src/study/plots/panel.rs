//! One scatter panel drawn with plotters: a title, a subtitle, the axes of two [`Axis`] and the
//! points; the single plots and each cell of the overview are such a panel at different sizes.

use std::ops::Range;

use plotters::coord::Shift;
use plotters::coord::ranged1d::{DefaultFormatting, KeyPointHint, Ranged};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::axis::{Axis, Scale};
use super::canvas::Canvas;

/// The family named in every text style; [`Canvas`] sets all text in its one font whatever the
/// family, and this is plotters' default, so a style left at its default reads the same.
pub const FONT: &str = "sans-serif";

const POINT: RGBColor = RGBColor(31, 119, 180);
const MEDIAN: RGBColor = RGBColor(214, 39, 40);
const GRID: RGBColor = RGBColor(215, 215, 215);
const MINOR_GRID: RGBColor = RGBColor(238, 238, 238);
const GREY_TEXT: RGBColor = RGBColor(90, 90, 90);

/// Sizes in pixels: of the title, the other text, the tick labels, the points' radius and the
/// margin round the chart.
#[derive(Clone, Copy, Debug)]
pub struct Sizes {
    pub title: f64,
    pub text: f64,
    pub tick: f64,
    pub point: i32,
    pub margin: u32,
}

impl Sizes {
    /// The sizes for a panel `scale` times as large as the 800 × 600 single plot, with text
    /// kept legible in the small panels of a large overview.
    pub fn scaled(scale: f64) -> Sizes {
        Sizes {
            title: (20.0 * scale).max(12.0),
            text: (16.0 * scale).max(11.0),
            tick: (14.0 * scale).max(10.0),
            point: ((4.5 * scale).round() as i32).max(2),
            margin: ((14.0 * scale).round() as u32).max(6),
        }
    }
}

/// What one panel shows: points are positions on the two axes (see [`Axis::position`]).
pub struct Panel<'a> {
    pub title: String,
    pub subtitle: String,
    pub x: &'a Axis,
    pub y: &'a Axis,
    pub x_desc: String,
    pub y_desc: String,
    pub points: Vec<(f64, f64)>,
}

fn font(size: f64) -> TextStyle<'static> {
    (FONT, size).into_font().color(&BLACK)
}

fn fail(e: impl std::fmt::Display) -> String {
    format!("cannot draw a plot: {e}")
}

/// The widest of `labels` in pixels, in `style`.
fn widest(area: &DrawingArea<Canvas<'_>, Shift>, labels: &[String], style: &TextStyle) -> u32 {
    labels
        .iter()
        .filter_map(|l| area.estimate_text_size(l, style).ok())
        .map(|(w, _)| w)
        .max()
        .unwrap_or(0)
}

/// An [`Axis`] as a plotters coordinate: linear in positions, with the axis' own ticks (the
/// mesh's light lines at the minor ticks) and the label formatter given to the mesh.
struct Coord<'a>(&'a Axis);

impl Ranged for Coord<'_> {
    type ValueType = f64;
    type FormatOption = DefaultFormatting;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        // Halves, so that an axis over ±f64::MAX has a finite length.
        let fraction = (value / 2.0 - self.0.lo / 2.0) / (self.0.hi / 2.0 - self.0.lo / 2.0);
        let pixels = f64::from(limit.1 - limit.0) * fraction;
        // Far outside the axis (never a drawn point, which the axis range holds) the pixel is
        // clamped rather than wrapped.
        limit.0 + pixels.round().clamp(-1e6, 1e6) as i32
    }

    fn key_points<Hint: KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        if hint.weight().allow_light_points() {
            self.0.minor.clone()
        } else {
            self.0.ticks.clone()
        }
    }

    fn range(&self) -> Range<f64> {
        self.0.lo..self.0.hi
    }
}

/// `text` cut at its end, the cut marked with an ellipsis, to at most `room` pixels wide in
/// `style`: long column names in the small panels of an overview.
fn fit(area: &DrawingArea<Canvas<'_>, Shift>, text: &str, style: &TextStyle, room: u32) -> String {
    let fits = |t: &str| {
        area.estimate_text_size(t, style)
            .is_ok_and(|(w, _)| w <= room)
    };
    if fits(text) {
        return text.to_string();
    }
    let chars: Vec<char> = text.chars().collect();
    (0..chars.len())
        .rev()
        .map(|n| chars[..n].iter().collect::<String>() + "…")
        .find(|t| fits(t))
        .unwrap_or_default()
}

/// Draws `panel` filling `area`.
pub fn draw(
    area: &DrawingArea<Canvas<'_>, Shift>,
    panel: &Panel,
    sizes: Sizes,
) -> Result<(), String> {
    area.fill(&WHITE).map_err(fail)?;
    let (width, _) = area.dim_in_pixel();
    let room = width.saturating_sub(2 * sizes.margin);
    let title = fit(area, &panel.title, &font(sizes.title), room);
    let mut area = area.titled(&title, font(sizes.title)).map_err(fail)?;
    if !panel.subtitle.is_empty() {
        let style = font(sizes.text).color(&GREY_TEXT);
        let subtitle = fit(&area, &panel.subtitle, &style, room);
        area = area.titled(&subtitle, style).map_err(fail)?;
    }
    let tick_style = font(sizes.tick);
    let y_labels: Vec<String> = panel.y.ticks.iter().map(|&t| panel.y.label(t)).collect();
    // Room for the widest tick label, the gap to it and the rotated axis description.
    let y_area = widest(&area, &y_labels, &tick_style) + (sizes.text * 2.2) as u32;
    let x_area = (sizes.tick * 1.6 + sizes.text * 1.8) as u32;
    let mut chart = ChartBuilder::on(&area)
        .margin(sizes.margin)
        .margin_top(sizes.margin / 2)
        .x_label_area_size(x_area)
        .y_label_area_size(y_area)
        .build_cartesian_2d(Coord(panel.x), Coord(panel.y))
        .map_err(fail)?;
    let (plot_width, plot_height) = chart.plotting_area().dim_in_pixel();
    let x_desc = fit(&area, &panel.x_desc, &font(sizes.text), plot_width);
    let y_desc = fit(&area, &panel.y_desc, &font(sizes.text), plot_height);
    let x_label = |v: &f64| panel.x.label(*v);
    let y_label = |v: &f64| panel.y.label(*v);
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .x_label_formatter(&x_label)
        .y_label_formatter(&y_label)
        .label_style(tick_style.clone())
        .axis_desc_style(font(sizes.text))
        .bold_line_style(GRID)
        .light_line_style(MINOR_GRID)
        .draw()
        .map_err(fail)?;
    // The medians first, so that the points at the median stay visible on top of them.
    if matches!(panel.x.scale, Scale::Categories(_)) {
        let bars = medians(&panel.points).into_iter().map(|(x, m)| {
            PathElement::new(vec![(x - 0.3, m), (x + 0.3, m)], MEDIAN.stroke_width(2))
        });
        chart.draw_series(bars).map_err(fail)?;
    }
    let style = POINT.mix(0.6).filled();
    chart
        .draw_series(
            panel
                .points
                .iter()
                .map(|&p| Circle::new(p, sizes.point, style)),
        )
        .map_err(fail)?;
    if panel.points.is_empty() {
        let centre = (
            (panel.x.lo + panel.x.hi) / 2.0,
            (panel.y.lo + panel.y.hi) / 2.0,
        );
        let style = font(sizes.title)
            .color(&GREY_TEXT)
            .pos(Pos::new(HPos::Center, VPos::Center));
        chart
            .plotting_area()
            .draw(&Text::new("no data", centre, style))
            .map_err(fail)?;
    }
    Ok(())
}

/// The median y of the points at each x, in increasing x (the categories of a categorical x
/// axis, where the points sit at whole-number positions).
pub fn medians(points: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let mut sorted = points.to_vec();
    sorted.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    sorted
        .chunk_by(|a, b| a.0 == b.0)
        .map(|group| {
            let n = group.len();
            let median = if n % 2 == 1 {
                group[n / 2].1
            } else {
                (group[n / 2 - 1].1 + group[n / 2].1) / 2.0
            };
            (group[0].0, median)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    #[test]
    fn medians_per_category() {
        let points = [
            (1.0, 5.0),
            (0.0, 3.0),
            (1.0, 1.0),
            (0.0, 1.0),
            (0.0, 2.0),
            (1.0, 2.0),
            (1.0, 9.0),
        ];
        assert_eq!(super::medians(&points), vec![(0.0, 2.0), (1.0, 3.5)]);
        assert_eq!(super::medians(&[]), Vec::<(f64, f64)>::new());
    }
}
