//! Shared by the render tests: the paper's slope scene built by hand, and the GPU policy
//! (skip with a note when no adapter exists, unless `DDA3D_REQUIRE_GPU=1` makes it a failure).

#![allow(dead_code)]

use dda3d::render::{Gpu, RenderError, gpu_required_by_env};
use dda3d::snapshot::*;
use glam::DVec3;

/// A GPU, or `None` (with a note) when there is no adapter and the environment allows skipping.
pub fn gpu_or_skip(test: &str) -> Option<Gpu> {
    match Gpu::headless() {
        Ok(gpu) => Some(gpu),
        Err(RenderError::NoAdapter) if !gpu_required_by_env() => {
            eprintln!("note: {test}: skipped, {}", RenderError::NoAdapter);
            None
        }
        Err(e) => panic!("{test}: {e} (DDA3D_REQUIRE_GPU is set, a GPU adapter is required)"),
    }
}

/// Slope angle of the paper's example, 30°.
pub fn slope_normal() -> DVec3 {
    let a = 30f64.to_radians();
    DVec3::new(a.sin(), 0.0, a.cos())
}

/// Down-slope unit direction on the 30° face.
pub fn downslope() -> DVec3 {
    let a = 30f64.to_radians();
    DVec3::new(a.cos(), 0.0, -a.sin())
}

/// Orients every face counter-clockwise seen from outside (the convex block's centroid is
/// inside), so the hand-written faces below need not get the order right.
fn orient(vertices: &[[f64; 3]], faces: Vec<Vec<u32>>) -> Vec<Vec<u32>> {
    let c = vertices
        .iter()
        .map(|v| DVec3::from_array(*v))
        .sum::<DVec3>()
        / vertices.len() as f64;
    faces
        .into_iter()
        .map(|mut f| {
            let p: Vec<DVec3> = f
                .iter()
                .map(|&i| DVec3::from_array(vertices[i as usize]))
                .collect();
            let n = (p[1] - p[0]).cross(p[2] - p[0]);
            let fc = p.iter().sum::<DVec3>() / p.len() as f64;
            if n.dot(fc - c) < 0.0 {
                f.reverse();
            }
            f
        })
        .collect()
}

fn centroid(vertices: &[[f64; 3]]) -> [f64; 3] {
    (vertices
        .iter()
        .map(|v| DVec3::from_array(*v))
        .sum::<DVec3>()
        / vertices.len() as f64)
        .to_array()
}

/// The fixed triangular prism of the slope body.
pub fn slope_block() -> BlockSnapshot {
    let h = 5.7735;
    let vertices = vec![
        [0.0, -1.0, 0.0],
        [10.0, -1.0, 0.0],
        [0.0, -1.0, h],
        [0.0, 5.0, 0.0],
        [10.0, 5.0, 0.0],
        [0.0, 5.0, h],
    ];
    let faces = orient(
        &vertices,
        vec![
            vec![0, 1, 2],
            vec![3, 5, 4],
            vec![0, 3, 4, 1],
            vec![0, 2, 5, 3],
            vec![1, 4, 5, 2],
        ],
    );
    BlockSnapshot {
        name: "slope".into(),
        fixed: true,
        centroid: centroid(&vertices),
        vertices,
        faces,
        velocity: [0.0; 3],
        displacement: [0.0; 3],
        rock_mass: None,
        stress: [0.0; 6],
        volume: 1.0,
    }
}

/// The 2 m (along slope) × 4 m (across, y 0..4) × 1 m box resting on the 30° face, its
/// up-slope bottom edge `s` metres down the face from the crest.
pub fn box_block(s: f64) -> BlockSnapshot {
    let crest = DVec3::new(0.0, 0.0, 5.7735);
    let (d, n) = (downslope(), slope_normal());
    let p0 = crest + d * s;
    let y = DVec3::new(0.0, 4.0, 0.0);
    let bottom = [p0, p0 + d * 2.0, p0 + d * 2.0 + y, p0 + y];
    let mut vertices: Vec<[f64; 3]> = bottom.iter().map(|p| p.to_array()).collect();
    vertices.extend(bottom.iter().map(|p| (*p + n).to_array()));
    let faces = orient(
        &vertices,
        vec![
            vec![0, 1, 2, 3],
            vec![4, 5, 6, 7],
            vec![0, 1, 5, 4],
            vec![1, 2, 6, 5],
            vec![2, 3, 7, 6],
            vec![3, 0, 4, 7],
        ],
    );
    BlockSnapshot {
        name: "block".into(),
        fixed: false,
        centroid: centroid(&vertices),
        vertices,
        faces,
        velocity: [0.0; 3],
        displacement: [0.0; 3],
        rock_mass: None,
        stress: [0.0; 6],
        volume: 1.0,
    }
}

/// The slope scene at time `t` with the box `s` metres down from the crest, and the four
/// vertex–face contacts at the box's bottom corners (down-slope corners carry more).
pub fn slope_snapshot(t: f64, step: u64, s: f64, state: ContactState) -> Snapshot {
    let slope = slope_block();
    let block = box_block(s);
    let n = slope_normal().to_array();
    let forces = [33204.0, 60154.0, 60154.0, 33204.0];
    let contacts = (0..4)
        .map(|k| ContactSnapshot {
            block_i: 1,
            block_j: 0,
            mode: ContactMode::VertexFace,
            state,
            point: block.vertices[k],
            normal: n,
            normal_force: forces[k],
            shear_force: 0.5 * forces[k],
            shear: [0.5 * forces[k], 0.0, 0.0],
            penetration: 1e-5,
            penalty: 1e9,
            lambda: forces[k],
            joint: None,
        })
        .collect();
    Snapshot {
        scene_name: "slope".into(),
        time: t,
        step,
        blocks: vec![slope, block],
        contacts,
        stats: StepStats::default(),
        equilibrium: None,
        rock_masses: Vec::new(),
        joint_sets: Vec::new(),
    }
}

/// sRGB byte → linear light.
pub fn lin(c: u8) -> f32 {
    let v = c as f32 / 255.0;
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// Pixel at (x, y) of a tightly packed RGBA buffer.
pub fn pixel(rgba: &[u8], width: u32, x: u32, y: u32) -> [u8; 4] {
    let i = ((y * width + x) * 4) as usize;
    [rgba[i], rgba[i + 1], rgba[i + 2], rgba[i + 3]]
}

/// Whether a lit pixel has the hue of the base colour `srgb` (shading scales all channels
/// alike in linear light, so the channel ratios identify the colour).
pub fn same_hue(px: [u8; 4], srgb: u32) -> bool {
    let base = [
        lin((srgb >> 16) as u8),
        lin((srgb >> 8) as u8),
        lin(srgb as u8),
    ];
    let p = [lin(px[0]), lin(px[1]), lin(px[2])];
    let bm = base.iter().cloned().fold(0.0, f32::max);
    let pm = p.iter().cloned().fold(0.0, f32::max);
    if pm < 0.02 {
        return false;
    }
    (0..3).all(|k| (p[k] / pm - base[k] / bm).abs() < 0.12)
}

/// Strongly blue pixels (the colour of locked-contact arrows).
pub fn is_lock_blue(px: [u8; 4]) -> bool {
    let (r, g, b) = (px[0] as i32, px[1] as i32, px[2] as i32);
    b > 120 && b > r + 60 && b > g + 25
}

/// Pixels of an RGBA picture in the blue of locked-contact arrows.
pub fn lock_blue_pixels(img: &[u8]) -> usize {
    img.chunks_exact(4)
        .filter(|p| is_lock_blue([p[0], p[1], p[2], p[3]]))
        .count()
}

/// Pixels of an RGBA picture that are not the background.
pub fn drawn_pixels(img: &[u8]) -> usize {
    img.chunks_exact(4)
        .filter(|p| !is_background([p[0], p[1], p[2], p[3]]))
        .count()
}

/// The light background colour, exactly (opaque).
pub fn is_background(px: [u8; 4]) -> bool {
    let bg = dda3d::render::scene::BACKGROUND_SRGB;
    let bg = [(bg >> 16) as u8, (bg >> 8) as u8, bg as u8];
    (0..3).all(|k| px[k].abs_diff(bg[k]) <= 1) && px[3] == 255
}
