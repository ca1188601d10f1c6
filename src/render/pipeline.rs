//! The wgpu set-up that every pipeline of dda3d shares (the scene's solids, arrows and lines,
//! the window's egui painter): shader modules from WGSL, bind-group layouts, a uniform block
//! with its bind group, and [`PipelineSpec`], which declares a pipeline and builds it. What all
//! of them agree on (triangle lists, no culling, every colour channel written) is said once, in
//! [`PipelineSpec::build`].

use std::marker::PhantomData;

use wgpu::util::DeviceExt;

use super::gpu::DEPTH_FORMAT;

/// Compiles a WGSL module.
pub(crate) fn shader_module(device: &wgpu::Device, label: &str, wgsl: &str) -> wgpu::ShaderModule {
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(wgsl.into()),
    })
}

/// A uniform block at `binding`, read by the `visibility` stages.
pub(crate) fn uniform_entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// A filterable 2-D colour texture at `binding`, sampled by the fragment stage.
pub(crate) fn texture_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: true },
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    }
}

/// A filtering sampler at `binding`, for the fragment stage.
pub(crate) fn sampler_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
        count: None,
    }
}

pub(crate) fn bind_group_layout(
    device: &wgpu::Device,
    label: &str,
    entries: &[wgpu::BindGroupLayoutEntry],
) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(label),
        entries,
    })
}

/// A pipeline layout of the given bind groups, numbered in order (group 0 first).
pub(crate) fn pipeline_layout(
    device: &wgpu::Device,
    label: &str,
    groups: &[&wgpu::BindGroupLayout],
) -> wgpu::PipelineLayout {
    let groups: Vec<Option<&wgpu::BindGroupLayout>> = groups.iter().copied().map(Some).collect();
    device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts: &groups,
        immediate_size: 0,
    })
}

/// A uniform block of type `T` and the bind group that shows it to the shaders (its layout
/// holds this block alone, at binding 0).
pub(crate) struct Uniform<T> {
    buffer: wgpu::Buffer,
    layout: wgpu::BindGroupLayout,
    bind_group: wgpu::BindGroup,
    value: PhantomData<T>,
}

impl<T: bytemuck::Pod> Uniform<T> {
    pub(crate) fn new(
        device: &wgpu::Device,
        label: &str,
        initial: &T,
        visibility: wgpu::ShaderStages,
    ) -> Uniform<T> {
        let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: bytemuck::bytes_of(initial),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        let layout = bind_group_layout(device, label, &[uniform_entry(0, visibility)]);
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(label),
            layout: &layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: buffer.as_entire_binding(),
            }],
        });
        Uniform {
            buffer,
            layout,
            bind_group,
            value: PhantomData,
        }
    }

    /// Queues the new value for the next submission.
    pub(crate) fn write(&self, queue: &wgpu::Queue, value: &T) {
        queue.write_buffer(&self.buffer, 0, bytemuck::bytes_of(value));
    }

    pub(crate) fn layout(&self) -> &wgpu::BindGroupLayout {
        &self.layout
    }

    pub(crate) fn bind_group(&self) -> &wgpu::BindGroup {
        &self.bind_group
    }
}

/// The colour attachment a pipeline draws into.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ColorTarget {
    pub format: wgpu::TextureFormat,
    /// MSAA samples (1 = none).
    pub samples: u32,
}

/// How a pipeline uses the depth attachment (always [`DEPTH_FORMAT`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct DepthTest {
    pub write: bool,
    pub compare: wgpu::CompareFunction,
}

/// A render pipeline, declared: its shader entry points, its vertex buffers, the target, and
/// how it blends and depth-tests.
pub(crate) struct PipelineSpec<'a> {
    pub label: &'a str,
    pub layout: &'a wgpu::PipelineLayout,
    pub module: &'a wgpu::ShaderModule,
    pub vertex_entry: &'a str,
    pub fragment_entry: &'a str,
    /// Slot 0 first (an instanced pipeline: the template, then the instances).
    pub vertex_buffers: &'a [wgpu::VertexBufferLayout<'a>],
    pub target: ColorTarget,
    /// `None` replaces the target's pixels.
    pub blend: Option<wgpu::BlendState>,
    /// `None` for a pass without a depth attachment.
    pub depth: Option<DepthTest>,
}

impl PipelineSpec<'_> {
    pub(crate) fn build(&self, device: &wgpu::Device) -> wgpu::RenderPipeline {
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(self.label),
            layout: Some(self.layout),
            vertex: wgpu::VertexState {
                module: self.module,
                entry_point: Some(self.vertex_entry),
                compilation_options: Default::default(),
                buffers: &self
                    .vertex_buffers
                    .iter()
                    .cloned()
                    .map(Some)
                    .collect::<Vec<_>>(),
            },
            primitive: wgpu::PrimitiveState {
                topology: wgpu::PrimitiveTopology::TriangleList,
                // No culling: faces are lit two-sided, a block given with the wrong winding
                // must still show up, and egui's meshes have no consistent winding.
                cull_mode: None,
                ..Default::default()
            },
            depth_stencil: self.depth.map(|d| wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(d.write),
                depth_compare: Some(d.compare),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: wgpu::MultisampleState {
                count: self.target.samples,
                ..Default::default()
            },
            fragment: Some(wgpu::FragmentState {
                module: self.module,
                entry_point: Some(self.fragment_entry),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format: self.target.format,
                    blend: self.blend,
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        })
    }
}
