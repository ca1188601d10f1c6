//! Live diagnostic plots over the run: maximum penetration, contacts by state, iterations per
//! step, penalties and kinetic energy.

use egui::{Color32, RichText};
use egui_plot::{HLine, Legend, Line, LineStyle, Plot, PlotPoints};

use super::widgets::{ACCENT, color32, num};
use crate::params::{Method, SolverParams};
use crate::render::mesh::{LOCK_SRGB, OPEN_SRGB, SLIDE_SRGB};
use crate::render::overlay::STAGE_AMBER;
use crate::viewer::sim::StepRecord;
use crate::viewer::state::UiState;

/// Points per plotted line: about one per pixel of a plot's width. Each point becomes several
/// anti-aliased triangles, and on a software rasterizer triangles, not pixels, dominate the cost
/// of the plots.
pub(super) const PLOT_POINTS: usize = 240;

pub fn show(ui: &mut egui::Ui, state: &UiState) {
    let recs = &state.history.records;
    let dn_max = state
        .frame
        .as_ref()
        .map(|f| f.max_step_penetration)
        .unwrap_or(0.0);
    let params = state.frame.as_ref().map(|f| &f.params);
    let young = state.scene_file.young;
    let h = (ui.available_height() - 22.0).max(60.0);
    ui.add_space(2.0);
    let stage_tolerance = state
        .frame
        .as_ref()
        .and_then(|f| f.snapshot.equilibrium)
        .map(|r| r.tolerance);
    ui.columns(5, |cols| {
        if recs.last().is_some_and(|r| r.stage.is_some()) {
            stage_residual(&mut cols[0], recs, stage_tolerance, h);
        } else {
            penetration(&mut cols[0], recs, params, dn_max, h);
        }
        contacts(&mut cols[1], recs, h);
        iterations(&mut cols[2], recs, h);
        penalties(&mut cols[3], recs, params, young, h);
        kinetic_energy(&mut cols[4], recs, h);
    });
}

/// Downsamples `records` to at most `PLOT_POINTS` buckets, applying `reduce` to each bucket's
/// values (max for peaks so a spike is never hidden).
pub(super) fn series(
    records: &[StepRecord],
    value: impl Fn(&StepRecord) -> f64,
    reduce: fn(f64, f64) -> f64,
) -> Vec<[f64; 2]> {
    thinned(records, |r| r.time, value, reduce)
}

/// At most [`PLOT_POINTS`] points of `items` in order: each point stands for a run of
/// consecutive items, at the last one's time, with their finite values reduced by `reduce`.
pub(super) fn thinned<T>(
    items: &[T],
    time: impl Fn(&T) -> f64,
    value: impl Fn(&T) -> f64,
    reduce: fn(f64, f64) -> f64,
) -> Vec<[f64; 2]> {
    let n = items.len();
    if n == 0 {
        return Vec::new();
    }
    let per = n.div_ceil(PLOT_POINTS).max(1);
    items
        .chunks(per)
        .filter_map(|c| {
            let v = c
                .iter()
                .map(&value)
                .filter(|v| v.is_finite())
                .reduce(reduce)?;
            Some([time(&c[c.len() - 1]), v])
        })
        .collect()
}

pub(super) fn plot_title(ui: &mut egui::Ui, title: &str, tip: &str) {
    ui.label(RichText::new(title).strong().size(13.0))
        .on_hover_text(tip);
}

/// A dashed grey line marking a limit (a tolerance or a cap) on a plot.
fn limit_line(name: &str, y: f64) -> HLine {
    HLine::new(name, y)
        .style(LineStyle::dashed_loose())
        .color(Color32::from_gray(110))
}

/// The shortest time axis a plot shows, s. An equilibrium stage's records all stand at t = 0, and
/// egui_plot widens a range of zero width by an amount that follows the values plotted: the
/// contacts' plot, counting thousands, spanned −1000 s to 1000 s while the others spanned a
/// fraction of a second.
const MIN_TIME_SPAN: f64 = 0.01;

/// The time axis of a plot whose points run over `span`, (first, last) in s (None without
/// points): that range, its end moved forward to make it at least [`MIN_TIME_SPAN`] wide.
pub(super) fn time_axis(span: Option<(f64, f64)>) -> Option<(f64, f64)> {
    let (first, last) = span?;
    Some((first, last.max(first + MIN_TIME_SPAN)))
}

/// The times of the first and last of `records` (kept in the order of their steps, so these are
/// the least and the greatest).
pub(super) fn record_span(records: &[StepRecord]) -> Option<(f64, f64)> {
    Some((records.first()?.time, records.last()?.time))
}

/// A plot of the panel's style over the time axis [`time_axis`] makes of `span`.
pub(super) fn small_plot<'a>(id: &str, height: f32, span: Option<(f64, f64)>) -> Plot<'a> {
    let mut plot = Plot::new(id);
    if let Some((from, to)) = time_axis(span) {
        plot = plot.include_x(from).include_x(to);
    }
    plot.height(height)
        .allow_zoom(false)
        .allow_drag(false)
        .allow_scroll(false)
        .allow_boxed_zoom(false)
        .allow_double_click_reset(false)
        .show_x(true)
        .show_y(true)
        .y_axis_min_width(34.0)
        .legend(Legend::default().background_alpha(0.6))
        .link_cursor(egui::Id::unique("plots_x"), [true, false])
        .x_axis_formatter(|m, _| format!("{} s", num(m.value)))
}

/// Maximum penetration, mm, with the ALM target ε1·d_n,max.
fn penetration(
    ui: &mut egui::Ui,
    recs: &[StepRecord],
    params: Option<&SolverParams>,
    dn_max: f64,
    h: f32,
) {
    plot_title(
        ui,
        "Max penetration (mm)",
        "Largest penetration over closed contacts after each step. The dashed line is the \
         ALM target ε1·d_n,max (P23).",
    );
    let pen = series(recs, |r| r.max_penetration * 1e3, f64::max);
    small_plot("pen", h, record_span(recs)).show(ui, |p| {
        p.line(
            Line::new("max d_n", PlotPoints::from(pen))
                .color(ACCENT)
                .width(1.5),
        );
        if let Some(pr) = params
            && pr.method == Method::Alm
            && dn_max > 0.0
        {
            p.hline(limit_line("ε1·d_n,max", pr.contact.eps1 * dn_max * 1e3));
        }
    });
}

/// The initial equilibrium stage's R_max after each of its static steps, as log10, by step
/// (at most [`PLOT_POINTS`] points, each the largest of its run of steps).
fn stage_series(records: &[StepRecord]) -> Vec<[f64; 2]> {
    let stage: Vec<(u64, f64)> = records
        .iter()
        .filter_map(|r| r.stage)
        .filter(|&(_, residual)| residual > 0.0)
        .collect();
    thinned(&stage, |s| s.0 as f64, |s| s.1.log10(), f64::max)
}

/// While the initial equilibrium stage runs, R_max by stage step (log scale) with its tolerance
/// dashed, in place of the penetration: time stands at 0 then, so the plots over time show
/// nothing of the stage's progress.
fn stage_residual(ui: &mut egui::Ui, recs: &[StepRecord], tolerance: Option<f64>, h: f32) {
    plot_title(
        ui,
        "Equilibrium stage: R_max",
        "Largest unbalanced force of a free block over the forces it carries, after each \
         static step of the initial equilibrium stage (log scale). The stage ends when it falls \
         below the tolerance (dashed), or at its step limit.",
    );
    let points = stage_series(recs);
    let last = points.last().map_or(0.0, |p| p[0]);
    small_plot("stage", h, None)
        .include_x(0.0)
        .include_x(last.max(10.0))
        .x_axis_formatter(|m, _| format!("step {}", num(m.value)))
        .y_axis_formatter(|m, _| num(10f64.powf(m.value)))
        .show(ui, |p| {
            p.line(
                Line::new("R_max", PlotPoints::from(points))
                    .color(STAGE_AMBER)
                    .width(1.5),
            );
            if let Some(tol) = tolerance.filter(|t| *t > 0.0) {
                p.hline(limit_line("tolerance", tol.log10()));
            }
        });
}

/// Contacts by state.
fn contacts(ui: &mut egui::Ui, recs: &[StepRecord], h: f32) {
    plot_title(
        ui,
        "Contacts",
        "Closed contacts in the lock and slide states, and detected but open ones.",
    );
    let lock = series(recs, |r| r.lock as f64, f64::max);
    let slide = series(recs, |r| r.slide as f64, f64::max);
    let open = series(recs, |r| r.open as f64, f64::max);
    small_plot("contacts", h, record_span(recs)).show(ui, |p| {
        p.line(Line::new("lock", PlotPoints::from(lock)).color(color32(LOCK_SRGB)));
        p.line(Line::new("slide", PlotPoints::from(slide)).color(color32(SLIDE_SRGB)));
        p.line(Line::new("open", PlotPoints::from(open)).color(color32(OPEN_SRGB)));
    });
}

/// Iterations per step.
fn iterations(ui: &mut egui::Ui, recs: &[StepRecord], h: f32) {
    plot_title(
        ui,
        "Iterations / step",
        "Linear solves per step (ALM iterations summed over the open–close passes; one \
         per pass in penalty mode) and open–close passes, in the accepted attempt.",
    );
    let alm = series(recs, |r| r.alm_iterations as f64, f64::max);
    let oc = series(recs, |r| r.open_close_iterations as f64, f64::max);
    let cuts = series(recs, |r| r.cuts as f64, f64::max);
    small_plot("iters", h, record_span(recs)).show(ui, |p| {
        p.line(Line::new("ALM solves", PlotPoints::from(alm)).color(ACCENT));
        p.line(
            Line::new("open–close", PlotPoints::from(oc))
                .color(Color32::from_rgb(0x2F, 0x5F, 0xB0)),
        );
        p.line(
            Line::new("Δt cuts", PlotPoints::from(cuts))
                .color(Color32::from_gray(120))
                .style(LineStyle::dotted_dense()),
        );
    });
}

/// Penalties, as log10(p_n / E).
fn penalties(
    ui: &mut egui::Ui,
    recs: &[StepRecord],
    params: Option<&SolverParams>,
    young: f64,
    h: f32,
) {
    plot_title(
        ui,
        "Penalty p_n / E",
        "Smallest, mean and largest normal penalty over the closed contacts (log scale). \
         ALM raises p_n where convergence is slow, up to γ·E (dashed).",
    );
    let lg = move |v: f64| (v / young).log10();
    let pmax = series(recs, |r| lg(r.penalty_max), f64::max);
    let pmean = series(recs, |r| lg(r.penalty_mean), f64::max);
    let pmin = series(recs, |r| lg(r.penalty_min), f64::min);
    small_plot("penalty", h, record_span(recs))
        .y_axis_formatter(|m, _| num(10f64.powf(m.value)))
        .show(ui, |p| {
            p.line(Line::new("max", PlotPoints::from(pmax)).color(color32(SLIDE_SRGB)));
            p.line(Line::new("mean", PlotPoints::from(pmean)).color(ACCENT));
            p.line(Line::new("min", PlotPoints::from(pmin)).color(color32(LOCK_SRGB)));
            if let Some(pr) = params
                && pr.method == Method::Alm
            {
                p.hline(limit_line("γ·E", pr.contact.gamma.log10()));
            }
        });
}

/// Kinetic energy, kJ.
fn kinetic_energy(ui: &mut egui::Ui, recs: &[StepRecord], h: f32) {
    plot_title(
        ui,
        "Kinetic energy (kJ)",
        "Kinetic energy 1/2 v^T M v summed over all blocks after each step.",
    );
    let ke = series(recs, |r| r.kinetic_energy * 1e-3, f64::max);
    small_plot("ke", h, record_span(recs)).show(ui, |p| {
        p.line(
            Line::new("E_k", PlotPoints::from(ke))
                .color(Color32::from_rgb(0x6A, 0x3D, 0x9A))
                .fill(0.0)
                .fill_alpha(0.15),
        );
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::viewer::state::tests::rec;

    #[test]
    fn downsampling_keeps_spikes() {
        let mut r: Vec<StepRecord> = (0..10_000).map(|k| rec(k, 1.0)).collect();
        r[5_001].max_penetration = 50.0;
        let s = series(&r, |r| r.max_penetration, f64::max);
        assert!(s.len() <= PLOT_POINTS);
        assert!(s.iter().any(|p| p[1] == 50.0), "the spike survives");
        // Non-finite values (no contacts) are skipped, not plotted as zero.
        let s = series(&r, |r| r.penalty_min, f64::min);
        assert!(s.is_empty());
    }

    #[test]
    fn the_stage_is_plotted_by_step_and_the_run_is_left_out() {
        let mut r: Vec<StepRecord> = (0..6).map(|k| rec(k, 1.0)).collect();
        for (k, rec) in r.iter_mut().enumerate().take(4) {
            rec.stage = Some((k as u64 + 1, 10f64.powi(-(k as i32))));
        }
        // A stage step with R_max 0 has no logarithm: left out, not plotted at −∞.
        r[3].stage = Some((4, 0.0));
        let s = stage_series(&r);
        assert_eq!(s, vec![[1.0, 0.0], [2.0, -1.0], [3.0, -2.0]]);
    }

    #[test]
    fn a_time_axis_of_zero_width_is_widened_forward() {
        // An equilibrium stage: every record at t = 0.
        let stage: Vec<StepRecord> = (0..5)
            .map(|k| rec(k, 1.0))
            .map(|mut r| {
                r.time = 0.0;
                r
            })
            .collect();
        assert_eq!(time_axis(record_span(&stage)), Some((0.0, MIN_TIME_SPAN)));
        // A run's own range is kept where it is wider, and nothing is set without records.
        assert_eq!(time_axis(Some((0.5, 2.0))), Some((0.5, 2.0)));
        assert_eq!(
            time_axis(Some((1.0, 1.004))),
            Some((1.0, 1.0 + MIN_TIME_SPAN))
        );
        assert_eq!(time_axis(record_span(&[])), None);
    }
}
