//! A block freed by joint sets and run against a closed form, every other block held: what
//! `tests/joint_sets.rs` (a block on one joint, the Hoek–Bray wedge) and `tests/wedges.rs` (the
//! wedge at other sizes and stiffnesses, and on one plane) measure.

#![allow(dead_code)] // each test file uses part of it

use dda3d::params::Method;
use dda3d::physics::geometry::{Mat3, box_vertices, convex_hull};
use dda3d::rockmass::cut::{CutOptions, Plane, Polyhedron, cut};
use dda3d::rockmass::orientation::{Vec3, pole};
use dda3d::rockmass::wedge::{WedgeSolution, admissible, wedge};
use dda3d::scene;
use dda3d::solver::Solver;

pub const G: f64 = 9.8;

/// A rock of Young's modulus `young`, Pa, as a `[materials.rock]` table.
pub fn rock(young: f64) -> String {
    format!("[materials.rock]\ndensity = 2600.0\nyoung_modulus = {young:e}\npoisson_ratio = 0.25\n")
}

/// What the free block did: its centroid displacement over the run, and its mean acceleration
/// over the run's last `window` seconds (the velocity's change over that time).
pub struct Motion {
    pub displacement: Vec3,
    pub acceleration: Vec3,
}

/// How long to run, and how: `window` s at the end give the acceleration; `max_time_step`
/// overrides the scene's where set.
#[derive(Clone, Copy)]
pub struct Run {
    pub duration: f64,
    pub window: f64,
    pub method: Method,
    pub max_time_step: Option<f64>,
}

impl Run {
    /// `duration` s, the acceleration over the last 0.3 s, the scene's Δt.
    pub fn new(duration: f64, method: Method) -> Run {
        Run {
            duration,
            window: 0.3,
            method,
            max_time_step: None,
        }
    }
}

/// `text` loaded, every block but the one `free` picks held, run as `run` says: how the free
/// block moved.
pub fn run_free_block(text: &str, run: Run, free: impl Fn(&Vec3) -> bool) -> Motion {
    let mut s = scene::parse(text, "joints.toml", "joints").unwrap_or_else(|e| panic!("{e}"));
    s.params.method = run.method;
    if let Some(dt) = run.max_time_step {
        s.params.max_time_step = dt;
    }
    let mut free_blocks = 0;
    let mut k = usize::MAX;
    for (i, b) in s.model.blocks.iter_mut().enumerate() {
        if free(&b.mp.centroid) {
            free_blocks += 1;
            k = i;
        } else {
            b.fixed = true;
            b.anchors = b.vertices.clone();
        }
    }
    assert_eq!(free_blocks, 1, "one block is free");
    s.params.duration = run.duration;
    let mut solver = Solver::new(s.model, s.params);
    let start = Vec3::from(solver.snapshot().blocks[k].centroid);
    let mut v_before = None;
    while !solver.finished() {
        solver.step().expect("runs");
        let snap = solver.snapshot();
        if v_before.is_none() && snap.time >= run.duration - run.window - 1e-9 {
            v_before = Some((snap.time, Vec3::from(snap.blocks[k].velocity)));
        }
    }
    let snap = solver.snapshot();
    let (t0, v0) = v_before.expect("the run reaches its window");
    Motion {
        displacement: Vec3::from(snap.blocks[k].centroid) - start,
        acceleration: (Vec3::from(snap.blocks[k].velocity) - v0) / (snap.time - t0),
    }
}

/// How far a sliding block's run is off a closed form that slides it from rest with the
/// constant acceleration `a`.
pub struct OffClosedForm {
    /// Degrees between the block's displacement and `a`.
    pub angle: f64,
    /// |measured − closed-form acceleration| / |a|.
    pub acceleration: f64,
    /// The travel along `a` over the closed form's ½ |a| t² at `duration` s (below 1: a late
    /// start).
    pub travel: f64,
    /// ½ |a| t², m.
    pub theory: f64,
}

impl OffClosedForm {
    /// `m`, run for `duration` s from rest, against the closed form's acceleration `a`.
    pub fn of(m: &Motion, a: &Vec3, duration: f64) -> OffClosedForm {
        let direction = a.normalize();
        let angle = m
            .displacement
            .normalize()
            .dot(&direction)
            .clamp(-1.0, 1.0)
            .acos()
            .to_degrees();
        let theory = 0.5 * a.norm() * duration * duration;
        OffClosedForm {
            angle,
            acceleration: (m.acceleration - a).norm() / a.norm(),
            travel: m.displacement.dot(&direction) / theory,
            theory,
        }
    }
}

/// A convex slope domain: the box [−4, 4] × [−3, 6] × [−3, h] times `scale` behind the face
/// plane through the origin (dip/dip direction `face`), as `vertices` for a region; `h` is the
/// slope's height, m (already scaled).
pub fn slope_region(face: (f64, f64), h: f64, scale: f64) -> String {
    let corners = box_vertices(
        [8.0 * scale, 9.0 * scale, h + 3.0 * scale],
        [0.0, 1.5 * scale, (h - 3.0 * scale) / 2.0],
        &Mat3::identity(),
    );
    let (vertices, topo) = convex_hull(&corners).expect("a box");
    let faces = topo.faces;
    let n = pole(face.0, face.1);
    let (pieces, _) = cut(
        &[Polyhedron { vertices, faces }],
        &[vec![Plane {
            normal: n,
            offset: 0.0,
        }]],
        &CutOptions {
            min_volume: 0.0,
            max_aspect: 1e6,
            aspect_length: f64::INFINITY,
            max_blocks: 10,
        },
    )
    .expect("cuts");
    let rock = pieces
        .iter()
        .find(|p| n.dot(&p.centroid) < 0.0)
        .expect("rock behind the face");
    let points: Vec<String> = rock
        .vertices
        .iter()
        .map(|v| format!("[{}, {}, {}]", v.x, v.y, v.z))
        .collect();
    format!("{{ vertices = [{}] }}", points.join(", "))
}

/// One Hoek–Bray wedge: sets A and B (dip, dip direction, degrees) with friction angles `phi`,
/// under a slope face `face`, in a slope `2 · scale` m high of a rock of Young's modulus `young`.
pub struct WedgeCase {
    pub a: (f64, f64),
    pub b: (f64, f64),
    pub face: (f64, f64),
    pub phi: (f64, f64),
    pub scale: f64,
    pub young: f64,
}

impl WedgeCase {
    /// The closed form (rock-mass reference §3), checked to be a wedge that daylights in the face.
    pub fn solution(&self) -> WedgeSolution {
        let w = wedge(self.a, self.b, self.phi.0, self.phi.1, G).expect("a wedge");
        assert!(
            admissible(&w, self.face, (0.0, 0.0)),
            "{:?} {:?} daylight in {:?}",
            self.a,
            self.b,
            self.face
        );
        w
    }

    /// Two sets A and B through the origin cut the slope: the wedge above both; a vertical
    /// tension crack T across the line of intersection, through the line at half the slope's
    /// height, frees its front part (whose upper corners then lie inside the faces below it).
    /// T does not change F: the reactions per weight depend on A and B alone (R3.2). The scene
    /// and the free wedge's test on a block's centroid.
    pub fn scene(&self) -> (String, impl Fn(&Vec3) -> bool + use<>) {
        let w = self.solution();
        let (na, nb) = (pole(self.a.0, self.a.1), pole(self.b.0, self.b.1));
        let at = w.line * (self.scale / w.line.z);
        let nt = pole(90.0, w.trend);
        let free = move |c: &Vec3| na.dot(c) > 0.0 && nb.dot(c) > 0.0 && nt.dot(&(c - at)) > 0.0;
        let set = |name: &str, p: (f64, f64), phi: f64| {
            format!(
                "[[rock_masses.joint_sets]]\nname = \"{name}\"\ndip = {}\ndip_direction = {}\n\
                 spacing = {:?}\nfriction_angle = {phi}\n",
                p.0,
                p.1,
                1000.0 * self.scale
            )
        };
        let text = format!(
            "[joint]\nfriction_angle = 60.0\n{}[[rock_masses]]\nname = \"slope\"\n\
             material = \"rock\"\nregions = [ {} ]\n{}{}{}origin = [{}, {}, {}]\n",
            rock(self.young),
            slope_region(self.face, 2.0 * self.scale, self.scale),
            set("A", self.a, self.phi.0),
            set("B", self.b, self.phi.1),
            set("T", (90.0, w.trend), 60.0),
            at.x,
            at.y,
            at.z
        );
        (text, free)
    }
}
