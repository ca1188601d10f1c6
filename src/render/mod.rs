//! wgpu renderer for dda3d snapshots, shared by the headless frame capture and the interactive
//! viewer so both draw the same picture. Depends on [`crate::snapshot`] alone.
//!
//! Rooms, bottom up:
//! - [`camera`], [`mesh`], [`arrow_mesh`], [`scene`]: CPU-side camera and geometry (the
//!   arrows as instances of one unit arrow); [`scene`] turns a snapshot into a [`RenderScene`]
//!   (unit-tested without a GPU);
//! - `gpu`: the [`Gpu`] handle (adapter/device/queue), opened apart from the drawing so a
//!   window can bring its own;
//! - `pipeline`, `buffer`: the wgpu set-up every pipeline shares, the window's egui painter
//!   included (shader modules, bind groups, declared pipelines, growing buffers);
//! - `renderer`: the 3-D pass ([`Renderer`]: 4× MSAA where supported, Depth32Float) over one
//!   small renderer per primitive, each with its WGSL in `shaders/`: `solids` (block faces),
//!   `arrows` (contact arrows, instanced, faint where hidden), `lines` (outlines and grid);
//! - [`overlay`]: caption, legends and axis triad, painted with egui;
//! - [`offscreen`]: an off-screen target with row-aligned readback;
//! - [`capture`]: the pipelined PNG/GIF frame writer and single-frame screenshots.
//!
//! What the rest of the crate uses is re-exported below.

pub mod arrow_mesh;
mod arrows;
pub(crate) mod buffer;
pub mod camera;
pub mod capture;
mod gpu;
mod lines;
pub mod mesh;
pub mod offscreen;
pub mod overlay;
pub(crate) mod pipeline;
mod renderer;
pub mod scene;
mod solids;

use std::path::PathBuf;

pub use camera::{Camera, CameraOverride, Ray};
pub use capture::{CaptureOptions, CaptureReport, FrameCapture, Framing, render_to_png};
pub use gpu::{DEPTH_FORMAT, Gpu, OFFSCREEN_FORMAT};
pub use offscreen::Offscreen;
pub use overlay::{Overlay, paint_overlay};
pub use renderer::{RenderTargets, Renderer};
pub use scene::{ArrowMode, Coloring, RenderScene, SceneFrame, SceneStyle};

/// Everything that can go wrong between a snapshot and a file on disk.
#[derive(Clone, Debug, thiserror::Error)]
pub enum RenderError {
    /// No GPU adapter at all (no driver). The CLI maps this to exit status 2.
    #[error(
        "no GPU adapter found; install a GPU driver or the software Vulkan driver \
         (Debian/Ubuntu: apt-get install libvulkan1 mesa-vulkan-drivers)"
    )]
    NoAdapter,
    #[error("could not open the GPU device: {0}")]
    Device(String),
    /// A validation or out-of-memory error reported by wgpu while drawing.
    #[error("GPU error: {0}")]
    Gpu(String),
    #[error("invalid render options: {0}")]
    InvalidOptions(String),
    #[error("cannot draw snapshot: {0}")]
    InvalidSnapshot(String),
    #[error("{path}: {message}")]
    Io { path: PathBuf, message: String },
    #[error("image encoding failed: {0}")]
    Encode(String),
    /// The capture's worker threads stopped (the message says why).
    #[error("frame capture stopped: {0}")]
    Stopped(String),
}

impl RenderError {
    pub(crate) fn io(path: impl Into<PathBuf>, e: impl std::fmt::Display) -> RenderError {
        RenderError::Io {
            path: path.into(),
            message: e.to_string(),
        }
    }
}

/// True when the environment demands a GPU adapter (`DDA3D_REQUIRE_GPU=1`, set by CI), so a
/// missing adapter must fail a test instead of skipping it.
pub fn gpu_required_by_env() -> bool {
    std::env::var("DDA3D_REQUIRE_GPU")
        .map(|v| {
            let v = v.trim();
            !v.is_empty() && v != "0" && !v.eq_ignore_ascii_case("false")
        })
        .unwrap_or(false)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_adapter_message_says_what_to_install() {
        let msg = RenderError::NoAdapter.to_string();
        assert!(
            msg.contains("apt-get install libvulkan1 mesa-vulkan-drivers"),
            "{msg}"
        );
        assert!(!msg.contains('\n'), "one line");
    }
}
