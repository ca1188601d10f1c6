//! Off-screen rendering with readback: renders a [`RenderScene`] into a texture and copies it to a
//! mappable buffer whose rows are padded to wgpu's `COPY_BYTES_PER_ROW_ALIGNMENT` (256 bytes),
//! then strips the padding. Two readback buffers let the next frame be drawn while the previous
//! one is being read ([`Offscreen::submit`] / [`Offscreen::read`]).
//!
//! The copy, mapping and unpadding live in one place, [`Readback`], which the viewer's
//! whole-window screenshot uses too (for a surface that may store its bytes as BGRA).

use std::sync::mpsc;

use super::camera::Camera;
use super::overlay::Overlay;
use super::scene::RenderScene;
use super::{Gpu, OFFSCREEN_FORMAT, RenderError, RenderTargets, Renderer};

/// Bytes per row of the readback buffer: `width * 4` rounded up to the copy alignment.
fn padded_bytes_per_row(width: u32) -> u32 {
    let unpadded = width * 4;
    let align = wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    unpadded.div_ceil(align) * align
}

/// Copies `height` rows of `width * 4` bytes out of a buffer with `padded` bytes per row.
fn strip_row_padding(padded_data: &[u8], width: u32, height: u32, padded: u32) -> Vec<u8> {
    let row = (width * 4) as usize;
    let mut out = Vec::with_capacity(row * height as usize);
    for chunk in padded_data.chunks(padded as usize).take(height as usize) {
        out.extend_from_slice(&chunk[..row.min(chunk.len())]);
    }
    out
}

/// The byte order of a texture with four 8-bit channels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ChannelOrder {
    Rgba,
    /// Blue first, as window surfaces often are.
    Bgra,
}

impl ChannelOrder {
    /// The order of `format`, or `None` for a format that is not 8-bit RGBA or BGRA.
    pub fn of(format: wgpu::TextureFormat) -> Option<ChannelOrder> {
        match format {
            wgpu::TextureFormat::Rgba8Unorm | wgpu::TextureFormat::Rgba8UnormSrgb => {
                Some(ChannelOrder::Rgba)
            }
            wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb => {
                Some(ChannelOrder::Bgra)
            }
            _ => None,
        }
    }
}

/// A mappable buffer that receives the copy of a whole `width`×`height` single-sample texture
/// and gives it back as RGBA bytes, top row first.
pub struct Readback {
    buffer: wgpu::Buffer,
    padded_row: u32,
    width: u32,
    height: u32,
    order: ChannelOrder,
}

/// The mapping of a [`Readback`] requested after its copy was submitted.
pub struct Mapping(mpsc::Receiver<Result<(), wgpu::BufferAsyncError>>);

impl Readback {
    /// Bytes the buffer needs for a `width`×`height` texture (for checking the GPU's limit).
    pub fn buffer_size(width: u32, height: u32) -> u64 {
        padded_bytes_per_row(width) as u64 * height as u64
    }

    pub fn new(
        device: &wgpu::Device,
        label: &str,
        order: ChannelOrder,
        width: u32,
        height: u32,
    ) -> Readback {
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: Readback::buffer_size(width, height),
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        Readback {
            buffer,
            padded_row: padded_bytes_per_row(width),
            width,
            height,
            order,
        }
    }

    /// Records the copy of `texture` (of this readback's size) into the buffer.
    pub fn copy_from(&self, encoder: &mut wgpu::CommandEncoder, texture: &wgpu::Texture) {
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &self.buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(self.padded_row),
                    rows_per_image: Some(self.height),
                },
            },
            wgpu::Extent3d {
                width: self.width,
                height: self.height,
                depth_or_array_layers: 1,
            },
        );
    }

    /// Requests the buffer's mapping; call once the copy has been submitted.
    pub fn map(&self) -> Mapping {
        let (tx, rx) = mpsc::channel();
        self.buffer.map_async(wgpu::MapMode::Read, .., move |r| {
            let _ = tx.send(r);
        });
        Mapping(rx)
    }

    /// Waits for `submission` (`None`: all submitted work) and the mapping, and returns
    /// `width * height * 4` bytes of RGBA, top row first.
    pub fn read(
        &self,
        device: &wgpu::Device,
        mapping: Mapping,
        submission: Option<wgpu::SubmissionIndex>,
    ) -> Result<Vec<u8>, RenderError> {
        device
            .poll(wgpu::PollType::Wait {
                submission_index: submission,
                timeout: None,
            })
            .map_err(|e| RenderError::Gpu(e.to_string()))?;
        mapping
            .0
            .recv()
            .map_err(|_| RenderError::Gpu("readback callback never ran".into()))?
            .map_err(|e| RenderError::Gpu(format!("readback failed: {e}")))?;
        let mut pixels = {
            let view = self
                .buffer
                .get_mapped_range(..)
                .map_err(|e| RenderError::Gpu(format!("readback mapping: {e}")))?;
            strip_row_padding(&view, self.width, self.height, self.padded_row)
        };
        self.buffer.unmap();
        if self.order == ChannelOrder::Bgra {
            for p in pixels.chunks_exact_mut(4) {
                p.swap(0, 2);
            }
        }
        Ok(pixels)
    }
}

struct Slot {
    readback: Readback,
    busy: bool,
}

/// A frame on its way back from the GPU; pass it to [`Offscreen::read`].
pub struct Pending {
    slot: usize,
    submission: wgpu::SubmissionIndex,
    mapped: Mapping,
}

/// An off-screen render target of fixed size with its own renderer and overlay.
pub struct Offscreen {
    gpu: Gpu,
    renderer: Renderer,
    overlay: Overlay,
    width: u32,
    height: u32,
    targets: RenderTargets,
    output: wgpu::Texture,
    output_view: wgpu::TextureView,
    slots: Vec<Slot>,
}

impl Offscreen {
    /// Sets up a `width`×`height` target (RGBA8 sRGB) with 4× MSAA where supported.
    pub fn new(gpu: Gpu, width: u32, height: u32) -> Result<Offscreen, RenderError> {
        Offscreen::with_max_samples(gpu, width, height, 4)
    }

    /// As [`Offscreen::new`] with at most `max_samples` MSAA samples (1 = no MSAA).
    pub fn with_max_samples(
        gpu: Gpu,
        width: u32,
        height: u32,
        max_samples: u32,
    ) -> Result<Offscreen, RenderError> {
        Offscreen::with_format(gpu, width, height, OFFSCREEN_FORMAT, max_samples)
    }

    /// As [`Offscreen::with_max_samples`] drawing into `format`: `Rgba8UnormSrgb` (the
    /// default), or `Rgba8Unorm`, the kind of target a window surface shared with egui is
    /// (the shader then encodes sRGB itself); the bytes read back are sRGB either way.
    pub fn with_format(
        gpu: Gpu,
        width: u32,
        height: u32,
        format: wgpu::TextureFormat,
        max_samples: u32,
    ) -> Result<Offscreen, RenderError> {
        if !matches!(
            format,
            wgpu::TextureFormat::Rgba8UnormSrgb | wgpu::TextureFormat::Rgba8Unorm
        ) {
            return Err(RenderError::InvalidOptions(format!(
                "off-screen format {format:?} is not supported (use Rgba8UnormSrgb or Rgba8Unorm)"
            )));
        }
        let limits = gpu.device.limits();
        let max = limits.max_texture_dimension_2d;
        if width == 0 || height == 0 || width > max || height > max {
            return Err(RenderError::InvalidOptions(format!(
                "image size {width}x{height} is outside 1..={max} pixels per side on this GPU"
            )));
        }
        let buffer_size = Readback::buffer_size(width, height);
        if buffer_size > limits.max_buffer_size {
            return Err(RenderError::InvalidOptions(format!(
                "image size {width}x{height} needs a {buffer_size}-byte readback buffer; \
                 this GPU allows {}",
                limits.max_buffer_size
            )));
        }
        let renderer = Renderer::with_max_samples(&gpu, format, max_samples);
        let overlay = Overlay::new(&gpu.device, format);
        let targets = renderer.create_targets(&gpu.device, width, height);
        let output = readable_target(&gpu.device, "dda3d frame", format, width, height);
        let output_view = output.create_view(&Default::default());
        let slots = (0..2)
            .map(|_| Slot {
                readback: Readback::new(
                    &gpu.device,
                    "dda3d readback",
                    ChannelOrder::Rgba,
                    width,
                    height,
                ),
                busy: false,
            })
            .collect();
        gpu.take_error()?;
        Ok(Offscreen {
            gpu,
            renderer,
            overlay,
            width,
            height,
            targets,
            output,
            output_view,
            slots,
        })
    }

    pub fn gpu(&self) -> &Gpu {
        &self.gpu
    }

    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// MSAA samples in use.
    pub fn samples(&self) -> u32 {
        self.renderer.samples()
    }

    /// Width / height, for the camera.
    pub fn aspect(&self) -> f32 {
        self.width as f32 / self.height as f32
    }

    /// Draws the scene and queues its copy to a free readback buffer. At most two frames may
    /// be in flight.
    pub fn submit(&mut self, scene: &RenderScene, camera: &Camera) -> Result<Pending, RenderError> {
        let slot = self.slots.iter().position(|s| !s.busy).ok_or_else(|| {
            RenderError::InvalidOptions("two frames already in flight; read one first".into())
        })?;
        let device = &self.gpu.device;
        let queue = &self.gpu.queue;
        self.renderer
            .prepare(device, queue, scene, camera, self.width, self.height)?;
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("dda3d frame"),
        });
        self.renderer
            .encode(&mut encoder, &self.targets, &self.output_view);
        if scene.overlay {
            self.overlay.encode(
                device,
                queue,
                &mut encoder,
                &self.output_view,
                self.width,
                self.height,
                scene,
                camera,
            );
        }
        let readback = &self.slots[slot].readback;
        readback.copy_from(&mut encoder, &self.output);
        let submission = queue.submit([encoder.finish()]);
        let mapped = readback.map();
        self.slots[slot].busy = true;
        self.gpu.take_error()?;
        Ok(Pending {
            slot,
            submission,
            mapped,
        })
    }

    /// Waits for a submitted frame and returns its pixels: `width * height * 4` bytes of RGBA
    /// (sRGB; premultiplied alpha when the background is transparent), top row first.
    pub fn read(&mut self, pending: Pending) -> Result<Vec<u8>, RenderError> {
        let slot = &mut self.slots[pending.slot];
        let pixels =
            slot.readback
                .read(&self.gpu.device, pending.mapped, Some(pending.submission))?;
        slot.busy = false;
        self.gpu.take_error()?;
        Ok(pixels)
    }

    /// Renders one frame and waits for it.
    pub fn render(&mut self, scene: &RenderScene, camera: &Camera) -> Result<Vec<u8>, RenderError> {
        let p = self.submit(scene, camera)?;
        self.read(p)
    }
}

/// A single-sample colour target that can be drawn into and then copied to a buffer for reading
/// back (frames, screenshots).
pub fn readable_target(
    device: &wgpu::Device,
    label: &str,
    format: wgpu::TextureFormat,
    width: u32,
    height: u32,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn row_padding() {
        assert_eq!(padded_bytes_per_row(64), 256);
        assert_eq!(padded_bytes_per_row(65), 512);
        assert_eq!(padded_bytes_per_row(1280), 5120);
        assert_eq!(padded_bytes_per_row(1), 256);
        // 3 rows of 2 pixels, padded to 256 bytes.
        let mut data = vec![0u8; 256 * 3];
        for r in 0..3 {
            for b in 0..8 {
                data[r * 256 + b] = (r * 10 + b) as u8;
            }
        }
        let out = strip_row_padding(&data, 2, 3, 256);
        assert_eq!(out.len(), 24);
        assert_eq!(&out[8..16], &[10, 11, 12, 13, 14, 15, 16, 17]);
    }
}
