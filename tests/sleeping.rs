//! Sleeping islands (issue #15, `solver.sleep_velocity`, `solver.sleep_time`): a group of blocks
//! at rest is held exactly and costs nothing until a moving block comes within contact search
//! distance of it. What must hold:
//! - a standing wall falls asleep, stays exactly where it is, and where it would have stood
//!   without sleeping;
//! - a rock dropped onto a sleeping column wakes it in time: the impact, the rebound and the
//!   rest are those of the run without sleeping;
//! - a block that slides or starts to slide never sleeps, down to factors of safety of 0.999:
//!   its run is the same to the bit as without sleeping;
//! - with `sleep_velocity = 0` no block sleeps.

use dda3d::params::SolverParams;
use dda3d::scene::{self, Scene};
use dda3d::solver::Solver;

/// Every block's centroid, m.
fn centroids(s: &Solver) -> Vec<[f64; 3]> {
    s.snapshot().blocks.iter().map(|b| b.centroid).collect()
}

fn largest_gap(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter()
        .zip(b)
        .flat_map(|(p, q)| (0..3).map(move |k| (p[k] - q[k]).abs()))
        .fold(0.0, f64::max)
}

fn solver(s: &Scene, set: impl Fn(&mut SolverParams)) -> Solver {
    let mut params = s.params.clone();
    set(&mut params);
    Solver::new(s.model.clone(), params)
}

/// Steps to time `t` (a limit past the duration stops at the duration).
fn run_to(s: &mut Solver, t: f64) {
    while s.time < t.min(s.params.duration) - 1e-9 {
        s.step_until(t).expect("runs");
    }
}

#[test]
fn a_standing_wall_falls_asleep_where_it_stands() {
    for (blocks, layers) in [(20, 5), (12, 3), (6, 6)] {
        let text = dda3d::generate::column_wall(blocks, layers, false);
        let mut s = scene::parse(&text, "wall.toml", "wall").expect("scene parses");
        s.params.duration = 3.0;
        let mut on = solver(&s, |_| {});
        let mut off = solver(&s, |p| p.sleep_velocity = 0.0);
        let n = on.model.blocks.len();
        // Asleep by 2 s (the generated wall settles under gravity in its first second).
        run_to(&mut on, 2.0);
        let case = format!("wall of {blocks} in layers of {layers}");
        assert!(
            (0..n).all(|i| on.is_asleep(i)),
            "{case}: every block sleeps by 2 s"
        );
        assert!(on.totals.sleeping_steps > 0);
        let asleep_at = centroids(&on);
        let vertices: Vec<_> = on.model.blocks.iter().map(|b| b.vertices.clone()).collect();
        run_to(&mut on, 3.0);
        run_to(&mut off, 3.0);
        assert_eq!(off.totals.sleeping_steps, 0, "{case}: sleep_velocity 0");
        assert!(
            (0..n).all(|i| on.model.blocks[i].vertices == vertices[i]),
            "{case}: a sleeping block does not move by a bit"
        );
        // Without sleeping the wall stands too (measured: at most 1.5·10⁻¹⁰ m apart).
        let gap = largest_gap(&asleep_at, &centroids(&off));
        println!("{case}: sleeping and awake walls {gap:.2e} m apart at 3 s");
        assert!(gap < 1e-8, "{case}: {gap:.3e} m");
        // The sleeping wall still shows its contacts, with their forces.
        assert_eq!(on.contacts().len(), off.contacts().len(), "{case}");
        let load = |s: &Solver| s.contacts().iter().map(|c| c.normal_force).sum::<f64>();
        let (a, b) = (load(&on), load(&off));
        assert!(
            (a - b).abs() < 1e-3 * b,
            "{case}: contact forces {a} N against {b} N"
        );
    }
}

/// A column of `layers` blocks of 1.2 × 1.2 × 2 m on a fixed ground, and a cube of `rock` m
/// dropped from `height` m above its top, `offset` m off its axis.
fn dropped_rock(layers: usize, rock: f64, height: f64, offset: f64) -> String {
    let mut text = String::from(
        r#"name = "rock dropped on a column"
[solver]
duration = 3.0
[joint]
friction_angle = 35.0
[materials.rock]
density = 2750.0
young_modulus = 2.0e10
poisson_ratio = 0.25
[[blocks]]
name = "ground"
material = "rock"
fixed = true
box = { size = [8, 8, 1], center = [0, 0, -0.5] }
"#,
    );
    for k in 0..layers {
        text += &format!(
            "[[blocks]]\nname = \"c{k}\"\nmaterial = \"rock\"\n\
             box = {{ size = [1.2, 1.2, 2], center = [0, 0, {}] }}\n",
            2.0 * k as f64 + 1.0
        );
    }
    let z = 2.0 * layers as f64 + height + rock / 2.0;
    text += &format!(
        "[[blocks]]\nname = \"rock\"\nmaterial = \"rock\"\n\
         box = {{ size = [{rock}, {rock}, {rock}], center = [{offset}, {}, {z}] }}\n",
        offset / 2.0
    );
    text
}

#[test]
fn a_rock_dropped_on_a_sleeping_column_wakes_it_in_time() {
    for (layers, rock, height, offset) in
        [(3, 0.8, 10.0, 0.1), (2, 0.6, 6.0, 0.0), (4, 1.0, 8.0, 0.2)]
    {
        let case = format!("{layers} layers, {rock} m rock from {height} m");
        let text = dropped_rock(layers, rock, height, offset);
        let s = scene::parse(&text, "drop.toml", "drop").expect("scene parses");
        let mut on = solver(&s, |_| {});
        let mut off = solver(&s, |p| p.sleep_velocity = 0.0);
        let column = 1..=layers;
        let rock_index = layers + 1;
        // The column sleeps while the rock falls, and wakes before the rock can touch it.
        let (mut slept, mut woke) = (false, false);
        let mut penetration = (0.0f64, 0.0f64);
        while !on.finished() {
            let asleep = column.clone().all(|i| on.is_asleep(i));
            let stats = on.step().expect("runs").clone();
            penetration.0 = penetration.0.max(stats.max_penetration);
            slept |= asleep;
            woke |= slept && !on.is_asleep(1);
            // No contact joins a sleeping block to an awake movable one: the rock on the
            // column sleeps with it or not at all.
            for c in on.contacts() {
                let movable = |i: usize| !on.model.blocks[i].fixed;
                if movable(c.block_i) && movable(c.block_j) {
                    assert_eq!(
                        on.is_asleep(c.block_i),
                        on.is_asleep(c.block_j),
                        "{case}: a contact between a sleeping and an awake block at {} s",
                        on.time
                    );
                }
            }
        }
        while !off.finished() {
            let stats = off.step().expect("runs");
            penetration.1 = penetration.1.max(stats.max_penetration);
        }
        assert!(slept && woke, "{case}: slept {slept}, woke {woke}");
        // The rock rests on the column in both runs, at the same place within a few
        // millimetres (its bounces amplify a difference of 10⁻¹² m at the impact).
        let (a, b) = (centroids(&on), centroids(&off));
        let top = 2.0 * layers as f64 + rock / 2.0;
        for (run, c) in [("sleeping", &a), ("awake", &b)] {
            let z = c[rock_index][2];
            assert!(
                (z - top).abs() < 0.01,
                "{case}, {run}: the rock at z = {z} m"
            );
        }
        let gap = largest_gap(&a, &b);
        println!(
            "{case}: runs {gap:.2e} m apart at 3 s; largest penetration {:.2e} / {:.2e} m",
            penetration.0, penetration.1
        );
        assert!(gap < 5e-3, "{case}: {gap:.3e} m");
        assert!(penetration.0 < 2.0 * penetration.1.max(1e-5), "{case}");
    }
}

/// A block of 2 × 2 × 1 m on a fixed plane of `theta` degrees at a factor of safety `fos`.
fn block_on_plane(theta: f64, fos: f64) -> String {
    let phi = (fos * theta.to_radians().tan()).atan().to_degrees();
    let t = theta.to_radians();
    let at = |s: f64| format!("[{}, 0, {}]", t.sin() * s, t.cos() * s);
    format!(
        r#"name = "block on a plane"
[solver]
duration = 1.5
[joint]
friction_angle = {phi}
[materials.rock]
density = 2750.0
young_modulus = 2.0e10
poisson_ratio = 0.25
[[blocks]]
name = "plane"
material = "rock"
fixed = true
box = {{ size = [12, 6, 2], center = {}, rotation = [0, {theta}, 0] }}
[[blocks]]
name = "block"
material = "rock"
box = {{ size = [2, 2, 1], center = {}, rotation = [0, {theta}, 0] }}
"#,
        at(-1.0),
        at(0.5)
    )
}

#[test]
fn a_block_that_slides_never_sleeps() {
    for theta in [20.0, 35.0] {
        for fos in [0.5, 0.9, 0.99, 0.999] {
            let case = format!("{theta}° at a factor of safety of {fos}");
            let s = scene::parse(&block_on_plane(theta, fos), "plane.toml", "plane").unwrap();
            let mut on = solver(&s, |_| {});
            let mut off = solver(&s, |p| p.sleep_velocity = 0.0);
            run_to(&mut on, 1.5);
            run_to(&mut off, 1.5);
            assert_eq!(on.totals.sleeping_steps, 0, "{case}");
            assert_eq!(centroids(&on), centroids(&off), "{case}");
            // It slides: Coulomb's a = g (sin θ − cos θ tan φ) moves it ½ a t² by 1.5 s.
            let g = 9.8;
            let t = theta.to_radians();
            let a = g * (t.sin() - t.cos() * fos * t.tan());
            let (start, end) = (s.model.blocks[1].mp.centroid, centroids(&on)[1]);
            let travel = (0..3)
                .map(|k| (end[k] - start[k]).powi(2))
                .sum::<f64>()
                .sqrt();
            println!(
                "{case}: {travel:.4e} m (Coulomb {:.4e} m)",
                0.5 * a * 1.5 * 1.5
            );
            let coulomb = 0.5 * a * 1.5 * 1.5;
            assert!(
                (travel / coulomb - 1.0).abs() < 0.2,
                "{case}: {travel:.3e} m against {coulomb:.3e} m"
            );
        }
    }
}

/// Two columns of three blocks 4 m apart on one fixed slab, and a cube dropped from 6 m onto
/// the second.
fn two_columns_one_struck() -> String {
    let mut text = dropped_rock(3, 0.8, 6.0, 0.0).replace("[8, 8, 1]", "[14, 8, 1]");
    for k in 0..3 {
        text += &format!(
            "[[blocks]]\nname = \"d{k}\"\nmaterial = \"rock\"\n\
             box = {{ size = [1.2, 1.2, 2], center = [4, 0, {}] }}\n",
            2.0 * k as f64 + 1.0
        );
    }
    // The rock falls on the second column instead of the first.
    text.replace("center = [0, 0, 12.4]", "center = [4, 0, 12.4]")
}

#[test]
fn a_column_sleeps_on_a_slab_shared_with_a_struck_one() {
    let text = two_columns_one_struck();
    assert!(
        text.contains("center = [4, 0, 12.4]"),
        "the rock is above the second column"
    );
    let s = scene::parse(&text, "two.toml", "two").expect("scene parses");
    let mut on = solver(&s, |_| {});
    let mut off = solver(&s, |p| p.sleep_velocity = 0.0);
    let (first, second) = (1..=3, 5..=7);
    let (mut shared, mut woken) = (false, false);
    while !on.finished() {
        on.step().expect("runs");
        let first_asleep = first.clone().all(|i| on.is_asleep(i));
        let second_awake = second.clone().all(|i| !on.is_asleep(i));
        if first_asleep && second_awake {
            // The slab is awake under the struck column, and its contacts with the sleeping
            // one are solved with that column held.
            assert!(!on.is_asleep(0), "the slab is awake");
            shared = true;
        }
        woken |= shared && !first_asleep;
    }
    assert!(shared, "the first column sleeps while the second is awake");
    // The impact shakes the slab on its vertex springs, which changes the forces under the
    // first column and wakes it, so that it follows the slab as it does without sleeping.
    assert!(woken, "the shaken slab wakes the first column");
    while !off.finished() {
        off.step().expect("runs");
    }
    let (a, b) = (centroids(&on), centroids(&off));
    let slab = largest_gap(&a[..1], &b[..1]);
    let column = largest_gap(&a[1..4], &b[1..4]);
    println!("slab {slab:.2e} m, first column {column:.2e} m from the run without sleeping");
    // Measured: slab 4.7·10⁻¹⁰ m, column 2.3·10⁻⁸ m; without the waking, which let the held
    // column lose its support on the shaken slab, 1.5·10⁻⁸ and 3.4·10⁻⁷ m.
    assert!(
        slab < 5e-9 && column < 1e-7,
        "slab {slab:.3e} m, column {column:.3e} m"
    );
}

/// A step asked for at or past the duration, or at a limit already reached, is not taken (a
/// step of zero length would change nothing, forever, in a loop like `run_to`'s).
#[test]
fn no_step_is_taken_without_room() {
    let s = scene::parse(&block_on_plane(30.0, 0.5), "plane.toml", "plane").unwrap();
    let mut solver = solver(&s, |p| p.duration = 0.05);
    run_to(&mut solver, 1.0);
    let (time, steps) = (solver.time, solver.totals.steps);
    assert!((time - 0.05).abs() < 1e-12, "{time}");
    solver.step_until(1.0).expect("no step");
    solver.step().expect("no step");
    solver.step_until(0.01).expect("no step");
    assert_eq!((solver.time, solver.totals.steps), (time, steps));
}
