//! The plots of a comparison: run A's and run B's maximum penetration, kinetic energy and
//! contacts over one time axis, and the largest block displacement difference between A and
//! B at the common times the panes showed.

use egui::Color32;
use egui_plot::{Line, LineStyle, PlotPoints};

use super::plots::{plot_title, series, small_plot};
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
    ui.columns(4, |cols| {
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
            ("Closed contacts", "contacts_ab"),
            "Contacts in the lock or slide state after each step, run A and run B.",
            (a, b),
            |r| (r.lock + r.slide) as f64,
            h,
        );
        difference(&mut cols[3], &c.difference, h);
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
    small_plot(id, h).show(ui, |p| {
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

/// The largest block displacement difference between A and B, mm, at the common times shown.
fn difference(ui: &mut egui::Ui, points: &[[f64; 2]], h: f32) {
    plot_title(
        ui,
        "|u_A − u_B| max (mm)",
        "The largest distance between a block's centroid in run A and in run B at the same \
         simulated time (the runs start from the same scene, so their displacements differ \
         by exactly this).",
    );
    let per = points.len().div_ceil(super::plots::PLOT_POINTS).max(1);
    let pts: Vec<[f64; 2]> = points
        .chunks(per)
        .filter_map(|c| {
            let v = c
                .iter()
                .map(|p| p[1])
                .filter(|v| v.is_finite())
                .reduce(f64::max)?;
            Some([c[c.len() - 1][0], v * 1e3])
        })
        .collect();
    small_plot("diff_ab", h).show(ui, |p| {
        p.line(
            Line::new("A − B", PlotPoints::from(pts))
                .color(Color32::from_rgb(0x6A, 0x3D, 0x9A))
                .fill(0.0)
                .fill_alpha(0.15),
        );
    });
}
