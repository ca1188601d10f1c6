//! The 3-D view's render target: a colour texture egui shows as an image, plus the renderer's
//! MSAA and depth attachments, sized to the view in pixels and redrawn only when the picture
//! changes.

use crate::render::{Camera, Gpu, RenderError, RenderScene, RenderTargets, Renderer};
use crate::viewer::painter::EguiPainter;

/// The colour format of the view texture: non-sRGB like the window (the renderer then encodes
/// sRGB in its shader), so egui shows its bytes as they are.
const VIEW_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

pub(super) struct ViewTarget {
    pub renderer: Renderer,
    targets: RenderTargets,
    view: wgpu::TextureView,
    /// The texture as egui knows it.
    pub id: egui::TextureId,
    pub size: (u32, u32),
    /// (scene version, camera, size) of the picture in the texture.
    drawn: Option<(u64, Camera, (u32, u32))>,
}

impl ViewTarget {
    pub fn new(gpu: &Gpu, egui: &mut EguiPainter, samples: u32) -> ViewTarget {
        let renderer = Renderer::with_max_samples(gpu, VIEW_FORMAT, samples);
        let (targets, view) = Self::textures(gpu, &renderer, 1, 1);
        let id = egui.register_native_texture(&gpu.device, &view);
        ViewTarget {
            renderer,
            targets,
            view,
            id,
            size: (1, 1),
            drawn: None,
        }
    }

    fn textures(
        gpu: &Gpu,
        renderer: &Renderer,
        w: u32,
        h: u32,
    ) -> (RenderTargets, wgpu::TextureView) {
        let targets = renderer.create_targets(&gpu.device, w, h);
        let tex = gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("dda3d view"),
            size: wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: VIEW_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        (targets, tex.create_view(&Default::default()))
    }

    pub fn resize(&mut self, gpu: &Gpu, egui: &mut EguiPainter, w: u32, h: u32) {
        let max = gpu.device.limits().max_texture_dimension_2d;
        let (w, h) = (w.clamp(1, max), h.clamp(1, max));
        if (w, h) == self.size {
            return;
        }
        let (targets, view) = Self::textures(gpu, &self.renderer, w, h);
        egui.update_native_texture(&gpu.device, &view, self.id);
        self.targets = targets;
        self.view = view;
        self.size = (w, h);
        self.drawn = None;
    }

    /// Records the drawing of `scene` (at `version`) seen by `camera`, unless the texture
    /// already holds that picture: it keeps its picture between frames. Returns whether it drew.
    pub fn draw(
        &mut self,
        gpu: &Gpu,
        encoder: &mut wgpu::CommandEncoder,
        scene: &RenderScene,
        camera: &Camera,
        version: u64,
    ) -> Result<bool, RenderError> {
        let (w, h) = self.size;
        let key = (version, camera.clone(), (w, h));
        if self.drawn.as_ref() == Some(&key) {
            return Ok(false);
        }
        self.renderer
            .prepare(&gpu.device, &gpu.queue, scene, camera, w, h)?;
        self.renderer.encode(encoder, &self.targets, &self.view);
        self.drawn = Some(key);
        Ok(true)
    }
}
