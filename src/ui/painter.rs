//! A small egui painter for the window.
//!
//! egui-wgpu's renderer works, but its fragment shader chooses between hardware and manual
//! texture filtering with a run-time branch, and Mesa's software rasterizer (llvmpipe) runs that
//! shader about four times slower than a plain `textureSample`: measured at 1280×720, egui alone
//! took ~65 ms a frame with egui-wgpu and ~15 ms with this painter. On a real GPU both are
//! negligible. The headless overlay (`render::overlay`) keeps egui-wgpu; it paints a few labels.
//!
//! Same conventions as egui-wgpu: textures and vertex colours are sRGB-encoded, premultiplied
//! alpha, blended in gamma space into a non-sRGB target.

use std::collections::HashMap;

use egui::epaint::{self, ImageData, Primitive, TextureId, textures::TextureFilter};
use wgpu::util::DeviceExt;

const SHADER: &str = r#"
struct Locals { screen_size: vec2<f32>, _pad: vec2<f32> };
@group(0) @binding(0) var<uniform> locals: Locals;
@group(1) @binding(0) var tex: texture_2d<f32>;
@group(1) @binding(1) var samp: sampler;

struct VOut {
    @builtin(position) pos: vec4<f32>,
    @location(0) uv: vec2<f32>,
    @location(1) color: vec4<f32>,
};

@vertex
fn vs(@location(0) p: vec2<f32>, @location(1) uv: vec2<f32>, @location(2) c: u32) -> VOut {
    var out: VOut;
    out.pos = vec4<f32>(2.0 * p.x / locals.screen_size.x - 1.0,
                        1.0 - 2.0 * p.y / locals.screen_size.y, 0.0, 1.0);
    out.uv = uv;
    out.color = unpack4x8unorm(c);
    return out;
}

@fragment
fn fs(in: VOut) -> @location(0) vec4<f32> {
    return in.color * textureSample(tex, samp, in.uv);
}
"#;

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
    locals: wgpu::Buffer,
    locals_bind_group: wgpu::BindGroup,
    texture_layout: wgpu::BindGroupLayout,
    textures: HashMap<TextureId, Texture>,
    samplers: HashMap<epaint::textures::TextureOptions, wgpu::Sampler>,
    vertices: Option<wgpu::Buffer>,
    indices: Option<wgpu::Buffer>,
    draws: Vec<Draw>,
    next_user_id: u64,
}

impl EguiPainter {
    /// A painter for targets of `format` (non-sRGB: egui blends in gamma space).
    pub fn new(device: &wgpu::Device, format: wgpu::TextureFormat) -> EguiPainter {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("dda3d egui"),
            source: wgpu::ShaderSource::Wgsl(SHADER.into()),
        });
        let locals = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("dda3d egui locals"),
            contents: bytemuck::cast_slice(&[0f32; 4]),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        let locals_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("dda3d egui locals"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            }],
        });
        let locals_bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("dda3d egui locals"),
            layout: &locals_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: locals.as_entire_binding(),
            }],
        });
        let texture_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("dda3d egui texture"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: true },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                    count: None,
                },
            ],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("dda3d egui"),
            bind_group_layouts: &[Some(&locals_layout), Some(&texture_layout)],
            immediate_size: 0,
        });
        let attrs = wgpu::vertex_attr_array![0 => Float32x2, 1 => Float32x2, 2 => Uint32];
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("dda3d egui"),
            layout: Some(&layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs"),
                compilation_options: Default::default(),
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: std::mem::size_of::<GpuVertex>() as u64,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &attrs,
                })],
            },
            primitive: wgpu::PrimitiveState {
                topology: wgpu::PrimitiveTopology::TriangleList,
                cull_mode: None,
                ..Default::default()
            },
            depth_stencil: None,
            multisample: wgpu::MultisampleState::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format,
                    // Premultiplied alpha, as egui-wgpu.
                    blend: Some(wgpu::BlendState {
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
                    }),
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        });
        EguiPainter {
            pipeline,
            locals,
            locals_bind_group,
            texture_layout,
            textures: HashMap::new(),
            samplers: HashMap::new(),
            vertices: None,
            indices: None,
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
        queue.write_buffer(
            &self.locals,
            0,
            bytemuck::cast_slice(&[sw as f32 / ppp, sh as f32 / ppp, 0.0, 0.0]),
        );
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
        upload(
            device,
            queue,
            &mut self.vertices,
            bytemuck::cast_slice(&vertices),
            wgpu::BufferUsages::VERTEX,
        );
        upload(
            device,
            queue,
            &mut self.indices,
            bytemuck::cast_slice(&indices),
            wgpu::BufferUsages::INDEX,
        );
    }

    /// Records the prepared meshes into `pass` (a target of the prepared size).
    pub fn render(&self, pass: &mut wgpu::RenderPass<'_>) {
        let (Some(vb), Some(ib)) = (&self.vertices, &self.indices) else {
            return;
        };
        if self.draws.is_empty() {
            return;
        }
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.locals_bind_group, &[]);
        pass.set_vertex_buffer(0, vb.slice(..));
        pass.set_index_buffer(ib.slice(..), wgpu::IndexFormat::Uint32);
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

/// Writes `data` into `slot`, growing the buffer (to the next power of two) when needed.
fn upload(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    slot: &mut Option<wgpu::Buffer>,
    data: &[u8],
    usage: wgpu::BufferUsages,
) {
    if data.is_empty() {
        return;
    }
    // Copies must be multiples of 4 bytes; vertices (20 B) and u32 indices always are.
    let need = data.len() as u64;
    if slot.as_ref().is_none_or(|b| b.size() < need) {
        *slot = Some(device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("dda3d egui mesh"),
            size: need.next_power_of_two().max(1 << 16),
            usage: usage | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        }));
    }
    if let Some(b) = slot {
        queue.write_buffer(b, 0, data);
    }
}
