//! Display options of the 3-D view: colouring, force arrows and their scale, edges, grid,
//! labels, legend, plots, and the camera buttons.

use egui::RichText;

use super::widgets::slider;
use crate::render::Coloring;
use crate::render::overlay::format_force;
use crate::viewer::state::UiState;
use crate::viewer::view::ViewControls;

pub fn show(ui: &mut egui::Ui, state: &mut UiState) {
    let d = &mut state.display;
    let before = d.clone();
    ui.horizontal(|ui| {
        ui.label("Colour by");
        egui::ComboBox::from_id_salt("coloring")
            .selected_text(match d.coloring {
                Coloring::PerBlock => "block",
                Coloring::Velocity => "speed |v|",
                Coloring::Displacement => "displacement |u|",
                Coloring::RockMass => "rock mass",
            })
            .show_ui(ui, |ui| {
                ui.selectable_value(&mut d.coloring, Coloring::PerBlock, "block");
                ui.selectable_value(&mut d.coloring, Coloring::Velocity, "speed |v|");
                ui.selectable_value(&mut d.coloring, Coloring::Displacement, "displacement |u|");
                ui.selectable_value(&mut d.coloring, Coloring::RockMass, "rock mass")
                    .on_hover_text("A colour per rock mass, shaded per region and block");
            });
    });
    ui.horizontal(|ui| {
        ui.checkbox(&mut d.forces, "Force arrows").on_hover_text(
            "Normal contact force on block i, coloured by state (lock blue, slide red)",
        );
        ui.checkbox(&mut d.normals, "Contact normals");
    });
    ui.add_enabled_ui(d.forces, |ui| {
        ui.horizontal(|ui| {
            ui.label("Scale");
            ui.selectable_value(&mut d.auto_force_scale, true, "auto")
                .on_hover_text("Chosen from the first step with contacts, then kept fixed");
            ui.selectable_value(&mut d.auto_force_scale, false, "manual");
            if d.auto_force_scale {
                if let Some(s) = state.scales.force {
                    ui.label(RichText::new(format!("1 m = {}", format_force(s))).weak());
                }
            } else {
                ui.add(
                    slider(&mut d.force_scale, 1.0..=1e10)
                        .logarithmic(true)
                        .custom_formatter(|v, _| format_force(v))
                        .text("per m"),
                );
            }
        });
        ui.horizontal(|ui| {
            ui.label("Show");
            ui.selectable_value(&mut d.strongest_only, false, "all")
                .on_hover_text("An arrow at every closed contact");
            ui.selectable_value(&mut d.strongest_only, true, "strongest")
                .on_hover_text(
                    "Arrows at the contacts with the largest normal force only: on a rock mass \
                     of thousands of contacts they show the load paths (and draw faster)",
                );
            if d.strongest_only {
                ui.add(
                    egui::Slider::new(&mut d.arrow_limit, 10..=20_000)
                        .logarithmic(true)
                        .text("contacts"),
                );
            }
        });
    });
    ui.horizontal(|ui| {
        ui.checkbox(&mut d.edges, "Edges");
        ui.checkbox(&mut d.wireframe, "Wireframe");
        ui.checkbox(&mut d.grid, "Grid");
    });
    ui.horizontal(|ui| {
        ui.checkbox(&mut d.labels, "Labels");
        ui.checkbox(&mut d.overlay, "Legend");
        ui.checkbox(&mut state.show_plots, "Plots");
    });
    if d.coloring != before.coloring {
        state.scales.field_max = 0.0;
    }
    if !before.auto_force_scale
        && d.auto_force_scale
        && let Some(s) = state.scales.force
    {
        d.force_scale = s;
    }
    if before.auto_force_scale && !d.auto_force_scale {
        d.force_scale = state.scales.force.unwrap_or(d.force_scale);
    }
    ui.horizontal(|ui| {
        if ui
            .button("Frame all (F)")
            .on_hover_text("Fit every block into the view, keeping the direction")
            .clicked()
            && let Some(f) = &state.frame
        {
            let snap = f.snapshot.clone();
            state.view.frame_all(&snap);
        }
        if ui.button("Reset view").clicked() {
            let aspect = state.view.camera.aspect;
            state.view = ViewControls::new(state.scene_frame.lo, state.scene_frame.hi, aspect);
        }
    });
    ui.label(
        RichText::new("Left drag: orbit · right/middle drag: pan · wheel: zoom · click: select")
            .small()
            .weak(),
    );
}
