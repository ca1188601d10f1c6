//! wgpu renderer for dda3d snapshots, shared by the headless frame capture and the interactive
//! viewer so both draw the same picture.
//!
//! Layers, bottom up:
//! - [`camera`], [`mesh`], [`scene`]: CPU-side camera and geometry (unit-tested without a GPU);
//! - [`Gpu`]: adapter/device/queue, created apart from the drawing so a window can bring its own;
//! - [`Renderer`]: pipelines and buffers; records the 3-D pass (4× MSAA where supported,
//!   Depth32Float) into any colour target of the format it was built for;
//! - [`overlay`]: caption, legends and axis triad, painted with egui;
//! - [`offscreen`]: an off-screen target with row-aligned readback;
//! - [`capture`]: the pipelined PNG/GIF frame writer.

pub mod camera;
pub mod capture;
pub mod mesh;
pub mod offscreen;
pub mod overlay;
pub mod scene;

use std::path::PathBuf;
use std::sync::{Arc, Mutex};

use bytemuck::Zeroable;
use glam::Vec3;
use wgpu::util::DeviceExt;

pub use camera::{Camera, CameraOverride, Ray};
pub use capture::{CaptureOptions, CaptureReport, FrameCapture, Framing, render_to_png};
pub use offscreen::Offscreen;
pub use overlay::{Overlay, paint_overlay};
pub use scene::{ArrowMode, Coloring, Scene, SceneFrame, SceneStyle};

use mesh::{LineInstance, SolidVertex};

/// Everything that can go wrong between a snapshot and a file on disk.
#[derive(Clone, Debug, thiserror::Error)]
pub enum RenderError {
    /// No GPU adapter at all (no driver). The CLI maps this to exit status 2.
    #[error(
        "no GPU adapter found; install a GPU driver or the software Vulkan driver \
         (Debian/Ubuntu: apt-get install libvulkan1 mesa-vulkan-drivers)"
    )]
    NoAdapter,
    #[error("could not open the GPU device: {0}")]
    Device(String),
    /// A validation or out-of-memory error reported by wgpu while drawing.
    #[error("GPU error: {0}")]
    Gpu(String),
    #[error("invalid render options: {0}")]
    InvalidOptions(String),
    #[error("cannot draw snapshot: {0}")]
    InvalidSnapshot(String),
    #[error("{path}: {message}")]
    Io { path: PathBuf, message: String },
    #[error("image encoding failed: {0}")]
    Encode(String),
    /// The capture's worker threads stopped (the message says why).
    #[error("frame capture stopped: {0}")]
    Stopped(String),
}

impl RenderError {
    pub(crate) fn io(path: impl Into<PathBuf>, e: impl std::fmt::Display) -> RenderError {
        RenderError::Io {
            path: path.into(),
            message: e.to_string(),
        }
    }
}

/// True when the environment demands a GPU adapter (`DDA3D_REQUIRE_GPU=1`, set by CI), so a
/// missing adapter must fail a test instead of skipping it.
pub fn gpu_required_by_env() -> bool {
    std::env::var("DDA3D_REQUIRE_GPU")
        .map(|v| {
            let v = v.trim();
            !v.is_empty() && v != "0" && !v.eq_ignore_ascii_case("false")
        })
        .unwrap_or(false)
}

/// A wgpu device and queue plus the adapter they came from.
#[derive(Clone)]
pub struct Gpu {
    pub instance: wgpu::Instance,
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    /// First uncaptured wgpu error (validation, out of memory) since the last check; wgpu's
    /// default handler would panic instead.
    errors: Arc<Mutex<Option<String>>>,
}

impl Gpu {
    /// Opens the best adapter without any window system (works over SSH and in CI). Honours
    /// wgpu's environment variables (`WGPU_BACKEND`, `WGPU_ADAPTER_NAME`, ...).
    pub fn headless() -> Result<Gpu, RenderError> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle().with_env());
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            compatible_surface: None,
            ..Default::default()
        }))
        .map_err(|_| RenderError::NoAdapter)?;
        Gpu::from_adapter(instance, adapter)
    }

    /// Opens a device on a chosen adapter (the interactive viewer picks one compatible with
    /// its window surface).
    pub fn from_adapter(
        instance: wgpu::Instance,
        adapter: wgpu::Adapter,
    ) -> Result<Gpu, RenderError> {
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("dda3d"),
            required_features: wgpu::Features::empty(),
            // What the adapter offers, so large captures are limited by the hardware only.
            required_limits: adapter.limits(),
            ..Default::default()
        }))
        .map_err(|e| RenderError::Device(e.to_string()))?;
        let errors: Arc<Mutex<Option<String>>> = Arc::new(Mutex::new(None));
        let sink = errors.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            if let Ok(mut slot) = sink.lock() {
                slot.get_or_insert_with(|| e.to_string());
            }
        }));
        Ok(Gpu {
            instance,
            adapter,
            device,
            queue,
            errors,
        })
    }

    /// "name (backend, type)" of the adapter, for logs and the benchmark report.
    pub fn adapter_summary(&self) -> String {
        let i = self.adapter.get_info();
        format!("{} ({:?}, {:?})", i.name, i.backend, i.device_type)
    }

    /// Returns (and clears) the first wgpu error reported since the last call.
    pub fn take_error(&self) -> Result<(), RenderError> {
        match self.errors.lock().ok().and_then(|mut e| e.take()) {
            Some(msg) => Err(RenderError::Gpu(msg)),
            None => Ok(()),
        }
    }

    /// Largest MSAA sample count ≤ `wanted` that both `color` and Depth32Float support as
    /// render attachments (1 always works).
    pub fn msaa_samples(&self, color: wgpu::TextureFormat, wanted: u32) -> u32 {
        let c = self.adapter.get_texture_format_features(color).flags;
        let d = self.adapter.get_texture_format_features(DEPTH_FORMAT).flags;
        [16, 8, 4, 2]
            .into_iter()
            .find(|&n| n <= wanted && c.sample_count_supported(n) && d.sample_count_supported(n))
            .unwrap_or(1)
    }
}

pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// Off-screen colour format: sRGB so lighting is computed in linear light and the bytes read
/// back are ready for PNG.
pub const OFFSCREEN_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
/// Opacity of arrows where a block hides them.
const GHOST_ALPHA: f32 = 0.35;
/// Outline endpoints move this fraction of the way to the eye (see scene.wgsl).
const LINE_PULL: f32 = 0.002;

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

/// A vertex buffer that grows (to the next power of two) when a frame needs more room.
struct GrowBuffer {
    label: &'static str,
    /// Bytes per element.
    stride: u64,
    buffer: Option<wgpu::Buffer>,
    len: u32,
}

impl GrowBuffer {
    fn new<T>(label: &'static str) -> GrowBuffer {
        GrowBuffer {
            label,
            stride: std::mem::size_of::<T>() as u64,
            buffer: None,
            len: 0,
        }
    }

    fn upload<T: bytemuck::Pod>(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, data: &[T]) {
        self.len = data.len() as u32;
        if data.is_empty() {
            return;
        }
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let need = bytes.len() as u64;
        match &self.buffer {
            Some(b) if b.size() >= need => queue.write_buffer(b, 0, bytes),
            _ => {
                // Grow geometrically so a slowly growing scene does not reallocate every frame,
                // but never past what the device allows (checked in `prepare`).
                let size = need
                    .next_power_of_two()
                    .max(4096)
                    .min(device.limits().max_buffer_size.max(need));
                let b = device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(self.label),
                    size,
                    usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                });
                queue.write_buffer(&b, 0, bytes);
                self.buffer = Some(b);
            }
        }
    }

    fn slice(&self) -> Option<wgpu::BufferSlice<'_>> {
        if self.len == 0 {
            return None;
        }
        let size = self.len as u64 * self.stride;
        self.buffer.as_ref().map(|b| b.slice(..size))
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

/// Pipelines and per-frame buffers for drawing a [`Scene`].
pub struct Renderer {
    color_format: wgpu::TextureFormat,
    samples: u32,
    /// 1.0 when the shader must apply the sRGB encoding (non-sRGB target).
    encode_srgb: f32,
    globals: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    solid: wgpu::RenderPipeline,
    ghost: wgpu::RenderPipeline,
    line: wgpu::RenderPipeline,
    solids: GrowBuffer,
    arrows: GrowBuffer,
    lines: GrowBuffer,
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
        let samples = gpu.msaa_samples(color_format, max_samples);
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("dda3d scene.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("../../shaders/scene.wgsl").into()),
        });
        let globals = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("dda3d globals"),
            contents: bytemuck::bytes_of(&Globals::zeroed()),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        let bgl = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("dda3d globals"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            }],
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("dda3d globals"),
            layout: &bgl,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: globals.as_entire_binding(),
            }],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("dda3d"),
            bind_group_layouts: &[Some(&bgl)],
            immediate_size: 0,
        });

        let solid_attrs = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x4];
        let solid_layout = wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<SolidVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &solid_attrs,
        };
        let line_attrs = wgpu::vertex_attr_array![
            0 => Float32x3, 1 => Float32, 2 => Float32x3, 3 => Float32x4
        ];
        // `b` starts at byte 16 (after a: 12 and width: 4); colour at 32 (after _pad).
        let line_attrs = [
            line_attrs[0],
            line_attrs[1],
            wgpu::VertexAttribute {
                offset: 16,
                ..line_attrs[2]
            },
            wgpu::VertexAttribute {
                offset: 32,
                ..line_attrs[3]
            },
        ];
        let line_layout = wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<LineInstance>() as u64,
            step_mode: wgpu::VertexStepMode::Instance,
            attributes: &line_attrs,
        };

        let make = |label: &str,
                    vs: &str,
                    fs: &str,
                    buffers: &[Option<wgpu::VertexBufferLayout>],
                    depth_write: bool,
                    compare: wgpu::CompareFunction,
                    blend: Option<wgpu::BlendState>| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(&layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some(vs),
                    compilation_options: Default::default(),
                    buffers,
                },
                primitive: wgpu::PrimitiveState {
                    topology: wgpu::PrimitiveTopology::TriangleList,
                    // No culling: faces are lit two-sided, and a block given with the wrong
                    // winding must still show up.
                    cull_mode: None,
                    ..Default::default()
                },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: DEPTH_FORMAT,
                    depth_write_enabled: Some(depth_write),
                    depth_compare: Some(compare),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                multisample: wgpu::MultisampleState {
                    count: samples,
                    ..Default::default()
                },
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some(fs),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format: color_format,
                        blend,
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let solid = make(
            "dda3d solids",
            "vs_solid",
            "fs_solid",
            &[Some(solid_layout.clone())],
            true,
            wgpu::CompareFunction::LessEqual,
            None,
        );
        let ghost = make(
            "dda3d hidden arrows",
            "vs_solid",
            "fs_ghost",
            &[Some(solid_layout)],
            false,
            wgpu::CompareFunction::Greater,
            Some(wgpu::BlendState::PREMULTIPLIED_ALPHA_BLENDING),
        );
        let line = make(
            "dda3d lines",
            "vs_line",
            "fs_line",
            &[Some(line_layout)],
            true,
            wgpu::CompareFunction::LessEqual,
            None,
        );
        Renderer {
            color_format,
            samples,
            encode_srgb: if color_format.is_srgb() { 0.0 } else { 1.0 },
            globals,
            bind_group,
            solid,
            ghost,
            line,
            solids: GrowBuffer::new::<SolidVertex>("dda3d solids"),
            arrows: GrowBuffer::new::<SolidVertex>("dda3d arrows"),
            lines: GrowBuffer::new::<LineInstance>("dda3d lines"),
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
        let msaa = (self.samples > 1).then(|| {
            device
                .create_texture(&wgpu::TextureDescriptor {
                    label: Some("dda3d msaa colour"),
                    size,
                    mip_level_count: 1,
                    sample_count: self.samples,
                    dimension: wgpu::TextureDimension::D2,
                    format: self.color_format,
                    usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
                    view_formats: &[],
                })
                .create_view(&Default::default())
        });
        let depth = device
            .create_texture(&wgpu::TextureDescriptor {
                label: Some("dda3d depth"),
                size,
                mip_level_count: 1,
                sample_count: self.samples,
                dimension: wgpu::TextureDimension::D2,
                format: DEPTH_FORMAT,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
                view_formats: &[],
            })
            .create_view(&Default::default());
        RenderTargets {
            width: size.width,
            height: size.height,
            msaa,
            depth,
        }
    }

    /// Uploads the scene and camera for the next [`Renderer::draw`]. The camera's aspect should
    /// match the target.
    pub fn prepare(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: &Scene,
        camera: &Camera,
        width: u32,
        height: u32,
    ) -> Result<(), RenderError> {
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
        let (right, _up, back) = camera.basis();
        let key = (right * -0.35 + back * 0.55 + Vec3::Z * 0.75).normalize();
        let fill = (right * 0.75 + back * 0.45 - Vec3::Z * 0.15).normalize();
        // Line widths are given for a 720-pixel-high image and scale with the height.
        let line_scale = (height as f32 / 720.0).max(1.0);
        let globals = Globals {
            view_proj: camera.view_proj().to_cols_array_2d(),
            eye: camera.eye().extend(1.0).to_array(),
            key_light: key.extend(0.0).to_array(),
            fill_light: fill.extend(0.0).to_array(),
            viewport: [width as f32, height as f32, line_scale, LINE_PULL],
            params: [GHOST_ALPHA, self.encode_srgb, 0.0, 0.0],
        };
        queue.write_buffer(&self.globals, 0, bytemuck::bytes_of(&globals));
        self.solids.upload(device, queue, &scene.solids);
        self.arrows.upload(device, queue, &scene.arrows);
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
        pass.set_bind_group(0, &self.bind_group, &[]);
        if let Some(s) = self.solids.slice() {
            pass.set_pipeline(&self.solid);
            pass.set_vertex_buffer(0, s);
            pass.draw(0..self.solids.len, 0..1);
        }
        if let Some(s) = self.arrows.slice() {
            pass.set_pipeline(&self.solid);
            pass.set_vertex_buffer(0, s);
            pass.draw(0..self.arrows.len, 0..1);
        }
        if let Some(s) = self.lines.slice() {
            pass.set_pipeline(&self.line);
            pass.set_vertex_buffer(0, s);
            pass.draw(0..6, 0..self.lines.len);
        }
        // Last, so the faint copy blends over whatever hides the arrow.
        if let Some(s) = self.arrows.slice() {
            pass.set_pipeline(&self.ghost);
            pass.set_vertex_buffer(0, s);
            pass.draw(0..self.arrows.len, 0..1);
        }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_adapter_message_says_what_to_install() {
        let msg = RenderError::NoAdapter.to_string();
        assert!(
            msg.contains("apt-get install libvulkan1 mesa-vulkan-drivers"),
            "{msg}"
        );
        assert!(!msg.contains('\n'), "one line");
    }
}
