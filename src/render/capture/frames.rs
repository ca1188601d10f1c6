//! From snapshot to pixels with the capture's look: [`FrameState`] keeps the camera, grid,
//! force scale and colour range of a sequence fixed, and [`render_rgba`]/[`render_to_png`]
//! draw a single frame the same way (screenshots for a report).

use std::path::Path;

use super::encode::write_png;
use super::options::{CaptureOptions, Framing};
use crate::render::RenderError;
use crate::render::camera::Camera;
use crate::render::gpu::Gpu;
use crate::render::offscreen::Offscreen;
use crate::render::scene::{self, Coloring, RenderScene, SceneFrame, SceneStyle};
use crate::snapshot::Snapshot;

/// Keeps camera, grid, force scale and colour range fixed across frames (unless framing is
/// per frame), so a sequence compares frame to frame.
pub(super) struct FrameState {
    frame: Option<SceneFrame>,
    style: SceneStyle,
    field_max: f64,
}

impl FrameState {
    pub(super) fn new(opts: &CaptureOptions) -> FrameState {
        FrameState {
            frame: match &opts.framing {
                Framing::Box { lo, hi } => Some(SceneFrame::from_box(*lo, *hi)),
                _ => None,
            },
            style: opts.style.clone(),
            field_max: 0.0,
        }
    }

    /// The next frame's scene and camera (for an image of `aspect` width / height).
    pub(super) fn scene(
        &mut self,
        snap: &Snapshot,
        opts: &CaptureOptions,
        aspect: f32,
    ) -> Result<(RenderScene, Camera), RenderError> {
        let fixed = opts.framing != Framing::EachFrame;
        let frame = if fixed {
            *self
                .frame
                .get_or_insert_with(|| SceneFrame::of_snapshot(snap))
        } else {
            SceneFrame::of_snapshot(snap)
        };
        if fixed && opts.style.field_range.is_none() && opts.style.coloring != Coloring::PerBlock {
            // The colour range only grows, so a colour means the same speed in later frames.
            self.field_max = self
                .field_max
                .max(scene::field_max(snap, opts.style.coloring));
            if self.field_max > 0.0 {
                self.style.field_range = Some((0.0, self.field_max));
            }
        }
        let scene = RenderScene::build(snap, &self.style, &frame)?;
        if fixed && self.style.force_scale.is_none() {
            // The first frame with contacts sets the arrow scale for the rest of the run.
            self.style.force_scale = scene.force_scale;
        }
        Ok((scene, frame.camera(aspect, &opts.camera)))
    }
}

/// Renders one snapshot to a PNG (a screenshot for a report) with the same look as a
/// capture. Returns the camera used, so callers can relate world points to pixels.
pub fn render_to_png(
    snapshot: &Snapshot,
    opts: &CaptureOptions,
    path: &Path,
) -> Result<Camera, RenderError> {
    opts.validate()?;
    let gpu = Gpu::headless()?;
    let mut off = Offscreen::with_max_samples(gpu, opts.width, opts.height, opts.max_msaa_samples)?;
    let (rgba, camera) = render_rgba(&mut off, snapshot, opts)?;
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        super::create_output_dir(dir)?;
    }
    write_png(path, &rgba, opts.width, opts.height, opts.style.transparent)?;
    Ok(camera)
}

/// Renders one snapshot on an existing off-screen target; returns RGBA (premultiplied when
/// transparent) and the camera.
pub fn render_rgba(
    off: &mut Offscreen,
    snapshot: &Snapshot,
    opts: &CaptureOptions,
) -> Result<(Vec<u8>, Camera), RenderError> {
    let mut state = FrameState::new(opts);
    let (scene, camera) = state.scene(snapshot, opts, off.aspect())?;
    let rgba = off.render(&scene, &camera)?;
    Ok((rgba, camera))
}
