//! The window and what draws into it: the winit window with its wgpu surface (the GPU is the
//! one that can present there), and egui's context, input state and painter.

use std::sync::Arc;

use winit::dpi::PhysicalSize;
use winit::event_loop::ActiveEventLoop;
use winit::window::Window;

use crate::render::Gpu;
use crate::viewer::ViewerError;
use crate::viewer::painter::EguiPainter;

/// The window, its surface and the surface's configuration.
pub(super) struct WindowSurface {
    pub window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    pub config: wgpu::SurfaceConfiguration,
    /// The format egui draws in: the surface's, or its non-sRGB view.
    pub render_format: wgpu::TextureFormat,
}

/// What [`WindowSurface::acquire`] got.
pub(super) enum Acquired {
    /// Draw into this texture. `suboptimal`: it still works, but the surface has been
    /// reconfigured for the next frame, which should follow at once.
    Texture {
        texture: wgpu::SurfaceTexture,
        suboptimal: bool,
    },
    /// Nothing to draw into now (timed out, or the window is hidden): try again shortly.
    Later,
    /// The surface no longer matched the window and has been reconfigured: skip this frame.
    Reconfigured,
}

/// Whether the GPU is a software rasterizer, which competes with the solver for the CPU.
pub(super) fn is_software(gpu: &Gpu) -> bool {
    gpu.adapter.get_info().device_type == wgpu::DeviceType::Cpu
}

impl WindowSurface {
    /// Opens a `size` window titled after the scene and finds a GPU that can draw into it.
    pub fn open(
        el: &ActiveEventLoop,
        scene_name: &str,
        size: (u32, u32),
    ) -> Result<(WindowSurface, Gpu), ViewerError> {
        let attrs = Window::default_attributes()
            .with_title(format!("dda3d — {scene_name}"))
            .with_inner_size(PhysicalSize::new(size.0, size.1))
            .with_min_inner_size(PhysicalSize::new(640, 400));
        let window = Arc::new(
            el.create_window(attrs)
                .map_err(|e| ViewerError::Failed(format!("cannot create a window: {e}")))?,
        );
        let (surface, gpu) = connect_gpu(el, &window)?;
        let caps = surface.get_capabilities(&gpu.adapter);
        let (format, render_format) = egui_formats(&caps, &gpu)?;
        let config = surface_config(&caps, &gpu, window.inner_size(), format, render_format);
        surface.configure(&gpu.device, &config);
        Ok((
            WindowSurface {
                window,
                surface,
                config,
                render_format,
            },
            gpu,
        ))
    }

    /// Follows the window's size (a minimised window keeps the old one) and asks for a frame.
    pub fn resize(&mut self, gpu: &Gpu, size: PhysicalSize<u32>) {
        if size.width == 0 || size.height == 0 {
            return; // minimised
        }
        self.config.width = size.width;
        self.config.height = size.height;
        self.surface.configure(&gpu.device, &self.config);
        self.window.request_redraw();
    }

    /// The texture to draw this frame into, if there is one.
    pub fn acquire(&mut self, gpu: &Gpu) -> Result<Acquired, ViewerError> {
        Ok(match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(texture) => Acquired::Texture {
                texture,
                suboptimal: false,
            },
            wgpu::CurrentSurfaceTexture::Suboptimal(texture) => {
                // Use this one; reconfigure for the next frame.
                self.surface.configure(&gpu.device, &self.config);
                Acquired::Texture {
                    texture,
                    suboptimal: true,
                }
            }
            wgpu::CurrentSurfaceTexture::Timeout | wgpu::CurrentSurfaceTexture::Occluded => {
                Acquired::Later
            }
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                let size = self.window.inner_size();
                self.resize(gpu, size);
                Acquired::Reconfigured
            }
            wgpu::CurrentSurfaceTexture::Validation => {
                let e = gpu.take_error().err();
                return Err(ViewerError::Failed(format!(
                    "cannot draw into the window: {}",
                    e.map(|e| e.to_string())
                        .unwrap_or_else(|| "surface validation error".into())
                )));
            }
        })
    }
}

/// The window's surface and a GPU that can present to it.
fn connect_gpu(
    el: &ActiveEventLoop,
    window: &Arc<Window>,
) -> Result<(wgpu::Surface<'static>, Gpu), ViewerError> {
    let instance = wgpu::Instance::new(
        wgpu::InstanceDescriptor::new_with_display_handle(Box::new(el.owned_display_handle()))
            .with_env(),
    );
    let surface = match instance.create_surface(window.clone()) {
        Ok(s) => s,
        Err(e) => {
            // With no usable backend at all, say what to install, as `render` does.
            let any = pollster::block_on(
                instance.request_adapter(&wgpu::RequestAdapterOptions::default()),
            );
            return Err(match any {
                Err(_) => ViewerError::NoAdapter,
                Ok(_) => ViewerError::Failed(format!("cannot draw into the window: {e}")),
            });
        }
    };
    let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
        power_preference: wgpu::PowerPreference::HighPerformance,
        force_fallback_adapter: false,
        compatible_surface: Some(&surface),
        ..Default::default()
    }))
    .map_err(|_| ViewerError::NoAdapter)?;
    let gpu =
        Gpu::from_adapter(instance, adapter).map_err(|e| ViewerError::Failed(e.to_string()))?;
    Ok((surface, gpu))
}

/// The surface's format and the format egui draws in. egui blends in gamma space and wants a
/// non-sRGB target; take one if the surface offers it, else draw through a non-sRGB view of an
/// sRGB surface.
fn egui_formats(
    caps: &wgpu::SurfaceCapabilities,
    gpu: &Gpu,
) -> Result<(wgpu::TextureFormat, wgpu::TextureFormat), ViewerError> {
    match caps.formats.iter().copied().find(|f| {
        matches!(
            f,
            wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Rgba8Unorm
        )
    }) {
        Some(f) => Ok((f, f)),
        None => {
            let f = *caps.formats.first().ok_or_else(|| {
                ViewerError::Failed(format!(
                    "the GPU ({}) cannot draw into this window",
                    gpu.adapter_summary()
                ))
            })?;
            Ok((f, f.remove_srgb_suffix()))
        }
    }
}

fn surface_config(
    caps: &wgpu::SurfaceCapabilities,
    gpu: &Gpu,
    size: PhysicalSize<u32>,
    format: wgpu::TextureFormat,
    render_format: wgpu::TextureFormat,
) -> wgpu::SurfaceConfiguration {
    // On a software rasterizer the window's picture is composed in a texture and copied in
    // (`frame_cache.rs`), where the surface allows it.
    let copy = if is_software(gpu) && caps.usages.contains(wgpu::TextureUsages::COPY_DST) {
        wgpu::TextureUsages::COPY_DST
    } else {
        wgpu::TextureUsages::empty()
    };
    wgpu::SurfaceConfiguration {
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | copy,
        format,
        width: size.width.max(1),
        height: size.height.max(1),
        // A software rasterizer rarely makes a 60 Hz deadline; with vsync a 20 ms frame
        // would wait for the next vblank and show at 30 fps. On a GPU, vsync.
        present_mode: if is_software(gpu) {
            wgpu::PresentMode::AutoNoVsync
        } else {
            wgpu::PresentMode::AutoVsync
        },
        color_space: Default::default(),
        desired_maximum_frame_latency: 2,
        alpha_mode: caps
            .alpha_modes
            .first()
            .copied()
            .unwrap_or(wgpu::CompositeAlphaMode::Auto),
        view_formats: if render_format != format {
            vec![render_format]
        } else {
            vec![]
        },
    }
}

/// egui: its context, the window input it reads, and the painter that draws its meshes.
pub(super) struct EguiLayer {
    pub ctx: egui::Context,
    pub state: egui_winit::State,
    pub painter: EguiPainter,
}

impl EguiLayer {
    pub fn new(window: &Window, gpu: &Gpu, format: wgpu::TextureFormat) -> EguiLayer {
        let ctx = egui::Context::default();
        setup_style(&ctx);
        let max_tex = gpu.device.limits().max_texture_dimension_2d as usize;
        let state = egui_winit::State::new(
            ctx.clone(),
            egui::ViewportId::ROOT,
            window,
            Some(window.scale_factor() as f32),
            None,
            Some(max_tex),
        );
        let painter = EguiPainter::new(&gpu.device, format);
        EguiLayer {
            ctx,
            state,
            painter,
        }
    }

    /// Records a pass that clears `target` to the panels' colour and draws the prepared meshes.
    pub fn paint(&self, encoder: &mut wgpu::CommandEncoder, target: &wgpu::TextureView) {
        let clear = self.ctx.global_style().visuals.panel_fill;
        let [r, g, b, a] = clear.to_normalized_gamma_f32();
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("dda3d egui"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: target,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    // egui works in gamma space on a non-sRGB target, so the clear value is the
                    // gamma-encoded colour as it is.
                    load: wgpu::LoadOp::Clear(wgpu::Color {
                        r: r as f64,
                        g: g as f64,
                        b: b as f64,
                        a: a as f64,
                    }),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        self.painter.render(&mut pass);
    }
}

/// A light theme that sits well next to the light-grey 3-D view, with slightly roomier rows.
fn setup_style(ctx: &egui::Context) {
    ctx.set_theme(egui::Theme::Light);
    ctx.all_styles_mut(|s| {
        s.spacing.item_spacing = egui::vec2(8.0, 5.0);
        s.spacing.slider_width = 120.0;
        s.spacing.interact_size.y = 20.0;
        s.visuals.panel_fill = egui::Color32::from_rgb(0xFA, 0xFA, 0xF8);
    });
}
