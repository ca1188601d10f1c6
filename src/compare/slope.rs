//! Scenes with a closed form: a single free block resting on a single fixed inclined body,
//! as in the paper's §3.1 (Tables 1 and 2). A scene is recognised from its geometry, its
//! gravity and its joint, never from its name, so any slope angle and friction angle works:
//!
//! - exactly two blocks, one fixed and one free, both hand-made (no rock mass, so every
//!   contact takes `[joint]`), no point loads, the free block at rest at t = 0;
//! - one face of the free block lies on one face of the fixed block (opposite outward
//!   normals, the same plane, the free face inside the fixed one), and that face looks up:
//!   θ, the angle between its normal and −g, lies in [0°, 90°);
//! - `[joint]` has no cohesion (the closed forms are Coulomb friction alone); φ is its
//!   friction angle.
//!
//! With tan φ ≥ tan θ the block **stands**: the contacts carry N = W cos θ normal to the face
//! and F = W sin θ along it (Table 1). Otherwise it **slides** from rest with
//! a = g (sin θ − cos θ tan φ), s = ½ a t² (Table 2); that needs dynamic mode and no initial
//! equilibrium stage (which would set the block moving before t = 0).

use serde::Serialize;

use crate::params::{Mode, SolverParams};
use crate::snapshot::{BlockSnapshot, Snapshot};
use crate::solver::Solver;

/// What the closed forms need of a block beyond its snapshot.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlockFacts {
    /// kg.
    pub mass: f64,
    /// No velocity and no spin.
    pub at_rest: bool,
    /// Has point loads.
    pub loaded: bool,
}

/// Whether the block stands or slides.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Motion {
    Stands,
    Slides,
}

/// A recognised block on a slope, with its closed form.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SlopeCase {
    /// The free block's name.
    pub block: String,
    /// The fixed block's name.
    pub slope: String,
    #[serde(skip)]
    pub block_index: usize,
    #[serde(skip)]
    pub slope_index: usize,
    pub motion: Motion,
    /// The face's inclination, degrees.
    pub theta_deg: f64,
    /// The joint's friction angle, degrees.
    pub phi_deg: f64,
    /// |g|, m/s².
    pub gravity: f64,
    pub mass: f64,
    /// W = m |g|, N.
    pub weight: f64,
    /// a = g (sin θ − cos θ tan φ) along the slope, m/s²; 0 where the block stands.
    pub acceleration: f64,
    /// The fixed face's outward normal (up out of the slope).
    pub normal: [f64; 3],
    /// Down the slope, in the face (gravity's part along it); zero on a level face.
    pub downslope: [f64; 3],
    /// The free block's centroid height above the face at t = 0, m: the lever of Table 1's
    /// closed form.
    pub centroid_height: f64,
    /// A point of the fixed face.
    #[serde(skip)]
    pub plane_point: [f64; 3],
    /// The free block's vertices and centroid at t = 0: the geometry of the closed forms.
    #[serde(skip)]
    pub initial_vertices: Vec<[f64; 3]>,
    #[serde(skip)]
    pub initial_centroid: [f64; 3],
}

pub(super) fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

pub(super) fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub(super) fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

pub(super) fn scaled(a: [f64; 3], s: f64) -> [f64; 3] {
    a.map(|x| x * s)
}

pub(super) fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

fn unit(a: [f64; 3]) -> Option<[f64; 3]> {
    let n = norm(a);
    (n > 0.0 && n.is_finite()).then(|| scaled(a, 1.0 / n))
}

/// The unit outward normal of a face (counter-clockwise seen from outside), by Newell's
/// formula, which averages over every vertex.
fn face_normal(b: &BlockSnapshot, face: &[u32]) -> Option<[f64; 3]> {
    let mut n = [0.0; 3];
    for (k, &i) in face.iter().enumerate() {
        let p = b.vertices[i as usize];
        let q = b.vertices[face[(k + 1) % face.len()] as usize];
        n[0] += (p[1] - q[1]) * (p[2] + q[2]);
        n[1] += (p[2] - q[2]) * (p[0] + q[0]);
        n[2] += (p[0] - q[0]) * (p[1] + q[1]);
    }
    unit(n)
}

/// Whether the free face `f` of `free` lies on the face `g` of `fixed`: opposite normals, the
/// same plane and `f` within `g`, to `tol` (a length).
fn lies_on(free: &BlockSnapshot, f: &[u32], fixed: &BlockSnapshot, g: &[u32], tol: f64) -> bool {
    let (Some(nf), Some(ng)) = (face_normal(free, f), face_normal(fixed, g)) else {
        return false;
    };
    if dot(nf, ng) > -(1.0 - 1e-9) {
        return false;
    }
    let q0 = fixed.vertices[g[0] as usize];
    f.iter().all(|&i| {
        let p = free.vertices[i as usize];
        let on_plane = dot(ng, sub(p, q0)).abs() <= tol;
        // Inside every edge of g (counter-clockwise about ng).
        let inside = (0..g.len()).all(|k| {
            let a = fixed.vertices[g[k] as usize];
            let b = fixed.vertices[g[(k + 1) % g.len()] as usize];
            dot(cross(sub(b, a), sub(p, a)), ng) >= -tol * dot(sub(b, a), sub(b, a)).sqrt()
        });
        on_plane && inside
    })
}

/// The facts of every block of a solver's model (its masses, whether each is at rest and
/// loaded), for [`recognise`].
pub fn facts(solver: &Solver) -> Vec<BlockFacts> {
    solver
        .model
        .blocks
        .iter()
        .map(|b| BlockFacts {
            mass: b.mass,
            at_rest: b.velocity.iter().all(|&v| v == 0.0),
            loaded: !b.loads.is_empty(),
        })
        .collect()
}

/// The closed form of a solver's scene at its start, or why it has none.
pub fn of_solver(solver: &Solver) -> Result<SlopeCase, String> {
    recognise(&solver.snapshot(), &facts(solver), &solver.params)
}

/// The free and the fixed block, if the scene is one of each, hand-made, the free one at rest
/// and unloaded.
fn two_blocks(s: &Snapshot, facts: &[BlockFacts]) -> Result<(usize, usize), String> {
    if s.blocks.len() != 2 || facts.len() != 2 {
        return Err(format!(
            "{} blocks: a closed form needs one free block on one fixed block",
            s.blocks.len()
        ));
    }
    let free = match (s.blocks[0].fixed, s.blocks[1].fixed) {
        (true, false) => 1,
        (false, true) => 0,
        _ => return Err("a closed form needs one fixed and one free block".into()),
    };
    if s.blocks.iter().any(|b| b.rock_mass.is_some()) {
        return Err("blocks cut from a rock mass take their joint sets' properties".into());
    }
    if !facts[free].at_rest || facts[free].loaded {
        return Err(format!(
            "block '{}' starts moving or carries point loads: the closed forms start from rest \
             under gravity alone",
            s.blocks[free].name
        ));
    }
    Ok((free, 1 - free))
}

/// The scene's block on a slope and its closed form, from the state at t = 0 (`s`), the
/// blocks' `facts` and the run's settings; or why the scene has none (one line).
pub fn recognise(
    s: &Snapshot,
    facts: &[BlockFacts],
    params: &SolverParams,
) -> Result<SlopeCase, String> {
    let (free, fixed) = two_blocks(s, facts)?;
    let (fb, xb) = (&s.blocks[free], &s.blocks[fixed]);
    if params.joint.cohesion != 0.0 || !params.joint_sets.is_empty() {
        return Err("the joint has cohesion: the closed forms are friction alone".into());
    }
    let g = params.gravity;
    let gravity = dot(g, g).sqrt();
    let down = unit(g).ok_or("no gravity")?;
    let size = fb.vertices.iter().fold(0.0f64, |m, p| {
        m.max(dot(sub(*p, fb.centroid), sub(*p, fb.centroid)).sqrt())
    });
    let tol = 1e-6 * size;
    let mut pairs = fb.faces.iter().flat_map(|f| {
        xb.faces
            .iter()
            .filter(move |g| lies_on(fb, f, xb, g, tol))
            .map(move |g| (f, g))
    });
    let (Some((_, g_face)), None) = (pairs.next(), pairs.next()) else {
        return Err(format!(
            "block '{}' does not rest on exactly one face of block '{}'",
            fb.name, xb.name
        ));
    };
    let normal = face_normal(xb, g_face).ok_or("a degenerate face")?;
    let cos_theta = -dot(normal, down);
    if cos_theta <= 1e-9 {
        return Err(format!(
            "block '{}' does not rest on top of its face",
            fb.name
        ));
    }
    let theta = cos_theta.min(1.0).acos();
    let phi = params.joint.friction_angle.to_radians();
    let slides = phi.tan() < theta.tan();
    if slides && (params.mode != Mode::Dynamic || params.initial_equilibrium) {
        return Err(
            "the block slides: its closed form needs dynamic mode from rest at t = 0, without \
             the initial equilibrium stage"
                .into(),
        );
    }
    let along = sub(down, scaled(normal, dot(down, normal)));
    let mass = facts[free].mass;
    Ok(SlopeCase {
        block: fb.name.clone(),
        slope: xb.name.clone(),
        block_index: free,
        slope_index: fixed,
        motion: if slides {
            Motion::Slides
        } else {
            Motion::Stands
        },
        theta_deg: theta.to_degrees(),
        phi_deg: params.joint.friction_angle,
        gravity,
        mass,
        weight: mass * gravity,
        acceleration: if slides {
            gravity * (theta.sin() - theta.cos() * phi.tan())
        } else {
            0.0
        },
        normal,
        downslope: unit(along).unwrap_or([0.0; 3]),
        centroid_height: dot(sub(fb.centroid, xb.vertices[g_face[0] as usize]), normal),
        plane_point: xb.vertices[g_face[0] as usize],
        initial_vertices: fb.vertices.clone(),
        initial_centroid: fb.centroid,
    })
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::snapshot::StepStats;

    /// A block of `size` (along the slope, across, high) on a slope of `theta_deg` falling
    /// toward the horizontal direction `azimuth_deg` (0: +x), the slope a wide wedge.
    pub(crate) fn slope_scene(theta_deg: f64, azimuth_deg: f64, size: [f64; 3]) -> Snapshot {
        let (t, az) = (theta_deg.to_radians(), azimuth_deg.to_radians());
        let (c, s) = (az.cos(), az.sin());
        // Frame: x down the slope's horizontal direction, y across, z up.
        let turn = |p: [f64; 3]| [c * p[0] - s * p[1], s * p[0] + c * p[1], p[2]];
        let height = 10.0 * t.tan();
        let wedge = [
            [0.0, -5.0, 0.0],
            [10.0, -5.0, 0.0],
            [0.0, -5.0, height],
            [0.0, 5.0, 0.0],
            [10.0, 5.0, 0.0],
            [0.0, 5.0, height],
        ];
        let mut slope = BlockSnapshot::test_cube("slope", [0.0; 3], 1.0);
        slope.fixed = true;
        slope.vertices = wedge.iter().map(|&p| turn(p)).collect();
        slope.faces = vec![
            vec![0, 3, 4, 1],
            vec![0, 1, 2],
            vec![3, 5, 4],
            vec![0, 2, 5, 3],
            vec![1, 4, 5, 2],
        ];
        let (down, up) = ([t.cos(), 0.0, -t.sin()], [t.sin(), 0.0, t.cos()]);
        // The block's upslope base edge 2 m down the face from the crest.
        let start = [2.0 * t.cos(), -1.0, height - 2.0 * t.sin()];
        let corner = |a: f64, b: f64, h: f64| {
            let p = [
                start[0] + a * down[0] + h * up[0],
                start[1] + b,
                start[2] + a * down[2] + h * up[2],
            ];
            turn(p)
        };
        let mut block = BlockSnapshot::test_cube("block", [0.0; 3], 1.0);
        block.vertices = (0..8)
            .map(|i| {
                corner(
                    size[0] * (i & 1) as f64,
                    size[1] * ((i >> 1) & 1) as f64,
                    size[2] * ((i >> 2) & 1) as f64,
                )
            })
            .collect();
        let mean = block.vertices.iter().fold([0.0; 3], |m, p| {
            [m[0] + p[0] / 8.0, m[1] + p[1] / 8.0, m[2] + p[2] / 8.0]
        });
        block.centroid = mean;
        Snapshot {
            scene_name: "slope".into(),
            time: 0.0,
            step: 0,
            blocks: vec![slope, block],
            contacts: Vec::new(),
            stats: StepStats::default(),
            equilibrium: None,
            rock_masses: Vec::new(),
            joint_sets: Vec::new(),
        }
    }

    pub(crate) const FACTS: [BlockFacts; 2] = [
        BlockFacts {
            mass: 1e6,
            at_rest: true,
            loaded: false,
        },
        BlockFacts {
            mass: 22000.0,
            at_rest: true,
            loaded: false,
        },
    ];

    pub(crate) fn params(phi: f64) -> SolverParams {
        let mut p = SolverParams::default();
        p.joint.friction_angle = phi;
        p
    }

    #[test]
    fn slopes_of_any_angle_and_direction_are_recognised() {
        for (theta, phi, azimuth) in [(30.0, 15.0, 0.0), (30.0, 35.0, 0.0), (20.0, 10.0, 90.0)]
            .into_iter()
            .chain([(40.0, 30.0, 215.0), (45.0, 50.0, 33.0), (10.0, 10.5, 0.0)])
        {
            let case = recognise(
                &slope_scene(theta, azimuth, [2.0, 4.0, 1.0]),
                &FACTS,
                &params(phi),
            )
            .unwrap_or_else(|e| panic!("{theta}/{phi}/{azimuth}: {e}"));
            assert!(
                (case.theta_deg - theta).abs() < 1e-9,
                "{theta}: {}",
                case.theta_deg
            );
            assert_eq!((case.block_index, case.slope_index), (1, 0));
            assert_eq!(case.weight, 22000.0 * 9.8);
            let (t, f) = (theta.to_radians(), phi.to_radians());
            if phi < theta {
                assert_eq!(case.motion, Motion::Slides);
                let a = 9.8 * (t.sin() - t.cos() * f.tan());
                assert!((case.acceleration - a).abs() < 1e-12);
                let az = azimuth.to_radians();
                let want = [t.cos() * az.cos(), t.cos() * az.sin(), -t.sin()];
                assert!((0..3).all(|k| (case.downslope[k] - want[k]).abs() < 1e-12));
            } else {
                assert_eq!(case.motion, Motion::Stands);
                assert_eq!(case.acceleration, 0.0);
            }
        }
    }

    #[test]
    fn other_scenes_say_why_they_have_none() {
        let s = slope_scene(30.0, 0.0, [2.0, 4.0, 1.0]);
        let mut p = params(15.0);
        let why =
            |s: &Snapshot, f: &[BlockFacts], p: &SolverParams| recognise(s, f, p).unwrap_err();
        let mut one = s.clone();
        one.blocks.pop();
        assert!(why(&one, &FACTS[..1], &p).contains("1 blocks"));
        let mut both_free = s.clone();
        both_free.blocks[0].fixed = false;
        assert!(why(&both_free, &FACTS, &p).contains("one fixed and one free"));
        let mut moving = FACTS;
        moving[1].at_rest = false;
        assert!(why(&s, &moving, &p).contains("from rest"));
        let mut lifted = s.clone();
        for v in &mut lifted.blocks[1].vertices {
            v[2] += 0.01;
        }
        assert!(why(&lifted, &FACTS, &p).contains("does not rest on exactly one face"));
        p.joint.cohesion = 1e5;
        assert!(why(&s, &FACTS, &p).contains("cohesion"));
        p.joint.cohesion = 0.0;
        p.mode = Mode::Static;
        assert!(why(&s, &FACTS, &p).contains("dynamic mode"));
        p.joint.friction_angle = 35.0;
        assert!(
            recognise(&s, &FACTS, &p).is_ok(),
            "a standing block in static mode"
        );
        p.gravity = [0.0; 3];
        assert!(why(&s, &FACTS, &p).contains("no gravity"));
    }
}
