//! What a capture is asked for: output directory, image size, camera and framing, the look of
//! the frames, GIF and encoder settings.

use std::path::PathBuf;

use crate::render::RenderError;
use crate::render::camera::CameraOverride;
use crate::render::scene::SceneStyle;

/// Which box the camera frames.
#[derive(Clone, Debug, PartialEq)]
pub enum Framing {
    /// The blocks of the first snapshot, then fixed: the camera, grid, force scale and
    /// colour-map range do not move between frames.
    FirstFrame,
    /// Re-framed on every snapshot (follows falling blocks, but the view jumps).
    EachFrame,
    /// A fixed box given by the caller (e.g. the scene's full extent).
    Box { lo: [f64; 3], hi: [f64; 3] },
}

/// Settings of a capture.
#[derive(Clone, Debug)]
pub struct CaptureOptions {
    pub out_dir: PathBuf,
    pub width: u32,
    pub height: u32,
    /// Overrides of the automatic camera (`--camera az,el,dist`).
    pub camera: CameraOverride,
    pub framing: Framing,
    pub style: SceneStyle,
    /// Also write `animation.gif`.
    pub gif: bool,
    /// Playback rate of the GIF, frames per second (normally the capture rate, `--fps`).
    pub fps: f64,
    /// GIF frames are downscaled by a whole factor to at most this width (GIF colour
    /// quantisation is slow and files get large at full HD).
    pub gif_max_width: u32,
    /// PNG encoder threads; 0 = one per core beyond the first, at least one.
    pub encoder_threads: usize,
    /// Upper bound on MSAA samples (4 by default; 1 turns antialiasing off, about 3× faster
    /// on the software driver, for quick previews).
    pub max_msaa_samples: u32,
    /// A side-by-side comparison (`render --compare`): the captions of the left (A) and right
    /// (B) halves. Each frame is then a pair of snapshots ([`super::FrameCapture::submit_pair`]),
    /// both halves seen by the same camera, and frames.csv lists both sides' times.
    pub sides: Option<[String; 2]>,
}

impl CaptureOptions {
    /// 1280×720 PNGs into `out_dir`, automatic camera fixed on the first frame.
    pub fn new(out_dir: impl Into<PathBuf>) -> CaptureOptions {
        CaptureOptions {
            out_dir: out_dir.into(),
            width: 1280,
            height: 720,
            camera: CameraOverride::default(),
            framing: Framing::FirstFrame,
            style: SceneStyle::default(),
            gif: false,
            fps: 30.0,
            gif_max_width: 640,
            encoder_threads: 0,
            max_msaa_samples: 4,
            sides: None,
        }
    }

    pub(super) fn validate(&self) -> Result<(), RenderError> {
        if self.width == 0 || self.height == 0 {
            return Err(RenderError::InvalidOptions(format!(
                "image size must be positive, got {}x{}",
                self.width, self.height
            )));
        }
        if self.sides.is_some() && self.width < 2 {
            return Err(RenderError::InvalidOptions(format!(
                "a side-by-side image needs a width of at least 2, got {}",
                self.width
            )));
        }
        if self.gif && !(self.fps.is_finite() && self.fps > 0.0) {
            return Err(RenderError::InvalidOptions(format!(
                "GIF frame rate must be positive, got {}",
                self.fps
            )));
        }
        if let Framing::Box { lo, hi } = &self.framing
            && !lo.iter().chain(hi.iter()).all(|v| v.is_finite())
        {
            return Err(RenderError::InvalidOptions(
                "camera box has non-finite corners".into(),
            ));
        }
        Ok(())
    }

    pub(super) fn encoder_count(&self) -> usize {
        if self.encoder_threads > 0 {
            return self.encoder_threads.min(64);
        }
        let cores = std::thread::available_parallelism().map_or(2, |n| n.get());
        (cores - 1).clamp(1, 8)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn options_are_checked() {
        let mut o = CaptureOptions::new("/tmp/x");
        o.width = 0;
        assert!(matches!(o.validate(), Err(RenderError::InvalidOptions(_))));
        let mut o = CaptureOptions::new("/tmp/x");
        o.gif = true;
        o.fps = 0.0;
        assert!(o.validate().is_err());
        assert!(CaptureOptions::new("/tmp/x").encoder_count() >= 1);
    }
}
