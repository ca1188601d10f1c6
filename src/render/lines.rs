//! Block outlines and the ground grid: each segment a [`LineInstance`] drawn as a screen-space
//! quad of constant pixel width (shaders/line.wgsl), since hardware lines are one pixel wide on
//! most backends, too thin for figures.

use std::mem::offset_of;

use super::buffer::GrowBuffer;
use super::mesh::LineInstance;
use super::pipeline::{ColorTarget, DepthTest, PipelineSpec, shader_module};

/// Outline endpoints move this fraction of the way to the eye, so an edge wins the depth test
/// against the faces it lies on (see line.wgsl).
pub(super) const LINE_PULL: f32 = 0.002;

/// Vertices per segment: the two triangles of its quad.
const QUAD_VERTICES: u32 = 6;

const LINE_WGSL: &str = concat!(
    include_str!("../../shaders/globals.wgsl"),
    include_str!("../../shaders/line.wgsl")
);

/// One [`LineInstance`] per segment, read at its `repr(C)` offsets (the padding after `b`
/// keeps the colour 16-byte aligned).
const ATTRIBUTES: [wgpu::VertexAttribute; 4] = [
    wgpu::VertexAttribute {
        format: wgpu::VertexFormat::Float32x3,
        offset: offset_of!(LineInstance, a) as u64,
        shader_location: 0,
    },
    wgpu::VertexAttribute {
        format: wgpu::VertexFormat::Float32,
        offset: offset_of!(LineInstance, width_px) as u64,
        shader_location: 1,
    },
    wgpu::VertexAttribute {
        format: wgpu::VertexFormat::Float32x3,
        offset: offset_of!(LineInstance, b) as u64,
        shader_location: 2,
    },
    wgpu::VertexAttribute {
        format: wgpu::VertexFormat::Float32x4,
        offset: offset_of!(LineInstance, color) as u64,
        shader_location: 3,
    },
];

pub(super) struct LineRenderer {
    pipeline: wgpu::RenderPipeline,
    segments: GrowBuffer<LineInstance>,
}

impl LineRenderer {
    /// `layout` carries the frame's uniform block at group 0.
    pub(super) fn new(
        device: &wgpu::Device,
        layout: &wgpu::PipelineLayout,
        target: ColorTarget,
    ) -> LineRenderer {
        let module = shader_module(device, "dda3d line.wgsl", LINE_WGSL);
        let pipeline = PipelineSpec {
            label: "dda3d lines",
            layout,
            module: &module,
            vertex_entry: "vs_line",
            fragment_entry: "fs_line",
            vertex_buffers: &[wgpu::VertexBufferLayout {
                array_stride: std::mem::size_of::<LineInstance>() as u64,
                step_mode: wgpu::VertexStepMode::Instance,
                attributes: &ATTRIBUTES,
            }],
            target,
            blend: None,
            depth: Some(DepthTest {
                write: true,
                compare: wgpu::CompareFunction::LessEqual,
            }),
        };
        LineRenderer {
            pipeline: pipeline.build(device),
            segments: GrowBuffer::vertices("dda3d lines"),
        }
    }

    pub(super) fn upload(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        lines: &[LineInstance],
    ) {
        self.segments.upload(device, queue, lines);
    }

    pub(super) fn draw(&self, pass: &mut wgpu::RenderPass<'_>) {
        if let Some(slice) = self.segments.slice() {
            pass.set_pipeline(&self.pipeline);
            pass.set_vertex_buffer(0, slice);
            pass.draw(0..QUAD_VERTICES, 0..self.segments.count());
        }
    }
}
