//! The contact arrows are drawn by a vertex shader (shaders/arrow.wgsl) from instances of one
//! unit arrow; `ArrowInstance::vertex` is its formula in Rust, unit-tested on the CPU. Here the
//! GPU's picture of the arrows is checked against that mirror: the same scene drawn with the
//! arrows as instances and with the mirror's triangles as plain solids must give the same
//! pixels, close up (16 sides) and from afar (the coarse templates).

mod render_support;

use dda3d::render::arrow_mesh::{ARROW_LODS, lod_seen};
use dda3d::render::{CameraOverride, Offscreen, RenderScene, SceneFrame, SceneStyle};
use dda3d::scene;
use dda3d::solver::Solver;
use render_support::*;

const W: u32 = 640;
const H: u32 = 400;

/// Pixels drawn (not the background) in one picture and not in the other.
fn coverage_mismatch(a: &[u8], b: &[u8]) -> usize {
    let drawn = |p: &[u8]| !is_background([p[0], p[1], p[2], p[3]]);
    a.chunks_exact(4)
        .zip(b.chunks_exact(4))
        .filter(|(p, q)| drawn(p) != drawn(q))
        .count()
}

/// Mean of the largest channel difference over the pixels drawn in both pictures and not in
/// `overlay` (the same scene without arrows).
fn mean_shade_difference(a: &[u8], b: &[u8], overlay: &[u8]) -> f64 {
    let drawn = |p: &[u8]| !is_background([p[0], p[1], p[2], p[3]]);
    let (mut sum, mut n) = (0.0, 0usize);
    for ((p, q), o) in a
        .chunks_exact(4)
        .zip(b.chunks_exact(4))
        .zip(overlay.chunks_exact(4))
    {
        if drawn(p) && drawn(q) && !drawn(o) {
            sum += f64::from((0..3).map(|k| p[k].abs_diff(q[k])).max().unwrap_or(0));
            n += 1;
        }
    }
    sum / n.max(1) as f64
}

#[test]
fn instanced_arrows_draw_the_mirror_triangles() {
    let Some(gpu) = gpu_or_skip("instanced_arrows_draw_the_mirror_triangles") else {
        return;
    };
    let s = scene::load(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/slope_stable.toml"),
    )
    .unwrap();
    let mut solver = Solver::new(s.model, s.params);
    solver.step().unwrap();
    let snap = solver.snapshot();
    assert!(!snap.contacts.is_empty(), "the block rests on its contacts");
    let frame = SceneFrame::of_snapshot(&snap);
    let style = SceneStyle {
        grid: false,
        ..SceneStyle::default()
    };
    let mut instanced = RenderScene::build(&snap, &style, &frame).unwrap();
    assert!(!instanced.arrows.is_empty());
    // The arrows alone: where a block hides them the renderer draws them again, faintly,
    // which plain solids do not do.
    instanced.solids.clear();
    instanced.lines.clear();
    let mut off = Offscreen::new(gpu, W, H).unwrap();
    // From 0.4 to 3 times the scene's framing distance: the mirror's triangles with the side
    // count the renderer chooses for each arrow, which goes down with the distance.
    let mut used = Vec::new();
    for distance in [0.4f32, 1.0, 3.0] {
        let mut camera = frame.camera(W as f32 / H as f32, &CameraOverride::default());
        camera.distance *= distance;
        let mut plain = instanced.clone();
        plain.arrows.clear();
        let mut sides = Vec::new();
        for a in &instanced.arrows {
            let n = ARROW_LODS[lod_seen(a, &camera, H)];
            plain.solids.extend(a.triangles_with(n));
            sides.push(n);
        }
        used.extend(sides.iter().copied());
        let gpu_picture = off.render(&instanced, &camera).unwrap();
        let cpu_picture = off.render(&plain, &camera).unwrap();
        let mut overlay_only = plain.clone();
        overlay_only.solids.clear();
        let overlay = off.render(&overlay_only, &camera).unwrap();
        let arrow_pixels = drawn_pixels(&gpu_picture) - drawn_pixels(&overlay);
        assert!(
            lock_blue_pixels(&gpu_picture) > 0 && arrow_pixels > 100,
            "arrows drawn at {distance}× the distance: {arrow_pixels} pixels"
        );
        // The same pixels covered: the shader places the template's vertices where the mirror
        // does (a pixel or two on the arrows' edges may round either way).
        let mismatch = coverage_mismatch(&gpu_picture, &cpu_picture);
        assert!(
            mismatch * 200 <= arrow_pixels,
            "{sides:?} sides: {mismatch} pixels covered by one picture only, of {arrow_pixels} arrow pixels"
        );
        // Shaded alike. Not equal: the renderer also draws an arrow's far side faintly through
        // its near side, as everything it hides (about 8 levels on average, close up). Radial
        // normals tilted 45° along the axis differ by 26.
        let shade = mean_shade_difference(&gpu_picture, &cpu_picture, &overlay);
        assert!(
            shade < 12.0,
            "{sides:?} sides: shades differ by {shade:.1} on average"
        );
    }
    used.sort_unstable();
    used.dedup();
    assert_eq!(
        used,
        ARROW_LODS.iter().rev().copied().collect::<Vec<_>>(),
        "every template drawn"
    );
}
