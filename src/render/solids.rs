//! Block faces: lit, flat-shaded, depth-tested triangles (`vs_solid`/`fs_solid` in
//! shaders/solid.wgsl). The arrows reuse this room's vertex layout and lit pipeline.

use super::buffer::GrowBuffer;
use super::mesh::SolidVertex;
use super::pipeline::{ColorTarget, DepthTest, PipelineSpec, shader_module};

/// Lit triangles' WGSL, after the frame's uniform block it reads.
pub(super) const SOLID_WGSL: &str = concat!(
    include_str!("../../shaders/globals.wgsl"),
    include_str!("../../shaders/solid.wgsl")
);

const ATTRIBUTES: [wgpu::VertexAttribute; 3] =
    wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x4];

/// One [`SolidVertex`] per vertex of a triangle list.
pub(super) fn solid_vertices() -> wgpu::VertexBufferLayout<'static> {
    wgpu::VertexBufferLayout {
        array_stride: std::mem::size_of::<SolidVertex>() as u64,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &ATTRIBUTES,
    }
}

/// The opaque pipeline for lit triangles: nearest surface wins, and it hides what is behind.
pub(super) fn lit_pipeline(
    device: &wgpu::Device,
    label: &str,
    module: &wgpu::ShaderModule,
    layout: &wgpu::PipelineLayout,
    target: ColorTarget,
) -> wgpu::RenderPipeline {
    PipelineSpec {
        label,
        layout,
        module,
        vertex_entry: "vs_solid",
        fragment_entry: "fs_solid",
        vertex_buffers: &[solid_vertices()],
        target,
        blend: None,
        depth: Some(DepthTest {
            write: true,
            compare: wgpu::CompareFunction::LessEqual,
        }),
    }
    .build(device)
}

/// Records one draw of a whole triangle list (nothing when it is empty).
pub(super) fn draw_triangles(
    pass: &mut wgpu::RenderPass<'_>,
    pipeline: &wgpu::RenderPipeline,
    vertices: &GrowBuffer<SolidVertex>,
) {
    if let Some(slice) = vertices.slice() {
        pass.set_pipeline(pipeline);
        pass.set_vertex_buffer(0, slice);
        pass.draw(0..vertices.count(), 0..1);
    }
}

pub(super) struct SolidRenderer {
    pipeline: wgpu::RenderPipeline,
    faces: GrowBuffer<SolidVertex>,
}

impl SolidRenderer {
    /// `layout` carries the frame's uniform block at group 0.
    pub(super) fn new(
        device: &wgpu::Device,
        layout: &wgpu::PipelineLayout,
        target: ColorTarget,
    ) -> SolidRenderer {
        let module = shader_module(device, "dda3d solid.wgsl", SOLID_WGSL);
        SolidRenderer {
            pipeline: lit_pipeline(device, "dda3d solids", &module, layout, target),
            faces: GrowBuffer::vertices("dda3d solids"),
        }
    }

    pub(super) fn upload(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        faces: &[SolidVertex],
    ) {
        self.faces.upload(device, queue, faces);
    }

    pub(super) fn draw(&self, pass: &mut wgpu::RenderPass<'_>) {
        draw_triangles(pass, &self.pipeline, &self.faces);
    }
}
