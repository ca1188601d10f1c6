//! From the scene file's entries to the model: materials checked, each block's shape turned into
//! a convex hull, and the blocks checked for overlap at the start. Messages here are the problem
//! alone; [`super::parse`] adds the file, the line and the block's name.

use super::format::{BlockSpec, ShapeSpec};
use super::{MAX_BLOCK_POINTS, MAX_HULL_VERTICES};
use crate::contact::Shape;
use crate::contact::detection::broad_phase;
use crate::contact::groups::MAX_BLOCK_PAIRS;
use crate::model::Block;
use crate::params::{Method, Mode, SolverParams};
use crate::physics::geometry::{
    Vec3, bounding_box, box_vertices, convex_hull, dodecahedron_vertices, overlap_depth,
    prism_vertices, rotation_xyz_degrees,
};
use crate::physics::mechanics::Material;
use crate::text::short;

/// The densities a material may have, kg/m³: from a light foam to ten times osmium's.
pub const DENSITY_RANGE: (f64, f64) = (1e-2, 2e5);
/// The Young's moduli a material may have, Pa: from a soft gel to ten times diamond's.
pub const YOUNG_RANGE: (f64, f64) = (1e2, 1e13);

/// Checks a material's constants; an error names the key it concerns.
pub(super) fn check_material(name: &str, m: &Material) -> Result<(), (&'static str, String)> {
    for (key, v) in [
        ("density", m.density),
        ("young_modulus", m.young_modulus),
        ("poisson_ratio", m.poisson_ratio),
    ] {
        if !v.is_finite() {
            return Err((
                key,
                format!("material '{name}': {key} is not a finite number"),
            ));
        }
    }
    // Bounds far outside any rock (or any solid) that still keep the step's matrices
    // representable: at a density of 1e308 or 1e-308 kg/m³, or E = 1e308 Pa, the first solve
    // was not finite and the run was reported as diverged instead of the input as bad; at
    // E = 1e-308 Pa a fixed block's springs held nothing and the ground fell.
    for (key, v, lo, hi, unit) in [
        (
            "density",
            m.density,
            DENSITY_RANGE.0,
            DENSITY_RANGE.1,
            "kg/m³",
        ),
        (
            "young_modulus",
            m.young_modulus,
            YOUNG_RANGE.0,
            YOUNG_RANGE.1,
            "Pa",
        ),
    ] {
        if v <= 0.0 {
            return Err((
                key,
                format!(
                    "material '{name}': {key} must be positive, got {}",
                    short(v)
                ),
            ));
        }
        if !(lo..=hi).contains(&v) {
            return Err((
                key,
                format!(
                    "material '{name}': {key} must lie in [{}, {}] {unit}, got {}",
                    short(lo),
                    short(hi),
                    short(v)
                ),
            ));
        }
    }
    if !(m.poisson_ratio > -1.0 && m.poisson_ratio < 0.5) {
        return Err((
            "poisson_ratio",
            format!(
                "material '{name}': poisson_ratio must lie in (-1, 0.5), got {}",
                short(m.poisson_ratio)
            ),
        ));
    }
    Ok(())
}

/// Checks the initial penalty against the scene's stiffest material (Young's modulus
/// `young`, Pa): at least 10⁻⁶ E, below which blocks pass through each other before any
/// contact holds them, and at most the (P21b) cap γ·E that no penalty may pass.
pub(super) fn check_penalty_scale(params: &SolverParams, young: f64) -> Result<(), String> {
    let (p, gamma) = (params.contact.initial_penalty, params.contact.gamma);
    let (lo, hi) = (1e-6 * young, gamma * young);
    if (lo..=hi).contains(&p) {
        return Ok(());
    }
    Err(format!(
        "solver.contact.initial_penalty = {} N/m must lie in [1e-6, γ] times the stiffest \
         material's E = {} Pa (γ = {}): [{}, {}] N/m",
        short(p),
        short(young),
        short(gamma),
        short(lo),
        short(hi)
    ))
}

/// How far a free block's inertia at Δt_max, 2m/Δt_max², may exceed the penalty cap γE of its
/// material before a scene is refused. Beyond γE the ALM's multipliers converge by a fraction
/// γE/(2m/Δt²) an iteration (`alm::update_multipliers` raises a stalled contact's penalty to
/// the inertia, but never past γE). Measured on a 20 × 20 × 10 m block sliding on 30° (factor
/// of safety 0.8, 1 s): at 10 and 21 times γE its travel was 1.1 % and 1.3 % long; at 41
/// times 277 % long, its loops ending at their cap without a word.
pub const MAX_INERTIA_PER_PENALTY_CAP: f64 = 20.0;

/// In dynamic mode under DDA-3a, refuses a Δt_max so short for the heaviest free block that its
/// inertia 2m/Δt_max² exceeds [`MAX_INERTIA_PER_PENALTY_CAP`] times its material's γE, naming
/// the Δt_max and the γ that would do. DDA-3p keeps its fixed p_n,1 at any Δt: γE is no cap of
/// its, and its soft springs' errors are its own (the README's "Short steps and heavy blocks").
pub fn check_inertia_scale(blocks: &[Block], params: &SolverParams) -> Result<(), String> {
    if params.mode != Mode::Dynamic || params.method != Method::Alm {
        return Ok(());
    }
    let dt = params.max_time_step;
    let cap = |b: &Block| params.contact.gamma * b.material.young_modulus;
    let ratio = |b: &Block| 2.0 * b.mass / (dt * dt) / cap(b);
    let Some(b) = blocks
        .iter()
        .filter(|b| !b.fixed)
        .max_by(|a, b| ratio(a).total_cmp(&ratio(b)))
    else {
        return Ok(());
    };
    if ratio(b) <= MAX_INERTIA_PER_PENALTY_CAP {
        return Ok(());
    }
    // A hair above the bounds, so that the printed values, rounded, pass.
    let dt_least = 1.01 * (2.0 * b.mass / (MAX_INERTIA_PER_PENALTY_CAP * cap(b))).sqrt();
    let gamma_least = 1.01 * params.contact.gamma * ratio(b) / MAX_INERTIA_PER_PENALTY_CAP;
    Err(format!(
        "solver.max_time_step = {} s is too short for block '{}' ({} kg): its inertia 2m/Δt² \
         is {} times the penalty cap γE (at most {MAX_INERTIA_PER_PENALTY_CAP}); use \
         max_time_step ≥ {} s or solver.contact.gamma ≥ {}",
        short(dt),
        b.name,
        short(b.mass),
        short(ratio(b)),
        short(dt_least),
        short(gamma_least)
    ))
}

/// An error when a shape has more points than [`MAX_BLOCK_POINTS`] (`what` says which points):
/// checked before the hull, whose cost grows with them.
fn check_point_count(points: usize, what: impl FnOnce() -> String) -> Result<(), String> {
    if points > MAX_BLOCK_POINTS {
        return Err(format!(
            "{}, more than the limit of {MAX_BLOCK_POINTS} points for a block",
            what()
        ));
    }
    Ok(())
}

fn finite(v: &[f64]) -> bool {
    v.iter().all(|x| x.is_finite())
}

/// The points whose convex hull is the block: exactly one of `vertices`, `box`,
/// `dodecahedron` or `prism`.
pub(super) fn shape_points(spec: &ShapeSpec) -> Result<Vec<Vec3>, String> {
    let given = [
        spec.vertices.is_some(),
        spec.box_.is_some(),
        spec.dodecahedron.is_some(),
        spec.prism.is_some(),
    ]
    .iter()
    .filter(|&&b| b)
    .count();
    if given != 1 {
        return Err("give exactly one of vertices, box, dodecahedron or prism".into());
    }
    if let Some(v) = spec.vertices {
        check_point_count(v.len(), || format!("vertices: {} points", v.len()))?;
        return Ok(v.iter().map(|p| Vec3::from(p.0)).collect());
    }
    if let Some(b) = spec.box_ {
        if !finite(&b.size) || !finite(&b.center) || !finite(&b.rotation) {
            return Err("box has a non-finite number".into());
        }
        if b.size.iter().any(|&s| s <= 0.0) {
            return Err("box size must be positive".into());
        }
        return Ok(box_vertices(
            b.size,
            b.center,
            &rotation_xyz_degrees(b.rotation),
        ));
    }
    if let Some(d) = spec.dodecahedron {
        if !d.edge.is_finite() || !finite(&d.center) || !finite(&d.rotation) {
            return Err("dodecahedron has a non-finite number".into());
        }
        if d.edge <= 0.0 {
            return Err("dodecahedron edge must be positive".into());
        }
        return Ok(dodecahedron_vertices(
            d.edge,
            d.center,
            &rotation_xyz_degrees(d.rotation),
        ));
    }
    let p = spec.prism.expect("one shape given");
    // The prism's vertices are its base and the base swept.
    check_point_count(2 * p.base.len(), || {
        format!(
            "prism: a base of {} points makes {} vertices",
            p.base.len(),
            2 * p.base.len()
        )
    })?;
    let base: Vec<[f64; 3]> = p.base.iter().map(|b| b.0).collect();
    if !finite(&p.extrude) || base.iter().any(|b| !finite(b)) {
        return Err("prism has a non-finite number".into());
    }
    Ok(prism_vertices(&base, p.extrude))
}

/// One block from its `[[blocks]]` entry.
pub(super) fn build_block(
    spec: &BlockSpec,
    name: String,
    material: Material,
) -> Result<Block, String> {
    let points = shape_points(&spec.shape())?;
    let (vertices, topo) = convex_hull(&points).map_err(|e| e.to_string())?;
    if vertices.len() > MAX_HULL_VERTICES {
        return Err(format!(
            "its convex hull has {} corners, more than the limit of {MAX_HULL_VERTICES}: simplify the shape (contact detection tests every corner against every face)",
            vertices.len()
        ));
    }
    if !finite(&spec.velocity) || !finite(&spec.angular_velocity) {
        return Err("velocity is not finite".into());
    }
    let mut loads = Vec::new();
    for l in &spec.loads {
        if !finite(&l.point) || !finite(&l.force) {
            return Err("load has a non-finite number".into());
        }
        loads.push((Vec3::from(l.point), Vec3::from(l.force)));
    }
    Ok(Block::new(
        name,
        material,
        spec.fixed,
        vertices,
        topo,
        Vec3::from(spec.velocity),
        Vec3::from(spec.angular_velocity),
        loads,
    ))
}

/// The most pairs of blocks with overlapping boxes a scene may have per block. A step keeps
/// about 8.5 kB per such pair (the system's blocks, the contacts, the factor): sixty joint sets
/// through one point of a 2 m cube cut 1618 blocks that all meet there, 808 pairs a block, and
/// one step took 10.9 GB (35 sets: 366 a block, 2.3 GB). Rock masses cut by three random sets
/// with slivers reach 56 (`scripts/probe-rock-masses.py`), a jointed slope 10, a wall 2.5.
pub const MAX_PAIRS_PER_BLOCK: usize = 200;

/// An error, at the block that overlaps the most others, when the boxes' `pairs` exceed
/// [`MAX_PAIRS_PER_BLOCK`] times the blocks.
fn check_pairs_per_block(
    pairs: &[(usize, usize)],
    blocks: &[Block],
) -> Result<(), (usize, String)> {
    if pairs.len() <= MAX_PAIRS_PER_BLOCK * blocks.len() {
        return Ok(());
    }
    let mut degree = vec![0usize; blocks.len()];
    for &(a, b) in pairs {
        degree[a] += 1;
        degree[b] += 1;
    }
    let worst = (0..blocks.len())
        .max_by_key(|&k| (degree[k], std::cmp::Reverse(k)))
        .unwrap_or(0);
    Err((
        worst,
        format!(
            "{} pairs of blocks have overlapping bounding boxes, {} a block (more than {}): \
             block '{}' alone overlaps {} others. Blocks that all meet along one line or point \
             (joint sets through one point?) each touch hundreds of others, and a step would \
             need about {} GB",
            pairs.len(),
            short(pairs.len() as f64 / blocks.len() as f64),
            MAX_PAIRS_PER_BLOCK,
            blocks[worst].name,
            degree[worst],
            short((pairs.len() as f64 * 8.5e3 / 1e9).max(0.1))
        ),
    ))
}

/// Blocks may touch at the start but not overlap: the separating-axis depth of every nearby
/// pair must stay below a small tolerance (10⁻⁴ of the model half-size, for coordinates typed
/// with a few decimals).
pub(super) fn check_overlaps(blocks: &[Block]) -> Result<(), (usize, String)> {
    let all: Vec<Vec3> = blocks
        .iter()
        .flat_map(|b| b.vertices.iter().copied())
        .collect();
    let (lo, hi) = bounding_box(&all);
    let tol = 1e-4 * 0.5 * (hi - lo).max();
    let shapes: Vec<Shape> = blocks
        .iter()
        .map(|b| Shape {
            fixed: false,
            ..Shape::of(b)
        })
        .collect();
    let pairs = broad_phase(&shapes, 0.0, MAX_BLOCK_PAIRS);
    // Each pair would be checked here, and (unless both are fixed) searched for contacts at
    // every step. The error names the line of a block of one of them.
    if let Some(&(_, b)) = pairs.get(MAX_BLOCK_PAIRS) {
        return Err((
            b,
            format!(
                "more than {} pairs of blocks have overlapping bounding boxes, too many to check \
                 for overlap or to search for contacts: blocks far thinner than they are long (a \
                 joint set spaced far closer than the blocks are long?) each lie across hundreds \
                 of others",
                short(MAX_BLOCK_PAIRS as f64)
            ),
        ));
    }
    // Within the whole search's limit, the pairs per block (the search stops past the limit,
    // so only then is the count a block's own).
    check_pairs_per_block(&pairs, blocks)?;
    for (a, b) in pairs {
        let depth = overlap_depth(
            &blocks[a].vertices,
            &blocks[a].topo,
            &blocks[b].vertices,
            &blocks[b].topo,
        );
        if depth > tol {
            return Err((
                b,
                format!(
                    "blocks '{}' and '{}' overlap by {} m at the start (touching is fine)",
                    blocks[a].name,
                    blocks[b].name,
                    short(depth)
                ),
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The initial penalty lies within [10⁻⁶, γ] times the stiffest E, ends included; the
    /// message gives the range in N/m.
    #[test]
    fn the_initial_penalty_is_held_to_the_stiffest_material() {
        let with = |p: f64, gamma: f64| {
            let mut s = SolverParams::default();
            s.contact.initial_penalty = p;
            s.contact.gamma = gamma;
            s
        };
        let e = 2.0e10;
        for p in [2e4, 2e8, 2e12] {
            assert!(check_penalty_scale(&with(p, 100.0), e).is_ok(), "{p}");
        }
        for p in [1.9e4, 2.1e12, 1e30] {
            let m = check_penalty_scale(&with(p, 100.0), e).unwrap_err();
            assert!(m.contains("[20000, 2e12] N/m"), "{m}");
        }
        // A cap below the start: no penalty could be both.
        let m = check_penalty_scale(&with(2e8, 1e-3), e).unwrap_err();
        assert!(m.contains("γ = 0.001"), "{m}");
    }
}
