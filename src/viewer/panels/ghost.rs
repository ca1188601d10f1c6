//! Run B as a translucent ghost over run A's pane (the one-pane mode of a comparison): B's
//! movable blocks as filled faces and outlines, projected with the shared camera and drawn by
//! egui over A's picture, so where the two runs part is seen in place.

use egui::{Color32, Pos2, Rect, Shape, Stroke};

use crate::snapshot::Snapshot;
use crate::viewer::state::UiState;

/// Blocks drawn as a ghost at most: every face is an egui shape, and a rock mass of thousands
/// of blocks would cost more than the pane itself.
const GHOST_BLOCKS: usize = 2000;
/// B's colour in the ghost (the blue of B's dashed lines in the plots), with its face and edge
/// opacity.
const GHOST_FILL: Color32 = Color32::from_rgba_premultiplied(0x09, 0x13, 0x23, 0x30);
const GHOST_EDGE: Color32 = Color32::from_rgba_premultiplied(0x2F, 0x5F, 0xB0, 0xD0);

/// Draws B's snapshot over `rect` (A's pane), seen by the shared camera.
pub fn paint(painter: &egui::Painter, state: &UiState, b: &Snapshot, rect: Rect) {
    let to_screen = super::view_3d::projector(state, rect);
    for block in b.blocks.iter().filter(|b| !b.fixed).take(GHOST_BLOCKS) {
        let pts: Vec<Option<Pos2>> = block.vertices.iter().map(|v| to_screen(*v)).collect();
        for face in &block.faces {
            let poly: Option<Vec<Pos2>> = face
                .iter()
                .map(|&k| pts.get(k as usize).copied().flatten())
                .collect();
            if let Some(poly) = poly.filter(|p| p.len() >= 3) {
                painter.add(Shape::convex_polygon(
                    poly,
                    GHOST_FILL,
                    Stroke::new(1.2, GHOST_EDGE),
                ));
            }
        }
    }
}
