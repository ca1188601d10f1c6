//! Run statistics: the solver's totals since t = 0, and the GPU in use.

use super::widgets::{length, seconds};
use crate::viewer::state::UiState;

pub fn show(ui: &mut egui::Ui, state: &UiState) {
    let Some(f) = state.frame.clone() else {
        return;
    };
    let t = &f.totals;
    egui::Grid::new("totals")
        .num_columns(2)
        .spacing([10.0, 2.0])
        .show(ui, |ui| {
            let mut row = |k: &str, v: String| {
                ui.label(k);
                ui.label(v);
                ui.end_row();
            };
            row("Steps", t.steps.to_string());
            row("Open–close passes", t.open_close_iterations.to_string());
            row("Linear solves (ALM)", t.alm_iterations.to_string());
            row("Factorizations", t.factorizations.to_string());
            row("Time-step cuts", t.time_step_cuts.to_string());
            row("Unconverged steps", t.unconverged_steps.to_string());
            row("ALM cap hits", t.alm_cap_hits.to_string());
            // Islands at rest, held still (`solver.sleep_velocity`).
            row(
                "Blocks asleep",
                format!(
                    "{} of {}",
                    f.snapshot.stats.blocks_asleep,
                    f.snapshot.blocks.len()
                ),
            );
            row("Max penetration", length(t.max_penetration));
            row("d_n,max = 2δw0", length(f.max_step_penetration));
            row("Solver time / step", seconds(f.seconds_per_step));
            row("GPU", state.adapter.clone());
        });
}
