//! In a comparison, which run the solver panel edits: A, B or both (an edit to both changes
//! only the keys edited, so B keeps the settings that set it apart).

use egui::RichText;

use crate::viewer::compare_ui::{EditTarget, method_name};
use crate::viewer::state::UiState;

pub fn show(ui: &mut egui::Ui, state: &mut UiState) {
    let Some(c) = state.compare.as_deref() else {
        return;
    };
    let name = |f: Option<&std::sync::Arc<crate::viewer::sim::Frame>>| {
        f.map_or("", |f| method_name(f.params.method))
    };
    let (a, b) = (name(state.frame.as_ref()), name(c.frame_b.as_ref()));
    let mut target = c.target;
    ui.horizontal(|ui| {
        ui.label(RichText::new("Edit").strong());
        ui.selectable_value(&mut target, EditTarget::A, "A")
            .on_hover_text(format!("Run A: {a}"));
        ui.selectable_value(&mut target, EditTarget::B, "B")
            .on_hover_text(format!("Run B: {b}"));
        ui.selectable_value(&mut target, EditTarget::Both, "A and B")
            .on_hover_text("The keys edited change in both runs; the others stay as they are");
    });
    if target != c.target {
        state.set_edit_target(target);
    }
    ui.add_space(4.0);
}
