//! The rock-mass cutting benchmark: a box cut by three joint sets into about N blocks, timing
//! the cut alone ([`crate::rockmass::cut::cut`]) and the whole load of the scene (the cut, the
//! blocks' hulls, their joint faces and the overlap check).

use std::time::Instant;

use crate::physics::geometry::{Mat3, box_vertices, convex_hull};
use crate::rockmass::cut::{CutOptions, Plane, Polyhedron, cut};
use crate::rockmass::orientation::{SetGeometry, Vec3, planes_through};
use crate::scene;

/// The three sets: orthogonal, or the oblique sets of the rock-mass reference's worked domain
/// (60/030, 80/140, 10/250).
const ORTHOGONAL: [(f64, f64); 3] = [(90.0, 90.0), (90.0, 0.0), (0.0, 0.0)];
const OBLIQUE: [(f64, f64); 3] = [(60.0, 30.0), (80.0, 140.0), (10.0, 250.0)];

/// Prints the cutting table for boxes of about `sizes` blocks (1 m spacing), best of `repeat`.
pub fn cut_table(sizes: &[usize], repeat: usize) -> Result<(), String> {
    println!("\n## Rock-mass cutting: a box cut by three joint sets 1 m apart, best of {repeat}\n");
    println!(
        "| sets | box m | blocks | cut s | scene load s (cut, hulls, joint faces, overlap check) |"
    );
    println!("|---|---|---|---|---|");
    for &n in sizes {
        let side = (n as f64).cbrt().round().max(1.0);
        for (label, sets) in [("orthogonal", ORTHOGONAL), ("oblique", OBLIQUE)] {
            let (blocks, cut_s) = time_cut(side, &sets, repeat)?;
            let text = scene_text(side, &sets);
            let mut load_s = f64::INFINITY;
            for _ in 0..repeat {
                let t = Instant::now();
                scene::parse(&text, "cut benchmark", "cut").map_err(|e| e.to_string())?;
                load_s = load_s.min(t.elapsed().as_secs_f64());
            }
            println!("| {label} | {side} | {blocks} | {cut_s:.3} | {load_s:.3} |");
        }
    }
    Ok(())
}

/// The cut alone: blocks made and the best time.
fn time_cut(side: f64, sets: &[(f64, f64); 3], repeat: usize) -> Result<(usize, f64), String> {
    let corners = box_vertices([side; 3], [side / 2.0; 3], &Mat3::identity());
    let (vertices, topo) = convex_hull(&corners).map_err(|e| e.to_string())?;
    let planes: Vec<Vec<Plane>> = sets
        .iter()
        .map(|&(dip, dip_direction)| {
            let set = SetGeometry {
                dip,
                dip_direction,
                spacing: 1.0,
                origin: Vec3::repeat(0.3),
                spacing_deviation: 0.0,
                orientation_deviation: 0.0,
                seed: 0,
            };
            planes_through(&set, &vertices, 1e-9 * side, usize::MAX)
                .map(|p| p.iter().map(Plane::from).collect())
        })
        .collect::<Result<_, _>>()
        .map_err(|n| format!("{n} planes"))?;
    let region = [Polyhedron {
        vertices,
        faces: topo.faces,
    }];
    let opts = CutOptions {
        min_volume: 0.0,
        max_aspect: 30.0,
        aspect_length: 1.0,
        max_blocks: scene::MAX_BLOCKS,
    };
    let mut best = (0, f64::INFINITY);
    for _ in 0..repeat {
        let t = Instant::now();
        let (pieces, _) = cut(&region, &planes, &opts).map_err(|e| e.to_string())?;
        best = (pieces.len(), best.1.min(t.elapsed().as_secs_f64()));
    }
    Ok(best)
}

/// The same box and sets as a scene.
fn scene_text(side: f64, sets: &[(f64, f64); 3]) -> String {
    let mut text = format!(
        "[materials.rock]\ndensity = 2600.0\nyoung_modulus = 1e10\npoisson_ratio = 0.25\n\
         [[rock_masses]]\nname = \"box\"\nmaterial = \"rock\"\nmin_volume = 0.0\n\
         regions = [ {{ box = {{ size = [{side}, {side}, {side}], center = [{h}, {h}, {h}] }} }} ]\n",
        h = side / 2.0
    );
    for (k, (dip, dd)) in sets.iter().enumerate() {
        text += &format!(
            "[[rock_masses.joint_sets]]\nname = \"S{k}\"\ndip = {dip}\ndip_direction = {dd}\n\
             spacing = 1.0\norigin = [0.3, 0.3, 0.3]\n"
        );
    }
    text
}
