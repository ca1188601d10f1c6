//! Contact arrows: an indexed unit arrow drawn once per [`ArrowInstance`]
//! (`vs_arrow` in shaders/arrow.wgsl), lit as the blocks are, with as many sides as its size on
//! screen needs ([`lod_seen`]: llvmpipe's time goes with the triangles). Drawn twice: once
//! depth-tested like the blocks and once, last of all, faintly where a block hides them, so an
//! arrow inside or behind a block still reads (`fs_ghost` in shaders/solid.wgsl).

use std::mem::offset_of;

use wgpu::util::DeviceExt;

use super::arrow_mesh::{ARROW_LODS, ArrowInstance, ArrowTemplateVertex, arrow_template, lod_seen};
use super::buffer::GrowBuffer;
use super::camera::Camera;
use super::pipeline::{ColorTarget, DepthTest, PipelineSpec, shader_module};

/// Opacity of arrows where a block hides them.
pub(super) const GHOST_ALPHA: f32 = 0.35;

const ARROW_WGSL: &str = concat!(
    include_str!("../../shaders/globals.wgsl"),
    include_str!("../../shaders/solid.wgsl"),
    include_str!("../../shaders/arrow.wgsl")
);

const TEMPLATE_ATTRIBUTES: [wgpu::VertexAttribute; 2] =
    wgpu::vertex_attr_array![0 => Float32x2, 1 => Float32x3];

/// One [`ArrowInstance`] per arrow, read at its `repr(C)` offsets.
const INSTANCE_ATTRIBUTES: [wgpu::VertexAttribute; 6] = [
    attribute(
        wgpu::VertexFormat::Float32x3,
        offset_of!(ArrowInstance, base),
        2,
    ),
    attribute(
        wgpu::VertexFormat::Float32,
        offset_of!(ArrowInstance, length),
        3,
    ),
    attribute(
        wgpu::VertexFormat::Float32x3,
        offset_of!(ArrowInstance, dir),
        4,
    ),
    attribute(
        wgpu::VertexFormat::Float32,
        offset_of!(ArrowInstance, shaft_radius),
        5,
    ),
    attribute(
        wgpu::VertexFormat::Float32x2,
        offset_of!(ArrowInstance, head),
        6,
    ),
    attribute(
        wgpu::VertexFormat::Float32x4,
        offset_of!(ArrowInstance, color),
        7,
    ),
];

const fn attribute(
    format: wgpu::VertexFormat,
    offset: usize,
    shader_location: u32,
) -> wgpu::VertexAttribute {
    wgpu::VertexAttribute {
        format,
        offset: offset as u64,
        shader_location,
    }
}

/// The template's vertices (slot 0), then the instances (slot 1).
fn vertex_buffers() -> [wgpu::VertexBufferLayout<'static>; 2] {
    [
        wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<ArrowTemplateVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &TEMPLATE_ATTRIBUTES,
        },
        wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<ArrowInstance>() as u64,
            step_mode: wgpu::VertexStepMode::Instance,
            attributes: &INSTANCE_ATTRIBUTES,
        },
    ]
}

pub(super) struct ArrowRenderer {
    seen: wgpu::RenderPipeline,
    hidden: wgpu::RenderPipeline,
    /// One per entry of [`ARROW_LODS`].
    lods: Vec<Lod>,
}

/// A template of one side count and this frame's arrows drawn with it.
struct Lod {
    template: wgpu::Buffer,
    indices: wgpu::Buffer,
    index_count: u32,
    arrows: GrowBuffer<ArrowInstance>,
    /// This frame's arrows, gathered before the upload (kept to spare the allocation).
    chosen: Vec<ArrowInstance>,
}

impl Lod {
    fn new(device: &wgpu::Device, sides: usize) -> Lod {
        let (vertices, indices) = arrow_template(sides);
        let index_count = indices.len() as u32;
        Lod {
            template: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("dda3d arrow template"),
                contents: bytemuck::cast_slice(&vertices),
                usage: wgpu::BufferUsages::VERTEX,
            }),
            indices: device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("dda3d arrow template indices"),
                // Padded to a multiple of 4 bytes, as every buffer's size.
                contents: bytemuck::cast_slice(&padded(indices)),
                usage: wgpu::BufferUsages::INDEX,
            }),
            index_count,
            arrows: GrowBuffer::vertices("dda3d arrows"),
            chosen: Vec::new(),
        }
    }
}

impl ArrowRenderer {
    /// `layout` carries the frame's uniform block at group 0.
    pub(super) fn new(
        device: &wgpu::Device,
        layout: &wgpu::PipelineLayout,
        target: ColorTarget,
    ) -> ArrowRenderer {
        let module = shader_module(device, "dda3d arrow.wgsl", ARROW_WGSL);
        let buffers = vertex_buffers();
        let spec = |label, fragment_entry, blend, depth| PipelineSpec {
            label,
            layout,
            module: &module,
            vertex_entry: "vs_arrow",
            fragment_entry,
            vertex_buffers: &buffers,
            target,
            blend,
            depth: Some(depth),
        };
        // Nearest surface wins, as for the blocks.
        let seen = spec(
            "dda3d arrows",
            "fs_solid",
            None,
            DepthTest {
                write: true,
                compare: wgpu::CompareFunction::LessEqual,
            },
        );
        // Only where something nearer was drawn, and without hiding anything itself.
        let hidden = spec(
            "dda3d hidden arrows",
            "fs_ghost",
            Some(wgpu::BlendState::PREMULTIPLIED_ALPHA_BLENDING),
            DepthTest {
                write: false,
                compare: wgpu::CompareFunction::Greater,
            },
        );
        ArrowRenderer {
            seen: seen.build(device),
            hidden: hidden.build(device),
            lods: ARROW_LODS.iter().map(|&n| Lod::new(device, n)).collect(),
        }
    }

    /// Uploads `arrows`, each with the template its size seen by `camera` on a target
    /// `height` pixels high calls for (in their order within each template).
    pub(super) fn upload(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        arrows: &[ArrowInstance],
        camera: &Camera,
        height: u32,
    ) {
        for lod in &mut self.lods {
            lod.chosen.clear();
        }
        for a in arrows {
            self.lods[lod_seen(a, camera, height)].chosen.push(*a);
        }
        for lod in &mut self.lods {
            lod.arrows.upload(device, queue, &lod.chosen);
        }
    }

    /// The visible parts, depth-tested against the blocks.
    pub(super) fn draw(&self, pass: &mut wgpu::RenderPass<'_>) {
        self.draw_with(pass, &self.seen);
    }

    /// The hidden parts, blended over whatever hides them: call after everything else.
    pub(super) fn draw_hidden(&self, pass: &mut wgpu::RenderPass<'_>) {
        self.draw_with(pass, &self.hidden);
    }

    fn draw_with(&self, pass: &mut wgpu::RenderPass<'_>, pipeline: &wgpu::RenderPipeline) {
        pass.set_pipeline(pipeline);
        for lod in &self.lods {
            if let Some(instances) = lod.arrows.slice() {
                pass.set_vertex_buffer(0, lod.template.slice(..));
                pass.set_vertex_buffer(1, instances);
                pass.set_index_buffer(lod.indices.slice(..), wgpu::IndexFormat::Uint16);
                pass.draw_indexed(0..lod.index_count, 0, 0..lod.arrows.count());
            }
        }
    }
}

/// `indices` with a zero appended when their count is odd.
fn padded(mut indices: Vec<u16>) -> Vec<u16> {
    if indices.len() % 2 == 1 {
        indices.push(0);
    }
    indices
}
