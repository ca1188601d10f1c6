//! A block on a slope slides as Coulomb says whatever the slope's dip direction and the block's
//! yaw on it, and a tall one topples when its centroid overhangs its turned base:
//! `tests/sliding_accuracy.rs` and `tests/toppling.rs` run slopes dipping toward +x with blocks
//! square to the dip; here the slope turns about the vertical and the block about its normal.

use dda3d::params::Method;
use dda3d::physics::geometry::{Mat3, Vec3, box_vertices};
use nalgebra::Rotation3;

mod travel_support;
use travel_support::displacement;

/// The points as a scene's `vertices`.
fn points(v: &[Vec3]) -> String {
    let p: Vec<String> = v
        .iter()
        .map(|p| format!("[{:?}, {:?}, {:?}]", p.x, p.y, p.z))
        .collect();
    format!("[{}]", p.join(", "))
}

/// A slope of `theta` degrees dipping toward the azimuth `psi` (degrees from +x toward +y), its
/// face through the origin, 8a + 40 m long; on it an `a` × `a` × `h` block turned by `yaw`
/// degrees about the slope's normal, near its upper end; the friction angle `phi` degrees.
/// Returns the scene, the unit down-dip direction and the slope's outward normal.
fn scene_text(
    theta: f64,
    psi: f64,
    yaw: f64,
    phi: f64,
    (a, h): (f64, f64),
) -> (String, Vec3, Vec3) {
    let about = |axis: Vec3, deg: f64| {
        Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(axis), deg.to_radians())
            .into_inner()
    };
    let slope: Mat3 = about(Vec3::z(), psi) * about(Vec3::y(), theta);
    let block: Mat3 = slope * about(Vec3::z(), yaw);
    let (n, down) = (slope * Vec3::z(), slope * Vec3::x());
    let length = 8.0 * a + 40.0;
    let depth = a;
    let base = box_vertices(
        [length, 4.0 * a + 4.0, depth],
        (-n * depth / 2.0).into(),
        &slope,
    );
    let on = n * h / 2.0 - down * (length / 2.0 - 2.0 * a);
    let rock = box_vertices([a, a, h], on.into(), &block);
    let text = format!(
        "[solver]\nduration = 1.0\n[joint]\nfriction_angle = {phi:?}\n\
         [materials.rock]\ndensity = 2750.0\nyoung_modulus = 1e10\npoisson_ratio = 0.25\n\
         [[blocks]]\nname = \"slope\"\nmaterial = \"rock\"\nfixed = true\nvertices = {}\n\
         [[blocks]]\nname = \"block\"\nmaterial = \"rock\"\nvertices = {}\n",
        points(&base),
        points(&rock)
    );
    (text, down, n)
}

/// DDA-3a, 1 s from rest, θ 10–60°, dip directions 37° and 200°, yaws 15° and 45°, blocks of
/// 0.1 and 5 m, F = 0.5 and 0.95: the travel down the dip within 1.5 % of ½ g (sin θ −
/// cos θ tan φ) t² (measured: 28 of the 36 within 0.1 %; the 5 m blocks at F = 0.95 0.47–1.28 %
/// long, the first-step kick of a heavy block as gravity is switched on) and at most 0.1 % of
/// it across the dip in the slope's plane (measured 2.4·10⁻⁵ m at most); at F = 1.2 it stands
/// (under 0.1 mm: the 5 m block settles into its contacts by up to 8·10⁻⁵ m). DDA-3p is not
/// run: a 10 cm block yawed 15° on 10° at F = 0.95 stands under it (the README's "Any dip
/// direction, any yaw", and the performance log's session 38).
#[test]
fn a_block_slides_as_coulomb_says_whatever_the_slopes_dip_direction_and_its_yaw() {
    let mut worst = (0.0f64, String::new());
    for theta in [10.0f64, 30.0, 60.0] {
        for (psi, yaw) in [(37.0, 15.0), (200.0, 45.0), (200.0, 15.0)] {
            for a in [0.1, 5.0] {
                for fos in [0.5, 0.95, 1.2] {
                    let label = format!("θ {theta}°, dip dir. {psi}°, yaw {yaw}°, {a} m, F {fos}");
                    let t = theta.to_radians();
                    let phi = (fos * t.tan()).atan().to_degrees();
                    let (text, down, n) = scene_text(theta, psi, yaw, phi, (a, a / 2.0));
                    let d = Vec3::from(displacement(&text, Method::Alm, None));
                    let coulomb = 0.5 * 9.8 * (t.sin() - t.cos() * fos * t.tan());
                    if fos >= 1.0 {
                        assert!(d.norm() < 1e-4, "{label}: moved {d:?}");
                        continue;
                    }
                    let along = d.dot(&down);
                    let across = (d - down * along - n * n.dot(&d)).norm();
                    let error = (along - coulomb).abs() / coulomb;
                    eprintln!("{label}: {along:.5} m of {coulomb:.5}, {across:.1e} m across");
                    if error > worst.0 {
                        worst = (error, label.clone());
                    }
                    assert!(
                        error < 0.015,
                        "{label}: travelled {along} m, Coulomb {coulomb}"
                    );
                    assert!(
                        across < 1e-3 * coulomb,
                        "{label}: {across} m across the dip"
                    );
                }
            }
        }
    }
    eprintln!("worst: {:.3} % ({})", 100.0 * worst.0, worst.1);
}

/// A tall block yawed on its slope topples when the vertical through its centroid leaves its
/// base: the point (h/2) tan θ down the dip from the base's centre lies outside the b × b square
/// turned by the yaw, whose edge is (b/2) / max(|cos yaw|, |sin yaw|) away along the dip. So a
/// block that topples square to the dip may stand yawed 45° (its base reaches √2 farther along
/// the dip) and topple at 15° (1.035 farther). θ 20–45°, dip directions 0°, 37° and 200°, yaws
/// 0°, 15°, 30° and 45°, 15 % either side of the limit, friction 80° (no sliding), DDA-3a: moved
/// more than 10 cm in 1 s where it topples, under 0.1 mm where it stands (measured: at least
/// 0.21 m, at most 1.2·10⁻⁵ m).
#[test]
fn a_yawed_block_topples_when_its_centroid_overhangs_its_turned_base() {
    for theta in [20.0f64, 30.0, 45.0] {
        for (psi, yaw) in [(0.0f64, 0.0f64), (37.0, 15.0), (200.0, 30.0), (37.0, 45.0)] {
            let reach = 0.5
                / yaw
                    .to_radians()
                    .cos()
                    .abs()
                    .max(yaw.to_radians().sin().abs());
            for (ratio, topples) in [(0.85, true), (1.15, false)] {
                // (h/2) tan θ = reach · b / ratio, with b = 1 m.
                let h = 2.0 * reach / (ratio * theta.to_radians().tan());
                let label =
                    format!("θ {theta}°, dip dir. {psi}°, yaw {yaw}°, {ratio} of the limit");
                let moved = Vec3::from(displacement(
                    &scene_text(theta, psi, yaw, 80.0, (1.0, h)).0,
                    Method::Alm,
                    None,
                ));
                eprintln!("{label}: moved {:.3e} m", moved.norm());
                if topples {
                    assert!(moved.norm() > 0.1, "{label}: stood, moved {moved:?}");
                } else {
                    assert!(moved.norm() < 1e-4, "{label}: moved {moved:?}");
                }
            }
        }
    }
}
