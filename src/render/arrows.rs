//! Contact arrows: lit triangles drawn twice, once depth-tested like the blocks and once, last
//! of all, faintly where a block hides them, so an arrow inside or behind a block still reads
//! (`fs_ghost` in shaders/solid.wgsl).

use super::buffer::GrowBuffer;
use super::mesh::SolidVertex;
use super::pipeline::{ColorTarget, DepthTest, PipelineSpec, shader_module};
use super::solids::{SOLID_WGSL, draw_triangles, lit_pipeline, solid_vertices};

/// Opacity of arrows where a block hides them.
pub(super) const GHOST_ALPHA: f32 = 0.35;

pub(super) struct ArrowRenderer {
    seen: wgpu::RenderPipeline,
    hidden: wgpu::RenderPipeline,
    arrows: GrowBuffer<SolidVertex>,
}

impl ArrowRenderer {
    /// `layout` carries the frame's uniform block at group 0.
    pub(super) fn new(
        device: &wgpu::Device,
        layout: &wgpu::PipelineLayout,
        target: ColorTarget,
    ) -> ArrowRenderer {
        let module = shader_module(device, "dda3d solid.wgsl", SOLID_WGSL);
        let hidden = PipelineSpec {
            label: "dda3d hidden arrows",
            layout,
            module: &module,
            vertex_entry: "vs_solid",
            fragment_entry: "fs_ghost",
            vertex_buffer: solid_vertices(),
            target,
            blend: Some(wgpu::BlendState::PREMULTIPLIED_ALPHA_BLENDING),
            // Only where something nearer was drawn, and without hiding anything itself.
            depth: Some(DepthTest {
                write: false,
                compare: wgpu::CompareFunction::Greater,
            }),
        };
        ArrowRenderer {
            seen: lit_pipeline(device, "dda3d arrows", &module, layout, target),
            hidden: hidden.build(device),
            arrows: GrowBuffer::vertices("dda3d arrows"),
        }
    }

    pub(super) fn upload(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        arrows: &[SolidVertex],
    ) {
        self.arrows.upload(device, queue, arrows);
    }

    /// The visible parts, depth-tested against the blocks.
    pub(super) fn draw(&self, pass: &mut wgpu::RenderPass<'_>) {
        draw_triangles(pass, &self.seen, &self.arrows);
    }

    /// The hidden parts, blended over whatever hides them: call after everything else.
    pub(super) fn draw_hidden(&self, pass: &mut wgpu::RenderPass<'_>) {
        draw_triangles(pass, &self.hidden, &self.arrows);
    }
}
