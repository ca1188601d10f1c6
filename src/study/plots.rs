//! PNG plots of a study's outcomes against its varied parameters: one scatter per (outcome,
//! parameter) pair and an overview grid of them all.
//!
//! Drawn with plotters into an RGB buffer and encoded by `image`'s PNG encoder, the text set
//! from a compiled-in font (see [`canvas`]): no system font library, so the plots look the same,
//! byte for byte, on every machine.

mod axis;
mod canvas;
mod panel;

use std::collections::HashSet;
use std::fs;
use std::path::{Path, PathBuf};

use image::ImageEncoder;
use image::codecs::png::{CompressionType, FilterType, PngEncoder};
use plotters::prelude::*;

use axis::Axis;
use canvas::Canvas;
use panel::{Panel, Sizes};

/// One column of the study table for plotting: a varied parameter or an outcome.
pub struct PlotColumn {
    /// e.g. "blocks.rock.velocity[0]" or "runout"
    pub name: String,
    /// One per case, in case order; None: a failed case or not a number.
    pub values: Vec<Option<f64>>,
    /// Some: the values are indexes into these labels (a grid of strings such as
    /// ["alm", "penalty"]).
    pub categories: Option<Vec<String>>,
    /// A log-uniform parameter: draw its axis in log scale.
    pub log_scale: bool,
    /// "m", "N", "J", "" ... shown in the axis label.
    pub unit: String,
}

/// The size of a single plot.
pub const SINGLE: (u32, u32) = (800, 600);
/// The size of one overview panel at full scale; many panels are drawn smaller.
const PANEL: (u32, u32) = (400, 300);
/// The overview is drawn at most this wide and tall, down to [`MIN_PANEL_SCALE`]...
const OVERVIEW_MAX: u32 = 2400;
const MIN_PANEL_SCALE: f64 = 0.6;
/// ...and shows at most this many outcomes and parameters; every pair still has its own file.
pub const OVERVIEW_MAX_ROWS: usize = 12;
pub const OVERVIEW_MAX_COLS: usize = 12;
/// The height added to the overview for its heading.
const HEADER: u32 = 44;
/// A file-name part is cut to this many characters, so that a pair's name stays well inside
/// the 255 bytes a file name may have.
const MAX_SLUG: usize = 100;

/// Writes DIR/plots/<outcome>_vs_<parameter>.png for every (outcome, parameter) pair, and
/// DIR/plots/overview.png (all pairs in one grid: a row per outcome, a column per parameter);
/// returns the files written, in a fixed order: the pairs outcome by outcome, parameter by
/// parameter, then the overview.
///
/// Errors (one line each): columns of different lengths, a directory or file that cannot be
/// written.
pub fn write_plots(
    dir: &Path,
    parameters: &[PlotColumn],
    outcomes: &[PlotColumn],
) -> Result<Vec<PathBuf>, String> {
    check_lengths(parameters, outcomes)?;
    let plots = dir.join("plots");
    crate::files::create_dir_clearly(&plots).map_err(|e| {
        format!(
            "{}: cannot create the output directory: {e}",
            plots.display()
        )
    })?;
    let mut written = Vec::new();
    for (name, (o, p)) in pair_file_names(parameters, outcomes) {
        let png = single_plot(&parameters[p], &outcomes[o])?;
        written.push(write_png(&plots.join(name), &png)?);
    }
    let png = overview(parameters, outcomes)?;
    written.push(write_png(&plots.join("overview.png"), &png)?);
    Ok(written)
}

/// Every column has one value per case.
fn check_lengths(parameters: &[PlotColumn], outcomes: &[PlotColumn]) -> Result<(), String> {
    let mut columns = parameters.iter().chain(outcomes);
    let Some(first) = columns.next() else {
        return Ok(());
    };
    for column in columns {
        if column.values.len() != first.values.len() {
            return Err(format!(
                "study plots: column '{}' has {} values but '{}' has {}",
                column.name,
                column.values.len(),
                first.name,
                first.values.len()
            ));
        }
    }
    Ok(())
}

/// A file-name part from a column name: lower case, runs of other characters become '_', cut
/// to [`MAX_SLUG`] characters; "column" for a name with no letter or digit.
pub fn slug(name: &str) -> String {
    let mut s = String::new();
    for ch in name.chars() {
        if ch.is_ascii_alphanumeric() {
            s.push(ch.to_ascii_lowercase());
        } else if !s.ends_with('_') {
            s.push('_');
        }
    }
    let mut s = s.trim_matches('_').to_string();
    // ASCII only, so any byte index is a character boundary.
    s.truncate(MAX_SLUG);
    let s = s.trim_end_matches('_').to_string();
    if s.is_empty() { "column".into() } else { s }
}

/// The file name of each pair, (outcome index, parameter index), outcome by outcome. Two
/// names that slug alike ("a.b" and "a_b") get "_2", "_3"... on the later pair rather than
/// overwrite the first.
fn pair_file_names(
    parameters: &[PlotColumn],
    outcomes: &[PlotColumn],
) -> Vec<(String, (usize, usize))> {
    let mut used = HashSet::new();
    let mut names = Vec::new();
    for (o, outcome) in outcomes.iter().enumerate() {
        for (p, parameter) in parameters.iter().enumerate() {
            let stem = format!("{}_vs_{}", slug(&outcome.name), slug(&parameter.name));
            let mut name = format!("{stem}.png");
            let mut k = 2;
            while !used.insert(name.clone()) {
                name = format!("{stem}_{k}.png");
                k += 1;
            }
            names.push((name, (o, p)));
        }
    }
    names
}

/// A column's axis, with about `max_ticks` labelled ticks.
fn axis_of(column: &PlotColumn, max_ticks: usize) -> Axis {
    Axis::new(
        &column.values,
        column.log_scale,
        column.categories.as_deref(),
        max_ticks,
    )
}

/// "name (unit)", or the name alone without a unit.
fn describe(column: &PlotColumn) -> String {
    if column.unit.is_empty() {
        column.name.clone()
    } else {
        format!("{} ({})", column.name, column.unit)
    }
}

/// The positions of the cases where both columns have a value that can be drawn, and how many
/// cases there are in all.
fn pair_points(
    x: &PlotColumn,
    x_axis: &Axis,
    y: &PlotColumn,
    y_axis: &Axis,
) -> (Vec<(f64, f64)>, usize) {
    let points = x
        .values
        .iter()
        .zip(&y.values)
        .filter_map(|(&xv, &yv)| Some((x_axis.position(xv?)?, y_axis.position(yv?)?)))
        .collect();
    (points, x.values.len().min(y.values.len()))
}

/// "37 cases (3 failed cases not shown)".
fn count_note(shown: usize, cases: usize) -> String {
    let plural = |n: usize| if n == 1 { "case" } else { "cases" };
    let mut note = format!("{shown} {}", plural(shown));
    let hidden = cases.saturating_sub(shown);
    if hidden > 0 {
        note += &format!(" ({hidden} failed {} not shown)", plural(hidden));
    }
    note
}

/// The 800 × 600 plot of `outcome` against `parameter`, as PNG bytes.
fn single_plot(parameter: &PlotColumn, outcome: &PlotColumn) -> Result<Vec<u8>, String> {
    let x = axis_of(parameter, 8);
    let y = axis_of(outcome, 8);
    let (points, cases) = pair_points(parameter, &x, outcome, &y);
    let mut subtitle = count_note(points.len(), cases);
    if parameter.categories.is_some() && !points.is_empty() {
        subtitle += "; red bars: medians";
    }
    let panel = Panel {
        title: format!("{} vs {}", outcome.name, parameter.name),
        subtitle,
        x: &x,
        y: &y,
        x_desc: describe(parameter),
        y_desc: describe(outcome),
        points,
    };
    render(SINGLE, |root| panel::draw(root, &panel, Sizes::scaled(1.0)))
}

/// The overview's panel scale: full size while the grid fits in [`OVERVIEW_MAX`] pixels,
/// smaller for larger grids, but not below [`MIN_PANEL_SCALE`].
fn overview_scale(rows: usize, cols: usize) -> f64 {
    let fit_x = OVERVIEW_MAX as f64 / (cols.max(1) as f64 * PANEL.0 as f64);
    let fit_y = OVERVIEW_MAX as f64 / (rows.max(1) as f64 * PANEL.1 as f64);
    fit_x.min(fit_y).clamp(MIN_PANEL_SCALE, 1.0)
}

/// The overview's size in pixels for `rows` × `cols` panels.
pub fn overview_size(rows: usize, cols: usize) -> (u32, u32) {
    if rows == 0 || cols == 0 {
        return SINGLE;
    }
    let scale = overview_scale(rows, cols);
    let panel_w = (PANEL.0 as f64 * scale).round() as u32;
    let panel_h = (PANEL.1 as f64 * scale).round() as u32;
    (panel_w * cols as u32, panel_h * rows as u32 + HEADER)
}

/// The grid of every pair (up to [`OVERVIEW_MAX_ROWS`] × [`OVERVIEW_MAX_COLS`]), as PNG bytes.
fn overview(parameters: &[PlotColumn], outcomes: &[PlotColumn]) -> Result<Vec<u8>, String> {
    let shown_parameters = &parameters[..parameters.len().min(OVERVIEW_MAX_COLS)];
    let shown_outcomes = &outcomes[..outcomes.len().min(OVERVIEW_MAX_ROWS)];
    let (rows, cols) = (shown_outcomes.len(), shown_parameters.len());
    let cases = parameters
        .iter()
        .chain(outcomes)
        .map(|c| c.values.len())
        .next()
        .unwrap_or(0);
    let mut heading = format!(
        "Study: {} against {} ({})",
        plural(outcomes.len(), "outcome"),
        plural(parameters.len(), "parameter"),
        plural(cases, "case")
    );
    if rows < outcomes.len() || cols < parameters.len() {
        heading += &format!("; the first {rows} × {cols} shown, every pair has its own file");
    }
    let size = overview_size(rows, cols);
    if rows == 0 || cols == 0 {
        let empty = Axis::new(&[], false, None, 6);
        let panel = Panel {
            title: heading,
            subtitle: String::new(),
            x: &empty,
            y: &empty,
            x_desc: String::new(),
            y_desc: String::new(),
            points: Vec::new(),
        };
        return render(size, |root| panel::draw(root, &panel, Sizes::scaled(1.0)));
    }
    let scale = overview_scale(rows, cols);
    let sizes = Sizes::scaled(scale * 0.8);
    // About one tick label per 55 px across and per 45 px up.
    let ticks = |pixels: u32, per: f64| ((pixels as f64 * scale) / per).floor().max(3.0) as usize;
    let x_axes: Vec<Axis> = shown_parameters
        .iter()
        .map(|p| axis_of(p, ticks(PANEL.0, 55.0)))
        .collect();
    let y_axes: Vec<Axis> = shown_outcomes
        .iter()
        .map(|o| axis_of(o, ticks(PANEL.1, 45.0)))
        .collect();
    render(size, |root| {
        root.fill(&WHITE)
            .map_err(|e| format!("cannot draw a plot: {e}"))?;
        let style = (panel::FONT, Sizes::scaled(1.0).title)
            .into_font()
            .color(&BLACK);
        let grid = root
            .titled(&heading, style)
            .map_err(|e| format!("cannot draw a plot: {e}"))?;
        let cells = grid.split_evenly((rows, cols));
        for (cell, k) in cells.iter().zip(0..) {
            let (o, p) = (k / cols, k % cols);
            let (points, cases) = pair_points(
                &shown_parameters[p],
                &x_axes[p],
                &shown_outcomes[o],
                &y_axes[o],
            );
            let panel = Panel {
                title: format!("{} vs {}", shown_outcomes[o].name, shown_parameters[p].name),
                subtitle: count_note(points.len(), cases),
                x: &x_axes[p],
                y: &y_axes[o],
                x_desc: describe(&shown_parameters[p]),
                y_desc: describe(&shown_outcomes[o]),
                points,
            };
            panel::draw(cell, &panel, sizes)?;
        }
        Ok(())
    })
}

fn plural(n: usize, noun: &str) -> String {
    if n == 1 {
        format!("1 {noun}")
    } else {
        format!("{n} {noun}s")
    }
}

/// Draws with `draw` on a white `size` image and encodes it as PNG: with a fixed compression
/// and filter, the same picture gives the same bytes.
fn render(
    size: (u32, u32),
    draw: impl FnOnce(&DrawingArea<Canvas<'_>, plotters::coord::Shift>) -> Result<(), String>,
) -> Result<Vec<u8>, String> {
    let mut rgb = vec![255u8; size.0 as usize * size.1 as usize * 3];
    {
        let root = Canvas::new(&mut rgb, size)?.into_drawing_area();
        draw(&root)?;
        root.present()
            .map_err(|e| format!("cannot draw a plot: {e}"))?;
    }
    let mut png = Vec::new();
    PngEncoder::new_with_quality(&mut png, CompressionType::Default, FilterType::Adaptive)
        .write_image(&rgb, size.0, size.1, image::ExtendedColorType::Rgb8)
        .map_err(|e| format!("cannot encode a plot as PNG: {e}"))?;
    Ok(png)
}

fn write_png(path: &Path, png: &[u8]) -> Result<PathBuf, String> {
    fs::write(path, png).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    Ok(path.to_path_buf())
}

#[cfg(test)]
mod tests;
