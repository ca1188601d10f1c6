//! The 3-D view: the rendered image, camera input and picking, and what egui draws over it
//! (the selected block's outline, block labels, the legend overlay, the selection card and the
//! status toasts).

use std::time::Duration;

use egui::{Align2, Color32, FontId, PointerButton, Pos2, Rect, Sense, Stroke, Vec2};
use glam::DVec3;

use super::widgets::{ACCENT, ERROR_RED, length, num};
use crate::render::overlay::format_force;
use crate::render::paint_overlay;
use crate::snapshot::{BlockSnapshot, ContactState, Snapshot};
use crate::viewer::state::UiState;
use crate::viewer::view::DragButton;

pub fn show(ui: &mut egui::Ui, state: &mut UiState, texture: egui::TextureId) {
    let full = ui.max_rect();
    // A comparison splits the view into two panes, A left and B right, seen by one camera:
    // one response over both, so orbit and zoom in either pane move both.
    let split = state.compare.as_deref().is_some_and(|c| !c.ghost);
    let (rect, rect_b) = if split {
        let (l, r) = full.split_left_right_at_fraction(0.5);
        (l, Some(r.shrink2(Vec2::new(1.0, 0.0))))
    } else {
        (full, None)
    };
    state.view_rect = rect;
    state.view.set_viewport(rect.width(), rect.height());
    let response = ui.allocate_rect(full, Sense::click_and_drag());
    camera_input(ui, state, &response, rect, rect_b);
    if let Some(rb) = rect_b {
        pane_b(ui, state, rb);
    }

    let painter = ui.painter_at(rect);
    painter.image(
        texture,
        rect,
        Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0)),
        Color32::WHITE,
    );
    let Some(frame) = state.frame.clone() else {
        return;
    };
    let snap = &frame.snapshot;
    annotate(&painter, state, snap, rect);

    if let Some(b) = state.compare.as_deref().filter(|c| c.ghost)
        && let Some(fb) = &b.frame_b
    {
        super::ghost::paint(&painter, state, &fb.snapshot, rect);
    }
    if let Some(scene) = &state.scene
        && scene.overlay
    {
        paint_overlay(&painter, scene, &state.view.camera, rect);
    }

    if let Some(i) = state.selected
        && let Some(b) = snap.blocks.get(i)
    {
        selection_card(&painter, rect, state, snap, i, b);
    }
    status_toasts(ui, &painter, rect, state);

    if response.hovered() && !response.dragged() {
        ui.ctx().set_cursor_icon(egui::CursorIcon::Crosshair);
    }
}

/// Run B's pane of a comparison: its image, the selected block's outline and the overlay.
fn pane_b(ui: &egui::Ui, state: &mut UiState, rect: Rect) {
    let Some(c) = state.compare.as_deref_mut() else {
        return;
    };
    c.view_rect_b = rect;
    // The rest only reads.
    let state: &UiState = state;
    let Some(c) = state.compare.as_deref() else {
        return;
    };
    let painter = ui.painter_at(rect);
    if let Some(t) = c.texture_b {
        let uv = Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0));
        painter.image(t, rect, uv, Color32::WHITE);
    }
    let divider = [rect.left_top() - Vec2::X, rect.left_bottom() - Vec2::X];
    painter.line_segment(divider, Stroke::new(2.0, Color32::from_gray(90)));
    let Some(frame) = c.frame_b.clone() else {
        return;
    };
    annotate(&painter, state, &frame.snapshot, rect);
    if let Some(scene) = &c.scene_b
        && scene.overlay
    {
        paint_overlay(&painter, scene, &state.view.camera, rect);
    }
}

/// Orbit, pan and zoom the camera, and select the block under a click (in either pane of a
/// comparison, on that pane's run).
fn camera_input(
    ui: &egui::Ui,
    state: &mut UiState,
    response: &egui::Response,
    rect: Rect,
    rect_b: Option<Rect>,
) {
    let (w, h) = (rect.width(), rect.height());
    let delta = response.drag_delta();
    if response.dragged_by(PointerButton::Primary) {
        state.view.drag(DragButton::Left, delta.x, delta.y, h);
    } else if response.dragged_by(PointerButton::Secondary) {
        state.view.drag(DragButton::Right, delta.x, delta.y, h);
    } else if response.dragged_by(PointerButton::Middle) {
        state.view.drag(DragButton::Middle, delta.x, delta.y, h);
    }
    if response.hovered() {
        let scroll = ui.input(|i| i.smooth_scroll_delta.y);
        if scroll != 0.0 {
            state.view.scroll(scroll);
        }
    }
    let Some(pos) = response
        .interact_pointer_pos()
        .filter(|_| response.clicked())
    else {
        return;
    };
    let (pane, frame) = match (rect_b, state.compare.as_deref()) {
        (Some(rb), Some(c)) if rb.contains(pos) => (rb, c.frame_b.clone()),
        _ => (rect, state.frame.clone()),
    };
    if let Some(f) = frame {
        let p = pos - pane.min;
        state.selected = state.view.pick(&f.snapshot, p.x, p.y, w, h);
    }
}

/// The selected block's outline, on top of everything (drawn through other blocks on purpose, so
/// a block hidden behind others can still be followed).
/// The shared camera's projection of a world point into `rect` (None behind the camera).
pub(super) fn projector(state: &UiState, rect: Rect) -> impl Fn([f64; 3]) -> Option<Pos2> + '_ {
    let (w, h) = (rect.width(), rect.height());
    move |p| {
        state
            .view
            .project(p, w, h)
            .map(|(x, y)| rect.min + Vec2::new(x, y))
    }
}

/// The selected block's outline and, when asked for, the block labels of `snap` in `rect`.
fn annotate(painter: &egui::Painter, state: &UiState, snap: &Snapshot, rect: Rect) {
    let to_screen = projector(state, rect);
    if let Some(b) = state.selected.and_then(|i| snap.blocks.get(i)) {
        outline(painter, b, &to_screen);
    }
    if state.display.labels {
        block_labels(painter, rect, snap, state.selected, &to_screen);
    }
}

fn outline(
    painter: &egui::Painter,
    b: &BlockSnapshot,
    to_screen: &impl Fn([f64; 3]) -> Option<Pos2>,
) {
    let pts: Vec<Option<Pos2>> = b.vertices.iter().map(|v| to_screen(*v)).collect();
    let stroke = Stroke::new(2.5, ACCENT);
    for face in &b.faces {
        for k in 0..face.len() {
            let (a, c) = (face[k] as usize, face[(k + 1) % face.len()] as usize);
            if a < c
                && let (Some(Some(p)), Some(Some(q))) = (pts.get(a), pts.get(c))
            {
                painter.line_segment([*p, *q], stroke);
            }
        }
    }
    if let Some(c) = to_screen(b.centroid) {
        painter.circle_filled(c, 3.5, ACCENT);
    }
}

/// Block names at their centroids (the first 300 blocks; the selected one in the accent colour).
fn block_labels(
    painter: &egui::Painter,
    rect: Rect,
    snap: &Snapshot,
    selected: Option<usize>,
    to_screen: &impl Fn([f64; 3]) -> Option<Pos2>,
) {
    for (i, b) in snap.blocks.iter().enumerate().take(300) {
        if let Some(c) = to_screen(b.centroid)
            && rect.contains(c)
        {
            let color = if selected == Some(i) {
                ACCENT
            } else {
                Color32::from_gray(20)
            };
            let galley = painter.layout_no_wrap(b.name.clone(), FontId::proportional(13.0), color);
            let r = Align2::CENTER_CENTER.anchor_size(c, galley.size());
            painter.rect_filled(
                r.expand(2.0),
                3.0,
                Color32::from_rgba_unmultiplied(255, 255, 255, 190),
            );
            painter.galley(r.min, galley, color);
        }
    }
}

/// A translucent card with lines of text, anchored at `anchor` of `rect` (inset by a margin).
fn card(painter: &egui::Painter, rect: Rect, anchor: Align2, lines: &[(String, Color32, bool)]) {
    let galleys: Vec<_> = lines
        .iter()
        .map(|(t, c, strong)| {
            let font = if *strong {
                FontId::proportional(15.0)
            } else {
                FontId::proportional(13.0)
            };
            painter.layout_no_wrap(t.clone(), font, *c)
        })
        .collect();
    let w = galleys.iter().map(|g| g.size().x).fold(0.0, f32::max);
    let h: f32 = galleys.iter().map(|g| g.size().y + 2.0).sum();
    let pad = 18.0;
    let inner = rect.shrink(pad);
    let r = anchor.align_size_within_rect(Vec2::new(w, h), inner);
    painter.rect_filled(
        r.expand(7.0),
        5.0,
        Color32::from_rgba_unmultiplied(255, 255, 255, 215),
    );
    let mut y = r.min.y;
    for (g, (_, c, _)) in galleys.into_iter().zip(lines) {
        let gh = g.size().y;
        painter.galley(Pos2::new(r.min.x, y), g, *c);
        y += gh + 2.0;
    }
}

/// The selected block's vital numbers, top right of the view (the full contact list is in
/// the panel).
fn selection_card(
    painter: &egui::Painter,
    rect: Rect,
    state: &UiState,
    snap: &Snapshot,
    i: usize,
    b: &BlockSnapshot,
) {
    let text = Color32::from_gray(25);
    let dim = Color32::from_gray(80);
    let u = DVec3::from_array(b.displacement).length();
    let v = DVec3::from_array(b.velocity).length();
    let contacts: Vec<_> = snap
        .contacts
        .iter()
        .filter(|c| c.block_i == i || c.block_j == i)
        .collect();
    let n: f64 = contacts.iter().map(|c| c.normal_force).sum();
    let sliding = contacts
        .iter()
        .filter(|c| c.state == ContactState::Slide)
        .count();
    let mut lines = vec![(
        format!("{}{}", b.name, if b.fixed { " (fixed)" } else { "" }),
        ACCENT,
        true,
    )];
    if let Some(info) = state.scene_file.blocks.get(i) {
        lines.push((format!("mass {} kg", num(info.mass)), dim, false));
    }
    lines.push((
        format!("|u| = {}    |v| = {} m/s", length(u), num(v)),
        text,
        false,
    ));
    lines.push((
        format!(
            "{} contacts ({} sliding), Σ N = {}",
            contacts.len(),
            sliding,
            format_force(n)
        ),
        text,
        false,
    ));
    lines.push(("details in the panel · Esc to clear".into(), dim, false));
    card(painter, rect, Align2::RIGHT_TOP, &lines);
}

/// Recording indicator and the latest message, bottom centre of the view.
fn status_toasts(ui: &egui::Ui, painter: &egui::Painter, rect: Rect, state: &UiState) {
    let mut lines = Vec::new();
    if let Some(r) = &state.recording {
        lines.push((
            format!("REC  {} frames to {}", r.frames, r.dir.display()),
            ERROR_RED,
            true,
        ));
    }
    const SHOW: Duration = Duration::from_secs(8);
    if let Some(m) = &state.message {
        let age = m.at.elapsed();
        if age < SHOW {
            let c = if m.error {
                ERROR_RED
            } else {
                Color32::from_gray(40)
            };
            lines.push((m.text.clone(), c, false));
            // Redraw when it should disappear, even if nothing else moves.
            ui.ctx().request_repaint_after(SHOW - age);
        }
    }
    if !lines.is_empty() {
        card(painter, rect, Align2::CENTER_BOTTOM, &lines);
    }
}
