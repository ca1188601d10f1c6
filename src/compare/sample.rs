//! What a comparison keeps of one run at one time, and that state between two steps.
//!
//! A and B keep the steps of their own runs (so that each side's files are those of a plain
//! `run`, byte for byte), and two runs with different settings step at different times. They
//! are compared at common times, each side's state there taken between its two steps around
//! it: block positions by cubic Hermite interpolation on the centroids' displacements and
//! velocities (exact for a constant acceleration: a block sliding at Coulomb's rate, a free
//! fall), velocities and the scalar totals linearly. A step that lands on the time is taken
//! as it is.

use crate::snapshot::Snapshot;

/// One run at one time, as much as a comparison reads.
#[derive(Clone, Debug, PartialEq)]
pub struct Sample {
    /// Simulated time, s.
    pub time: f64,
    /// Each block's centroid displacement since t = 0, m.
    pub displacements: Vec<[f64; 3]>,
    /// Each block's centroid velocity, m/s.
    pub velocities: Vec<[f64; 3]>,
    /// The total contact force: the sum over closed contacts of each contact's force,
    /// normal and shear together (√(N² + S²)), N. A sum of magnitudes, not of vectors: the
    /// forces between two free blocks cancel in a vector sum, and what is compared is how much
    /// force the contacts carry.
    pub contact_force: f64,
    /// The sum over closed contacts of the normal force (compression positive), N.
    pub normal_force: f64,
    /// The sum over closed contacts of the shear force's magnitude, N.
    pub shear_force: f64,
    /// The largest penetration of the step beyond a contact's kept overlap, m (the step's
    /// `max_penetration`, as `summary.json` takes its largest).
    pub max_penetration: f64,
    /// Kinetic energy, J.
    pub kinetic_energy: f64,
}

impl Sample {
    pub fn of(s: &Snapshot) -> Sample {
        let (mut contact, mut normal, mut shear) = (0.0, 0.0, 0.0);
        for c in &s.contacts {
            contact += c.normal_force.hypot(c.shear_force);
            normal += c.normal_force;
            shear += c.shear_force;
        }
        Sample {
            time: s.time,
            displacements: s.blocks.iter().map(|b| b.displacement).collect(),
            velocities: s.blocks.iter().map(|b| b.velocity).collect(),
            contact_force: contact,
            normal_force: normal,
            shear_force: shear,
            max_penetration: s.stats.max_penetration,
            kinetic_energy: s.stats.kinetic_energy,
        }
    }

    /// The state at `time`, between `self` (before it) and `next` (at or after it). A time
    /// outside the two, or two samples at the same time, give the nearer one as it is.
    pub fn at(&self, next: &Sample, time: f64) -> Sample {
        let h = next.time - self.time;
        if h.is_nan() || h <= 0.0 || time >= next.time {
            return Sample {
                time,
                ..next.clone()
            };
        }
        if time <= self.time {
            return Sample {
                time,
                ..self.clone()
            };
        }
        let s = (time - self.time) / h;
        let lerp = |a: f64, b: f64| a + s * (b - a);
        // Hermite basis on [0, 1], with the velocities scaled by the step.
        let (s2, s3) = (s * s, s * s * s);
        let (h00, h10) = (2.0 * s3 - 3.0 * s2 + 1.0, s3 - 2.0 * s2 + s);
        let (h01, h11) = (3.0 * s2 - 2.0 * s3, s3 - s2);
        let displacements = (self.displacements.iter().zip(&self.velocities))
            .zip(next.displacements.iter().zip(&next.velocities))
            .map(|((p0, v0), (p1, v1))| {
                std::array::from_fn(|k| {
                    h00 * p0[k] + h10 * h * v0[k] + h01 * p1[k] + h11 * h * v1[k]
                })
            })
            .collect();
        let velocities = self
            .velocities
            .iter()
            .zip(&next.velocities)
            .map(|(a, b)| std::array::from_fn(|k| lerp(a[k], b[k])))
            .collect();
        Sample {
            time,
            displacements,
            velocities,
            contact_force: lerp(self.contact_force, next.contact_force),
            normal_force: lerp(self.normal_force, next.normal_force),
            shear_force: lerp(self.shear_force, next.shear_force),
            max_penetration: lerp(self.max_penetration, next.max_penetration),
            kinetic_energy: lerp(self.kinetic_energy, next.kinetic_energy),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn falling(t: f64, a: f64) -> Sample {
        Sample {
            time: t,
            displacements: vec![[0.5 * a * t * t, 1.0 * t, 0.0]],
            velocities: vec![[a * t, 1.0, 0.0]],
            contact_force: 10.0 * t,
            normal_force: 8.0 * t,
            shear_force: 6.0 * t,
            max_penetration: 1e-6,
            kinetic_energy: t,
        }
    }

    #[test]
    fn constant_acceleration_is_interpolated_exactly() {
        let (a, t0, t1) = (-9.8, 0.013, 0.0227);
        let (p, q) = (falling(t0, a), falling(t1, a));
        for t in [0.014, 0.02, 0.0226] {
            let s = p.at(&q, t);
            let want = falling(t, a);
            assert_eq!(s.time, t);
            for k in 0..3 {
                assert!((s.displacements[0][k] - want.displacements[0][k]).abs() < 1e-15);
                assert!((s.velocities[0][k] - want.velocities[0][k]).abs() < 1e-13);
            }
            assert!((s.contact_force - 10.0 * t).abs() < 1e-12);
        }
    }

    #[test]
    fn a_time_on_or_beyond_a_step_takes_that_step() {
        let (p, q) = (falling(0.01, 1.0), falling(0.02, 1.0));
        assert_eq!(p.at(&q, 0.02), q);
        assert_eq!(p.at(&q, 0.03).displacements, q.displacements);
        assert_eq!(p.at(&q, 0.01), p);
        assert_eq!(q.at(&q, 0.02), q, "no step between: the sample itself");
    }
}
