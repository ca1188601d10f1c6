//! Joint-set properties reach the contacts (issue #14), checked against closed forms: a block cut
//! off by one joint plane slides with a = g (sin δ − cos δ tan φ) when the set's friction is
//! below its dip and stands when it is above, whatever `[joint]` says; and the Hoek–Bray
//! tetrahedral wedge cut by two sets slides along their line of intersection with
//! a = g sin ψ (1 − F) when F < 1 and stands when F ≥ 1 (rock-mass reference §3).

use dda3d::params::Method;
use dda3d::rockmass::orientation::{Vec3, pole};
use dda3d::rockmass::wedge::Sliding;
use dda3d::scene;
use dda3d::solver::Solver;

mod slope_support;
mod wedge_support;

use slope_support::{first_second, shipped};
use wedge_support::{G, OffClosedForm, Run, WedgeCase, rock, run_free_block};

/// One joint set J (dip `dip`, dipping east, friction `phi`) through the origin, and a vertical
/// release joint R at x = 0, in a 3 m wide slab of rock whose top is 1 m above J and parallel to
/// it; `[joint]` has friction `other`. The block above J and in front of R is the free one, a
/// squat slab 1 m thick and 3 / cos δ long. (Under a top at a fixed height the block above J was
/// thicker at its front than at its back: at 25° its back corners carried almost nothing, and it
/// rocked onto them as it slid.)
fn planar(dip: f64, phi: f64, other: f64) -> String {
    let rock = rock(1e10);
    let (t, top) = (dip.to_radians().tan(), 1.0 / dip.to_radians().cos());
    format!(
        "[joint]\nfriction_angle = {other}\n{rock}[[rock_masses]]\nname = \"m\"\n\
         material = \"rock\"\nregions = [ {{ prism = {{ base = [[-3, -1.5, -3], [3, -1.5, -3], \
         [3, -1.5, {}], [-3, -1.5, {}]], extrude = [0, 3, 0] }} }} ]\n\
         [[rock_masses.joint_sets]]\nname = \"J\"\ndip = {dip}\ndip_direction = 90.0\n\
         spacing = 100.0\nfriction_angle = {phi}\n\
         [[rock_masses.joint_sets]]\nname = \"R\"\ndip = 90.0\ndip_direction = 90.0\n\
         spacing = 100.0\n",
        -3.0 * t + top,
        3.0 * t + top
    )
}

/// The block above a joint plane takes the set's friction, not `[joint]`'s: with the set's
/// friction below the dip it slides (where `[joint]` would hold it), above the dip it stands
/// (where `[joint]` would let it slide). Where it slides, its acceleration down the dip is
/// Coulomb's a = g (sin δ − cos δ tan φ) within 1 %, for a family of dips from 20° to 50° and
/// factors of safety from 0.4 to 0.93. (The block on the 50° joint still starts about two steps
/// late: printed, not asserted.)
#[test]
fn a_block_on_a_joint_takes_its_sets_friction() {
    for (dip, phi) in [
        (30.0f64, 20.0f64),
        (40.0, 30.0),
        (25.0, 15.0),
        (20.0, 10.0),
        (50.0, 35.0),
        (35.0, 33.0),
    ] {
        let n = pole(dip, 90.0);
        let above = |c: &Vec3| n.dot(c) > 0.0 && c.x > 0.0;
        let t = 0.5;
        // [joint] would hold the block: only the set's friction lets it slide.
        let m = run_free_block(&planar(dip, phi, 60.0), Run::new(t, Method::Alm), above);
        let (dr, pr) = (dip.to_radians(), phi.to_radians());
        let want = dda3d::rockmass::orientation::dip_vector(dip, 90.0)
            * (G * (dr.sin() - dr.cos() * pr.tan()));
        let along = m.displacement.dot(&want.normalize());
        assert!(
            along > 0.1 * 0.5 * want.norm() * t * t,
            "dip {dip}, φ {phi}: travelled only {along} m"
        );
        assert!(
            (m.acceleration - want).norm() < 0.01 * want.norm(),
            "dip {dip}, φ {phi}: a = {:?}, closed form {want:?}",
            m.acceleration
        );
        // A late start (printed, not asserted): the travel falls short of the closed form's by
        // what a late start of this many steps gives.
        let travel = 0.5 * want.norm() * t * t;
        eprintln!(
            "dip {dip}, φ {phi}: travelled {along:.4} m of {travel:.4} m: a start {:.1} steps late",
            (t - (2.0 * along / want.norm()).sqrt()) / 0.01
        );
        // [joint] would let it slide: the set's friction holds it.
        let m = run_free_block(
            &planar(dip, dip + 5.0, 1.0),
            Run::new(t, Method::Alm),
            above,
        );
        assert!(
            m.displacement.norm() < 1e-4,
            "dip {dip}: crept {} m",
            m.displacement.norm()
        );
    }
}

/// The Hoek–Bray wedge cut by two sets: when F < 1 it slides along the line of intersection of A
/// and B (within 2°) with the closed form's acceleration a = g sin ψ (1 − F) within 1 % (over
/// the last 0.3 s of 0.5 s), and when F ≥ 1 it stands (under 0.1 mm in 0.5 s). A family: the
/// reference's wedge (A 45/105, B 70/235, face 65/185) at several friction angles, a symmetric
/// and a flatter wedge. The table it prints is the README's.
/// How far a sliding wedge's travel at 0.5 s may fall short of ½ a t²: its friction is lined
/// up with its slide from the first steps (`ONSET_TURN` in `src/solver/open_close.rs`; before
/// it, up to 8.6 %, a start a step late).
#[test]
fn the_hoek_bray_wedge_slides_along_its_line_or_stands() {
    hoek_bray_family(
        Method::Alm,
        Bounds {
            travel: 0.03,
            acceleration: 0.01,
            creep: 1e-4,
        },
    );
}

/// The same family under DDA-3p, the baseline: the acceleration within 6 % (0.02–1.3 %, and
/// 5.9 % at F = 0.905), but a first step that gains too much speed, so that the travel at 0.5 s
/// is 0.1–37 % too long (the nearer F is to 1, the longer); a standing wedge settles into its
/// soft springs by up to 0.8 mm.
#[test]
fn the_hoek_bray_wedge_slides_under_the_baseline_too() {
    hoek_bray_family(
        Method::Penalty,
        Bounds {
            travel: 0.4,
            acceleration: 0.06,
            creep: 1e-3,
        },
    );
}

/// How far a method's wedges may be off the closed form: `travel` and `acceleration` as
/// fractions (travel at 0.5 s against ½ a t², acceleration over the last 0.3 s), `creep` m for
/// a wedge that stands.
struct Bounds {
    travel: f64,
    acceleration: f64,
    creep: f64,
}

fn hoek_bray_family(method: Method, bounds: Bounds) {
    let cases = [
        ((45.0, 105.0), (70.0, 235.0), (65.0, 185.0), (20.0, 20.0)),
        ((45.0, 105.0), (70.0, 235.0), (65.0, 185.0), (10.0, 10.0)),
        ((45.0, 105.0), (70.0, 235.0), (65.0, 185.0), (15.0, 25.0)),
        ((50.0, 130.0), (50.0, 230.0), (70.0, 180.0), (25.0, 25.0)),
        ((40.0, 140.0), (60.0, 240.0), (60.0, 190.0), (15.0, 20.0)),
        ((55.0, 120.0), (65.0, 245.0), (75.0, 180.0), (20.0, 25.0)),
        ((35.0, 150.0), (45.0, 215.0), (60.0, 185.0), (12.0, 18.0)),
        // Stable: F = 1.107 (the reference's worked example), 1.435 and 1.129.
        ((45.0, 105.0), (70.0, 235.0), (65.0, 185.0), (20.0, 30.0)),
        ((45.0, 105.0), (70.0, 235.0), (65.0, 185.0), (30.0, 30.0)),
        ((50.0, 130.0), (50.0, 230.0), (70.0, 180.0), (35.0, 35.0)),
    ];
    println!("{method:?}:");
    println!(
        "| set A (dip, dip dir.) | set B | slope face | φ_A, φ_B | F | a, closed form (m/s²) | a, dda3d | error |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for (a, b, face, phi) in cases {
        let case = WedgeCase {
            a,
            b,
            face,
            phi,
            scale: 1.0,
            young: 1e10,
        };
        let w = case.solution();
        assert!(matches!(w.sliding, Sliding::TwoPlanes), "{a:?} {b:?}");
        let t = 0.5;
        let (text, free) = case.scene();
        let m = run_free_block(&text, Run::new(t, method), free);
        let label = format!("A {a:?} B {b:?} φ {phi:?}: F = {:.4}", w.factor_of_safety);
        if w.factor_of_safety < 1.0 {
            let d = m.displacement;
            // Along the line: for two-plane sliding a points down the line of intersection.
            let off = OffClosedForm::of(&m, &w.acceleration, t);
            let (angle, error) = (off.angle, off.acceleration);
            // The travel from rest, which a late start shortens: ½ a t² along the line.
            let (travel, theory) = (off.travel * off.theory, off.theory);
            let late = (off.travel - 1.0).abs();
            eprintln!(
                "{label}: travel {travel:.5} m, theory {theory:.5} m ({:.2} %)",
                100.0 * late
            );
            assert!(
                late < bounds.travel,
                "{label}: travelled {travel} m, theory {theory} m"
            );
            println!(
                "| {a:?} | {b:?} | {face:?} | {phi:?} | {:.4} | {:.4} | {:.4} | {:.2} % |",
                w.factor_of_safety,
                w.acceleration.norm(),
                m.acceleration.norm(),
                100.0 * error
            );
            assert!(
                d.norm() > 1e-3 && angle < 2.0,
                "{label}: moved {d:?}, {angle:.2}° off the line {:?}",
                w.line
            );
            assert!(
                error < bounds.acceleration,
                "{label}: a = {:?}, closed form {:?}",
                m.acceleration,
                w.acceleration
            );
        } else {
            let d = m.displacement.norm();
            println!(
                "| {a:?} | {b:?} | {face:?} | {phi:?} | {:.4} | stands | moved {:.1e} m | |",
                w.factor_of_safety, d
            );
            assert!(d < bounds.creep, "{label}: crept {d} m");
        }
    }
}

/// `layers` slabs 1 m thick and 3 m wide, cut by one joint set (dip `dip`, dipping west, friction
/// `phi`) from a parallelogram of rock resting on a fixed incline of the same dip (the contact
/// with the incline takes `[joint]`, also at `phi`); with `cross`, a second set dipping east at
/// that angle, every 2.5 m, cuts the slabs across.
fn stack(dip: f64, phi: f64, layers: u32, cross: Option<f64>) -> String {
    let rock = rock(1e10);
    let (t, c) = (dip.to_radians().tan(), dip.to_radians().cos());
    let h = f64::from(layers) / c;
    let cross = cross.map_or(String::new(), |d| {
        format!(
            "[[rock_masses.joint_sets]]\nname = \"C\"\ndip = {d}\ndip_direction = 90.0\n\
             spacing = 2.5\norigin = [0.3, 0.0, 0.0]\nfriction_angle = {phi}\n"
        )
    });
    format!(
        "[joint]\nfriction_angle = {phi}\n{rock}[[blocks]]\nname = \"incline\"\n\
         material = \"rock\"\nfixed = true\nprism = {{ base = [[-5, -1.5, -6], [5, -1.5, -6], \
         [5, -1.5, {}], [-5, -1.5, {}]], extrude = [0, 3, 0] }}\n\
         [[rock_masses]]\nname = \"m\"\nmaterial = \"rock\"\nregions = [ {{ prism = {{ base = \
         [[-3, -1.5, {}], [3, -1.5, {}], [3, -1.5, {}], [-3, -1.5, {}]], extrude = [0, 3, 0] }} }} ]\n\
         [[rock_masses.joint_sets]]\nname = \"J\"\ndip = {dip}\ndip_direction = 270.0\n\
         spacing = 1.0\norigin = [0.0, 0.0, {}]\nfriction_angle = {phi}\n{cross}",
        5.0 * t,
        -5.0 * t,
        -3.0 * t,
        3.0 * t,
        3.0 * t + h,
        -3.0 * t + h,
        1.0 / c
    )
}

/// A stack of slabs on a joint dipping at more than its friction angle slides as one, every slab
/// at Coulomb's a = g (sin δ − cos δ tan φ) within 1 % over the last 0.3 s of 0.5 s, for two to
/// four slabs and a family of dips and friction angles, whole or cut across by a second, steep
/// set; with the friction above the dip the stack stands (no block moves 0.1 mm). Each slab's
/// corners slide on the slab below while the slip of a step is still small against what friction
/// alone gives in a step; with the sliding direction taken from the last solve as a fixed point,
/// the slabs yawed, their corners stuck, and stacks of two or three stood or slid at up to 11 %
/// off the closed form. Where the cross set meets the slabs' joints, four blocks meet along a
/// line and the diagonal ones touch along it only; closed on the cross joint's plane, that
/// contact held the block behind it (see `Candidate::tied`).
#[test]
fn a_stack_of_slabs_on_a_joint_slides_as_one() {
    for (dip, phi, layers, cross) in [
        (35.0f64, 25.0f64, 2, None),
        (35.0, 25.0, 3, None),
        (30.0, 20.0, 3, None),
        (40.0, 32.0, 2, None),
        (45.0, 30.0, 4, None),
        (35.0, 25.0, 2, Some(80.0)),
        (30.0, 20.0, 2, Some(70.0)),
    ] {
        let mut s = scene::parse(&stack(dip, phi, layers, cross), "stack.toml", "stack")
            .unwrap_or_else(|e| panic!("{e}"));
        let want_blocks = if cross.is_some() { 2 * layers } else { layers };
        assert!(
            s.model.blocks.len() as u32 > want_blocks,
            "the blocks and the incline"
        );
        let t = 0.5;
        s.params.duration = t;
        let mut solver = Solver::new(s.model, s.params);
        let start: Vec<Vec3> = solver
            .snapshot()
            .blocks
            .iter()
            .map(|b| Vec3::from(b.centroid))
            .collect();
        let mut v0 = None;
        while !solver.finished() {
            solver.step().expect("runs");
            let snap = solver.snapshot();
            if v0.is_none() && snap.time >= t - 0.3 - 1e-9 {
                let v: Vec<Vec3> = snap.blocks.iter().map(|b| Vec3::from(b.velocity)).collect();
                v0 = Some((snap.time, v));
            }
        }
        let snap = solver.snapshot();
        let (t0, v0) = v0.expect("the run reaches its last 0.3 s");
        let (dr, pr) = (dip.to_radians(), phi.to_radians());
        let want = dda3d::rockmass::orientation::dip_vector(dip, 270.0)
            * (G * (dr.sin() - dr.cos() * pr.tan()));
        for (k, b) in snap.blocks.iter().enumerate().skip(1) {
            let a = (Vec3::from(b.velocity) - v0[k]) / (snap.time - t0);
            let moved = Vec3::from(b.centroid) - start[k];
            eprintln!(
                "dip {dip}, φ {phi}, {layers} slabs, cross {cross:?}, {}: a = {:.4} of {:.4} m/s², moved {:.4} m",
                b.name,
                a.norm(),
                want.norm(),
                moved.norm()
            );
            assert!(
                (a - want).norm() < 0.01 * want.norm(),
                "dip {dip}, φ {phi}, {layers} slabs, cross {cross:?}, {}: a = {a:?}, closed form {want:?}",
                b.name
            );
        }
        // The same stack with the friction above the dip stands.
        assert_stack_stands(dip, dip + 5.0, layers, cross, t);
    }
}

/// Runs [`stack`] for `duration` from rest and asserts that no block moves 0.1 mm.
fn assert_stack_stands(dip: f64, phi: f64, layers: u32, cross: Option<f64>, duration: f64) {
    let mut s = scene::parse(&stack(dip, phi, layers, cross), "stack.toml", "stack")
        .unwrap_or_else(|e| panic!("{e}"));
    s.params.duration = duration;
    let mut solver = Solver::new(s.model, s.params);
    let start = solver.snapshot();
    while !solver.finished() {
        solver.step().expect("runs");
    }
    for (b, b0) in solver.snapshot().blocks.iter().zip(&start.blocks) {
        let crept = (Vec3::from(b.centroid) - Vec3::from(b0.centroid)).norm();
        assert!(
            crept < 1e-4,
            "dip {dip}, φ {phi}, {layers} slabs, cross set {cross:?}, {}: crept {crept} m",
            b.name
        );
    }
}

/// Slabs cut by a 75° cross set, whose blocks meet four to a junction, slide as one at
/// Coulomb's rate (their travel in 0.5 s from rest within 1.5 %, their acceleration over the
/// last 0.3 s within 2 %). The slabs' joints sit exactly at their friction limit (each slab
/// alone slides at the same rate), and their contacts rock by micrometres. While (P21) raised
/// the penalty of a closed contact the solve pulled apart, those penalties went a hundredfold
/// up, their forces swung by 10⁵ N, and the first stack stopped within a step after 0.15 s
/// (0.11 m in 0.5 s instead of 0.246 m).
///
/// Three slabs on 40° with φ 25° lagged by 5 % (accelerations 6 % off) until a sliding
/// contact's friction turned by the trial force instead of the direction of its last slip
/// (`law::turned`); they are within 0.2 % and 0.4 % now.
///
/// Not held to the closed form: four slabs cut by an 80° set. The set dips into the slope, so
/// the upslope end column overhangs the stack and leans on it: its top block leads (20 mm
/// against 15 mm at 0.1 s), the blocks below it lag, and the column pushes the rest 4–9 %
/// beyond Coulomb's travel. That is a mechanism of its own, not a slide as one.
#[test]
fn slabs_cut_by_a_cross_set_slide_as_one() {
    // Also: with a 65° cross set on 40°/φ 30°, the top end's 0.08 m³ sliver, lying on the cross
    // joint that dips at 65° out of the stack's free end face, slides off it and falls (9.2 m/s²
    // over the last 0.3 s), as it should; it is not in this family.
    for (dip, phi, layers, cross) in [
        (40.0f64, 30.0f64, 3, 75.0f64),
        (45.0, 35.0, 3, 75.0),
        (35.0, 25.0, 2, 75.0),
        (40.0, 30.0, 2, 70.0),
        (40.0, 25.0, 3, 75.0),
        (35.0, 25.0, 3, 65.0),
        (30.0, 20.0, 2, 70.0),
    ] {
        let t = 0.5;
        let run = |phi: f64| {
            let text = stack(dip, phi, layers, Some(cross));
            let mut s =
                scene::parse(&text, "stack.toml", "stack").unwrap_or_else(|e| panic!("{e}"));
            s.params.duration = t;
            let mut solver = Solver::new(s.model, s.params);
            let start = solver.snapshot();
            let mut mid = None;
            while !solver.finished() {
                solver.step().expect("runs");
                if mid.is_none() && solver.time >= t - 0.3 - 1e-9 {
                    mid = Some(solver.snapshot());
                }
            }
            (start, mid.expect("the last 0.3 s"), solver.snapshot())
        };
        let (start, mid, end) = run(phi);
        let (dr, pr) = (dip.to_radians(), phi.to_radians());
        let want = dda3d::rockmass::orientation::dip_vector(dip, 270.0)
            * (G * (dr.sin() - dr.cos() * pr.tan()));
        for ((b, b1), b0) in end
            .blocks
            .iter()
            .zip(&mid.blocks)
            .zip(&start.blocks)
            .skip(1)
        {
            let a = (Vec3::from(b.velocity) - Vec3::from(b1.velocity)) / (end.time - mid.time);
            let moved = Vec3::from(b.centroid) - Vec3::from(b0.centroid);
            let travel = want * (0.5 * end.time * end.time);
            eprintln!(
                "dip {dip}, φ {phi}, {layers} slabs, cross {cross}: {}: a = {:.4} of {:.4} m/s², \
                 moved {:.4} of {:.4} m",
                b.name,
                a.norm(),
                want.norm(),
                moved.norm(),
                travel.norm()
            );
            // The travel from rest within 1.5 %; the acceleration of the last 0.3 s, a difference
            // of two velocities through the junctions' rocking, within 2 %.
            assert!(
                (moved - travel).norm() < 0.015 * travel.norm()
                    && (a - want).norm() < 0.02 * want.norm(),
                "dip {dip}, φ {phi}, {layers} slabs, cross {cross}, {}: a = {a:?}, moved \
                 {moved:?}; closed form {want:?}, {travel:?}",
                b.name
            );
        }
    }
}

/// Cross-cut stacks whose joints' friction angle is above their dip stand: no block moves
/// 0.1 mm in 1.5 s. Three slabs on 45° under φ 50°, cut at 75°, crept faster and faster (2.9 mm
/// in 1.5 s, the downslope end column most) while a sliding corner's friction turned to the
/// direction of each micrometre slip of the blocks' rocking: τ swung by up to 90° a pass, the
/// open–close iteration did not converge, and 60 contacts a step were settled in whatever state
/// they had. Four slabs under φ 48° cut at 80° crept 0.84 mm, three on 30° cut at 65° 0.14 mm.
#[test]
fn cross_cut_stacks_with_friction_above_their_dip_stand() {
    for (dip, phi, layers, cross) in [
        (45.0, 50.0, 3, 75.0),
        (45.0, 50.0, 2, 75.0),
        (40.0, 50.0, 3, 75.0),
        (35.0, 45.0, 3, 70.0),
        (40.0, 48.0, 4, 80.0),
        (30.0, 38.0, 3, 65.0),
    ] {
        assert_stack_stands(dip, phi, layers, Some(cross), 1.5);
    }
}

/// A 5 m wide slice of the shipped `scenes/jointed_slope.toml`, run for 1 s after its
/// equilibrium stage: every block of the upper mass above J1's lowest daylighting plane (F =
/// 0.67) slides out as Coulomb's 1.88 m/s² has it (0.940 m from rest), and every other block
/// stands, within 1 mm. While a contact that changed state three times in a step was settled,
/// locked contacts held shear beyond their strength and the free blocks lagged: the least moved
/// 0.475 m, the median 0.547 m (9.3 cm and 22 cm before friction turned by the trial force).
/// Before the contacts of acute joint edges were read right (a vertex beside an acute edge taken
/// as 6 cm deep, crossed edges near their ends as 5 cm deep) and the stick update's shear was
/// capped, this slice diverged at 0.8 s, its upper face blocks thrown out at 50 m/s; with only
/// the first of those, a block fell through the rock under it.
/// Few contacts are settled (the open–close iteration converges by the contact law).
#[test]
fn a_slice_of_the_jointed_slope_releases_its_free_blocks_and_the_rest_stands() {
    let slice = shipped()
        .replace("extrude = [0, 20, 0]", "extrude = [0, 5, 0]")
        .replace(
            "box = { size = [50, 24, 4], center = [5, 10, -2] }",
            "box = { size = [50, 9, 4], center = [5, 2.5, -2] }",
        );
    assert_eq!(slice.matches("extrude = [0, 5, 0]").count(), 2);
    assert!(slice.contains("size = [50, 9, 4]"));
    let run = first_second(&slice, "slice.toml");
    let (free, coulomb) = (&run.free, run.coulomb);
    let (least, median) = (free[0], free[free.len() / 2]);
    let (most_other, name) = &run.most_other;
    assert!(*most_other < 0.001, "{name} moved {most_other} m");
    assert!(free.len() >= 10, "{} free blocks", free.len());
    // Coulomb's motion on J1 (35°, φ 25°) from rest: ½ g (sin 35° − cos 35° tan 25°) t² =
    // 0.940 m in 1 s (measured: the least-moved 0.936 m, the median 0.938 m, the others 0.1 mm
    // or less; counted from the scene, before the stage, 0.983 m and 0.987 m).
    assert!(
        least > 0.97 * coulomb,
        "a free block moved {least} m of {coulomb} m"
    );
    assert!(
        (median / coulomb - 1.0).abs() < 0.02,
        "half the free blocks moved {median} m or less, Coulomb {coulomb} m"
    );
    // The open–close iteration converges by the contact law, not by settling: a settled
    // contact's state is the solver's guess. While a sliding contact at its friction limit
    // could stop, slide and stop again within a step, 1457 contacts were settled in this
    // second (2 since it stops once an attempt).
    let settled = run.settled;
    assert!(settled <= 50, "{settled} contacts settled");
}
