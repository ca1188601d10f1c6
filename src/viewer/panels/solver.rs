//! The solver panel: method and mode, the contact law (P21)–(P24), joint strength, time
//! stepping, more contact settings, and the preset buttons. Labels, tooltips and slider ranges
//! come from [`crate::params::table`].

use egui::RichText;

use super::widgets::{length, num, param_label, param_slider, seconds};
use crate::params::table::{self, Value};
use crate::params::{JointParams, Method, Mode, SolverParams};
use crate::physics::integrator::Scheme;
use crate::viewer::state::UiState;

/// The paper's p_n,1 = 0.01 E (§3.1), the "Paper defaults" button's initial penalty.
const PAPER_PENALTY_PER_E: f64 = 0.01;

/// What a grid row needs to know about the model.
struct Model {
    /// E, Pa: penalties are shown relative to it.
    young: f64,
    /// w0, m: half the model's largest extent.
    w0: f64,
}

pub fn show(ui: &mut egui::Ui, state: &mut UiState) {
    let model = Model {
        young: state.scene_file.young,
        w0: state
            .frame
            .as_ref()
            .map(|f| f.max_step_penetration / (2.0 * f.params.max_displacement_ratio))
            .filter(|v| v.is_finite() && *v > 0.0)
            .unwrap_or(1.0),
    };
    let e = &mut state.params.edit;
    method_and_mode(ui, e, state.resumed_from);
    ui.add_space(4.0);
    egui::Grid::new("params")
        .num_columns(3)
        .spacing([8.0, 5.0])
        .striped(true)
        .show(ui, |ui| {
            penalty_rows(ui, e, &model);
            tolerance_rows(ui, e, &model);
            joint_rows(ui, e, &model);
            time_rows(ui, e, &model);
        });
    more_contact_settings(ui, e, &model);
    ui.add_space(4.0);
    presets(ui, state);
}

fn method_and_mode(ui: &mut egui::Ui, e: &mut SolverParams, resumed_from: Option<f64>) {
    ui.horizontal(|ui| {
        param_label(ui, &table::METHOD);
        ui.selectable_value(&mut e.method, Method::Alm, "ALM (DDA-3a)");
        ui.selectable_value(&mut e.method, Method::Penalty, "Penalty (DDA-3p)");
    });
    ui.horizontal(|ui| {
        param_label(ui, &table::MODE);
        ui.selectable_value(&mut e.mode, Mode::Dynamic, "Dynamic");
        ui.selectable_value(&mut e.mode, Mode::Static, "Static");
    });
    ui.horizontal(|ui| {
        param_label(ui, &table::INITIAL_EQUILIBRIUM);
        match resumed_from {
            // Reset goes back to the checkpoint, which is past any stage: the box would do
            // nothing, so it says so instead of seeming to promise a stage.
            Some(t) => {
                ui.add_enabled(
                    false,
                    egui::Checkbox::without_text(&mut e.initial_equilibrium),
                )
                .on_disabled_hover_text(format!(
                    "This run started from a checkpoint at t = {}: Reset goes back to \
                         it, after any stage. Run the scene file to change the stage.",
                    seconds(t)
                ));
            }
            None => {
                ui.checkbox(&mut e.initial_equilibrium, "")
                    .on_hover_text("Takes effect at Reset: the run restarts with the stage.");
            }
        }
    });
}

/// p_n,1, and the adaptive penalty of (P21): α, β, γ (ALM only).
fn penalty_rows(ui: &mut egui::Ui, e: &mut SolverParams, model: &Model) {
    let (young, alm) = (model.young, e.method == Method::Alm);
    let c = &mut e.contact;
    param_label(ui, &table::INITIAL_PENALTY);
    ui.add(param_slider(
        &mut c.initial_penalty,
        &table::INITIAL_PENALTY,
        young,
    ));
    ui.label(RichText::new(format!("{} E", num(c.initial_penalty / young))).weak())
        .on_hover_text(format!("as a multiple of E = {} Pa", num(young)));
    ui.end_row();

    ui.add_enabled_ui(alm, |ui| param_label(ui, &table::ALPHA));
    ui.add_enabled(alm, param_slider(&mut c.alpha, &table::ALPHA, young));
    ui.label("");
    ui.end_row();

    ui.add_enabled_ui(alm, |ui| param_label(ui, &table::BETA));
    ui.add_enabled(
        alm,
        param_slider(&mut c.beta, &table::BETA, young).fixed_decimals(2),
    );
    ui.label("");
    ui.end_row();

    ui.add_enabled_ui(alm, |ui| param_label(ui, &table::GAMMA));
    ui.add_enabled(alm, param_slider(&mut c.gamma, &table::GAMMA, young));
    ui.label(RichText::new(format!("{} N/m", num(c.gamma * young))).weak());
    ui.end_row();
}

/// The ALM convergence tests (P23) and (P24): ε1 and ε2.
fn tolerance_rows(ui: &mut egui::Ui, e: &mut SolverParams, model: &Model) {
    let alm = e.method == Method::Alm;
    let d_n_max = 2.0 * e.max_displacement_ratio * model.w0;
    let c = &mut e.contact;
    ui.add_enabled_ui(alm, |ui| param_label(ui, &table::EPS1));
    ui.add_enabled(alm, param_slider(&mut c.eps1, &table::EPS1, model.young));
    ui.label(RichText::new(format!("≤ {}", length(c.eps1 * d_n_max))).weak())
        .on_hover_text("ε1·d_n,max: the penetration ALM aims for");
    ui.end_row();

    ui.add_enabled_ui(alm, |ui| param_label(ui, &table::EPS2));
    ui.add_enabled(alm, param_slider(&mut c.eps2, &table::EPS2, model.young));
    ui.label("");
    ui.end_row();

    ui.add_enabled_ui(alm, |ui| param_label(ui, &table::PENALTY_FLOOR));
    ui.add_enabled(
        alm,
        param_slider(&mut c.penalty_floor, &table::PENALTY_FLOOR, model.young),
    );
    ui.label(RichText::new(format!("≥ {}", length(c.penalty_floor * c.eps1 * d_n_max))).weak())
        .on_hover_text("penetrations below this do not raise p_n (P21)");
    ui.end_row();
}

/// Joint strength: φ and c (Mohr–Coulomb) of `[joint]`, then of each joint set of the scene's
/// rock masses (their contacts take their set's, issue #14).
fn joint_rows(ui: &mut egui::Ui, e: &mut SolverParams, model: &Model) {
    let young = model.young;
    strength_rows(ui, &mut e.joint, young, None);
    for set in &mut e.joint_sets {
        let name = format!("{}/{}", set.rock_mass, set.name);
        strength_rows(ui, &mut set.joint, young, Some(&name));
    }
}

/// The φ and c rows of one joint: `[joint]`'s (`set` None) or a joint set's.
fn strength_rows(ui: &mut egui::Ui, j: &mut JointParams, young: f64, set: Option<&str>) {
    let label = |ui: &mut egui::Ui, p: &table::Param| match set {
        None => param_label(ui, p),
        Some(name) => {
            ui.label(format!("{name}: {}", p.label)).on_hover_text(format!(
                "Joint set {name}: contacts between faces cut by one of its planes take this. {}",
                p.doc()
            ));
        }
    };
    label(ui, &table::FRICTION_ANGLE);
    ui.add(param_slider(&mut j.friction_angle, &table::FRICTION_ANGLE, young).fixed_decimals(1));
    ui.label(
        RichText::new(format!(
            "tan φ = {:.2}",
            j.friction_angle.to_radians().tan()
        ))
        .weak(),
    );
    ui.end_row();

    label(ui, &table::COHESION);
    ui.add(param_slider(&mut j.cohesion, &table::COHESION, young).smallest_positive(1e2));
    ui.label("");
    ui.end_row();
}

/// Time stepping: δ, Δt_max, ρ∞, sleeping and the end time.
fn time_rows(ui: &mut egui::Ui, e: &mut SolverParams, model: &Model) {
    let young = model.young;
    param_label(ui, &table::MAX_DISPLACEMENT_RATIO);
    ui.add(param_slider(
        &mut e.max_displacement_ratio,
        &table::MAX_DISPLACEMENT_RATIO,
        young,
    ));
    ui.label(
        RichText::new(format!(
            "δ·w0 = {}",
            length(e.max_displacement_ratio * model.w0)
        ))
        .weak(),
    );
    ui.end_row();

    param_label(ui, &table::MAX_TIME_STEP);
    ui.add(param_slider(
        &mut e.max_time_step,
        &table::MAX_TIME_STEP,
        young,
    ));
    ui.label(RichText::new(seconds(e.max_time_step)).weak());
    ui.end_row();

    let dynamic = e.mode == Mode::Dynamic;
    ui.add_enabled_ui(dynamic, |ui| param_label(ui, &table::SPECTRAL_RADIUS));
    ui.add_enabled(
        dynamic,
        param_slider(&mut e.spectral_radius, &table::SPECTRAL_RADIUS, young),
    );
    let scheme = if e.spectral_radius >= 1.0 {
        "Shi's step".to_owned()
    } else {
        format!(
            "β = {:.4}",
            Scheme::with_spectral_radius(e.spectral_radius).beta
        )
    };
    ui.label(RichText::new(scheme).weak());
    ui.end_row();

    // Sleeping islands (dynamic runs only): 0 switches sleeping off.
    ui.add_enabled_ui(dynamic, |ui| param_label(ui, &table::SLEEP_VELOCITY));
    ui.add_enabled(
        dynamic,
        param_slider(&mut e.sleep_velocity, &table::SLEEP_VELOCITY, young).smallest_positive(1e-7),
    );
    ui.label(
        RichText::new(if e.sleep_velocity > 0.0 {
            ""
        } else {
            "never sleeps"
        })
        .weak(),
    );
    ui.end_row();
    ui.add_enabled_ui(dynamic, |ui| param_label(ui, &table::SLEEP_TIME));
    ui.add_enabled(
        dynamic && e.sleep_velocity > 0.0,
        param_slider(&mut e.sleep_time, &table::SLEEP_TIME, young),
    );
    ui.label(RichText::new(seconds(e.sleep_time)).weak());
    ui.end_row();

    param_label(ui, &table::DURATION);
    ui.add(
        egui::DragValue::new(&mut e.duration)
            .range(table::DURATION.widget_range(young))
            .clamp_existing_to_range(false)
            .speed(0.05)
            .suffix(table::DURATION.suffix()),
    );
    ui.label("");
    ui.end_row();
}

/// The shear spring, the iteration caps and warm starting, folded away.
fn more_contact_settings(ui: &mut egui::Ui, e: &mut SolverParams, model: &Model) {
    let (c, young) = (&mut e.contact, model.young);
    egui::CollapsingHeader::new("More contact settings")
        .default_open(false)
        .show(ui, |ui| {
            egui::Grid::new("params_more")
                .num_columns(2)
                .spacing([8.0, 5.0])
                .show(ui, |ui| {
                    let p = &table::SHEAR_PENALTY_RATIO;
                    param_label(ui, p);
                    ui.add(param_slider(&mut c.shear_penalty_ratio, p, young));
                    ui.end_row();
                    let p = &table::MAX_ALM_ITERATIONS;
                    param_label(ui, p);
                    ui.add(param_slider(&mut c.max_alm_iterations, p, young));
                    ui.end_row();
                    let p = &table::MAX_OPEN_CLOSE_ITERATIONS;
                    param_label(ui, p);
                    ui.add(param_slider(&mut c.max_open_close_iterations, p, young));
                    ui.end_row();
                    param_label(ui, &table::WARM_START);
                    ui.checkbox(&mut c.warm_start, "");
                    ui.end_row();
                });
        });
}

/// "Paper defaults" and "Scene values".
fn presets(ui: &mut egui::Ui, state: &mut UiState) {
    let young = state.scene_file.young;
    let e = &mut state.params.edit;
    ui.horizontal(|ui| {
        if ui
            .button("Paper defaults")
            .on_hover_text(paper_defaults_tip())
            .clicked()
        {
            let d = SolverParams::default();
            let keep = e.clone();
            *e = SolverParams {
                method: keep.method,
                mode: keep.mode,
                spectral_radius: keep.spectral_radius,
                duration: keep.duration,
                gravity: keep.gravity,
                joint: keep.joint.clone(),
                ..d
            };
            e.contact.initial_penalty = PAPER_PENALTY_PER_E * young;
        }
        if ui
            .button("Scene values")
            .on_hover_text("Every parameter back to what the scene file says")
            .clicked()
        {
            let end = e.duration;
            *e = state.scene_file.params.clone();
            e.duration = end.max(state.scene_file.params.duration);
        }
    });
}

/// The "Paper defaults" tooltip, with the values the button sets (the table's defaults).
fn paper_defaults_tip() -> String {
    let values: Vec<String> = [
        &table::ALPHA,
        &table::BETA,
        &table::GAMMA,
        &table::EPS1,
        &table::EPS2,
        &table::MAX_DISPLACEMENT_RATIO,
        &table::MAX_TIME_STEP,
    ]
    .into_iter()
    .filter_map(|p| match p.default {
        Value::Real(v) => Some(format!("{} = {}{}", p.label, num(v), p.suffix())),
        _ => None,
    })
    .collect();
    format!(
        "Contact law and time stepping of the paper (Zhang Hong 2019, §3): p_n,1 = {} E, {}. \
         Method, mode, ρ∞, joint and end time are kept.",
        num(PAPER_PENALTY_PER_E),
        values.join(", ")
    )
}
