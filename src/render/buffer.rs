//! GPU buffers refilled every frame (the scene's vertices, egui's meshes): one buffer each that
//! is rewritten in place and only reallocated when a frame needs more room.

use std::marker::PhantomData;

/// Smallest vertex buffer allocated for the scene, bytes.
const MIN_VERTEX_BYTES: u64 = 4096;

/// A buffer of `T`s that grows (to the next power of two) when a frame needs more room.
pub(crate) struct GrowBuffer<T> {
    label: &'static str,
    usage: wgpu::BufferUsages,
    min_bytes: u64,
    buffer: Option<wgpu::Buffer>,
    /// Elements uploaded for the current frame.
    count: u32,
    element: PhantomData<T>,
}

impl<T: bytemuck::Pod> GrowBuffer<T> {
    /// A buffer used as `usage` (copies into it are always allowed), never smaller than
    /// `min_bytes` once allocated.
    pub(crate) fn new(
        label: &'static str,
        usage: wgpu::BufferUsages,
        min_bytes: u64,
    ) -> GrowBuffer<T> {
        GrowBuffer {
            label,
            usage: usage | wgpu::BufferUsages::COPY_DST,
            min_bytes,
            buffer: None,
            count: 0,
            element: PhantomData,
        }
    }

    /// A vertex buffer for the scene.
    pub(crate) fn vertices(label: &'static str) -> GrowBuffer<T> {
        GrowBuffer::new(label, wgpu::BufferUsages::VERTEX, MIN_VERTEX_BYTES)
    }

    /// Replaces the contents with `data` (whose byte size must be a multiple of 4, as every
    /// buffer copy's).
    pub(crate) fn upload(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, data: &[T]) {
        self.count = data.len() as u32;
        if data.is_empty() {
            return;
        }
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let need = bytes.len() as u64;
        match &self.buffer {
            Some(b) if b.size() >= need => queue.write_buffer(b, 0, bytes),
            _ => {
                // Grow geometrically so a slowly growing scene does not reallocate every frame,
                // but never past what the device allows (the scene renderer checks sizes first).
                let size = need
                    .next_power_of_two()
                    .max(self.min_bytes)
                    .min(device.limits().max_buffer_size.max(need));
                let b = device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(self.label),
                    size,
                    usage: self.usage,
                    mapped_at_creation: false,
                });
                queue.write_buffer(&b, 0, bytes);
                self.buffer = Some(b);
            }
        }
    }

    /// Elements of the last upload.
    pub(crate) fn count(&self) -> u32 {
        self.count
    }

    /// The bytes of the last upload (`None` when it was empty).
    pub(crate) fn slice(&self) -> Option<wgpu::BufferSlice<'_>> {
        if self.count == 0 {
            return None;
        }
        let size = self.count as u64 * std::mem::size_of::<T>() as u64;
        self.buffer.as_ref().map(|b| b.slice(..size))
    }
}
