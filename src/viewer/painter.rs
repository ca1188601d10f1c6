//! A small egui painter for the window.
//!
//! egui-wgpu's renderer works, but its fragment shader chooses between hardware and manual
//! texture filtering with a run-time branch, and Mesa's software rasterizer (llvmpipe) runs that
//! shader about four times slower than a plain `textureSample`: measured at 1280×720, egui alone
//! took ~65 ms a frame with egui-wgpu and ~15 ms with this painter. On a real GPU both are
//! negligible. The headless overlay (`render::overlay`) keeps egui-wgpu; it paints a few labels.
//!
//! Same conventions as egui-wgpu: textures and vertex colours are sRGB-encoded, premultiplied
//! alpha, blended in gamma space into a non-sRGB target. The shader is `shaders/egui.wgsl`; the
//! pipeline is declared with the renderer's set-up helpers (`render::pipeline`).

use std::collections::HashMap;

use egui::epaint::{self, ImageData, Primitive, TextureId, textures::TextureFilter};

use crate::render::buffer::GrowBuffer;
use crate::render::pipeline::{
    ColorTarget, PipelineSpec, Uniform, bind_group_layout, pipeline_layout, sampler_entry,
    shader_module, texture_entry,
};

/// Smallest mesh buffer allocated, bytes: a typical frame's meshes fit from the start.
const MIN_MESH_BYTES: u64 = 1 << 16;

const VERTEX_ATTRIBUTES: [wgpu::VertexAttribute; 3] =
    wgpu::vertex_attr_array![0 => Float32x2, 1 => Float32x2, 2 => Uint32];

/// Premultiplied alpha, as egui-wgpu.
const BLEND: wgpu::BlendState = wgpu::BlendState {
    color: wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::One,
        dst_factor: wgpu::BlendFactor::OneMinusSrcAlpha,
        operation: wgpu::BlendOperation::Add,
    },
    alpha: wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::OneMinusDstAlpha,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Add,
    },
};

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuVertex {
    pos: [f32; 2],
    uv: [f32; 2],
    color: u32,
}

struct Texture {
    /// `None` for textures owned by the app (the 3-D view).
    texture: Option<wgpu::Texture>,
    bind_group: wgpu::BindGroup,
    options: Option<epaint::textures::TextureOptions>,
}

/// One mesh of the frame: where its indices are, which texture, which pixels it may touch.
struct Draw {
    texture: TextureId,
    indices: std::ops::Range<u32>,
    base_vertex: i32,
    scissor: [u32; 4],
}

/// Pixel size and scale of the target.
#[derive(Clone, Copy, Debug)]
pub struct Screen {
    pub size_in_pixels: [u32; 2],
    pub pixels_per_point: f32,
}

pub struct EguiPainter {
    pipeline: wgpu::RenderPipeline,
    /// Screen size in points (x, y; the rest is padding).
    locals: Uniform<[f32; 4]>,
    texture_layout: wgpu::BindGroupLayout,
    textures: HashMap<TextureId, Texture>,
    samplers: HashMap<epaint::textures::TextureOptions, wgpu::Sampler>,
    vertices: GrowBuffer<GpuVertex>,
    indices: GrowBuffer<u32>,
    draws: Vec<Draw>,
    next_user_id: u64,
}

impl EguiPainter {
    /// A painter for targets of `format` (non-sRGB: egui blends in gamma space).
    pub fn new(device: &wgpu::Device, format: wgpu::TextureFormat) -> EguiPainter {
        let locals = Uniform::new(
            device,
            "dda3d egui locals",
            &[0f32; 4],
            wgpu::ShaderStages::VERTEX,
        );
        let texture_layout = bind_group_layout(
            device,
            "dda3d egui texture",
            &[texture_entry(0), sampler_entry(1)],
        );
        let layout = pipeline_layout(device, "dda3d egui", &[locals.layout(), &texture_layout]);
        let module = shader_module(
            device,
            "dda3d egui.wgsl",
            include_str!("../../shaders/egui.wgsl"),
        );
        let pipeline = PipelineSpec {
            label: "dda3d egui",
            layout: &layout,
            module: &module,
            vertex_entry: "vs",
            fragment_entry: "fs",
            vertex_buffers: &[wgpu::VertexBufferLayout {
                array_stride: std::mem::size_of::<GpuVertex>() as u64,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &VERTEX_ATTRIBUTES,
            }],
            target: ColorTarget { format, samples: 1 },
            blend: Some(BLEND),
            depth: None,
        }
        .build(device);
        EguiPainter {
            pipeline,
            locals,
            texture_layout,
            textures: HashMap::new(),
            samplers: HashMap::new(),
            vertices: GrowBuffer::new(
                "dda3d egui vertices",
                wgpu::BufferUsages::VERTEX,
                MIN_MESH_BYTES,
            ),
            indices: GrowBuffer::new(
                "dda3d egui indices",
                wgpu::BufferUsages::INDEX,
                MIN_MESH_BYTES,
            ),
            draws: Vec::new(),
            next_user_id: 0,
        }
    }

    fn sampler(
        &mut self,
        device: &wgpu::Device,
        o: epaint::textures::TextureOptions,
    ) -> &wgpu::Sampler {
        self.samplers.entry(o).or_insert_with(|| {
            let filter = |f: TextureFilter| match f {
                TextureFilter::Nearest => wgpu::FilterMode::Nearest,
                TextureFilter::Linear => wgpu::FilterMode::Linear,
            };
            let address = match o.wrap_mode {
                epaint::textures::TextureWrapMode::ClampToEdge => wgpu::AddressMode::ClampToEdge,
                epaint::textures::TextureWrapMode::Repeat => wgpu::AddressMode::Repeat,
                epaint::textures::TextureWrapMode::MirroredRepeat => {
                    wgpu::AddressMode::MirrorRepeat
                }
            };
            device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("dda3d egui"),
                mag_filter: filter(o.magnification),
                min_filter: filter(o.minification),
                mipmap_filter: match o.mipmap_mode {
                    Some(TextureFilter::Linear) => wgpu::MipmapFilterMode::Linear,
                    _ => wgpu::MipmapFilterMode::Nearest,
                },
                address_mode_u: address,
                address_mode_v: address,
                ..Default::default()
            })
        })
    }

    /// Keeps an egui-owned texture under `id` with a bind group for its sampling options.
    fn insert_texture(
        &mut self,
        device: &wgpu::Device,
        id: TextureId,
        tex: &wgpu::Texture,
        options: epaint::textures::TextureOptions,
    ) {
        let view = tex.create_view(&Default::default());
        let bind_group = self.bind_group(device, &view, options);
        self.textures.insert(
            id,
            Texture {
                texture: Some(tex.clone()),
                bind_group,
                options: Some(options),
            },
        );
    }

    fn bind_group(
        &mut self,
        device: &wgpu::Device,
        view: &wgpu::TextureView,
        options: epaint::textures::TextureOptions,
    ) -> wgpu::BindGroup {
        self.sampler(device, options);
        let sampler = &self.samplers[&options];
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("dda3d egui texture"),
            layout: &self.texture_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(view),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::Sampler(sampler),
                },
            ],
        })
    }

    /// Makes an app-owned texture (any filterable colour format) drawable by egui; returns
    /// its id for `egui::Image` / `Painter::image`.
    pub fn register_native_texture(
        &mut self,
        device: &wgpu::Device,
        view: &wgpu::TextureView,
    ) -> TextureId {
        self.next_user_id += 1;
        let id = TextureId::User(self.next_user_id);
        self.update_native_texture(device, view, id);
        id
    }

    /// Points an id from [`EguiPainter::register_native_texture`] at a new texture (after a
    /// resize). The view is shown 1:1, so it is sampled without filtering.
    pub fn update_native_texture(
        &mut self,
        device: &wgpu::Device,
        view: &wgpu::TextureView,
        id: TextureId,
    ) {
        let bind_group = self.bind_group(device, view, epaint::textures::TextureOptions::NEAREST);
        self.textures.insert(
            id,
            Texture {
                texture: None,
                bind_group,
                options: None,
            },
        );
    }

    /// Applies one of egui's texture updates (font atlas, images).
    pub fn update_texture(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        id: TextureId,
        delta: &epaint::ImageDelta,
    ) {
        let ImageData::Color(image) = &delta.image;
        let [w, h] = image.size;
        if w == 0 || h == 0 || image.pixels.len() != w * h {
            return;
        }
        let bytes: Vec<u8> = image.pixels.iter().flat_map(|c| c.to_array()).collect();
        let size = wgpu::Extent3d {
            width: w as u32,
            height: h as u32,
            depth_or_array_layers: 1,
        };
        let origin = match delta.pos {
            Some([x, y]) => wgpu::Origin3d {
                x: x as u32,
                y: y as u32,
                z: 0,
            },
            None => wgpu::Origin3d::ZERO,
        };
        let existing = self
            .textures
            .get(&id)
            .and_then(|t| t.texture.clone().map(|tex| (tex, t.options)));
        let texture = match (delta.pos, existing) {
            (Some(_), Some((tex, options))) => {
                if options != Some(delta.options) {
                    self.insert_texture(device, id, &tex, delta.options);
                }
                tex
            }
            // A partial update of a texture we do not have cannot be applied.
            (Some(_), None) => return,
            (None, _) => {
                let tex = device.create_texture(&wgpu::TextureDescriptor {
                    label: Some("dda3d egui texture"),
                    size,
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format: wgpu::TextureFormat::Rgba8Unorm,
                    usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                    view_formats: &[],
                });
                self.insert_texture(device, id, &tex, delta.options);
                tex
            }
        };
        queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &texture,
                mip_level: 0,
                origin,
                aspect: wgpu::TextureAspect::All,
            },
            &bytes,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(4 * w as u32),
                rows_per_image: Some(h as u32),
            },
            size,
        );
    }

    pub fn free_texture(&mut self, id: &TextureId) {
        if let Some(t) = self.textures.remove(id)
            && let Some(tex) = t.texture
        {
            tex.destroy();
        }
    }

    /// Uploads the frame's meshes. Call once per frame, before [`EguiPainter::render`] (which
    /// may then be called for several targets of the same size).
    pub fn prepare(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        primitives: &[epaint::ClippedPrimitive],
        screen: Screen,
    ) {
        let ppp = screen.pixels_per_point;
        let [sw, sh] = screen.size_in_pixels;
        self.locals
            .write(queue, &[sw as f32 / ppp, sh as f32 / ppp, 0.0, 0.0]);
        self.draws.clear();
        let mut vertices: Vec<GpuVertex> = Vec::new();
        let mut indices: Vec<u32> = Vec::new();
        for p in primitives {
            let Primitive::Mesh(mesh) = &p.primitive else {
                continue; // paint callbacks are not used by the viewer
            };
            if mesh.indices.is_empty() {
                continue;
            }
            // Clip rectangle in whole pixels, inside the target.
            let x0 = (p.clip_rect.min.x * ppp).round().clamp(0.0, sw as f32) as u32;
            let y0 = (p.clip_rect.min.y * ppp).round().clamp(0.0, sh as f32) as u32;
            let x1 = (p.clip_rect.max.x * ppp).round().clamp(0.0, sw as f32) as u32;
            let y1 = (p.clip_rect.max.y * ppp).round().clamp(0.0, sh as f32) as u32;
            if x1 <= x0 || y1 <= y0 {
                continue;
            }
            let base_vertex = vertices.len() as i32;
            let start = indices.len() as u32;
            vertices.extend(mesh.vertices.iter().map(|v| GpuVertex {
                pos: [v.pos.x, v.pos.y],
                uv: [v.uv.x, v.uv.y],
                color: u32::from_le_bytes(v.color.to_array()),
            }));
            indices.extend_from_slice(&mesh.indices);
            self.draws.push(Draw {
                texture: mesh.texture_id,
                indices: start..indices.len() as u32,
                base_vertex,
                scissor: [x0, y0, x1 - x0, y1 - y0],
            });
        }
        self.vertices.upload(device, queue, &vertices);
        self.indices.upload(device, queue, &indices);
    }

    /// Records the prepared meshes into `pass` (a target of the prepared size).
    pub fn render(&self, pass: &mut wgpu::RenderPass<'_>) {
        let (Some(vb), Some(ib)) = (self.vertices.slice(), self.indices.slice()) else {
            return;
        };
        if self.draws.is_empty() {
            return;
        }
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, self.locals.bind_group(), &[]);
        pass.set_vertex_buffer(0, vb);
        pass.set_index_buffer(ib, wgpu::IndexFormat::Uint32);
        for d in &self.draws {
            let Some(t) = self.textures.get(&d.texture) else {
                continue;
            };
            let [x, y, w, h] = d.scissor;
            pass.set_scissor_rect(x, y, w, h);
            pass.set_bind_group(1, &t.bind_group, &[]);
            pass.draw_indexed(d.indices.clone(), d.base_vertex, 0..1);
        }
    }
}
