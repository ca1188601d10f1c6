//! The GPU handle: adapter, device and queue, opened apart from any drawing so the headless
//! capture opens its own and the window brings one compatible with its surface. Also the two
//! texture formats every pass agrees on.

use std::sync::{Arc, Mutex};

use super::RenderError;

/// A wgpu device and queue plus the adapter they came from.
#[derive(Clone)]
pub struct Gpu {
    pub instance: wgpu::Instance,
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    /// First uncaptured wgpu error (validation, out of memory) since the last check; wgpu's
    /// default handler would panic instead.
    errors: Arc<Mutex<Option<String>>>,
}

impl Gpu {
    /// Opens the best adapter without any window system (works over SSH and in CI). Honours
    /// wgpu's environment variables (`WGPU_BACKEND`, `WGPU_ADAPTER_NAME`, ...).
    pub fn headless() -> Result<Gpu, RenderError> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle().with_env());
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            compatible_surface: None,
            ..Default::default()
        }))
        .map_err(|_| RenderError::NoAdapter)?;
        Gpu::from_adapter(instance, adapter)
    }

    /// Opens a device on a chosen adapter (the interactive viewer picks one compatible with
    /// its window surface).
    pub fn from_adapter(
        instance: wgpu::Instance,
        adapter: wgpu::Adapter,
    ) -> Result<Gpu, RenderError> {
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("dda3d"),
            required_features: wgpu::Features::empty(),
            // What the adapter offers, so large captures are limited by the hardware only.
            required_limits: adapter.limits(),
            ..Default::default()
        }))
        .map_err(|e| RenderError::Device(e.to_string()))?;
        let errors: Arc<Mutex<Option<String>>> = Arc::new(Mutex::new(None));
        let sink = errors.clone();
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            if let Ok(mut slot) = sink.lock() {
                slot.get_or_insert_with(|| e.to_string());
            }
        }));
        Ok(Gpu {
            instance,
            adapter,
            device,
            queue,
            errors,
        })
    }

    /// "name (backend, type)" of the adapter, for logs and the benchmark report.
    pub fn adapter_summary(&self) -> String {
        let i = self.adapter.get_info();
        format!("{} ({:?}, {:?})", i.name, i.backend, i.device_type)
    }

    /// Returns (and clears) the first wgpu error reported since the last call.
    pub fn take_error(&self) -> Result<(), RenderError> {
        match self.errors.lock().ok().and_then(|mut e| e.take()) {
            Some(msg) => Err(RenderError::Gpu(msg)),
            None => Ok(()),
        }
    }

    /// Largest MSAA sample count ≤ `wanted` that both `color` and Depth32Float support as
    /// render attachments (1 always works).
    pub fn msaa_samples(&self, color: wgpu::TextureFormat, wanted: u32) -> u32 {
        let c = self.adapter.get_texture_format_features(color).flags;
        let d = self.adapter.get_texture_format_features(DEPTH_FORMAT).flags;
        [16, 8, 4, 2]
            .into_iter()
            .find(|&n| n <= wanted && c.sample_count_supported(n) && d.sample_count_supported(n))
            .unwrap_or(1)
    }
}

/// Depth attachment of the 3-D pass (no stencil is used).
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// Off-screen colour format: sRGB so lighting is computed in linear light and the bytes read
/// back are ready for PNG.
pub const OFFSCREEN_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
