//! Example figures for the README and for eyeballing changes to the renderer:
//! `cargo test --release --test render_gallery -- --ignored`, then look in
//! `target/tmp/render_gallery/`.

mod render_support;

use dda3d::render::{ArrowMode, CameraOverride, CaptureOptions, Coloring, render_to_png};
use dda3d::snapshot::*;
use glam::{DMat3, DVec3};
use render_support::*;

fn dir() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("render_gallery")
}

/// A cube of edge `a` rotated by `rot` about its centre `c`.
fn rock(name: &str, c: DVec3, a: f64, rot: DMat3, v: DVec3) -> BlockSnapshot {
    let mut vertices = Vec::new();
    for i in 0..8 {
        let p = DVec3::new(
            if i & 1 == 0 { -0.5 } else { 0.5 },
            if i & 2 == 0 { -0.5 } else { 0.5 },
            if i & 4 == 0 { -0.5 } else { 0.5 },
        ) * a;
        vertices.push((c + rot * p).to_array());
    }
    let faces = vec![
        vec![0, 2, 3, 1],
        vec![4, 5, 7, 6],
        vec![0, 1, 5, 4],
        vec![1, 3, 7, 5],
        vec![3, 2, 6, 7],
        vec![2, 0, 4, 6],
    ];
    BlockSnapshot {
        name: name.into(),
        fixed: false,
        vertices,
        faces,
        centroid: c.to_array(),
        velocity: v.to_array(),
        displacement: (v * 0.3).to_array(),
        rock_mass: None,
        stress: [0.0; 6],
        volume: 1.0,
    }
}

fn rockfall() -> Snapshot {
    let mut blocks = vec![slope_block()];
    let mut contacts = Vec::new();
    for k in 0..12 {
        let s = 1.0 + (k % 4) as f64 * 2.3;
        let y = 0.2 + (k / 4) as f64 * 1.6;
        let lift = 0.6 + 0.4 * ((k * 7) % 5) as f64;
        let c = DVec3::new(0.0, 0.0, 5.7735)
            + downslope() * s
            + slope_normal() * lift
            + DVec3::new(0.0, y, 0.0);
        let rot = DMat3::from_euler(glam::EulerRot::XYZ, 0.3 * k as f64, 0.7 * k as f64, 0.1);
        let speed = 0.4 * k as f64;
        blocks.push(rock(&format!("rock{k}"), c, 0.7, rot, downslope() * speed));
        if lift < 1.0 {
            let foot = c - slope_normal() * lift;
            contacts.push(ContactSnapshot {
                block_i: k + 1,
                block_j: 0,
                mode: ContactMode::VertexFace,
                state: if k % 2 == 0 {
                    ContactState::Slide
                } else {
                    ContactState::Lock
                },
                point: foot.to_array(),
                normal: slope_normal().to_array(),
                normal_force: 3000.0 + 1500.0 * k as f64,
                shear_force: 100.0,
                shear: [100.0, 0.0, 0.0],
                penetration: 0.0,
                penalty: 0.0,
                lambda: 0.0,
                joint: None,
            });
        }
    }
    Snapshot {
        scene_name: "rockfall (synthetic)".into(),
        time: 1.2345,
        step: 1234,
        blocks,
        contacts,
        stats: StepStats::default(),
        equilibrium: None,
        rock_masses: Vec::new(),
        joint_sets: Vec::new(),
    }
}

#[test]
#[ignore = "writes example figures; run with --ignored"]
fn gallery() {
    if gpu_or_skip("gallery").is_none() {
        return;
    }
    let d = dir();
    let mut o = CaptureOptions::new(&d);
    render_to_png(&rockfall(), &o, &d.join("rockfall_blocks.png")).unwrap();

    o.style.coloring = Coloring::Velocity;
    o.style.arrows = ArrowMode::Both;
    render_to_png(&rockfall(), &o, &d.join("rockfall_velocity.png")).unwrap();

    let mut o = CaptureOptions::new(&d);
    o.camera = CameraOverride::parse("-90,0").unwrap();
    render_to_png(
        &slope_snapshot(0.0, 0, 3.0, ContactState::Lock),
        &o,
        &d.join("slope_side.png"),
    )
    .unwrap();

    let mut o = CaptureOptions::new(&d);
    o.camera = CameraOverride::parse("-40,35,30").unwrap();
    o.style.coloring = Coloring::Displacement;
    o.width = 1920;
    o.height = 1080;
    render_to_png(
        &slope_snapshot(0.5, 50, 5.0, ContactState::Slide),
        &o,
        &d.join("slope_1080p.png"),
    )
    .unwrap();
}
