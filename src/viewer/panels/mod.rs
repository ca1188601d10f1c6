//! The viewer's panels, one file each (after egui's demo app): the [`toolbar`], the left column
//! ([`solver`] parameters, [`display`] options, [`selection`] details, [`run`] statistics), the
//! [`plots`] at the bottom and the [`view_3d`] in the middle, plus the keyboard shortcuts. In a
//! comparison, [`compare_target`] picks the run the solver panel edits and [`compare_plots`]
//! replaces the plots. Each
//! panel is a `show` function that draws from and edits [`UiState`] and pushes the [`Action`]s
//! the app must carry out. No GPU code here: the 3-D image arrives as an egui texture id and is
//! drawn by [`super::app`].

mod compare_plots;
mod compare_target;
mod display;
mod ghost;
mod plots;
mod run;
mod selection;
mod solver;
mod toolbar;
mod view_3d;
pub mod widgets;

use egui::{Color32, CornerRadius, Key, RichText, Stroke};

use super::sim::Command;
use super::state::{Action, UiState};
use widgets::ERROR_RED;

/// Builds the frame's UI. `view_texture` is the 3-D image drawn by the app (sized to
/// `state.view_rect` × pixels per point).
pub fn build(ui: &mut egui::Ui, state: &mut UiState, view_texture: egui::TextureId) -> Vec<Action> {
    let mut actions = Vec::new();
    state.build_scene();
    state.build_scene_b();
    // Panels are not filled: the window is cleared to the panel colour, and on a software
    // rasterizer every filled pixel counts (about a third of the frame time).
    let panel = |m: egui::Margin| egui::Frame::new().inner_margin(m);
    egui::Panel::top("toolbar")
        .frame(panel(egui::Margin::symmetric(8, 5)))
        .show(ui, |ui| toolbar::show(ui, state, &mut actions));
    if state.show_plots {
        egui::Panel::bottom("plots")
            .frame(panel(egui::Margin::symmetric(8, 2)))
            .resizable(true)
            .default_size(190.0)
            .min_size(120.0)
            .show(ui, |ui| {
                if state.compare.is_some() {
                    compare_plots::show(ui, state);
                } else {
                    plots::show(ui, state);
                }
            });
    }
    egui::Panel::left("controls")
        .frame(panel(egui::Margin::symmetric(8, 2)))
        .resizable(true)
        .default_size(318.0)
        .min_size(260.0)
        .show(ui, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| {
                ui.add_space(4.0);
                if let Some(err) = state.frame.as_ref().and_then(|f| f.error.clone()) {
                    error_box(ui, &err);
                }
                egui::CollapsingHeader::new(RichText::new("Solver").strong())
                    .default_open(true)
                    .show(ui, |ui| {
                        compare_target::show(ui, state, &mut actions);
                        solver::show(ui, state);
                    });
                egui::CollapsingHeader::new(RichText::new("Display").strong())
                    .default_open(true)
                    .show(ui, |ui| display::show(ui, state));
                let title = match state.selected.zip(state.frame.as_ref()) {
                    Some((i, f)) if i < f.snapshot.blocks.len() => {
                        format!("Selection: {}", f.snapshot.blocks[i].name)
                    }
                    _ => "Selection".to_owned(),
                };
                egui::CollapsingHeader::new(RichText::new(title).strong())
                    .id_salt("selection")
                    .default_open(true)
                    .show(ui, |ui| selection::show(ui, state));
                egui::CollapsingHeader::new(RichText::new("Run statistics").strong())
                    .default_open(false)
                    .show(ui, |ui| run::show(ui, state));
            });
        });
    egui::CentralPanel::no_frame().show(ui, |ui| view_3d::show(ui, state, view_texture));
    keyboard(ui, state, &mut actions);
    actions
}

fn error_box(ui: &mut egui::Ui, err: &str) {
    egui::Frame::new()
        .fill(Color32::from_rgb(0xFB, 0xE4, 0xE1))
        .stroke(Stroke::new(1.0, ERROR_RED))
        .corner_radius(CornerRadius::same(4))
        .inner_margin(egui::Margin::same(6))
        .show(ui, |ui| {
            ui.set_width(ui.available_width());
            ui.label(RichText::new("Solver error").strong().color(ERROR_RED));
            ui.label(RichText::new(err).color(Color32::from_rgb(0x60, 0x10, 0x10)));
            ui.label(RichText::new("Change parameters and press Play to retry, or Reset.").weak());
        });
    ui.add_space(6.0);
}

fn keyboard(ui: &mut egui::Ui, state: &mut UiState, actions: &mut Vec<Action>) {
    if ui.ctx().egui_wants_keyboard_input() {
        return;
    }
    let (space, step, reset, frame_all, esc) = ui.input(|i| {
        (
            i.key_pressed(Key::Space),
            i.key_pressed(Key::ArrowRight) || i.key_pressed(Key::S),
            i.key_pressed(Key::R),
            i.key_pressed(Key::F),
            i.key_pressed(Key::Escape),
        )
    });
    if space {
        actions.push(Action::Sim(if state.running() {
            Command::Pause
        } else {
            Command::Play
        }));
    }
    if step {
        actions.push(Action::Sim(Command::Step));
    }
    if reset {
        actions.push(Action::Sim(Command::Reset));
    }
    if frame_all && let Some(f) = &state.frame {
        let snap = f.snapshot.clone();
        state.view.frame_all(&snap);
    }
    if esc {
        state.selected = None;
    }
}
