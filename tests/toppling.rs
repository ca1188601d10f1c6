//! A block on an incline whose friction holds it topples exactly when the vertical through its
//! centroid falls outside its base: tan θ > b/h for a block b wide (along the dip) and h high
//! (Goodman and Bray's toppling criterion). A family of slopes, sizes and both methods, just
//! either side of the limit. Until the open test's tension threshold was bounded by the block's
//! weight, a 0.3 × 0.3 × 1 m block on a 20° slope 20 m long (b/h = 0.3 < tan 20° = 0.364)
//! stood: its uphill corners carried 120 N of tension against the 400 N (p_n,1·f0·w0, w0 the
//! slope's) a contact needed to open.

use dda3d::params::Method;

mod travel_support;
use travel_support::{on_slope, travel};

/// A block `b` × `b` × `h` standing on a fixed slope of `theta` degrees, 20 m long, with a
/// friction angle 20° above the slope's (it cannot slide).
fn incline(theta: f64, b: f64, h: f64) -> String {
    let c = |s: f64, along: f64| on_slope(theta, s, along);
    format!(
        "[solver]\nduration = 1.5\nmax_time_step = 0.005\n\
         [joint]\nfriction_angle = {}\n\
         [materials.rock]\ndensity = 2700.0\nyoung_modulus = 2.0e10\npoisson_ratio = 0.25\n\
         [[blocks]]\nname = \"slope\"\nmaterial = \"rock\"\nfixed = true\n\
         box = {{ size = [20, {}, 2], center = {}, rotation = [0, {theta}, 0] }}\n\
         [[blocks]]\nname = \"block\"\nmaterial = \"rock\"\n\
         box = {{ size = [{b}, {b}, {h}], center = {}, rotation = [0, {theta}, 0] }}\n",
        theta + 20.0,
        4.0 * b,
        c(-1.0, 0.0),
        c(h / 2.0, -5.0)
    )
}

#[test]
fn blocks_topple_exactly_when_their_centroid_overhangs_the_base() {
    for theta in [10.0f64, 20.0, 30.0] {
        let limit = theta.to_radians().tan();
        for h in [1.0, 2.0] {
            for (ratio, topples) in [(0.9, true), (1.1, false)] {
                let b = ratio * limit * h;
                for method in [Method::Alm, Method::Penalty] {
                    let moved = travel(&incline(theta, b, h), method, None);
                    let case = format!("{method:?}, θ {theta}°, b/h = {ratio} tan θ, h {h} m");
                    eprintln!("{case}: moved {moved:.3e} m");
                    // DDA-3p's soft penalty springs let a standing block settle by a fraction
                    // of a millimetre; a toppling one falls over by tens of centimetres.
                    let settle = match method {
                        Method::Alm => 1e-5,
                        Method::Penalty => 1e-3,
                    };
                    if topples {
                        assert!(moved > 0.1, "{case}: stood (moved {moved:.2e} m)");
                    } else {
                        assert!(moved < settle, "{case}: moved {moved:.2e} m");
                    }
                }
            }
        }
    }
}
