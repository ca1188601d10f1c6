//! The 2-D layer over the 3-D view: caption (scene, simulated time, step), force-scale and
//! colour-map legends, and an axis triad. Painted with egui so the off-screen frames and the
//! interactive viewer (which already runs egui) share [`paint_overlay`].

use egui::{Align2, Color32, FontId, Pos2, Rect, Stroke, Vec2, epaint::Mesh};
use glam::Vec3;

use super::camera::Camera;
use super::mesh::{self, LOCK_SRGB, SLIDE_SRGB};
use super::scene::{FieldLegend, RenderScene};
use crate::text::short;

const TEXT: Color32 = Color32::from_rgb(0x20, 0x20, 0x20);
const TEXT_DIM: Color32 = Color32::from_rgb(0x44, 0x44, 0x44);
/// The equilibrium stage's colour (the caption's line, the viewer's toolbar label): the run has
/// not started yet.
pub const STAGE_AMBER: Color32 = Color32::from_rgb(0xB0, 0x70, 0x10);
/// Axis colours of the triad: x red, y green, z blue, the CAD convention.
const AXIS_COLORS: [Color32; 3] = [
    Color32::from_rgb(0xC0, 0x39, 0x2B),
    Color32::from_rgb(0x2E, 0x8B, 0x3E),
    Color32::from_rgb(0x2F, 0x5F, 0xB0),
];

fn color32(srgb: u32) -> Color32 {
    Color32::from_rgb((srgb >> 16) as u8, (srgb >> 8) as u8, srgb as u8)
}

/// A translucent white card behind text, so it reads over blocks and grid alike.
fn card(painter: &egui::Painter, rect: Rect, transparent_bg: bool) {
    let alpha = if transparent_bg { 150 } else { 205 };
    painter.rect_filled(
        rect.expand(7.0),
        5.0,
        Color32::from_rgba_unmultiplied(255, 255, 255, alpha),
    );
}

/// "12.5 kN", "800 N", "2 MN" — forces as an engineer writes them.
pub fn format_force(newtons: f64) -> String {
    let a = newtons.abs();
    let (v, unit) = if a >= 1e9 {
        (newtons / 1e9, "GN")
    } else if a >= 1e6 {
        (newtons / 1e6, "MN")
    } else if a >= 1e3 {
        (newtons / 1e3, "kN")
    } else {
        (newtons, "N")
    };
    format!("{} {unit}", trim_number(v))
}

/// Up to 3 significant decimals, no trailing zeros.
fn trim_number(v: f64) -> String {
    let s = format!("{v:.3}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".into() } else { s.into() }
}

/// Compact value for a colour-map end label.
fn format_value(v: f64) -> String {
    let a = v.abs();
    if a != 0.0 && !(1e-3..1e5).contains(&a) {
        format!("{v:.2e}")
    } else {
        trim_number(v)
    }
}

/// Simulated time with a precision that suits its size.
pub fn format_time(t: f64) -> String {
    if t.abs() < 100.0 {
        format!("{t:.3} s")
    } else {
        format!("{t:.1} s")
    }
}

/// Paints the caption (top left), legends (bottom left) and axis triad (bottom right) into
/// `rect` (egui points).
pub fn paint_overlay(painter: &egui::Painter, scene: &RenderScene, camera: &Camera, rect: Rect) {
    let pad = 18.0;
    paint_caption(painter, scene, rect.min + Vec2::splat(pad));
    // Legends, stacked upward from the bottom-left corner.
    let legends = Legends {
        painter,
        x: rect.min.x + pad,
        transparent: scene.transparent,
        font: FontId::proportional(15.0),
    };
    let mut y = rect.max.y - pad;
    if let Some(f) = &scene.field {
        y = legends.field(f, y);
    }
    if let Some(scale) = scene.force_scale {
        let counts = (scene.contacts_lock, scene.contacts_slide);
        y = legends.forces(scale, counts, scene.arrows_shown, y);
    }
    if let Some(step) = scene.grid_step {
        legends.grid(step, y);
    }
    paint_axis_triad(painter, camera, rect);
}

/// Scene name over simulated time and step (and the equilibrium stage's progress while it
/// runs), on a card at `top_left`.
fn paint_caption(painter: &egui::Painter, scene: &RenderScene, top_left: Pos2) {
    let title = painter.layout_no_wrap(
        if scene.caption.scene_name.is_empty() {
            "dda3d".to_owned()
        } else {
            scene.caption.scene_name.clone()
        },
        FontId::proportional(22.0),
        TEXT,
    );
    let sub = painter.layout_no_wrap(
        format!(
            "t = {}    step {}",
            format_time(scene.caption.time),
            scene.caption.step
        ),
        FontId::proportional(16.0),
        TEXT_DIM,
    );
    let stage = scene.caption.stage.map(|(steps, residual)| {
        painter.layout_no_wrap(
            // Before its first static step the stage has no residual yet (R_max is ∞).
            if residual.is_finite() {
                format!("equilibrium stage: step {steps}, R_max {}", short(residual))
            } else {
                format!("equilibrium stage: step {steps}")
            },
            FontId::proportional(16.0),
            STAGE_AMBER,
        )
    });
    let sub_pos = top_left + Vec2::new(0.0, title.size().y + 3.0);
    let stage_pos = sub_pos + Vec2::new(0.0, sub.size().y + 3.0);
    let (stage_w, stage_h) = stage
        .as_ref()
        .map_or((0.0, 0.0), |g| (g.size().x, g.size().y + 3.0));
    let caption_rect = Rect::from_min_size(
        top_left,
        Vec2::new(
            title.size().x.max(sub.size().x).max(stage_w),
            title.size().y + 3.0 + sub.size().y + stage_h,
        ),
    );
    card(painter, caption_rect, scene.transparent);
    painter.galley(top_left, title, TEXT);
    painter.galley(sub_pos, sub, TEXT_DIM);
    if let Some(g) = stage {
        painter.galley(stage_pos, g, STAGE_AMBER);
    }
}

/// The legend column at the left edge. Each legend is drawn with its bottom at `y` and returns
/// the `y` for the next one up.
struct Legends<'a> {
    painter: &'a egui::Painter,
    x: f32,
    transparent: bool,
    font: FontId,
}

impl Legends<'_> {
    /// Colour bar with its quantity, unit and end values.
    fn field(&self, f: &FieldLegend, y: f32) -> f32 {
        let (painter, x, font) = (self.painter, self.x, &self.font);
        let bar = Vec2::new(200.0, 12.0);
        let lo = painter.layout_no_wrap(format_value(f.min), font.clone(), TEXT);
        // A frame where every block has the same value (all at rest) has no range to show.
        let hi_text = if f.max > f.min {
            format_value(f.max)
        } else {
            "(all equal)".to_owned()
        };
        let hi = painter.layout_no_wrap(hi_text, font.clone(), TEXT);
        let label = painter.layout_no_wrap(format!("{} ({})", f.label, f.unit), font.clone(), TEXT);
        let h = label.size().y + 4.0 + bar.y + 3.0 + lo.size().y;
        let top = y - h;
        let block = Rect::from_min_size(Pos2::new(x, top), Vec2::new(bar.x.max(label.size().x), h));
        card(painter, block, self.transparent);
        painter.galley(Pos2::new(x, top), label.clone(), TEXT);
        let bar_rect = Rect::from_min_size(Pos2::new(x, top + label.size().y + 4.0), bar);
        painter.add(egui::Shape::mesh(colormap_bar(bar_rect.min, bar)));
        painter.rect_stroke(
            bar_rect,
            0.0,
            Stroke::new(1.0, TEXT_DIM),
            egui::StrokeKind::Outside,
        );
        let ly = bar_rect.max.y + 3.0;
        painter.galley(Pos2::new(x, ly), lo, TEXT);
        painter.galley(Pos2::new(bar_rect.max.x - hi.size().x, ly), hi, TEXT);
        top - 20.0
    }

    /// Arrow scale (and how many contacts have arrows, when not all), then sample arrows in the
    /// lock and slide colours with their counts.
    fn forces(
        &self,
        scale: f64,
        (locks, slides): (usize, usize),
        shown: Option<usize>,
        y: f32,
    ) -> f32 {
        let (painter, x, font) = (self.painter, self.x, &self.font);
        let strongest = shown.map_or(String::new(), |n| format!(" (the strongest {n})"));
        let line1 = painter.layout_no_wrap(
            format!(
                "contact force: 1 m of arrow = {}{strongest}",
                format_force(scale)
            ),
            font.clone(),
            TEXT,
        );
        let lock = painter.layout_no_wrap(format!("lock ({locks})"), font.clone(), TEXT);
        let slide = painter.layout_no_wrap(format!("slide ({slides})"), font.clone(), TEXT);
        let row = line1.size().y;
        let arrow_w = 34.0;
        let top = y - 2.0 * row - 6.0;
        let width = (arrow_w + 8.0 + line1.size().x)
            .max(2.0 * (arrow_w + 8.0) + lock.size().x + 16.0 + slide.size().x);
        card(
            painter,
            Rect::from_min_size(Pos2::new(x, top), Vec2::new(width, 2.0 * row + 6.0)),
            self.transparent,
        );
        let sample_arrow = |at: Pos2, color: Color32| {
            let mid = at.y + row * 0.5;
            painter.arrow(
                Pos2::new(at.x, mid),
                Vec2::new(arrow_w - 4.0, 0.0),
                Stroke::new(3.0, color),
            );
        };
        sample_arrow(Pos2::new(x, top), TEXT_DIM);
        painter.galley(Pos2::new(x + arrow_w + 8.0, top), line1, TEXT);
        let y2 = top + row + 6.0;
        sample_arrow(Pos2::new(x, y2), color32(LOCK_SRGB));
        let lock_w = lock.size().x;
        painter.galley(Pos2::new(x + arrow_w + 8.0, y2), lock, TEXT);
        let sx = x + arrow_w + 8.0 + lock_w + 16.0;
        sample_arrow(Pos2::new(sx, y2), color32(SLIDE_SRGB));
        painter.galley(Pos2::new(sx + arrow_w + 8.0, y2), slide, TEXT);
        top - 20.0
    }

    /// Grid spacing, as plain text (no card).
    fn grid(&self, step: f64, y: f32) {
        self.painter.text(
            Pos2::new(self.x, y),
            Align2::LEFT_BOTTOM,
            format!("grid {} m", trim_number(step)),
            FontId::proportional(13.0),
            TEXT_DIM,
        );
    }
}

/// The colour map from 0 (left) to 1 (right) across a `size` rectangle at `min`, in 32 bands.
fn colormap_bar(min: Pos2, size: Vec2) -> Mesh {
    const STEPS: usize = 32;
    let rect = Rect::from_min_size(min, size);
    let mut m = Mesh::default();
    for k in 0..=STEPS {
        let t = k as f32 / STEPS as f32;
        let c = mesh::linear_to_srgb(mesh::colormap(t));
        let c = Color32::from_rgb(
            (c[0] * 255.0).round() as u8,
            (c[1] * 255.0).round() as u8,
            (c[2] * 255.0).round() as u8,
        );
        let px = rect.min.x + t * size.x;
        m.colored_vertex(Pos2::new(px, rect.min.y), c);
        m.colored_vertex(Pos2::new(px, rect.max.y), c);
        if k > 0 {
            let i = (2 * k) as u32;
            m.add_triangle(i - 2, i - 1, i);
            m.add_triangle(i - 1, i + 1, i);
        }
    }
    m
}

/// World x, y, z as the camera sees them, bottom right; the axis nearest the eye is drawn last.
fn paint_axis_triad(painter: &egui::Painter, camera: &Camera, rect: Rect) {
    let (right, up, back) = camera.basis();
    let centre = Pos2::new(rect.max.x - 62.0, rect.max.y - 62.0);
    let len = 40.0;
    let mut axes: Vec<(usize, Vec3)> = vec![(0, Vec3::X), (1, Vec3::Y), (2, Vec3::Z)];
    axes.sort_by(|a, b| a.1.dot(back).total_cmp(&b.1.dot(back)));
    for (k, e) in axes {
        let d = Vec2::new(e.dot(right), -e.dot(up)) * len;
        let tip = centre + d;
        painter.line_segment([centre, tip], Stroke::new(2.5, AXIS_COLORS[k]));
        let dir = if d.length() > 1e-3 {
            d.normalized()
        } else {
            Vec2::new(1.0, 0.0)
        };
        painter.text(
            tip + dir * 10.0,
            Align2::CENTER_CENTER,
            ["x", "y", "z"][k],
            FontId::proportional(15.0),
            AXIS_COLORS[k],
        );
    }
    painter.circle_filled(centre, 2.5, TEXT_DIM);
}

/// egui context + egui-wgpu renderer that draw [`paint_overlay`] over a finished 3-D image.
pub struct Overlay {
    ctx: egui::Context,
    renderer: egui_wgpu::Renderer,
    max_texture_side: usize,
}

impl Overlay {
    /// An overlay for targets of `format` (single-sampled; drawn after the MSAA resolve).
    pub fn new(device: &wgpu::Device, format: wgpu::TextureFormat) -> Overlay {
        let renderer = egui_wgpu::Renderer::new(
            device,
            format,
            egui_wgpu::RendererOptions {
                msaa_samples: 1,
                depth_stencil_format: None,
                // Dithering adds noise; frames must be identical run to run.
                dithering: false,
                predictable_texture_filtering: false,
            },
        );
        Overlay {
            ctx: egui::Context::default(),
            renderer,
            max_texture_side: device.limits().max_texture_dimension_2d as usize,
        }
    }

    /// egui points per pixel: text and strokes are laid out for a 720-pixel-high image and
    /// scale with the height (never below 0.75 so small images keep legible text).
    pub fn pixels_per_point(height: u32) -> f32 {
        (height as f32 / 720.0).clamp(0.75, 8.0)
    }

    /// Records a pass that loads `target` and paints the overlay over it.
    #[allow(clippy::too_many_arguments)]
    pub fn encode(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        target: &wgpu::TextureView,
        width: u32,
        height: u32,
        scene: &RenderScene,
        camera: &Camera,
    ) {
        let ppp = Self::pixels_per_point(height);
        let rect = Rect::from_min_size(
            Pos2::ZERO,
            Vec2::new(width as f32 / ppp, height as f32 / ppp),
        );
        let mut input = egui::RawInput {
            screen_rect: Some(rect),
            max_texture_side: Some(self.max_texture_side),
            ..Default::default()
        };
        input
            .viewports
            .entry(egui::ViewportId::ROOT)
            .or_default()
            .native_pixels_per_point = Some(ppp);
        let output = self.ctx.run_pass(input, |ctx| {
            let painter = ctx.layer_painter(egui::LayerId::new(
                egui::Order::Foreground,
                egui::Id::unique("dda3d overlay"),
            ));
            paint_overlay(&painter, scene, camera, rect);
        });
        let primitives = self.ctx.tessellate(output.shapes, output.pixels_per_point);
        for (id, deltas) in &output.textures_delta.set {
            for delta in deltas {
                self.renderer.update_texture(device, queue, *id, delta);
            }
        }
        let screen = egui_wgpu::ScreenDescriptor {
            size_in_pixels: [width, height],
            pixels_per_point: output.pixels_per_point,
        };
        // No paint callbacks are used, so there are no extra command buffers to submit.
        let _ = self
            .renderer
            .update_buffers(device, queue, encoder, &primitives, &screen);
        {
            let pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("dda3d overlay"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: target,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Load,
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            let mut pass = pass.forget_lifetime();
            self.renderer.render(&mut pass, &primitives, &screen);
        }
        for id in &output.textures_delta.free {
            self.renderer.free_texture(id);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn number_formats() {
        assert_eq!(format_force(50_000.0), "50 kN");
        assert_eq!(format_force(2500.0), "2.5 kN");
        assert_eq!(format_force(800.0), "800 N");
        assert_eq!(format_force(2e6), "2 MN");
        assert_eq!(format_time(1.23456), "1.235 s");
        assert_eq!(format_time(1234.5), "1234.5 s");
        assert_eq!(format_value(0.0), "0");
        assert_eq!(format_value(1.5), "1.5");
        assert_eq!(format_value(1e-5), "1.00e-5");
        assert_eq!(trim_number(-0.0001), "0");
    }
}
