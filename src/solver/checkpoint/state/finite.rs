//! A restored state's numbers are finite: a file whose checksum was made to match a state
//! holding inf or NaN is corrupt, not a run that diverges (such a file ran to its end and wrote
//! `inf` into `contacts.csv`).

use super::{SavedBlock, SavedSolver};

impl SavedSolver {
    /// Every number the next step starts from is finite (a file whose checksum was made to
    /// match a state holding inf or NaN is corrupt, not a run that diverges).
    pub(super) fn check_finite(&self) -> Result<(), String> {
        fn finite(mut v: impl Iterator<Item = f64>, what: &str) -> Result<(), String> {
            v.all(f64::is_finite)
                .then_some(())
                .ok_or_else(|| format!("{what} is not finite"))
        }
        finite([self.time, self.dt, self.w0].into_iter(), "the run's clock")?;
        let boxes = self
            .initial_boxes
            .iter()
            .flat_map(|(a, b)| a.iter().chain(b));
        finite(boxes.copied(), "an initial box")?;
        for b in &self.blocks {
            b.check_finite()?;
        }
        for (_, r) in &self.records {
            let vectors = [r.reference, r.tau, r.normal].into_iter().flatten();
            let values = [r.lambda, r.penalty, r.normal_force, r.shear_force];
            let more = [r.penetration, r.cohesion_area, r.overlap];
            finite(vectors.chain(values).chain(more), "a contact record")?;
        }
        for (_, held) in self.stage.iter().flat_map(|s| &s.held) {
            finite(held.iter().copied(), "the equilibrium stage")?;
        }
        let l = &self.last;
        let stats = [
            l.time_step,
            l.max_penetration,
            l.max_overlap,
            l.kinetic_energy,
        ];
        let energies = [l.potential_energy, l.elastic_energy];
        finite(
            stats.into_iter().chain(energies),
            "the last step's statistics",
        )?;
        for c in &self.contacts {
            let values = [c.normal_force, c.shear_force, c.penetration, c.penalty];
            let vectors = [c.point, c.normal, c.shear].into_iter().flatten();
            finite(vectors.chain(values), "a published contact")?;
        }
        let sleep = self.still.iter().copied().chain(self.resting);
        finite(sleep, "a block's still time")?;
        if self.energy.as_ref().is_some_and(|e| !e.is_finite()) {
            return Err("the energy balance is not finite".into());
        }
        Ok(())
    }
}

impl SavedBlock {
    /// The block's material, geometry, motion and loads are finite numbers.
    pub(super) fn check_finite(&self) -> Result<(), String> {
        let m = &self.material;
        let scalars = [m.density, m.young_modulus, m.poisson_ratio, self.mass];
        let points = self.vertices.iter().chain(&self.anchors).flatten();
        let loads = self.loads.iter().flat_map(|(a, b)| a.iter().chain(b));
        let motion = self.velocity.iter().chain(&self.acceleration);
        let state = self
            .stress
            .iter()
            .chain(&self.strain)
            .chain(&self.initial_centroid);
        let all = points.chain(loads).chain(motion).chain(state).copied();
        if scalars.into_iter().chain(all).all(f64::is_finite) {
            Ok(())
        } else {
            Err(format!("block '{}': a value is not finite", self.name))
        }
    }
}
