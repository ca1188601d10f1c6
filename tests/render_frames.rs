//! Frame-sequence capture: N snapshots in → N PNGs, N rows of frames.csv with increasing
//! times, and an animated GIF on request.

mod render_support;

use dda3d::render::{CaptureOptions, FrameCapture, Framing};
use dda3d::snapshot::ContactState;
use render_support::*;

fn fresh_dir(name: &str) -> std::path::PathBuf {
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn read_csv(dir: &std::path::Path) -> Vec<(usize, f64, u64, String)> {
    let text = std::fs::read_to_string(dir.join("frames.csv")).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("frame,time,step,file"));
    lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            assert_eq!(f.len(), 4, "bad row {l:?}");
            (
                f[0].parse().unwrap(),
                f[1].parse().unwrap(),
                f[2].parse().unwrap(),
                f[3].to_string(),
            )
        })
        .collect()
}

#[test]
fn n_snapshots_give_n_frames_in_time_order() {
    if gpu_or_skip("n_snapshots_give_n_frames_in_time_order").is_none() {
        return;
    }
    let dir = fresh_dir("render_frames_seq");
    let mut opts = CaptureOptions::new(&dir);
    opts.width = 480;
    opts.height = 270;
    let cap = FrameCapture::start(opts).unwrap();
    const N: usize = 7;
    for k in 0..N {
        // The block slides down the slope; the last frames have sliding contacts.
        let state = if k < 3 {
            ContactState::Lock
        } else {
            ContactState::Slide
        };
        let snap = slope_snapshot(k as f64 / 30.0, 10 * k as u64, 3.0 + 0.3 * k as f64, state);
        cap.submit(snap).unwrap();
    }
    let report = cap.finish().unwrap();
    assert_eq!(report.frames, N);
    assert!(report.gif.is_none());

    let rows = read_csv(&dir);
    assert_eq!(rows.len(), N);
    for (k, (frame, time, step, file)) in rows.iter().enumerate() {
        assert_eq!(*frame, k);
        assert_eq!(*step, 10 * k as u64);
        assert_eq!(file, &format!("frame_{k:05}.png"));
        if k > 0 {
            assert!(*time > rows[k - 1].1, "times must increase: {rows:?}");
        }
        let img = image::open(dir.join(file)).unwrap();
        assert_eq!((img.width(), img.height()), (480, 270));
    }
    let pngs = std::fs::read_dir(&dir)
        .unwrap()
        .filter(|e| {
            e.as_ref()
                .unwrap()
                .file_name()
                .to_string_lossy()
                .ends_with(".png")
        })
        .count();
    assert_eq!(pngs, N);
    // A moving block must change the picture.
    let first = std::fs::read(dir.join("frame_00000.png")).unwrap();
    let last = std::fs::read(dir.join(format!("frame_{:05}.png", N - 1))).unwrap();
    assert_ne!(first, last);
    eprintln!(
        "{} frames at 480x270 on {}: render {:.1} ms/frame, PNG {:.1} ms/frame",
        report.frames,
        report.adapter,
        report.render_ms_per_frame(),
        report.encode_ms_per_frame()
    );
}

#[test]
fn gif_and_fixed_box_framing() {
    if gpu_or_skip("gif_and_fixed_box_framing").is_none() {
        return;
    }
    let dir = fresh_dir("render_frames_gif");
    let mut opts = CaptureOptions::new(&dir);
    opts.width = 320;
    opts.height = 180;
    opts.gif = true;
    opts.fps = 10.0;
    opts.framing = Framing::Box {
        lo: [-2.0, -2.0, 0.0],
        hi: [12.0, 6.0, 6.0],
    };
    opts.style.transparent = true;
    let cap = FrameCapture::start(opts).unwrap();
    for k in 0..4 {
        cap.submit(slope_snapshot(
            0.1 * k as f64,
            k,
            3.0 + 0.5 * k as f64,
            ContactState::Slide,
        ))
        .unwrap();
    }
    let report = cap.finish().unwrap();
    assert_eq!(report.frames, 4);
    let gif = report.gif.expect("gif requested");
    use image::AnimationDecoder;
    let decoder = image::codecs::gif::GifDecoder::new(std::io::BufReader::new(
        std::fs::File::open(&gif).unwrap(),
    ))
    .unwrap();
    let frames = decoder.into_frames().collect_frames().unwrap();
    assert_eq!(frames.len(), 4);
    assert_eq!(frames[0].buffer().dimensions(), (320, 180));
    assert_eq!(read_csv(&dir).len(), 4);
}

#[test]
fn empty_capture_writes_header_only() {
    if gpu_or_skip("empty_capture_writes_header_only").is_none() {
        return;
    }
    let dir = fresh_dir("render_frames_empty");
    let cap = FrameCapture::start(CaptureOptions::new(&dir)).unwrap();
    let report = cap.finish().unwrap();
    assert_eq!(report.frames, 0);
    assert!(read_csv(&dir).is_empty());
}

#[test]
fn bad_frame_stops_the_capture_with_its_error() {
    if gpu_or_skip("bad_frame_stops_the_capture_with_its_error").is_none() {
        return;
    }
    let dir = fresh_dir("render_frames_bad");
    let mut opts = CaptureOptions::new(&dir);
    opts.width = 160;
    opts.height = 90;
    let cap = FrameCapture::start(opts).unwrap();
    let mut snap = slope_snapshot(0.0, 0, 3.0, ContactState::Lock);
    snap.blocks[0].vertices[0][2] = f64::NAN;
    // Later submits may fail once the render thread has stopped; finish reports the cause.
    for _ in 0..4 {
        if cap.submit(snap.clone()).is_err() {
            break;
        }
    }
    let err = cap.finish().unwrap_err();
    assert!(err.to_string().contains("not finite"), "{err}");
}
