//! Throughput of the headless capture at 1280×720 (a benchmark, not a timed test):
//! `cargo test --release --test render_bench -- --ignored --nocapture`.

mod render_support;

use std::time::Instant;

use dda3d::render::capture::{render_rgba, write_png};
use dda3d::render::{CaptureOptions, FrameCapture, Offscreen};
use dda3d::snapshot::ContactState;
use render_support::*;

#[test]
#[ignore = "benchmark; run with --ignored --nocapture"]
fn capture_throughput_1280x720() {
    let Some(gpu) = gpu_or_skip("capture_throughput_1280x720") else {
        return;
    };
    const N: usize = 60;
    let snaps: Vec<_> = (0..N)
        .map(|k| {
            slope_snapshot(
                k as f64 / 30.0,
                k as u64,
                3.0 + 0.05 * k as f64,
                ContactState::Slide,
            )
        })
        .collect();
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("render_bench");
    let _ = std::fs::remove_dir_all(&dir);

    // Stages one at a time, on one thread.
    let opts = CaptureOptions::new(&dir);
    let mut off = Offscreen::new(gpu.clone(), 1280, 720).unwrap();
    let _ = render_rgba(&mut off, &snaps[0], &opts).unwrap(); // shader compile
    std::fs::create_dir_all(&dir).unwrap();
    let (mut t_render, mut t_png) = (0.0, 0.0);
    for s in snaps.iter().take(20) {
        let t = Instant::now();
        let (rgba, _) = render_rgba(&mut off, s, &opts).unwrap();
        t_render += t.elapsed().as_secs_f64();
        let t = Instant::now();
        write_png(&dir.join("serial.png"), &rgba, 1280, 720, false).unwrap();
        t_png += t.elapsed().as_secs_f64();
    }
    eprintln!(
        "serial, {}: render+readback {:.1} ms/frame, PNG encode {:.1} ms/frame",
        gpu.adapter_summary(),
        t_render * 1e3 / 20.0,
        t_png * 1e3 / 20.0
    );
    drop(off);

    // The pipelined capture.
    let cap = FrameCapture::start_with_gpu(gpu, CaptureOptions::new(&dir)).unwrap();
    let t = Instant::now();
    for s in snaps {
        cap.submit(s).unwrap();
    }
    let r = cap.finish().unwrap();
    let wall = t.elapsed().as_secs_f64();
    eprintln!(
        "pipelined: {} frames in {:.2} s = {:.1} frames/s; render thread {:.1} ms/frame, \
         PNG {:.1} ms/frame over the encoder threads, submit blocked {:.2} s, setup {:.2} s",
        r.frames,
        wall,
        r.frames as f64 / wall,
        r.render_ms_per_frame(),
        r.encode_ms_per_frame(),
        r.submit_blocked_seconds,
        r.setup_seconds
    );
}

#[test]
#[ignore = "benchmark; run with --ignored --nocapture"]
fn gif_throughput_1280x720() {
    let Some(gpu) = gpu_or_skip("gif_throughput_1280x720") else {
        return;
    };
    const N: usize = 30;
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("render_bench_gif");
    let _ = std::fs::remove_dir_all(&dir);
    let mut opts = CaptureOptions::new(&dir);
    opts.gif = true;
    let cap = FrameCapture::start_with_gpu(gpu, opts).unwrap();
    let t = Instant::now();
    for k in 0..N {
        cap.submit(slope_snapshot(
            k as f64 / 30.0,
            k as u64,
            3.0 + 0.05 * k as f64,
            ContactState::Slide,
        ))
        .unwrap();
    }
    let r = cap.finish().unwrap();
    let wall = t.elapsed().as_secs_f64();
    eprintln!(
        "with --gif: {} frames in {:.2} s = {:.1} frames/s; GIF {:.1} ms/frame (640x360)",
        r.frames,
        wall,
        r.frames as f64 / wall,
        r.gif_seconds * 1e3 / r.frames as f64
    );
}
