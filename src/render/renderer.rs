//! The 3-D pass: draws a [`RenderScene`] into any colour target of the format the [`Renderer`]
//! was built for (4× MSAA where supported, resolved into the target; depth in
//! [`DEPTH_FORMAT`]). One small renderer per primitive ([`solids`](super::solids),
//! [`arrows`](super::arrows), [`lines`](super::lines)) declares its pipeline; this room owns
//! what they share: the per-frame uniform block (camera, lights, viewport), the attachments,
//! and the order of the draws.

use bytemuck::Zeroable;
use glam::Vec3;

use super::RenderError;
use super::arrows::{ArrowRenderer, GHOST_ALPHA};
use super::camera::Camera;
use super::gpu::{DEPTH_FORMAT, Gpu};
use super::lines::{LINE_PULL, LineRenderer};
use super::mesh;
use super::pipeline::{ColorTarget, Uniform, pipeline_layout};
use super::scene::RenderScene;
use super::solids::SolidRenderer;

/// The uniform block of shaders/globals.wgsl (same layout, field for field).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Globals {
    view_proj: [[f32; 4]; 4],
    eye: [f32; 4],
    key_light: [f32; 4],
    fill_light: [f32; 4],
    viewport: [f32; 4],
    params: [f32; 4],
}

impl Globals {
    /// Camera and lights for a `width`×`height` target; `encode_srgb` is 1.0 when the shader
    /// must encode sRGB itself.
    fn new(camera: &Camera, width: u32, height: u32, encode_srgb: f32) -> Globals {
        // The lights turn with the camera, so every view is lit from the upper left and front.
        let (right, _up, back) = camera.basis();
        let key = (right * -0.35 + back * 0.55 + Vec3::Z * 0.75).normalize();
        let fill = (right * 0.75 + back * 0.45 - Vec3::Z * 0.15).normalize();
        // Line widths are given for a 720-pixel-high image and scale with the height.
        let line_scale = (height as f32 / 720.0).max(1.0);
        Globals {
            view_proj: camera.view_proj().to_cols_array_2d(),
            eye: camera.eye().extend(1.0).to_array(),
            key_light: key.extend(0.0).to_array(),
            fill_light: fill.extend(0.0).to_array(),
            viewport: [width as f32, height as f32, line_scale, LINE_PULL],
            params: [GHOST_ALPHA, encode_srgb, 0.0, 0.0],
        }
    }
}

/// The multisampled colour and depth attachments for one target size.
pub struct RenderTargets {
    pub width: u32,
    pub height: u32,
    /// `None` when the renderer runs without MSAA (then it draws straight into the output).
    pub msaa: Option<wgpu::TextureView>,
    pub depth: wgpu::TextureView,
}

/// Pipelines and per-frame buffers for drawing a [`RenderScene`].
pub struct Renderer {
    color_format: wgpu::TextureFormat,
    samples: u32,
    /// 1.0 when the shader must apply the sRGB encoding (non-sRGB target).
    encode_srgb: f32,
    globals: Uniform<Globals>,
    solids: SolidRenderer,
    arrows: ArrowRenderer,
    lines: LineRenderer,
    clear: wgpu::Color,
}

impl Renderer {
    /// Builds the pipelines for targets of `color_format`, with up to 4× MSAA (fewer where the
    /// adapter does not support it). Any RGBA/BGRA 8-bit format works: for a non-sRGB target
    /// (a typical window surface that egui also draws into) the shader encodes sRGB itself.
    pub fn new(gpu: &Gpu, color_format: wgpu::TextureFormat) -> Renderer {
        Renderer::with_max_samples(gpu, color_format, 4)
    }

    /// As [`Renderer::new`] with at most `max_samples` MSAA samples (1 turns MSAA off).
    pub fn with_max_samples(
        gpu: &Gpu,
        color_format: wgpu::TextureFormat,
        max_samples: u32,
    ) -> Renderer {
        let device = &gpu.device;
        let target = ColorTarget {
            format: color_format,
            samples: gpu.msaa_samples(color_format, max_samples),
        };
        let globals = Uniform::new(
            device,
            "dda3d globals",
            &Globals::zeroed(),
            wgpu::ShaderStages::VERTEX_FRAGMENT,
        );
        let layout = pipeline_layout(device, "dda3d", &[globals.layout()]);
        Renderer {
            color_format,
            samples: target.samples,
            encode_srgb: if color_format.is_srgb() { 0.0 } else { 1.0 },
            solids: SolidRenderer::new(device, &layout, target),
            arrows: ArrowRenderer::new(device, &layout, target),
            lines: LineRenderer::new(device, &layout, target),
            globals,
            clear: wgpu::Color::WHITE,
        }
    }

    /// MSAA sample count in use (4, or 1 where unsupported).
    pub fn samples(&self) -> u32 {
        self.samples
    }

    pub fn color_format(&self) -> wgpu::TextureFormat {
        self.color_format
    }

    /// Attachments for a `width`×`height` target.
    pub fn create_targets(&self, device: &wgpu::Device, width: u32, height: u32) -> RenderTargets {
        let size = wgpu::Extent3d {
            width: width.max(1),
            height: height.max(1),
            depth_or_array_layers: 1,
        };
        let attachment = |label: &str, format: wgpu::TextureFormat| {
            device
                .create_texture(&wgpu::TextureDescriptor {
                    label: Some(label),
                    size,
                    mip_level_count: 1,
                    sample_count: self.samples,
                    dimension: wgpu::TextureDimension::D2,
                    format,
                    usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
                    view_formats: &[],
                })
                .create_view(&Default::default())
        };
        RenderTargets {
            width: size.width,
            height: size.height,
            msaa: (self.samples > 1).then(|| attachment("dda3d msaa colour", self.color_format)),
            depth: attachment("dda3d depth", DEPTH_FORMAT),
        }
    }

    /// Uploads the scene and camera for the next [`Renderer::draw`]. The camera's aspect should
    /// match the target.
    pub fn prepare(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: &RenderScene,
        camera: &Camera,
        width: u32,
        height: u32,
    ) -> Result<(), RenderError> {
        check_buffer_sizes(device, scene)?;
        self.globals.write(
            queue,
            &Globals::new(camera, width, height, self.encode_srgb),
        );
        self.solids.upload(device, queue, &scene.solids);
        self.arrows
            .upload(device, queue, &scene.arrows, camera, height);
        self.lines.upload(device, queue, &scene.lines);
        let mut bg = scene.background();
        if self.encode_srgb > 0.5 {
            // The clear value is stored as given, so a non-sRGB target needs it encoded.
            bg = mesh::linear_to_srgb(bg);
        }
        self.clear = wgpu::Color {
            r: bg[0] as f64,
            g: bg[1] as f64,
            b: bg[2] as f64,
            a: bg[3] as f64,
        };
        Ok(())
    }

    /// Background colour of the last prepared scene (linear; alpha 0 when transparent).
    pub fn clear_color(&self) -> wgpu::Color {
        self.clear
    }

    /// Records the draws into a pass whose attachments come from [`Renderer::create_targets`].
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>) {
        pass.set_bind_group(0, self.globals.bind_group(), &[]);
        self.solids.draw(pass);
        self.arrows.draw(pass);
        self.lines.draw(pass);
        // Last, so the faint copy blends over whatever hides the arrow.
        self.arrows.draw_hidden(pass);
    }

    /// Begins a pass that clears `targets` to the scene background, draws, and resolves into
    /// `output` (a single-sample view of the renderer's colour format).
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        targets: &RenderTargets,
        output: &wgpu::TextureView,
    ) {
        let (view, resolve_target) = match &targets.msaa {
            Some(msaa) => (msaa, Some(output)),
            None => (output, None),
        };
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("dda3d scene"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(self.clear),
                    // The multisampled samples are not needed after the resolve.
                    store: if resolve_target.is_some() {
                        wgpu::StoreOp::Discard
                    } else {
                        wgpu::StoreOp::Store
                    },
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &targets.depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Discard,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        self.draw(&mut pass);
    }
}

/// Refuses a scene whose geometry would not fit in one buffer of this device.
fn check_buffer_sizes(device: &wgpu::Device, scene: &RenderScene) -> Result<(), RenderError> {
    let max = device.limits().max_buffer_size;
    for (what, bytes) in [
        (
            "block faces",
            std::mem::size_of_val(scene.solids.as_slice()),
        ),
        ("arrows", std::mem::size_of_val(scene.arrows.as_slice())),
        ("lines", std::mem::size_of_val(scene.lines.as_slice())),
    ] {
        if bytes as u64 > max {
            return Err(RenderError::InvalidSnapshot(format!(
                "{what} need {bytes} bytes of vertex data; this GPU allows {max} per buffer"
            )));
        }
    }
    Ok(())
}
