//! The Compare switch: start comparing the run with the other method (both from t = 0), or end
//! the comparison. In a comparison, which run the solver panel edits: A, B or both (an edit to
//! both changes only the keys edited, so B keeps the settings that set it apart); and the
//! one-pane mode with B as a ghost over A.

use egui::RichText;

use crate::compare::method_name;
use crate::params::Method;
use crate::viewer::compare_ui::EditTarget;
use crate::viewer::state::{Action, UiState};

pub fn show(ui: &mut egui::Ui, state: &mut UiState, actions: &mut Vec<Action>) {
    let Some(c) = state.compare.as_deref() else {
        if let Some(f) = state.frame.as_ref() {
            let mut b = f.params.clone();
            b.method = match b.method {
                Method::Alm => Method::Penalty,
                Method::Penalty => Method::Alm,
            };
            let label = format!("Compare with {}", method_name(b.method));
            if ui
                .button(label)
                .on_hover_text(
                    "Run this scene twice side by side from t = 0: A with these settings, B with \
                     the other method (then edit A, B or both)",
                )
                .clicked()
            {
                actions.push(Action::Compare(Some(Box::new(b))));
            }
            ui.add_space(4.0);
        }
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
    let mut ghost = c.ghost;
    ui.horizontal(|ui| {
        ui.checkbox(&mut ghost, "One pane, B as a ghost over A")
            .on_hover_text("Draw run B's blocks translucent in blue over run A's picture");
        if ui
            .button("End comparison")
            .on_hover_text("Back to run A alone, from t = 0")
            .clicked()
        {
            actions.push(Action::Compare(None));
        }
    });
    if target != c.target {
        state.set_edit_target(target);
    }
    if let Some(c) = state.compare.as_deref_mut() {
        c.ghost = ghost;
    }
    ui.add_space(4.0);
}
