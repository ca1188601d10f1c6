//! The toolbar: play/step/reset, simulation speed, simulated time and run state, frame rate,
//! and the record and screenshot buttons.

use std::cell::RefCell;

use egui::containers::Sides;
use egui::{Color32, RichText};

use super::widgets::{ERROR_RED, Icon, OK_GREEN, icon_button, num, seconds};
use crate::params::table;
use crate::render::overlay::{STAGE_AMBER, format_time};
use crate::text::round_significant;
use crate::viewer::sim::{Command, Frame, RunState, Speed};
use crate::viewer::state::{Action, UiState};

const SPEEDS: [f64; 8] = [0.05, 0.1, 0.25, 0.5, 1.0, 2.0, 5.0, 10.0];

fn speed_label(s: Speed) -> String {
    match s {
        Speed::Max => "as fast as possible".into(),
        Speed::RealTime(f) if (f - 1.0).abs() < 1e-12 => "real time (1×)".into(),
        Speed::RealTime(f) => format!("{}× real time", num(f)),
    }
}

pub fn show(ui: &mut egui::Ui, state: &mut UiState, actions: &mut Vec<Action>) {
    let Some(frame) = state.frame.clone() else {
        ui.label("starting...");
        return;
    };
    ui.spacing_mut().item_spacing.x = 6.0;
    // The buttons on the right are laid out first and the run's progress gets what is left,
    // truncated: in a narrow window (or with the equilibrium stage's long label) it was drawn
    // under the Save/Load state buttons.
    // Sides runs one closure, then the other; both need the state and the actions.
    let shared = RefCell::new((state, actions));
    Sides::new().shrink_left().truncate().show(
        ui,
        |ui| {
            let (state, actions) = &mut *shared.borrow_mut();
            run_buttons(ui, &frame, actions);
            ui.separator();
            speed_box(ui, state, actions);
            ui.separator();
            progress(ui, &frame);
        },
        |ui| {
            let (state, actions) = &mut *shared.borrow_mut();
            rates(ui, state, &frame);
            ui.separator();
            capture_buttons(ui, state, actions);
            ui.separator();
            // Greyed out in a comparison, whose two runs would write one file per time (the
            // simulation link refuses them there too).
            ui.add_enabled_ui(state.compare.is_none(), |ui| {
                state_buttons(ui, state, actions);
            })
            .response
            .on_disabled_hover_text("Save and load state are not available in a comparison");
        },
    );
}

/// Play/Pause, Step and Reset.
fn run_buttons(ui: &mut egui::Ui, frame: &Frame, actions: &mut Vec<Action>) {
    let is_running = frame.state == RunState::Running;
    let (icon, text) = if is_running {
        (Icon::Pause, "Pause")
    } else {
        (Icon::Play, "Play")
    };
    let tip = if frame.state == RunState::Finished {
        "Continue past the end time (by another scene duration)  [Space]"
    } else {
        "Run / pause the simulation  [Space]"
    };
    let fill = (!is_running).then_some(Color32::from_rgb(0xD5, 0xEC, 0xD9));
    if icon_button(ui, 84.0, icon, text, fill)
        .on_hover_text(tip)
        .clicked()
    {
        actions.push(Action::Sim(if is_running {
            Command::Pause
        } else {
            Command::Play
        }));
    }
    if icon_button(ui, 70.0, Icon::Step, "Step", None)
        .on_hover_text("Advance one time step, then pause  [Right arrow or S]")
        .clicked()
    {
        actions.push(Action::Sim(Command::Step));
    }
    if icon_button(ui, 74.0, Icon::Reset, "Reset", None)
        .on_hover_text("Back to t = 0 with the current parameters  [R]")
        .clicked()
    {
        actions.push(Action::Sim(Command::Reset));
    }
}

/// The simulation speed (a real-time factor, or as fast as possible).
fn speed_box(ui: &mut egui::Ui, state: &mut UiState, actions: &mut Vec<Action>) {
    // No "Speed" label and a narrower box: at the default 1280 px the toolbar had no room left
    // for Δt and the cuts (the box's own text and tooltip say what it is).
    let before = state.speed;
    egui::ComboBox::from_id_salt("speed")
        .width(128.0)
        .selected_text(speed_label(state.speed))
        .show_ui(ui, |ui| {
            for f in SPEEDS {
                ui.selectable_value(
                    &mut state.speed,
                    Speed::RealTime(f),
                    speed_label(Speed::RealTime(f)),
                );
            }
            ui.selectable_value(&mut state.speed, Speed::Max, speed_label(Speed::Max));
        })
        .response
        .on_hover_text(
            "Simulated seconds per wall-clock second. \"As fast as possible\" steps back \
             to back; the window keeps drawing the newest state.",
        );
    if state.speed != before {
        actions.push(Action::Sim(Command::SetSpeed(state.speed)));
    }
}

/// Simulated time, step, the run state, the equilibrium stage's progress, Δt and cuts: the
/// most wanted first, as a narrow window truncates the end.
fn progress(ui: &mut egui::Ui, frame: &Frame) {
    let snap = &frame.snapshot;
    ui.label(RichText::new(format!("t = {}", format_time(snap.time))).strong())
        .on_hover_text("Simulated time");
    ui.label(RichText::new(format!("/ {}", format_time(frame.params.duration))).weak())
        .on_hover_text("End time: the run pauses here; Play continues past it");
    ui.label(format!("step {}", snap.step));
    let (text, color) = match frame.state {
        RunState::Running => ("RUNNING", OK_GREEN),
        RunState::Paused => ("PAUSED", Color32::from_gray(90)),
        RunState::Finished => ("AT END TIME", Color32::from_rgb(0x2F, 0x5F, 0xB0)),
        RunState::Failed => ("SOLVER ERROR", ERROR_RED),
    };
    ui.label(RichText::new(text).strong().color(color));
    if let Some(r) = snap.equilibrium {
        let text = if r.running {
            // Short: a narrow window truncates it; the view's caption spells it out.
            RichText::new(format!("STAGE {}", r.steps))
                .strong()
                .color(STAGE_AMBER)
        } else {
            RichText::new(format!("settled in {} steps", r.steps)).weak()
        };
        let tip = format!(
            "{}\n\nR_max now {} (tolerance {}){}",
            table::INITIAL_EQUILIBRIUM.doc(),
            num(r.residual),
            num(r.tolerance),
            if r.running || r.converged {
                ""
            } else {
                "; the stage reached its step limit without converging"
            }
        );
        ui.label(text).on_hover_text(tip);
    }
    // Three significant digits: Δt is chosen, not measured, and the width is scarce.
    ui.label(format!(
        "Δt {}",
        seconds(round_significant(snap.stats.time_step, 3))
    ))
    .on_hover_text("Length of the last accepted step");
    // Only once there are any: most runs have none, and the toolbar's width is scarce.
    let cuts = frame.totals.time_step_cuts;
    if cuts > 0 {
        ui.label(format!("cuts {cuts}")).on_hover_text(
            "Time-step cuts so far: attempts redone with a smaller Δt (displacement over \
             δ·w0, or open–close not converging)",
        );
    }
}

/// Frames per second of the window and steps per second of the solver.
fn rates(ui: &mut egui::Ui, state: &UiState, frame: &Frame) {
    let (interval, busy) = state.perf.recent_ms();
    let fps = if interval > 0.0 { 1e3 / interval } else { 0.0 };
    let sps = frame.steps_per_second;
    ui.label(
        RichText::new(format!(
            "{fps:.0} fps · {} steps/s",
            if sps > 0.0 {
                num(sps.round())
            } else {
                "–".into()
            }
        ))
        .monospace()
        .weak(),
    )
    .on_hover_text(format!(
        "Window: {interval:.1} ms between frames, {busy:.1} ms of CPU per frame.\n\
         Solver: {} per step.\nGPU: {}",
        seconds(frame.seconds_per_step),
        state.adapter
    ));
}

/// Save state and Load state (a menu of the checkpoints in the output directory, latest
/// first), laid out right to left.
fn state_buttons(ui: &mut egui::Ui, state: &UiState, actions: &mut Vec<Action>) {
    let dir = &state.out_dir;
    ui.menu_button("Load state", |ui| {
        let files = crate::viewer::sim::states::list(dir);
        if files.is_empty() {
            ui.label(format!("no checkpoint_*.ckpt in {}", dir.display()));
        }
        for path in files {
            let name = path.file_name().map(|n| n.to_string_lossy().into_owned());
            if ui.button(name.unwrap_or_default()).clicked() {
                actions.push(Action::Sim(Command::LoadState(path)));
                ui.close();
            }
        }
    })
    .response
    .on_hover_text(format!(
        "Replace the run with a saved state of this scene (paused): the checkpoints in {}, \
         from Save state or `dda3d run --checkpoint-every`",
        dir.display()
    ));
    if ui
        .button("Save state")
        .on_hover_text(format!(
            "Write the solver's complete state to {}/checkpoint_<t>.ckpt: Load state \
             reopens it, and `dda3d run --resume FILE` goes on with it headless",
            dir.display()
        ))
        .clicked()
    {
        actions.push(Action::Sim(Command::SaveState(dir.clone())));
    }
}

/// Record (or Stop) and Screenshot, laid out right to left.
fn capture_buttons(ui: &mut egui::Ui, state: &UiState, actions: &mut Vec<Action>) {
    let rec = state.recording.is_some();
    let (icon, text) = if rec {
        (Icon::Stop, "Stop")
    } else {
        (Icon::Record, "Record")
    };
    if icon_button(ui, 84.0, icon, text, None)
        .on_hover_text(
            "Write a PNG of the 3-D view for every new step shown while running \
             (window size, camera fixed at the start), plus frames.csv",
        )
        .clicked()
    {
        actions.push(Action::ToggleRecord);
    }
    if icon_button(ui, 112.0, Icon::Camera, "Screenshot", None)
        .on_hover_text("Write the 3-D view at window size as a PNG")
        .clicked()
    {
        actions.push(Action::Screenshot);
    }
}
