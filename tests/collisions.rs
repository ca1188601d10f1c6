//! Collisions on a frictionless base, both methods: the base pushes only vertically and the
//! blocks push each other with equal and opposite forces, so the blocks' horizontal momentum is
//! conserved exactly through the impact, and no energy is gained. A family of 64 head-on
//! collisions: a 1 m cube at 0.5–6 m/s strikes a resting block of 0.3–2 m (0.9 × 0.8 m
//! section) 0.3 m ahead, the pair turned about z by 0–70°, for 1 s.
//!
//! Before a frictionless contact settled sliding (`contact::law::settle`), DDA-3p, which settles
//! a contact after its second change of state in a step, settled the struck block's corners
//! locked on the base in the impact step: 32 of the 64 collisions lost 3–124 % of their momentum
//! to the base (the struck pair of a 0.3 m block at 1 m/s ended moving backwards). DDA-3a,
//! which allows six changes, conserved it to 3·10⁻⁹ before and after.
//!
//! With friction the base may take momentum, but no more than Mohr–Coulomb allows: in every step
//! its horizontal impulse on the blocks is at most tan φ times its vertical one. DDA-3a keeps
//! within 16 % of that (the README's "Friction at impacts" says where the excess comes from);
//! DDA-3p, whose friction takes the previous solve's normal force, exceeds it many times over in
//! steps where a struck block hops, and is printed, not held to it.

use dda3d::params::Method;
use dda3d::scene;
use dda3d::solver::Solver;

const DENSITY: f64 = 2600.0;

/// The cube at `speed` along the direction `yaw` degrees from x, the block of length `length`
/// at rest 0.3 m ahead, both turned by `yaw`, on a fixed base of friction angle `phi`.
fn collision(length: f64, speed: f64, yaw: f64, phi: f64) -> String {
    let (s, c) = yaw.to_radians().sin_cos();
    let ahead = 0.5 + 0.3 + length / 2.0;
    format!(
        "name = \"collision\"\n[joint]\nfriction_angle = {phi}\n\
         [materials.rock]\ndensity = {DENSITY}\nyoung_modulus = 2e10\npoisson_ratio = 0.25\n\
         [[blocks]]\nname = \"base\"\nmaterial = \"rock\"\nfixed = true\n\
         box = {{ size = [30, 30, 1], center = [3, 0.2, -0.5] }}\n\
         [[blocks]]\nname = \"striker\"\nmaterial = \"rock\"\n\
         box = {{ size = [1, 1, 1], center = [0, 0, 0.5], rotation = [0, 0, {yaw}] }}\n\
         velocity = [{}, {}, 0]\n\
         [[blocks]]\nname = \"struck\"\nmaterial = \"rock\"\n\
         box = {{ size = [{length}, 0.9, 0.8], center = [{}, {}, 0.4], rotation = [0, 0, {yaw}] }}\n",
        speed * c,
        speed * s,
        ahead * c,
        ahead * s
    )
}

/// The collision of [`collision`] with `method`, ready to run for 1 s.
fn solver(length: f64, speed: f64, yaw: f64, phi: f64, method: Method) -> Solver {
    let text = collision(length, speed, yaw, phi);
    let mut s = scene::parse(&text, "c.toml", "c").expect("parses");
    s.params.method = method;
    s.params.duration = 1.0;
    Solver::new(s.model, s.params)
}

/// The free blocks' momentum, kg·m/s.
fn momentum(solver: &Solver) -> [f64; 3] {
    let free = &solver.model.blocks[1..];
    [0, 1, 2].map(|k| free.iter().map(|b| b.mass * b.velocity[k]).sum::<f64>())
}

/// The free blocks' horizontal momentum, kg·m/s, and kinetic plus gravitational energy, J
/// (the blocks settle onto the base by their contacts' compliance: kinetic energy alone may
/// grow by what they sink).
fn momentum_and_energy(solver: &Solver) -> ([f64; 2], f64) {
    let free = &solver.model.blocks[1..];
    let [px, py, _] = momentum(solver);
    let g = -solver.params.gravity[2];
    let energy = free
        .iter()
        .map(|b| b.kinetic_energy() + b.mass * g * b.mp.centroid.z)
        .sum();
    ([px, py], energy)
}

/// The largest change of the horizontal momentum over the run, relative to the striker's, the
/// largest gain of energy over the striker's kinetic energy, and the struck block's final
/// speed.
fn run(length: f64, speed: f64, yaw: f64, method: Method) -> (f64, f64, f64) {
    let mut solver = solver(length, speed, yaw, 0.0, method);
    let (p0, e0) = momentum_and_energy(&solver);
    let kinetic = solver.model.blocks[1].kinetic_energy();
    let (mut change, mut energy) = (0.0f64, f64::NEG_INFINITY);
    while !solver.finished() {
        solver.step().expect("runs");
        let (p, e) = momentum_and_energy(&solver);
        change = change.max((p[0] - p0[0]).hypot(p[1] - p0[1]));
        energy = energy.max(e - e0);
    }
    let v = solver.model.blocks[2].velocity;
    (
        change / p0[0].hypot(p0[1]),
        energy / kinetic,
        v[0].hypot(v[1]),
    )
}

#[test]
fn frictionless_collisions_conserve_momentum() {
    for method in [Method::Alm, Method::Penalty] {
        let (mut worst, mut gain) = (0.0f64, f64::NEG_INFINITY);
        for length in [0.3, 0.5, 1.0, 2.0] {
            for speed in [0.5, 1.0, 3.0, 6.0] {
                for yaw in [0.0, 20.0, 45.0, 70.0] {
                    let (change, energy, struck) = run(length, speed, yaw, method);
                    println!(
                        "{method:?} block {length} m, {speed} m/s, yaw {yaw}°: momentum \
                         changed by {change:.2e}, energy gained at most {energy:.1e} of the \
                         striker's, struck block at {struck:.3} m/s"
                    );
                    // The struck block moves off: the collision happened.
                    assert!(struck > 0.1 * speed, "{method:?} {length} {speed} {yaw}");
                    worst = worst.max(change);
                    gain = gain.max(energy);
                }
            }
        }
        assert!(worst < 1e-7, "{method:?}: momentum changed by {worst:.2e}");
        assert!(
            gain < 1e-6,
            "{method:?}: energy grew by {gain:.2e} of the striker's"
        );
    }
}

/// The largest ratio, over the steps of 1 s, of the base's horizontal impulse on the blocks to
/// tan φ times its vertical one (steps in which the base pushes up with at least 1 % of the
/// blocks' weight; the blocks push each other with equal and opposite forces, and gravity is
/// vertical, so the change of the blocks' horizontal momentum is the base's horizontal impulse).
fn worst_coulomb_ratio(length: f64, speed: f64, yaw: f64, phi: f64, method: Method) -> f64 {
    let mut solver = solver(length, speed, yaw, phi, method);
    let mass: f64 = solver.model.blocks[1..].iter().map(|b| b.mass).sum();
    let g = -solver.params.gravity[2];
    let mut worst = 0.0f64;
    while !solver.finished() {
        let (p0, t0) = (momentum(&solver), solver.time);
        solver.step().expect("runs");
        let (p1, dt) = (momentum(&solver), solver.time - t0);
        let horizontal = (p1[0] - p0[0]).hypot(p1[1] - p0[1]);
        let vertical = p1[2] - p0[2] + mass * g * dt;
        if vertical > 0.01 * mass * g * dt {
            worst = worst.max(horizontal / (phi.to_radians().tan() * vertical));
        }
    }
    worst
}

/// 72 collisions (φ 10° and 30°; blocks of 0.3, 1 and 2 m; 1, 3 and 6 m/s; turned 0–70°): under
/// DDA-3a the base's friction stays within 5 % of Mohr–Coulomb in every step (measured: 3.4 % at
/// most, a 2 m block struck at 6 m/s on φ 10°; 3.1 % on φ 30°). The excess left is the impact
/// step's: the friction takes the normal force of the ALM's previous iterate, which (P24) bounds
/// for all the contacts together, not per contact. It was 15.0 % before a sliding contact whose
/// friction pushed across τ beyond its strength was solved again
/// (`open_close::pushed_beyond_friction`): the struck block's corners had just begun to slide,
/// τ a degree off their slip and k⊥ still p_τ. DDA-3p's worst step is printed (57 times
/// Mohr–Coulomb when measured, on φ 10°; 13.2 times on φ 30°).
#[test]
fn friction_at_impacts_stays_near_mohr_coulomb() {
    for method in [Method::Alm, Method::Penalty] {
        let mut worst = (0.0f64, String::new());
        for phi in [10.0, 30.0] {
            for length in [0.3, 1.0, 2.0] {
                for speed in [1.0, 3.0, 6.0] {
                    for yaw in [0.0, 20.0, 45.0, 70.0] {
                        let ratio = worst_coulomb_ratio(length, speed, yaw, phi, method);
                        println!(
                            "{method:?} φ {phi}°, block {length} m, {speed} m/s, yaw {yaw}°: \
                             the base's impulse at most {ratio:.4} of Mohr–Coulomb's"
                        );
                        if ratio > worst.0 {
                            worst = (
                                ratio,
                                format!("φ {phi}, {length} m, {speed} m/s, yaw {yaw}"),
                            );
                        }
                    }
                }
            }
        }
        println!(
            "{method:?}: at most {:.4} of Mohr–Coulomb ({})",
            worst.0, worst.1
        );
        // The family strikes: friction carries load in it.
        assert!(worst.0 > 0.5, "{method:?}: {worst:?}");
        if method == Method::Alm {
            assert!(
                worst.0 < 1.05,
                "{}: {:.4} of Mohr–Coulomb",
                worst.1,
                worst.0
            );
        }
    }
}
