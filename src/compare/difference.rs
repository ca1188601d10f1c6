//! Two runs of the same scene compared at one simulated time: how far apart their blocks are,
//! how much their contact forces differ, and each side's penetration and kinetic energy.

use serde::Serialize;

use super::sample::Sample;
use crate::snapshot::Snapshot;

/// One side at the comparison time.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct SideState {
    /// The total contact force ([`Sample::contact_force`]), N.
    pub contact_force: f64,
    pub max_penetration: f64,
    pub kinetic_energy: f64,
}

/// A and B at one time.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Comparison {
    pub time: f64,
    /// The largest distance between a block's centroid in A and in B, m (their displacements
    /// since t = 0 differ by exactly this: the scene, and so t = 0, is the same).
    pub max_displacement_difference: f64,
    /// The block it belongs to (none without blocks).
    pub block: Option<String>,
    /// |total contact force of A − that of B|, N.
    pub contact_force_difference: f64,
    pub a: SideState,
    pub b: SideState,
}

fn side(s: &Sample) -> SideState {
    SideState {
        contact_force: s.contact_force,
        max_penetration: s.max_penetration,
        kinetic_energy: s.kinetic_energy,
    }
}

/// A and B at the same time (the time is A's); `names` are the blocks', in the scene's order
/// (both sides have the scene's blocks). The first block of the largest difference wins a tie.
pub fn compare(a: &Sample, b: &Sample, names: &[String]) -> Comparison {
    let mut largest: Option<(usize, f64)> = None;
    for (k, (da, db)) in a.displacements.iter().zip(&b.displacements).enumerate() {
        let d = (0..3).map(|i| (da[i] - db[i]).powi(2)).sum::<f64>().sqrt();
        if largest.is_none_or(|(_, m)| d > m) {
            largest = Some((k, d));
        }
    }
    Comparison {
        time: a.time,
        max_displacement_difference: largest.map_or(0.0, |(_, d)| d),
        block: largest.and_then(|(k, _)| names.get(k).cloned()),
        contact_force_difference: (a.contact_force - b.contact_force).abs(),
        a: side(a),
        b: side(b),
    }
}

/// Two snapshots of the same scene compared as they are (the caller sees to it that they are
/// at the same time; the viewer's two panes, say).
pub fn compare_snapshots(a: &Snapshot, b: &Snapshot) -> Comparison {
    let names: Vec<String> = a.blocks.iter().map(|b| b.name.clone()).collect();
    compare(&Sample::of(a), &Sample::of(b), &names)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::snapshot::{BlockSnapshot, ContactMode, ContactSnapshot, ContactState, StepStats};

    fn snapshot(shift: f64, normal: f64) -> Snapshot {
        let mut moved = BlockSnapshot::test_cube("b", [0.0; 3], 1.0);
        moved.displacement = [shift, 0.0, 0.0];
        let contact = ContactSnapshot {
            block_i: 1,
            block_j: 0,
            mode: ContactMode::VertexFace,
            state: ContactState::Lock,
            point: [0.0; 3],
            normal: [0.0, 0.0, 1.0],
            normal_force: normal,
            shear_force: 0.75 * normal,
            shear: [0.75 * normal, 0.0, 0.0],
            penetration: 1e-6,
            penalty: 2e8,
            lambda: 0.0,
            joint: None,
        };
        Snapshot {
            scene_name: "s".into(),
            time: 0.5,
            step: 50,
            blocks: vec![BlockSnapshot::test_cube("a", [0.0; 3], 1.0), moved],
            contacts: vec![contact.clone(), contact],
            stats: StepStats {
                max_penetration: 1e-6,
                kinetic_energy: 3.0,
                ..StepStats::default()
            },
            equilibrium: None,
            rock_masses: Vec::new(),
            joint_sets: Vec::new(),
        }
    }

    #[test]
    fn the_largest_difference_names_its_block() {
        let c = compare_snapshots(&snapshot(0.25, 400.0), &snapshot(0.0, 100.0));
        assert_eq!(c.time, 0.5);
        assert_eq!(c.max_displacement_difference, 0.25);
        assert_eq!(c.block.as_deref(), Some("b"));
        // Two contacts of 400 N normal and 300 N shear: 1000 N against 250 N.
        assert_eq!(c.a.contact_force, 1000.0);
        assert_eq!(c.contact_force_difference, 750.0);
        assert_eq!(c.b.kinetic_energy, 3.0);
    }

    #[test]
    fn the_same_run_has_no_difference() {
        let c = compare_snapshots(&snapshot(0.1, 5.0), &snapshot(0.1, 5.0));
        assert_eq!(c.max_displacement_difference, 0.0);
        assert_eq!(
            c.block.as_deref(),
            Some("a"),
            "a tie goes to the first block"
        );
        assert_eq!(c.contact_force_difference, 0.0);
    }
}
