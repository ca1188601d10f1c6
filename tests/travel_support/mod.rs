//! What the slide, toppling and cohesion tests measure: how far a scene's block 1 travels; and
//! where their blocks sit on a slope.

#![allow(dead_code)] // each test file uses part of it

use dda3d::params::Method;
use dda3d::scene;
use dda3d::solver::Solver;

/// Block 1's centroid travel, m, from the start to the end of `text` run by `method` (for
/// `duration` s, or the scene's own duration).
pub fn travel(text: &str, method: Method, duration: Option<f64>) -> f64 {
    displacement(text, method, duration)
        .iter()
        .map(|d| d * d)
        .sum::<f64>()
        .sqrt()
}

/// Block 1's centroid displacement, m, from the start to the end of `text` run by `method` (for
/// `duration` s, or the scene's own duration).
pub fn displacement(text: &str, method: Method, duration: Option<f64>) -> [f64; 3] {
    let mut s = scene::parse(text, "block.toml", "block").expect("scene parses");
    s.params.method = method;
    if let Some(d) = duration {
        s.params.duration = d;
    }
    let mut solver = Solver::new(s.model, s.params);
    let start = solver.snapshot().blocks[1].centroid;
    while !solver.finished() {
        solver.step().expect("runs");
    }
    let end = solver.snapshot().blocks[1].centroid;
    [0, 1, 2].map(|k| end[k] - start[k])
}

/// The point `s` m off a slope of `theta` degrees (along its outward normal, in the x–z plane,
/// dipping toward +x) and `along` m down its dip from the origin, as a scene's `[x, y, z]`.
pub fn on_slope(theta: f64, s: f64, along: f64) -> String {
    across_slope(theta, s, along, 0.0)
}

/// [`on_slope`]'s point moved `y` m across the slope (along y).
pub fn across_slope(theta: f64, s: f64, along: f64, y: f64) -> String {
    let t = theta.to_radians();
    let n = [t.sin(), 0.0, t.cos()];
    let down = [t.cos(), 0.0, -t.sin()];
    let p: Vec<f64> = (0..3).map(|k| n[k] * s + down[k] * along).collect();
    format!("[{}, {}, {}]", p[0], p[1] + y, p[2])
}
