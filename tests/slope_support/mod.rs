//! The shipped jointed slope (`scenes/jointed_slope.toml`) or a variant of it, run for one second
//! after its equilibrium stage: what `tests/jointed_slope.rs` (the whole slope) and
//! `tests/joint_sets.rs` (a slice of it) measure.

use dda3d::physics::geometry::Vec3;
use dda3d::scene;
use dda3d::solver::Solver;

/// How the blocks of a jointed slope moved in its first second after the stage.
pub struct FirstSecond {
    /// The travel of each free block (the upper mass above J1's lowest daylighting plane, dip
    /// 35° toward −x through [5.7, 0, 9.5], as the scene's comments place it), m, sorted.
    pub free: Vec<f64>,
    /// The largest travel of any other block, m, and its name.
    pub most_other: (f64, String),
    /// Coulomb's travel of a block on J1 (35°, φ 25°) from rest in that second:
    /// ½ g (sin 35° − cos 35° tan 25°), m.
    pub coulomb: f64,
    /// The contacts settled in the run (`RunTotals::frozen_contacts`).
    #[allow(dead_code)] // read by tests/joint_sets.rs only
    pub settled: u64,
}

/// The text of the shipped `scenes/jointed_slope.toml`.
pub fn shipped() -> String {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/jointed_slope.toml");
    std::fs::read_to_string(path).expect("the shipped scene")
}

/// Runs the slope `text` (named `name` in messages) for 1 s after its equilibrium stage. Travel
/// counts from t = 0, after the stage, where the blocks start from rest (the free blocks slide
/// about 5 cm in its dynamic phase), as `scripts/jointed-slope-stats.py` measures it.
pub fn first_second(text: &str, name: &str) -> FirstSecond {
    let mut s = scene::parse(text, name, "slope").unwrap_or_else(|e| panic!("{e}"));
    s.params.duration = 1.0;
    let above_j1 = |c: &Vec3| c.z > 9.5 + (c.x - 5.7) * 35f64.to_radians().tan();
    let kinds: Vec<(String, bool)> = s
        .model
        .blocks
        .iter()
        .map(|b| {
            let free = !b.fixed && b.name.starts_with("upper/") && above_j1(&b.mp.centroid);
            (b.name.clone(), free)
        })
        .collect();
    let g = -s.params.gravity[2];
    let mut solver = Solver::new(s.model, s.params);
    while solver.in_equilibrium_stage() {
        solver.step().unwrap_or_else(|e| panic!("{e}"));
    }
    let at_rest = solver.snapshot();
    while !solver.finished() {
        solver.step().unwrap_or_else(|e| panic!("{e}"));
    }
    let snap = solver.snapshot();
    let (mut free, mut most_other) = (Vec::new(), (0.0f64, String::new()));
    for (((name, is_free), b0), b) in kinds.iter().zip(&at_rest.blocks).zip(&snap.blocks) {
        let moved = (Vec3::from(b.centroid) - Vec3::from(b0.centroid)).norm();
        if *is_free {
            free.push(moved);
        } else if moved > most_other.0 {
            most_other = (moved, name.clone());
        }
    }
    free.sort_by(f64::total_cmp);
    println!(
        "{name}: {} free blocks moved {:.3} m or more (median {:.3} m); the others {:.2e} m \
         or less ({})",
        free.len(),
        free[0],
        free[free.len() / 2],
        most_other.0,
        most_other.1
    );
    let (dip, phi) = (35f64.to_radians(), 25f64.to_radians());
    FirstSecond {
        free,
        most_other,
        coulomb: 0.5 * g * (dip.sin() - dip.cos() * phi.tan()),
        settled: solver.totals.frozen_contacts,
    }
}
