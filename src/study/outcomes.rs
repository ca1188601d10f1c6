//! The outcomes a study can ask of a case (their names are the study file's and the table's
//! columns), and their tracking as a case runs.

use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};

use crate::solver::Solver;

/// An outcome of a case.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    MaxDisplacement,
    Runout,
    BlocksMoved,
    BlocksToppled,
    BlocksRotated,
    PeakNormalForce,
    FinalKineticEnergy,
    MaxPenetration,
    Steps,
}

impl Outcome {
    pub const ALL: [Outcome; 9] = [
        Outcome::MaxDisplacement,
        Outcome::Runout,
        Outcome::BlocksMoved,
        Outcome::BlocksToppled,
        Outcome::BlocksRotated,
        Outcome::PeakNormalForce,
        Outcome::FinalKineticEnergy,
        Outcome::MaxPenetration,
        Outcome::Steps,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Outcome::MaxDisplacement => "max_displacement",
            Outcome::Runout => "runout",
            Outcome::BlocksMoved => "blocks_moved",
            Outcome::BlocksToppled => "blocks_toppled",
            Outcome::BlocksRotated => "blocks_rotated",
            Outcome::PeakNormalForce => "peak_normal_force",
            Outcome::FinalKineticEnergy => "final_kinetic_energy",
            Outcome::MaxPenetration => "max_penetration",
            Outcome::Steps => "steps",
        }
    }

    pub fn unit(self) -> &'static str {
        match self {
            Outcome::MaxDisplacement | Outcome::Runout | Outcome::MaxPenetration => "m",
            Outcome::BlocksMoved
            | Outcome::BlocksToppled
            | Outcome::BlocksRotated
            | Outcome::Steps => "",
            Outcome::PeakNormalForce => "N",
            Outcome::FinalKineticEnergy => "J",
        }
    }

    pub fn from_name(name: &str) -> Option<Outcome> {
        Outcome::ALL.into_iter().find(|o| o.name() == name)
    }
}

/// What the outcomes are measured with: the thresholds and the blocks watched.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct OutcomeSettings {
    /// m: a block whose centroid ends farther than this from its start has moved.
    pub moved_threshold: f64,
    /// Degrees: a block tilted more than this at the end has toppled (and one turned more than
    /// this, about any axis, has rotated).
    pub toppled_angle: f64,
    /// Block names (a trailing `*` matches a prefix) the block outcomes consider; empty: every
    /// free block.
    pub watch: Vec<String>,
}

impl Default for OutcomeSettings {
    fn default() -> Self {
        OutcomeSettings {
            moved_threshold: 0.1,
            toppled_angle: 30.0,
            watch: Vec::new(),
        }
    }
}

/// Whether `name` matches a watch pattern (`column*`: any name starting with `column`).
pub fn matches(pattern: &str, name: &str) -> bool {
    match pattern.strip_suffix('*') {
        Some(prefix) => name.starts_with(prefix),
        None => name == pattern,
    }
}

/// The blocks the block outcomes consider: free, and watched.
pub fn watched<'a>(
    settings: &OutcomeSettings,
    blocks: impl Iterator<Item = (&'a str, bool)>,
) -> Vec<usize> {
    blocks
        .enumerate()
        .filter(|(_, (name, fixed))| {
            !fixed && (settings.watch.is_empty() || settings.watch.iter().any(|p| matches(p, name)))
        })
        .map(|(k, _)| k)
        .collect()
}

/// The outcomes' running values over a case, from its start (after any equilibrium stage).
pub struct Tracker {
    watched: Vec<usize>,
    start_centroids: Vec<Vector3<f64>>,
    /// The watched blocks' vertices at the start, about their centroids.
    start_shapes: Vec<Vec<Vector3<f64>>>,
    max_displacement: f64,
    peak_normal_force: f64,
}

impl Tracker {
    pub fn start(solver: &Solver, settings: &OutcomeSettings) -> Tracker {
        let blocks = &solver.model.blocks;
        let watched = watched(settings, blocks.iter().map(|b| (b.name.as_str(), b.fixed)));
        let start_centroids = watched.iter().map(|&k| blocks[k].mp.centroid).collect();
        let start_shapes = watched
            .iter()
            .map(|&k| {
                let b = &blocks[k];
                b.vertices.iter().map(|v| v - b.mp.centroid).collect()
            })
            .collect();
        let mut t = Tracker {
            watched,
            start_centroids,
            start_shapes,
            max_displacement: 0.0,
            peak_normal_force: 0.0,
        };
        t.after_step(solver);
        t
    }

    fn displacements<'a>(&'a self, solver: &'a Solver) -> impl Iterator<Item = Vector3<f64>> + 'a {
        self.watched
            .iter()
            .zip(&self.start_centroids)
            .map(|(&k, c0)| solver.model.blocks[k].mp.centroid - c0)
    }

    pub fn after_step(&mut self, solver: &Solver) {
        let largest = self
            .displacements(solver)
            .map(|d| d.norm())
            .fold(0.0, f64::max);
        self.max_displacement = self.max_displacement.max(largest);
        let force = solver
            .contacts()
            .iter()
            .map(|c| c.normal_force)
            .fold(0.0, f64::max);
        self.peak_normal_force = self.peak_normal_force.max(force);
    }

    /// The rotation of watched block `i` since the start: the best-fit rotation of its
    /// vertices (polar decomposition of their cross-covariance), which the blocks' small
    /// strains do not disturb.
    fn rotation(&self, solver: &Solver, i: usize) -> Option<Matrix3<f64>> {
        let b = &solver.model.blocks[self.watched[i]];
        let mut h = Matrix3::zeros();
        for (v, v0) in b.vertices.iter().zip(&self.start_shapes[i]) {
            h += (v - b.mp.centroid) * v0.transpose();
        }
        let svd = h.svd(true, true);
        let (u, vt) = (svd.u?, svd.v_t?);
        let r = u * vt;
        Some(if r.determinant() < 0.0 {
            u * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, -1.0)) * vt
        } else {
            r
        })
    }

    /// The angle of that rotation, degrees.
    fn rotation_deg(&self, solver: &Solver, i: usize) -> f64 {
        self.rotation(solver, i).map_or(f64::NAN, |r| {
            ((r.trace() - 1.0) / 2.0)
                .clamp(-1.0, 1.0)
                .acos()
                .to_degrees()
        })
    }

    /// How far the rotation tilts the block, degrees: the angle between the direction of
    /// gravity and its image, so that a turn about the vertical (a block twisted in place by an
    /// off-centre strike) is not a topple. Without gravity, the whole rotation.
    fn tilt_deg(&self, solver: &Solver, i: usize) -> f64 {
        let Some(down) = Vector3::from(solver.params.gravity).try_normalize(0.0) else {
            return self.rotation_deg(solver, i);
        };
        self.rotation(solver, i).map_or(f64::NAN, |r| {
            (r * down).dot(&down).clamp(-1.0, 1.0).acos().to_degrees()
        })
    }

    /// The value of `outcome` at the end of the case.
    pub fn value(&self, outcome: Outcome, solver: &Solver, settings: &OutcomeSettings) -> f64 {
        match outcome {
            Outcome::MaxDisplacement => self.max_displacement,
            Outcome::Runout => {
                let g = Vector3::from(solver.params.gravity);
                let down = g.try_normalize(0.0);
                self.displacements(solver)
                    .map(|d| match down {
                        Some(n) => (d - n * n.dot(&d)).norm(),
                        None => d.norm(),
                    })
                    .fold(0.0, f64::max)
            }
            Outcome::BlocksMoved => self
                .displacements(solver)
                .filter(|d| d.norm() > settings.moved_threshold)
                .count() as f64,
            Outcome::BlocksToppled => (0..self.watched.len())
                .filter(|&i| self.tilt_deg(solver, i) > settings.toppled_angle)
                .count() as f64,
            Outcome::BlocksRotated => (0..self.watched.len())
                .filter(|&i| self.rotation_deg(solver, i) > settings.toppled_angle)
                .count() as f64,
            Outcome::PeakNormalForce => self.peak_normal_force,
            Outcome::FinalKineticEnergy => solver.last.kinetic_energy,
            Outcome::MaxPenetration => solver.totals.max_penetration,
            Outcome::Steps => solver.totals.steps as f64,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_watch_patterns_match() {
        for o in Outcome::ALL {
            assert_eq!(Outcome::from_name(o.name()), Some(o));
        }
        assert_eq!(Outcome::from_name("runoff"), None);
        assert!(matches("column*", "column4"));
        assert!(matches("column*", "column"));
        assert!(!matches("column*", "rock"));
        assert!(matches("rock", "rock") && !matches("rock", "rocks"));
        let s = OutcomeSettings {
            watch: vec!["column*".into()],
            ..OutcomeSettings::default()
        };
        let blocks = [
            ("base", true),
            ("column2", false),
            ("rock", false),
            ("column3", false),
        ];
        assert_eq!(watched(&s, blocks.into_iter()), vec![1, 3]);
        let all = OutcomeSettings::default();
        assert_eq!(watched(&all, blocks.into_iter()), vec![1, 2, 3]);
    }

    /// A free box, tracked from its start, then turned by `angle_deg` about `axis` and moved
    /// by `shift`.
    fn turned(axis: Vector3<f64>, angle_deg: f64, shift: Vector3<f64>) -> (Solver, Tracker) {
        let scene = crate::scene::parse(
            "[materials.r]\ndensity = 2000.0\nyoung_modulus = 1e9\npoisson_ratio = 0.2\n\
             [[blocks]]\nname = \"b\"\nmaterial = \"r\"\n\
             box = { size = [1.0, 2.0, 3.0], center = [0.0, 0.0, 5.0] }\n",
            "t.toml",
            "t",
        )
        .unwrap();
        let mut solver = Solver::new(scene.model, scene.params);
        let tracker = Tracker::start(&solver, &OutcomeSettings::default());
        let axis = nalgebra::Unit::new_normalize(axis);
        let rot = nalgebra::Rotation3::from_axis_angle(&axis, angle_deg.to_radians());
        let b = &mut solver.model.blocks[0];
        let c = b.mp.centroid;
        for v in &mut b.vertices {
            *v = c + rot * (*v - c) + shift;
        }
        b.refresh();
        (solver, tracker)
    }

    #[test]
    fn a_block_turned_by_a_known_angle_measures_it() {
        let settings = OutcomeSettings::default();
        let axis = Vector3::new(1.0, 2.0, 0.5);
        let (solver, tracker) = turned(axis, 40.0, Vector3::new(3.0, 0.0, -4.0));
        assert!((tracker.rotation_deg(&solver, 0) - 40.0).abs() < 1e-9);
        // The tilt: the angle between z and its image, cos = cos θ + (1 − cos θ) n_z².
        let nz2 = 0.25 / axis.norm_squared();
        let c = 40f64.to_radians().cos();
        let tilt = (c + (1.0 - c) * nz2).acos().to_degrees();
        assert!((tracker.tilt_deg(&solver, 0) - tilt).abs() < 1e-9);
        let runout = tracker.value(Outcome::Runout, &solver, &settings);
        assert!((runout - 3.0).abs() < 1e-9, "{runout}");
        assert_eq!(
            tracker.value(Outcome::BlocksToppled, &solver, &settings),
            1.0
        );
        assert_eq!(
            tracker.value(Outcome::BlocksRotated, &solver, &settings),
            1.0
        );
        assert_eq!(tracker.value(Outcome::BlocksMoved, &solver, &settings), 1.0);
        // Twisted about the vertical in place: rotated, not toppled, not moved.
        let (solver, tracker) = turned(Vector3::z(), 60.0, Vector3::zeros());
        assert!(tracker.tilt_deg(&solver, 0).abs() < 1e-6);
        assert_eq!(
            tracker.value(Outcome::BlocksToppled, &solver, &settings),
            0.0
        );
        assert_eq!(
            tracker.value(Outcome::BlocksRotated, &solver, &settings),
            1.0
        );
        assert_eq!(tracker.value(Outcome::BlocksMoved, &solver, &settings), 0.0);
    }
}
