//! Pixels to files: PNG frames (on the encoder threads, [`encode_loop`]) and the animated GIF
//! (on its own thread, [`gif_loop`]), with the alpha handling both need, since the GPU reads back premultiplied
//! alpha and GIF has only on/off transparency.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::mpsc::Receiver;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use image::ImageEncoder;

use crate::render::RenderError;
use crate::render::mesh::{self, hex};
use crate::render::scene::BACKGROUND_SRGB;

/// One frame for a PNG encoder thread.
pub(super) struct EncodeJob {
    pub path: PathBuf,
    pub rgba: Arc<Vec<u8>>,
    pub width: u32,
    pub height: u32,
    pub transparent: bool,
}

/// One frame for the GIF thread.
pub(super) struct GifFrame {
    pub rgba: Arc<Vec<u8>>,
    pub width: u32,
    pub height: u32,
    pub transparent: bool,
}

/// A PNG encoder thread: takes jobs until the queue closes; returns the time spent encoding.
pub(super) fn encode_loop(rx: &Mutex<Receiver<EncodeJob>>) -> Result<Duration, RenderError> {
    let mut total = Duration::ZERO;
    loop {
        // The lock is held only while waiting for a job, not while encoding.
        let job = match rx.lock() {
            Ok(r) => r.recv(),
            Err(_) => return Err(RenderError::Stopped("encoder queue poisoned".into())),
        };
        let Ok(job) = job else {
            return Ok(total);
        };
        let t = Instant::now();
        write_png(&job.path, &job.rgba, job.width, job.height, job.transparent)?;
        total += t.elapsed();
    }
}

/// Writes RGBA pixels as read back from the GPU to a PNG: RGB when opaque (smaller, faster);
/// with `transparent`, RGBA with the GPU's premultiplied alpha converted to straight alpha.
pub fn write_png(
    path: &Path,
    rgba: &[u8],
    width: u32,
    height: u32,
    transparent: bool,
) -> Result<(), RenderError> {
    let expected = width as usize * height as usize * 4;
    if rgba.len() != expected {
        return Err(RenderError::Encode(format!(
            "{}: have {} bytes for a {width}x{height} RGBA image (need {expected})",
            path.display(),
            rgba.len()
        )));
    }
    // Written beside its final name and renamed when whole, so a run that is stopped or runs
    // out of disk never leaves a truncated PNG under a frame's name.
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".tmp");
    let tmp = PathBuf::from(tmp);
    let written = encode_png(&tmp, rgba, width, height, transparent)
        .and_then(|_| std::fs::rename(&tmp, path).map_err(|e| RenderError::io(path, e)));
    if written.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    written
}

fn encode_png(
    path: &Path,
    rgba: &[u8],
    width: u32,
    height: u32,
    transparent: bool,
) -> Result<(), RenderError> {
    let file = File::create(path).map_err(|e| RenderError::io(path, e))?;
    let mut out = BufWriter::new(file);
    let encoder = image::codecs::png::PngEncoder::new(&mut out);
    let result = if transparent {
        let mut straight = rgba.to_vec();
        unpremultiply(&mut straight);
        encoder.write_image(&straight, width, height, image::ExtendedColorType::Rgba8)
    } else {
        let rgb: Vec<u8> = rgba
            .chunks_exact(4)
            .flat_map(|p| [p[0], p[1], p[2]])
            .collect();
        encoder.write_image(&rgb, width, height, image::ExtendedColorType::Rgb8)
    };
    result.map_err(|e| RenderError::Encode(format!("{}: {e}", path.display())))?;
    out.flush().map_err(|e| RenderError::io(path, e))
}

fn srgb_lut() -> &'static [f32; 256] {
    static LUT: std::sync::OnceLock<[f32; 256]> = std::sync::OnceLock::new();
    LUT.get_or_init(|| {
        let mut t = [0.0; 256];
        for (k, v) in t.iter_mut().enumerate() {
            *v = mesh::srgb_to_linear([k as f32 / 255.0, 0.0, 0.0, 1.0])[0];
        }
        t
    })
}

fn encode_srgb(linear: f32) -> u8 {
    (mesh::linear_to_srgb([linear, 0.0, 0.0, 1.0])[0] * 255.0).round() as u8
}

/// Premultiplied (in linear light, sRGB-encoded) → straight alpha, in place. Only partly
/// covered pixels (antialiased edges, translucent overlay) change.
pub fn unpremultiply(rgba: &mut [u8]) {
    let lut = srgb_lut();
    for p in rgba.chunks_exact_mut(4) {
        let a = p[3];
        if a == 0 || a == 255 {
            continue;
        }
        let af = a as f32 / 255.0;
        for c in &mut p[..3] {
            *c = encode_srgb((lut[*c as usize] / af).min(1.0));
        }
    }
}

/// Composites premultiplied pixels over the opaque background (for GIF, which has only
/// on/off transparency).
fn composite_over_background(rgba: &mut [u8]) {
    let lut = srgb_lut();
    let bg = mesh::srgb_to_linear(hex(BACKGROUND_SRGB));
    for p in rgba.chunks_exact_mut(4) {
        let a = p[3];
        if a == 255 {
            continue;
        }
        let rest = 1.0 - a as f32 / 255.0;
        for k in 0..3 {
            p[k] = encode_srgb(lut[p[k] as usize] + bg[k] * rest);
        }
        p[3] = 255;
    }
}

/// Box-filter downscale of RGBA by a whole factor.
fn downscale(rgba: &[u8], width: u32, height: u32, factor: u32) -> (Vec<u8>, u32, u32) {
    if factor <= 1 {
        return (rgba.to_vec(), width, height);
    }
    let (w, h) = ((width / factor).max(1), (height / factor).max(1));
    let mut out = vec![0u8; (w * h * 4) as usize];
    let n = factor * factor;
    for y in 0..h {
        for x in 0..w {
            let mut acc = [0u32; 4];
            for dy in 0..factor {
                let row = ((y * factor + dy).min(height - 1) * width) as usize;
                for dx in 0..factor {
                    let i = (row + (x * factor + dx).min(width - 1) as usize) * 4;
                    for k in 0..4 {
                        acc[k] += rgba[i + k] as u32;
                    }
                }
            }
            let o = ((y * w + x) * 4) as usize;
            for k in 0..4 {
                out[o + k] = ((acc[k] + n / 2) / n) as u8;
            }
        }
    }
    (out, w, h)
}

/// The GIF thread: downscales and appends frames until the queue closes; returns its busy time.
pub(super) fn gif_loop(
    rx: Receiver<GifFrame>,
    file: File,
    path: &Path,
    fps: f64,
    max_width: u32,
) -> Result<Duration, RenderError> {
    use image::codecs::gif::{GifEncoder, Repeat};
    let mut total = Duration::ZERO;
    // Speed 10 of 1–30: close to the best palette at a fraction of the time of speed 1.
    let mut enc = GifEncoder::new_with_speed(BufWriter::new(file), 10);
    let err = |e: image::ImageError| RenderError::Encode(format!("{}: {e}", path.display()));
    enc.set_repeat(Repeat::Infinite).map_err(err)?;
    let delay = image::Delay::from_saturating_duration(Duration::from_secs_f64(1.0 / fps));
    for f in rx {
        let t = Instant::now();
        let factor = f.width.div_ceil(max_width.max(1)).max(1);
        let (mut px, w, h) = downscale(&f.rgba, f.width, f.height, factor);
        drop(f.rgba);
        if f.transparent {
            composite_over_background(&mut px);
        }
        let img = image::RgbaImage::from_raw(w, h, px)
            .ok_or_else(|| RenderError::Encode("GIF frame has the wrong size".into()))?;
        enc.encode_frame(image::Frame::from_parts(img, 0, 0, delay))
            .map_err(err)?;
        total += t.elapsed();
    }
    drop(enc);
    Ok(total)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unpremultiply_restores_colour() {
        // Half-covered pure red over transparent: premultiplied linear red = 0.5.
        let half = encode_srgb(0.5);
        let mut px = vec![half, 0, 0, 128, 10, 20, 30, 255, 0, 0, 0, 0];
        unpremultiply(&mut px);
        assert!(px[0] >= 254, "{}", px[0]);
        assert_eq!(&px[4..8], &[10, 20, 30, 255]);
        assert_eq!(&px[8..12], &[0, 0, 0, 0]);
    }

    #[test]
    fn downscale_averages() {
        let px: Vec<u8> = [0u8, 0, 0, 255, 200, 200, 200, 255].repeat(2);
        let (out, w, h) = downscale(&px, 2, 2, 2);
        assert_eq!((w, h), (1, 1));
        assert_eq!(out, vec![100, 100, 100, 255]);
    }

    #[test]
    fn png_size_mismatch_is_an_error() {
        let dir = std::env::temp_dir().join(format!("dda3d-png-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let e = write_png(&dir.join("x.png"), &[0; 10], 2, 2, false);
        assert!(matches!(e, Err(RenderError::Encode(_))));
        write_png(&dir.join("ok.png"), &[7; 16], 2, 2, true).unwrap();
        let img = image::open(dir.join("ok.png")).unwrap();
        assert_eq!((img.width(), img.height()), (2, 2));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
