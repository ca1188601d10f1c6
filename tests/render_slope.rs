//! Renders the paper's slope scene (block on a 30° slope, four vertex–face contacts) to PNG
//! and checks the picture against the camera matrices.

mod render_support;

use dda3d::render::capture::{render_rgba, write_png};
use dda3d::render::mesh::{BLOCK_PALETTE_SRGB, FIXED_BLOCK_SRGB};
use dda3d::render::{CaptureOptions, Offscreen, render_to_png};
use dda3d::snapshot::ContactState;
use render_support::*;

const W: u32 = 1280;
const H: u32 = 720;

fn out_dir() -> std::path::PathBuf {
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("render_slope");
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn slope_scene_renders_block_background_and_arrows() {
    let Some(gpu) = gpu_or_skip("slope_scene_renders_block_background_and_arrows") else {
        return;
    };
    let snap = slope_snapshot(0.0, 0, 3.0, ContactState::Lock);
    let opts = CaptureOptions::new(out_dir());
    let mut off = Offscreen::new(gpu, W, H).unwrap();
    let (rgba, camera) = render_rgba(&mut off, &snap, &opts).unwrap();
    assert_eq!(rgba.len(), (W * H * 4) as usize);
    write_png(&out_dir().join("slope_t0.png"), &rgba, W, H, false).unwrap();

    // Not blank: plenty of non-background pixels and many distinct colours.
    let mut non_bg = 0usize;
    let mut colours = std::collections::HashSet::new();
    for p in rgba.chunks_exact(4) {
        let px = [p[0], p[1], p[2], p[3]];
        if !is_background(px) {
            non_bg += 1;
        }
        colours.insert(px);
    }
    assert!(
        non_bg > (W * H / 10) as usize,
        "only {non_bg} non-background pixels"
    );
    assert!(colours.len() > 200, "only {} colours", colours.len());

    // The block's centroid, projected with the camera's matrices, is on block-coloured pixels.
    let block = &snap.blocks[1];
    let c = camera
        .project(block.centroid, W, H)
        .expect("centroid in front");
    assert!(c.x > 0.0 && c.x < W as f32 && c.y > 0.0 && c.y < H as f32);
    let block_colour = BLOCK_PALETTE_SRGB[1];
    let mut hits = 0;
    for dy in -2i32..=2 {
        for dx in -2i32..=2 {
            let px = pixel(&rgba, W, (c.x as i32 + dx) as u32, (c.y as i32 + dy) as u32);
            if same_hue(px, block_colour) {
                hits += 1;
            }
        }
    }
    assert!(
        hits >= 20,
        "centroid at {c:?}: {hits}/25 pixels have the block's colour"
    );

    // The slope body (fixed) is drawn in the muted stone colour.
    let slope_c = camera.project([1.0, 2.0, 1.0], W, H).unwrap();
    let px = pixel(&rgba, W, slope_c.x as u32, slope_c.y as u32);
    assert!(same_hue(px, FIXED_BLOCK_SRGB), "slope pixel {px:?}");

    // Background where nothing is: the top-right corner and the middle of the top edge.
    for (x, y) in [(W - 3, 3), (W / 2, 3), (W - 3, H / 3)] {
        let px = pixel(&rgba, W, x, y);
        assert!(
            is_background(px),
            "({x},{y}) is {px:?}, expected background"
        );
    }

    // Contact-force arrows: blue (locked) pixels that are absent without contacts.
    let mut bare = snap.clone();
    bare.contacts.clear();
    let (rgba_bare, _) = render_rgba(&mut off, &bare, &opts).unwrap();
    let (with, without) = (lock_blue_pixels(&rgba), lock_blue_pixels(&rgba_bare));
    assert!(
        with > without + 200,
        "arrow pixels: {with} with contacts, {without} without"
    );
    // The tip of a down-slope arrow (60154 N) is arrow-coloured where it pokes out of the box.
    write_png(
        &out_dir().join("slope_t0_no_contacts.png"),
        &rgba_bare,
        W,
        H,
        false,
    )
    .unwrap();
}

#[test]
fn render_to_png_writes_requested_size_and_transparency() {
    if gpu_or_skip("render_to_png_writes_requested_size_and_transparency").is_none() {
        return;
    }
    let snap = slope_snapshot(0.0, 0, 3.0, ContactState::Slide);
    let mut opts = CaptureOptions::new(out_dir());
    opts.width = 800;
    opts.height = 600;
    opts.style.transparent = true;
    let path = out_dir().join("slope_transparent.png");
    let camera = render_to_png(&snap, &opts, &path).unwrap();
    let img = image::open(&path).unwrap().to_rgba8();
    assert_eq!(img.dimensions(), (800, 600));
    assert_eq!(img.get_pixel(797, 2)[3], 0, "corner must be transparent");
    let c = camera.project(snap.blocks[1].centroid, 800, 600).unwrap();
    let px = img.get_pixel(c.x as u32, c.y as u32);
    assert_eq!(px[3], 255, "block must be opaque");
    assert!(same_hue(px.0, BLOCK_PALETTE_SRGB[1]), "{px:?}");
}

#[test]
fn consecutive_renders_are_identical() {
    let Some(gpu) = gpu_or_skip("consecutive_renders_are_identical") else {
        return;
    };
    let snap = slope_snapshot(1.5, 150, 4.0, ContactState::Slide);
    let opts = CaptureOptions::new(out_dir());
    let mut off = Offscreen::new(gpu, 640, 360).unwrap();
    let (a, _) = render_rgba(&mut off, &snap, &opts).unwrap();
    let (b, _) = render_rgba(&mut off, &snap, &opts).unwrap();
    assert!(a == b, "same snapshot, same camera, different pixels");
}

#[test]
fn bad_snapshot_is_an_error() {
    let Some(gpu) = gpu_or_skip("bad_snapshot_is_an_error") else {
        return;
    };
    let mut snap = slope_snapshot(0.0, 0, 3.0, ContactState::Lock);
    snap.blocks[1].faces[2] = vec![0, 1, 77];
    let mut off = Offscreen::new(gpu, 64, 64).unwrap();
    let err = render_rgba(&mut off, &snap, &CaptureOptions::new(out_dir())).unwrap_err();
    assert!(err.to_string().contains("77"), "{err}");
}

#[test]
fn without_msaa_the_picture_is_the_same_scene() {
    // Adapters without 4× MSAA get one sample; that path must draw the same picture.
    let Some(gpu) = gpu_or_skip("without_msaa_the_picture_is_the_same_scene") else {
        return;
    };
    let snap = slope_snapshot(0.0, 0, 3.0, ContactState::Lock);
    let opts = CaptureOptions::new(out_dir());
    let mut one = Offscreen::with_max_samples(gpu.clone(), 640, 360, 1).unwrap();
    assert_eq!(one.samples(), 1);
    let (a, camera) = render_rgba(&mut one, &snap, &opts).unwrap();
    let mut four = Offscreen::new(gpu, 640, 360).unwrap();
    eprintln!("MSAA samples available: {}", four.samples());
    let (b, _) = render_rgba(&mut four, &snap, &opts).unwrap();
    let c = camera.project(snap.blocks[1].centroid, 640, 360).unwrap();
    for img in [&a, &b] {
        let px = pixel(img, 640, c.x as u32, c.y as u32);
        assert!(same_hue(px, BLOCK_PALETTE_SRGB[1]), "{px:?}");
    }
    // Same picture up to antialiasing along edges.
    let differing = a
        .chunks_exact(4)
        .zip(b.chunks_exact(4))
        .filter(|(p, q)| p.iter().zip(q.iter()).any(|(x, y)| x.abs_diff(*y) > 40))
        .count();
    assert!(differing < 640 * 360 / 20, "{differing} pixels differ");
}

#[test]
fn non_srgb_target_gives_the_same_colours() {
    // A window surface shared with egui is usually not sRGB; the renderer encodes itself there.
    let Some(gpu) = gpu_or_skip("non_srgb_target_gives_the_same_colours") else {
        return;
    };
    let snap = slope_snapshot(0.0, 0, 3.0, ContactState::Lock);
    let mut opts = CaptureOptions::new(out_dir());
    // egui blends its translucent cards in gamma space on such targets, by design; compare
    // the 3-D scene only.
    opts.style.overlay = false;
    let mut srgb = Offscreen::new(gpu.clone(), 640, 360).unwrap();
    let mut unorm =
        Offscreen::with_format(gpu, 640, 360, wgpu::TextureFormat::Rgba8Unorm, 4).unwrap();
    let (a, _) = render_rgba(&mut srgb, &snap, &opts).unwrap();
    let (b, _) = render_rgba(&mut unorm, &snap, &opts).unwrap();
    let close = a
        .chunks_exact(4)
        .zip(b.chunks_exact(4))
        .filter(|(p, q)| p.iter().zip(q.iter()).all(|(x, y)| x.abs_diff(*y) <= 3))
        .count();
    assert!(close > 640 * 360 * 98 / 100, "only {close} pixels agree");
}
