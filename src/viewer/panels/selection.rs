//! The selected block: its name, mass, material and motion, and a table of its contacts.

use egui::RichText;
use glam::DVec3;

use super::widgets::{color32, length, num};
use crate::render::mesh::{LOCK_SRGB, OPEN_SRGB, SLIDE_SRGB};
use crate::render::overlay::format_force;
use crate::snapshot::{BlockSnapshot, ContactMode, ContactSnapshot, ContactState, Snapshot};
use crate::viewer::state::{BlockInfo, UiState};

pub fn show(ui: &mut egui::Ui, state: &UiState) {
    let Some(frame) = state.frame.clone() else {
        return;
    };
    let snap = &frame.snapshot;
    let Some(i) = state.selected.filter(|&i| i < snap.blocks.len()) else {
        ui.label(RichText::new("Click a block in the view to see its state and contacts.").weak());
        return;
    };
    block_facts(
        ui,
        i,
        &snap.blocks[i],
        state.scene_file.blocks.get(i),
        &snap.rock_masses,
    );
    // In a comparison, the block's contacts in both runs at the same time, A's first.
    let b = state
        .compare
        .as_deref()
        .and_then(|c| c.frame_b.clone())
        .filter(|fb| i < fb.snapshot.blocks.len());
    let heading_a = if b.is_some() { "Run A: " } else { "" };
    contact_table(ui, snap, i, state.scene_file.young, heading_a);
    if let Some(fb) = b {
        ui.add_space(6.0);
        contact_table(ui, &fb.snapshot, i, state.scene_file.young, "Run B: ");
    }
}

/// The closed contacts of block `i` in `snap`, under a heading that starts with `side`.
fn contact_table(ui: &mut egui::Ui, snap: &Snapshot, i: usize, young: f64, side: &str) {
    let contacts: Vec<_> = snap
        .contacts
        .iter()
        .filter(|c| c.block_i == i || c.block_j == i)
        .collect();
    ui.add_space(4.0);
    ui.label(RichText::new(format!("{side}{} closed contacts", contacts.len())).strong());
    if contacts.is_empty() {
        return;
    }
    let total_n: f64 = contacts.iter().map(|c| c.normal_force).sum();
    ui.label(
        RichText::new(format!("Σ N = {}", format_force(total_n)))
            .weak()
            .small(),
    );
    egui::ScrollArea::vertical()
        .id_salt(("sel_contacts", side))
        .max_height(220.0)
        .show(ui, |ui| {
            egui::Grid::new(("sel_contacts_grid", side))
                .num_columns(7)
                .striped(true)
                .spacing([8.0, 2.0])
                .show(ui, |ui| {
                    for h in ["with", "type", "state", "joint", "N", "d_n", "p_n"] {
                        ui.label(RichText::new(h).small().strong());
                    }
                    ui.end_row();
                    for c in contacts.iter().take(200) {
                        contact_row(ui, snap, i, c, young);
                        ui.end_row();
                    }
                });
        });
}

/// Name, mass, material, centroid, displacement and velocity of block `i`.
fn block_facts(
    ui: &mut egui::Ui,
    i: usize,
    b: &BlockSnapshot,
    info: Option<&BlockInfo>,
    rock_masses: &[String],
) {
    egui::Grid::new("sel")
        .num_columns(2)
        .spacing([10.0, 3.0])
        .show(ui, |ui| {
            ui.label("Block");
            ui.label(
                RichText::new(format!(
                    "{} (#{i}){}",
                    b.name,
                    if b.fixed { ", fixed" } else { "" }
                ))
                .strong(),
            );
            ui.end_row();
            if let Some((mass, region)) = b.rock_mass {
                ui.label("Rock mass");
                ui.label(format!(
                    "{}, region {}",
                    rock_masses
                        .get(usize::from(mass))
                        .map_or("?", String::as_str),
                    region + 1
                ));
                ui.end_row();
            }
            if let Some(info) = info {
                ui.label("Mass");
                ui.label(format!("{} kg", num(info.mass)));
                ui.end_row();
                ui.label("Material");
                ui.label(format!(
                    "ρ {} kg/m³, E {} Pa, ν {}",
                    num(info.density),
                    num(info.young),
                    num(info.poisson)
                ));
                ui.end_row();
            }
            let c = b.centroid;
            ui.label("Centroid");
            ui.label(format!("({:.3}, {:.3}, {:.3}) m", c[0], c[1], c[2]));
            ui.end_row();
            let u = DVec3::from_array(b.displacement);
            ui.label("Displacement");
            ui.label(format!(
                "|u| = {}  ({:.3}, {:.3}, {:.3}) m",
                length(u.length()),
                u.x,
                u.y,
                u.z
            ));
            ui.end_row();
            let v = DVec3::from_array(b.velocity);
            ui.label("Velocity");
            ui.label(format!(
                "|v| = {} m/s  ({:.2}, {:.2}, {:.2})",
                num(v.length()),
                v.x,
                v.y,
                v.z
            ));
            ui.end_row();
        });
}

/// One contact of block `i`: the other block, type, state, N, d_n and p_n (relative to E).
fn contact_row(ui: &mut egui::Ui, snap: &Snapshot, i: usize, c: &ContactSnapshot, young: f64) {
    let other = if c.block_i == i { c.block_j } else { c.block_i };
    let name = snap
        .blocks
        .get(other)
        .map(|b| b.name.as_str())
        .unwrap_or("?");
    ui.label(RichText::new(name).small());
    ui.label(
        RichText::new(match c.mode {
            ContactMode::VertexFace => "V–F",
            ContactMode::EdgeEdge => "E–E",
        })
        .small(),
    )
    .on_hover_text(if c.block_i == i {
        "this block owns the vertex / first edge"
    } else {
        "this block owns the face / second edge"
    });
    let (st, col) = match c.state {
        ContactState::Lock => ("lock", color32(LOCK_SRGB)),
        ContactState::Slide => ("slide", color32(SLIDE_SRGB)),
        ContactState::Open => ("open", color32(OPEN_SRGB)),
    };
    ui.label(RichText::new(st).small().color(col));
    let joint = c
        .joint
        .and_then(|k| snap.joint_sets.get(usize::from(k)))
        .map_or("[joint]", String::as_str);
    ui.label(RichText::new(joint).small()).on_hover_text(
        "The joint set whose plane the contact lies on (its friction and cohesion), or the \
         scene's [joint]",
    );
    ui.label(RichText::new(format_force(c.normal_force)).small())
        .on_hover_text(format!(
            "normal {} , shear {}, λ = {}",
            format_force(c.normal_force),
            format_force(c.shear_force),
            format_force(c.lambda)
        ));
    ui.label(RichText::new(length(c.penetration)).small())
        .on_hover_text("penetration (positive = overlap)");
    ui.label(RichText::new(format!("{} E", num(c.penalty / young))).small())
        .on_hover_text(format!("{} N/m", num(c.penalty)));
}
