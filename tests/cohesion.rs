//! A block held on a slope partly by its joint's cohesion stands exactly when limit equilibrium
//! says so: W sin θ ≤ W cos θ tan φ + c·A. Cohesion is lost at a contact's first slip, and judged
//! contact by contact the least pressed (uphill) corners of a block failed first and took the
//! joint with them: a 1 × 1 × 0.5 m block on 30° with φ = 20° slid with 1.43 times the cohesion
//! it needs. An intact joint is now judged whole (`holding_joints` in
//! `src/solver/open_close.rs`). (`tests/stable_dynamics.rs` covers flat blocks, whose corners
//! share the load evenly.)

use dda3d::params::Method;

mod travel_support;
use travel_support::{on_slope, travel};

const PHI: f64 = 20.0;

/// A block 1 × 1 × `h` m on a fixed slope of `theta` degrees, 20 m long, with φ = 20° and
/// `times` the cohesion limit equilibrium needs to hold it.
fn slope(theta: f64, h: f64, times: f64) -> String {
    let t = theta.to_radians();
    let weight = h * 2700.0 * 9.8;
    let cohesion = times * weight * (t.sin() - t.cos() * PHI.to_radians().tan());
    let c = |s: f64, along: f64| on_slope(theta, s, along);
    format!(
        "[joint]\nfriction_angle = {PHI}\ncohesion = {cohesion}\n\
         [materials.rock]\ndensity = 2700.0\nyoung_modulus = 2.0e10\npoisson_ratio = 0.25\n\
         [[blocks]]\nname = \"slope\"\nmaterial = \"rock\"\nfixed = true\n\
         box = {{ size = [20, 4, 2], center = {}, rotation = [0, {theta}, 0] }}\n\
         [[blocks]]\nname = \"block\"\nmaterial = \"rock\"\n\
         box = {{ size = [1, 1, {h}], center = {}, rotation = [0, {theta}, 0] }}\n",
        c(-1.0, 0.0),
        c(h / 2.0, -5.0)
    )
}

/// How far a block slides in 2 s on `theta` degrees without its cohesion, m:
/// ½ g (sin θ − cos θ tan φ) t².
fn frictional_travel(theta: f64) -> f64 {
    let t = theta.to_radians();
    2.0 * 9.8 * (t.sin() - t.cos() * PHI.to_radians().tan())
}

#[test]
fn cohesive_joints_hold_exactly_at_limit_equilibrium() {
    for theta in [25.0f64, 30.0, 35.0] {
        for h in [0.5, 1.0] {
            for (times, stands) in [(0.9, false), (1.05, true)] {
                // DDA-3p, the baseline, is left out: its first step loads the soft penalty
                // springs at once, the corners overshoot their strength and lose their
                // cohesion, and the block slides at 1.05 times the cohesion as it did before.
                let moved = travel(&slope(theta, h, times), Method::Alm, Some(2.0));
                let case = format!("θ {theta}°, h {h} m, {times} × c");
                eprintln!("{case}: moved {moved:.3e} m");
                if stands {
                    assert!(moved < 1e-5, "{case}: moved {moved:.2e} m");
                } else {
                    let want = frictional_travel(theta);
                    assert!(
                        moved > 0.9 * want,
                        "{case}: moved {moved:.3} m of {want:.3}"
                    );
                }
            }
        }
    }
}

/// A joint's shear is the resultant of its contacts' shear forces. The corners of a 10 cm block
/// of soft rock (E = 1 GPa) spread under its weight, and their springs pull sideways in
/// opposite directions as well as down the slope: summed as magnitudes, the joint's shear
/// passed its strength at 1.05 times the cohesion it needs and the block slid as if it had none.
#[test]
fn a_small_block_of_soft_rock_holds_on_its_cohesion() {
    for theta in [25.0f64, 35.0] {
        for (times, stands) in [(0.9, false), (1.05, true)] {
            let text = slope(theta, 0.05, times)
                .replace("size = [1, 1, 0.05]", "size = [0.1, 0.1, 0.05]")
                .replace("young_modulus = 2.0e10", "young_modulus = 1.0e9");
            assert!(text.contains("size = [0.1, 0.1, 0.05]") && text.contains("= 1.0e9"));
            let moved = travel(&text, Method::Alm, Some(2.0));
            let case = format!("θ {theta}°, {times} × c");
            if stands {
                assert!(moved < 1e-4, "{case}: moved {moved:.2e} m");
            } else {
                let want = frictional_travel(theta);
                assert!(
                    (moved - want).abs() < 0.01 * want,
                    "{case}: moved {moved:.3} m of {want:.3}"
                );
            }
        }
    }
}
