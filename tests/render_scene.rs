//! Renders the shipped slope scene (scenes/slope_stable.toml) through the solver: at t = 0, and
//! after the first step, when its four contacts exist and carry the block's weight.

mod cli_support;
mod render_support;

use cli_support::{bin, rockfall_checkpoint, tmp};
use dda3d::render::capture::render_rgba;
use dda3d::render::mesh::BLOCK_PALETTE_SRGB;
use dda3d::render::{CaptureOptions, Offscreen};
use dda3d::scene;
use dda3d::solver::Solver;
use render_support::*;
use std::process::Output;

const W: u32 = 1280;
const H: u32 = 720;

#[test]
fn shipped_slope_scene_renders_through_the_solver() {
    let Some(gpu) = gpu_or_skip("shipped_slope_scene_renders_through_the_solver") else {
        return;
    };
    let s = scene::load(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/slope_stable.toml"),
    )
    .unwrap();
    let mut solver = Solver::new(s.model, s.params);
    let snap0 = solver.snapshot();
    assert_eq!(snap0.time, 0.0);
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("render_scene");
    std::fs::create_dir_all(&dir).unwrap();
    let opts = CaptureOptions::new(&dir);
    let mut off = Offscreen::new(gpu, W, H).unwrap();
    let (rgba0, camera) = render_rgba(&mut off, &snap0, &opts).unwrap();
    assert_eq!(rgba0.len(), (W * H * 4) as usize, "requested size");
    let non_bg = drawn_pixels(&rgba0);
    assert!(
        non_bg > (W * H / 10) as usize,
        "not blank: {non_bg} drawn pixels"
    );

    // The block's centroid projected with the camera matrices lies on block-coloured pixels.
    let block = snap0.blocks.iter().position(|b| b.name == "block").unwrap();
    let c = camera
        .project(snap0.blocks[block].centroid, W, H)
        .expect("in front of the camera");
    let mut hits = 0;
    for dy in -2i32..=2 {
        for dx in -2i32..=2 {
            if same_hue(
                pixel(
                    &rgba0,
                    W,
                    (c.x as i32 + dx) as u32,
                    (c.y as i32 + dy) as u32,
                ),
                BLOCK_PALETTE_SRGB[block],
            ) {
                hits += 1;
            }
        }
    }
    assert!(
        hits >= 20,
        "centroid {c:?}: {hits}/25 block-coloured pixels"
    );
    for (x, y) in [(W - 3, 3), (W / 2, 3)] {
        assert!(
            is_background(pixel(&rgba0, W, x, y)),
            "({x},{y}) should be background"
        );
    }
    // No contact has been computed at t = 0, so no arrows yet.
    assert!(solver.contacts().is_empty());

    // After one step the four base contacts carry the weight: force arrows appear.
    solver.step().unwrap();
    let snap1 = solver.snapshot();
    assert_eq!(snap1.contacts.len(), 4);
    let (rgba1, _) = render_rgba(&mut off, &snap1, &opts).unwrap();
    let (with, without) = (lock_blue_pixels(&rgba1), lock_blue_pixels(&rgba0));
    assert!(
        with > without + 200,
        "arrow pixels: {with} with contacts, {without} without"
    );
}

/// `dda3d render` as a user runs it: N frame times requested, N files, increasing times.
#[test]
fn render_command_writes_the_requested_frames() {
    if gpu_or_skip("render_command_writes_the_requested_frames").is_none() {
        return;
    }
    let out = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("render_cmd");
    let _ = std::fs::remove_dir_all(&out);
    let scene = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/slope_sliding.toml");
    let st = std::process::Command::new(env!("CARGO_BIN_EXE_dda3d"))
        .arg("render")
        .arg(&scene)
        .args([
            "--duration",
            "0.2",
            "--fps",
            "20",
            "--width",
            "320",
            "--height",
            "180",
            "--quiet",
            "--out",
        ])
        .arg(&out)
        .status()
        .unwrap();
    assert!(st.success());
    let csv = std::fs::read_to_string(out.join("frames.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("frame,time,step,file"));
    let rows: Vec<Vec<String>> = lines
        .map(|l| l.split(',').map(String::from).collect())
        .collect();
    assert_eq!(rows.len(), 5, "t = 0, 0.05, 0.1, 0.15, 0.2");
    let mut last = -1.0;
    for (k, r) in rows.iter().enumerate() {
        let t: f64 = r[1].parse().unwrap();
        assert!(t > last, "times increase");
        assert!((t - 0.05 * k as f64).abs() < 1e-9, "frame {k} at t = {t}");
        last = t;
        let img = image::open(out.join(&r[3])).unwrap();
        assert_eq!((img.width(), img.height()), (320, 180));
    }
}

/// With no adapter at all (no Vulkan driver visible), `render` says what to install and exits 2.
#[test]
fn render_without_an_adapter_is_an_input_error() {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_dda3d"))
        .arg("render")
        .arg(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/slope_stable.toml"))
        .args(["--duration", "0.05", "--quiet", "--out"])
        .arg(std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("render_no_adapter"))
        .env("WGPU_BACKEND", "vulkan")
        .env("VK_ICD_FILENAMES", "/nonexistent/icd.json")
        .env("VK_DRIVER_FILES", "/nonexistent/icd.json")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("mesa-vulkan-drivers"), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
}

/// `render --resume CKPT` with `extra` flags into `out`, small and quiet.
fn render_resumed(ckpt: &std::path::Path, out: &std::path::Path, extra: &[&str]) -> Output {
    bin()
        .args(["render", "--resume"])
        .arg(ckpt)
        .args(extra)
        .args([
            "--width", "320", "--height", "180", "--msaa", "1", "--quiet", "--out",
        ])
        .arg(out)
        .output()
        .unwrap()
}

/// frames.csv's rows, split at the commas.
fn frame_rows(dir: &std::path::Path) -> Vec<Vec<String>> {
    let csv = std::fs::read_to_string(dir.join("frames.csv")).unwrap();
    csv.lines()
        .skip(1)
        .map(|l| l.split(',').map(String::from).collect())
        .collect()
}

/// `render --resume`, used badly: an end before the checkpoint, a solver flag (the
/// checkpoint's settings hold), a bad image option, a file that is not a checkpoint. One line
/// each, exit 2, nothing written; no GPU is needed to say so.
#[test]
fn render_from_a_checkpoint_refuses_bad_uses() {
    let tmp = tmp("resume_bad");
    let (ckpt, _) = rockfall_checkpoint(&tmp);
    let frames = tmp.join("frames");
    let not_one = tmp.join("run/summary.json");
    let bad: [(&std::path::Path, &[&str], &str); 4] = [
        (&ckpt, &["--duration", "0.3"], "give a later --duration"),
        (&ckpt, &["--method", "penalty"], "cannot be used with"),
        (&ckpt, &["--fps", "0"], "--fps must be positive"),
        (&not_one, &[], "summary.json: not a dda3d checkpoint"),
    ];
    for (file, extra, want) in bad {
        let o = render_resumed(file, &frames, extra);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{extra:?}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(err.contains(want), "{extra:?}: {err}");
        assert!(!frames.exists(), "{extra:?}: nothing written");
    }
}

/// `render --resume`: the frames start from a checkpoint of `run` (a large rock mass's
/// equilibrium stage computed once): the first frame is the checkpoint's state at its time and
/// step, the next ones fall on the multiples of 1/fps after it, up to the new end time; with
/// `--compare` both halves start there.
#[test]
fn render_resumes_from_a_checkpoint() {
    if gpu_or_skip("render_resumes_from_a_checkpoint").is_none() {
        return;
    }
    let tmp = tmp("resume");
    let (ckpt, t0) = rockfall_checkpoint(&tmp);
    let frames = tmp.join("frames");
    let o = render_resumed(&ckpt, &frames, &["--duration", "0.8", "--fps", "10"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rows = frame_rows(&frames);
    let times: Vec<f64> = rows.iter().map(|r| r[1].parse().unwrap()).collect();
    let steps: Vec<u64> = rows.iter().map(|r| r[2].parse().unwrap()).collect();
    assert_eq!(
        times.len(),
        4,
        "the checkpoint's state, then 0.6, 0.7, 0.8: {times:?}"
    );
    assert!((times[0] - t0).abs() < 1e-6, "{} against {t0}", times[0]);
    for (k, want) in [0.6, 0.7, 0.8].into_iter().enumerate() {
        assert!((times[k + 1] - want).abs() < 1e-9, "{times:?}");
    }
    // The step count goes on from the checkpoint's (the run's 0.5 s took tens of steps).
    assert!(steps[0] > 20, "{steps:?}");
    assert!(steps.windows(2).all(|w| w[0] < w[1]), "{steps:?}");
    for r in &rows {
        let img = image::open(frames.join(&r[3])).unwrap();
        assert_eq!((img.width(), img.height()), (320, 180));
    }

    // Compared: both halves start from the checkpoint (its time and step on both sides of the
    // first row), then each takes its own steps to the same frame times.
    let pair = tmp.join("pair");
    let extra = ["--compare", "penalty", "--duration", "0.7", "--fps", "10"];
    let o = render_resumed(&ckpt, &pair, &extra);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rows = frame_rows(&pair);
    assert_eq!(rows.len(), 3, "{rows:?}");
    assert_eq!((&rows[0][1], &rows[0][2]), (&rows[0][4], &rows[0][5]));
    assert_eq!(rows[0][2], steps[0].to_string());
    for r in &rows[1..] {
        assert_eq!(r[1], r[4], "one time on both sides: {rows:?}");
    }
}
