//! The last composed window picture, shown again while nothing in it changed.
//!
//! On a software rasterizer the window's egui pass (panels plus the 3-D view's image) costs
//! about 11 ms of llvmpipe time at 1280×800 even when the picture is the one already on screen,
//! and while a large model runs the solver publishes a new state only a few times a second: a
//! struck wall of 1000 blocks, playing at 30 frames/s, drew 123 of 150 frames identical to the
//! one before, and those passes took the cores the solver needed. egui is therefore drawn into
//! this texture, which is copied into the surface, and a frame whose egui shapes, textures, size
//! and 3-D views are all unchanged only copies it again (about a millisecond). Every frame is
//! still presented, so the window stays as responsive as before. GPUs draw straight into the
//! surface: the copy would save them nothing.

use egui::epaint::ClippedShape;

use crate::render::Gpu;
use crate::render::offscreen::readable_target;

/// The composed picture and what it was made of.
pub(super) struct FrameCache {
    /// The texture (egui's format) and a view of it.
    texture: Option<(wgpu::Texture, wgpu::TextureView)>,
    /// Its size in pixels.
    size: Option<(u32, u32)>,
    /// The egui shapes and points-to-pixels scale of the picture in the texture.
    shapes: Vec<ClippedShape>,
    pixels_per_point: f32,
    /// The texture holds a complete picture.
    valid: bool,
}

/// What a frame brings that could change the picture.
pub(super) struct FrameInputs<'a> {
    pub shapes: &'a [ClippedShape],
    pub pixels_per_point: f32,
    pub size: (u32, u32),
    /// egui set or replaced a texture (the font atlas, a plot image).
    pub textures_changed: bool,
    /// A 3-D view was drawn anew this frame.
    pub view_redrawn: bool,
}

impl FrameCache {
    pub fn new() -> FrameCache {
        FrameCache {
            texture: None,
            size: None,
            shapes: Vec::new(),
            pixels_per_point: 0.0,
            valid: false,
        }
    }

    /// Whether the picture in the texture is the one this frame would draw.
    pub fn unchanged(&self, f: &FrameInputs) -> bool {
        self.valid
            && !f.view_redrawn
            && !f.textures_changed
            && self.size == Some(f.size)
            && self.pixels_per_point == f.pixels_per_point
            && self.shapes == f.shapes
    }

    /// The texture to draw this frame's egui pass into: `size` pixels in egui's `format`, a
    /// target like the window capture's (its copy into the surface may add or drop the sRGB
    /// encoding). Invalid until [`Self::keep`].
    pub fn target(
        &mut self,
        gpu: &Gpu,
        format: wgpu::TextureFormat,
        size: (u32, u32),
    ) -> &wgpu::TextureView {
        self.valid = false;
        if self.texture.is_none() || self.size != Some(size) {
            let texture =
                readable_target(&gpu.device, "dda3d composed window", format, size.0, size.1);
            let view = texture.create_view(&Default::default());
            self.texture = Some((texture, view));
            self.size = Some(size);
        }
        &self.texture.as_ref().expect("just made").1
    }

    /// The texture now holds the picture of `shapes` at `pixels_per_point`.
    pub fn keep(&mut self, shapes: Vec<ClippedShape>, pixels_per_point: f32) {
        self.shapes = shapes;
        self.pixels_per_point = pixels_per_point;
        self.valid = self.texture.is_some();
    }

    /// Records the copy of the picture into the surface's texture (of the same size).
    pub fn copy_to(&self, encoder: &mut wgpu::CommandEncoder, surface: &wgpu::Texture) {
        let (Some((texture, _)), Some((w, h))) = (&self.texture, self.size) else {
            return;
        };
        encoder.copy_texture_to_texture(
            texture.as_image_copy(),
            surface.as_image_copy(),
            wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shape(x: f32) -> ClippedShape {
        ClippedShape {
            clip_rect: egui::Rect::EVERYTHING,
            shape: egui::Shape::circle_filled(egui::pos2(x, 1.0), 2.0, egui::Color32::RED),
            transform_after_tessellation: Default::default(),
        }
    }

    fn inputs(shapes: &[ClippedShape]) -> FrameInputs<'_> {
        FrameInputs {
            shapes,
            pixels_per_point: 1.0,
            size: (4, 3),
            textures_changed: false,
            view_redrawn: false,
        }
    }

    /// A cache that holds a 4×3 picture of `shapes` (its texture left out: no GPU here).
    fn holding(shapes: &[ClippedShape]) -> FrameCache {
        FrameCache {
            texture: None,
            size: Some((4, 3)),
            shapes: shapes.to_vec(),
            pixels_per_point: 1.0,
            valid: true,
        }
    }

    #[test]
    fn the_same_frame_is_reused() {
        let s = vec![shape(1.0), shape(2.0)];
        assert!(holding(&s).unchanged(&inputs(&s)));
    }

    #[test]
    fn an_empty_or_unfinished_cache_is_not_reused() {
        let s = vec![shape(1.0)];
        assert!(!FrameCache::new().unchanged(&inputs(&s)));
        let mut c = holding(&s);
        c.valid = false;
        assert!(!c.unchanged(&inputs(&s)));
    }

    #[test]
    fn any_change_draws_a_new_picture() {
        let s = vec![shape(1.0)];
        let c = holding(&s);
        let moved = vec![shape(1.5)];
        let more = vec![shape(1.0), shape(1.0)];
        let mut variants = Vec::new();
        for k in 0..6 {
            let mut i = inputs(&s);
            match k {
                0 => i.view_redrawn = true,
                1 => i.textures_changed = true,
                2 => i.size = (5, 3),
                3 => i.pixels_per_point = 2.0,
                4 => i.shapes = &moved,
                _ => i.shapes = &more,
            }
            variants.push(i);
        }
        for (k, i) in variants.iter().enumerate() {
            assert!(!c.unchanged(i), "change {k} went unseen");
        }
    }
}
