//! Side-by-side frames of a comparison (`render --compare`): run A left, run B right, each
//! half drawn on the capture's half-width target with the same camera and look (the frame,
//! arrow scale and colour range fixed by A's first frame), captioned with its side.

use super::frames::FrameState;
use super::{CaptureOptions, FrameMeta};
use crate::render::RenderError;
use crate::render::offscreen::Offscreen;
use crate::snapshot::Snapshot;

/// What the render thread is handed: one snapshot, or A's and B's at one time.
pub(super) enum Job {
    One(Snapshot),
    /// B boxed: a job is moved through a channel, and one snapshot's size is enough.
    Pair(Snapshot, Box<Snapshot>),
}

/// Draws both halves and puts them side by side: the frame's metadata and RGBA.
pub(super) fn render(
    off: &mut Offscreen,
    state: &mut FrameState,
    opts: &CaptureOptions,
    a: &Snapshot,
    b: &Snapshot,
    index: usize,
) -> Result<(FrameMeta, Vec<u8>), RenderError> {
    let captions = opts.sides.clone().unwrap_or_default();
    let mut halves = Vec::with_capacity(2);
    for (snap, caption) in [(a, &captions[0]), (b, &captions[1])] {
        let (mut scene, camera) = state.scene(snap, opts, off.aspect())?;
        scene.caption.scene_name = caption.clone();
        halves.push(off.render(&scene, &camera)?);
    }
    let (w, h) = off.size();
    let row = w as usize * 4;
    let mut rgba = Vec::with_capacity(2 * row * h as usize);
    for y in 0..h as usize {
        rgba.extend_from_slice(&halves[0][y * row..(y + 1) * row]);
        rgba.extend_from_slice(&halves[1][y * row..(y + 1) * row]);
    }
    let meta = FrameMeta {
        index,
        time: a.time,
        step: a.step,
        b: Some((b.time, b.step)),
    };
    Ok((meta, rgba))
}
