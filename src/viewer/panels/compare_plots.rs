//! The plots of a comparison: run A's and run B's maximum penetration, kinetic energy, ALM
//! solves per step and largest penalty over one time axis, and at the common times the panes
//! showed the largest block displacement difference and the difference of total contact force
//! between A and B.

use egui::Color32;
use egui_plot::{Line, LineStyle, PlotPoints};

use super::plots::{plot_title, record_span, series, small_plot, thinned};
use super::widgets::ACCENT;
use crate::viewer::sim::StepRecord;
use crate::viewer::state::UiState;

/// Run B's colour (A's is the accent).
const B_COLOR: Color32 = Color32::from_rgb(0x2F, 0x5F, 0xB0);

pub fn show(ui: &mut egui::Ui, state: &UiState) {
    let Some(c) = state.compare.as_deref() else {
        return;
    };
    let (a, b) = (&state.history.records[..], &c.history_b.records[..]);
    let h = (ui.available_height() - 22.0).max(60.0);
    ui.add_space(2.0);
    ui.columns(6, |cols| {
        overlay(
            &mut cols[0],
            ("Max penetration (mm)", "pen_ab"),
            "Largest penetration over closed contacts after each step, run A and run B.",
            (a, b),
            |r| r.max_penetration * 1e3,
            h,
        );
        overlay(
            &mut cols[1],
            ("Kinetic energy (kJ)", "ke_ab"),
            "Kinetic energy 1/2 v^T M v summed over all blocks after each step, run A and run B.",
            (a, b),
            |r| r.kinetic_energy * 1e-3,
            h,
        );
        overlay(
            &mut cols[2],
            ("ALM solves / step", "solves_ab"),
            "Linear solves of each step (all ALM iterations of all open–close passes; one per \
             pass for the penalty method), run A and run B.",
            (a, b),
            |r| f64::from(r.alm_iterations),
            h,
        );
        overlay(
            &mut cols[3],
            ("Largest p_n (log10 N/m)", "pn_ab"),
            "The largest normal penalty over the closed contacts after each step, run A and run \
             B: the ALM raises it (P21) where penetration converges slowly.",
            (a, b),
            |r| r.penalty_max.log10(),
            h,
        );
        difference(
            &mut cols[4],
            (
                "|u_A − u_B| max (mm)",
                "diff_ab",
                "The largest distance between a block's centroid in run A and in run B at the \
                 same simulated time (the runs start from the same scene, so their \
                 displacements differ by exactly this).",
            ),
            &c.difference,
            |p| p[1] * 1e3,
            h,
        );
        difference(
            &mut cols[5],
            (
                "|ΣF_A − ΣF_B| (kN)",
                "force_ab",
                "The difference of the total contact force of run A and run B at the same \
                 simulated time (each total: the sum over closed contacts of the force's \
                 magnitude).",
            ),
            &c.difference,
            |p| p[2] * 1e-3,
            h,
        );
    });
}

/// One quantity of both runs on one plot: A solid in the accent colour, B dashed in blue.
fn overlay(
    ui: &mut egui::Ui,
    (title, id): (&str, &str),
    tip: &str,
    (a, b): (&[StepRecord], &[StepRecord]),
    value: impl Fn(&StepRecord) -> f64 + Copy,
    h: f32,
) {
    plot_title(ui, title, tip);
    let (sa, sb) = (series(a, value, f64::max), series(b, value, f64::max));
    let span = match (record_span(a), record_span(b)) {
        (Some((a0, a1)), Some((b0, b1))) => Some((a0.min(b0), a1.max(b1))),
        (one, other) => one.or(other),
    };
    small_plot(id, h, span).show(ui, |p| {
        p.line(
            Line::new("A", PlotPoints::from(sa))
                .color(ACCENT)
                .width(1.5),
        );
        p.line(
            Line::new("B", PlotPoints::from(sb))
                .color(B_COLOR)
                .width(1.5)
                .style(LineStyle::dashed_dense()),
        );
    });
}

/// One difference between A and B at the common times shown (`value` of each point).
fn difference(
    ui: &mut egui::Ui,
    (title, id, tip): (&str, &str, &str),
    points: &[[f64; 3]],
    value: impl Fn(&[f64; 3]) -> f64,
    h: f32,
) {
    plot_title(ui, title, tip);
    let pts = thinned(points, |p| p[0], value, f64::max);
    let span = points.first().zip(points.last()).map(|(f, l)| (f[0], l[0]));
    small_plot(id, h, span).show(ui, |p| {
        p.line(
            Line::new("A − B", PlotPoints::from(pts))
                .color(Color32::from_rgb(0x6A, 0x3D, 0x9A))
                .fill(0.0)
                .fill_alpha(0.15),
        );
    });
}
