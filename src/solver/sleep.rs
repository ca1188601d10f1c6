//! Sleeping islands: a group of blocks at rest is not stepped until something comes near it.
//!
//! An *island* is a set of movable blocks linked, directly or through others, by the broad
//! phase's pairs (boxes within their search distance of each other); fixed blocks do not link
//! islands, as a ground slab under two walls does not make them one. An island sleeps while
//! every block in it has been *still* (its fastest vertex slower than `sleep_velocity`) for at
//! least `sleep_time` of simulated time. A sleeping block is held exactly where it is: it takes
//! no part in the narrow phase, the system or the commit, and the records of its contacts are
//! carried unchanged, so that when it wakes its contacts start from the forces they had.
//!
//! Nothing at the edge of an island is approximated: a block that comes within search distance
//! of a sleeping one joins its island in the broad phase, and the whole island is awake in the
//! step in which a contact between them could first be detected. What sleeping changes is only
//! this: a block slower than `sleep_velocity` for `sleep_time`, with all its island, stops. A
//! block that accelerates from rest at a is stopped only if a · sleep_time < sleep_velocity
//! (at the defaults, a < 10⁻⁴ m/s²: a block of factor of safety 1 − 2·10⁻⁵ on a 30° plane).
//!
//! A fixed block sleeps when every movable block near it sleeps, or, near none, when every
//! movable block of the scene does. A fixed block near both a sleeping and an awake block (a
//! ground slab under a settled column and a rolling rock) stays awake, and its contacts with the
//! sleeping block are solved with that block held: it keeps carrying the block's weight instead
//! of rising on its vertex springs and striking the block when it wakes. Where one of those
//! contacts changes state, or its force by more than ε2, in a step (the slab shaken by an impact
//! elsewhere), the sleeping island wakes for the next step and follows.
//!
//! While every block sleeps, a step only counts: nothing has moved since they fell asleep, so
//! the broad phase and the Δt prediction would give what they gave then.
//!
//! Rapier and Box2D put bodies to sleep by islands in the same way.

use super::active::Active;
use super::{Solver, commit, step_control};
use crate::contact::groups::ContactGroups;
use crate::contact::record::RecordMap;
use crate::params::{Mode, SolverParams};
use crate::physics::integrator::Kinematics;
use crate::snapshot::{ContactSnapshot, StepStats};

/// Whether block `i` is held by `held` (the sleeping blocks of a step; empty: none).
pub(crate) fn is_held(held: &[bool], i: usize) -> bool {
    held.get(i).copied().unwrap_or(false)
}

/// Which blocks sleep, and how long each has been still.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Sleep {
    /// Simulated time each block has been still without interruption, s.
    still: Vec<f64>,
    /// Whether each block sleeps in the step under way.
    asleep: Vec<bool>,
    /// While every block sleeps: the Δt the step control predicted when they all fell asleep.
    /// Nothing moves until something wakes them ([`Sleep::wake_all`]), so the broad phase and
    /// the prediction would give the same again.
    resting: Option<f64>,
}

impl Sleep {
    /// `n` blocks, all awake and none yet still.
    pub fn new(n: usize) -> Self {
        Sleep {
            still: vec![0.0; n],
            asleep: vec![false; n],
            resting: None,
        }
    }

    /// From saved state (a checkpoint); `None` if the lengths differ.
    pub fn from_parts(still: Vec<f64>, asleep: Vec<bool>, resting: Option<f64>) -> Option<Self> {
        (still.len() == asleep.len()).then_some(Sleep {
            still,
            asleep,
            resting,
        })
    }

    /// The time each block has been still, whether it sleeps, and the resting Δt (for a
    /// checkpoint).
    pub fn parts(&self) -> (&[f64], &[bool], Option<f64>) {
        (&self.still, &self.asleep, self.resting)
    }

    /// The Δt predicted when every block fell asleep, while they all still sleep.
    pub fn resting(&self) -> Option<f64> {
        self.resting
    }

    /// Whether block `i` sleeps in the step under way.
    pub fn is_asleep(&self, i: usize) -> bool {
        is_held(&self.asleep, i)
    }

    /// Whether each block sleeps in the step under way.
    pub fn asleep(&self) -> &[bool] {
        &self.asleep
    }

    /// Whether any block sleeps.
    pub fn any_asleep(&self) -> bool {
        self.asleep.iter().any(|&a| a)
    }

    /// Whether every block sleeps (the step then has nothing to solve).
    pub fn all_asleep(&self) -> bool {
        self.asleep.iter().all(|&a| a)
    }

    /// Block `i` was disturbed: it, and so its island, is no longer still.
    pub fn disturb(&mut self, i: usize) {
        self.still[i] = 0.0;
    }

    /// Wakes every block and forgets how long it was still: after a change of the parameters,
    /// the loads or the blocks from outside the solver.
    pub fn wake_all(&mut self) {
        self.still.fill(0.0);
        self.asleep.fill(false);
        self.resting = None;
    }

    /// Decides which blocks sleep in the coming step from the broad phase's `pairs` (a < b).
    /// Returns the blocks that fall asleep now, whose motion the caller stops.
    pub fn settle(
        &mut self,
        fixed: &[bool],
        pairs: &[(usize, usize)],
        sleep_time: f64,
    ) -> Vec<usize> {
        let asleep = sleeping_blocks(fixed, pairs, &self.still, sleep_time);
        let fallen = (0..asleep.len())
            .filter(|&i| asleep[i] && !self.asleep[i] && !fixed[i])
            .collect();
        self.asleep = asleep;
        fallen
    }

    /// After a step of `dt`: each awake movable block whose fastest vertex (`speeds`, m/s) is
    /// slower than `sleep_velocity` has been still `dt` longer; any other starts again from 0.
    /// A sleeping block keeps its time. `sleep_velocity` 0 keeps every block awake.
    pub fn record(&mut self, fixed: &[bool], speeds: &[f64], dt: f64, sleep_velocity: f64) {
        for (i, s) in self.still.iter_mut().enumerate() {
            if self.asleep[i] || fixed[i] {
                continue;
            }
            *s = if speeds[i] < sleep_velocity {
                *s + dt
            } else {
                0.0
            };
        }
    }
}

/// The solver's side of sleeping: deciding, holding, carrying and counting.
impl Solver {
    /// Whether blocks may sleep now: in a dynamic run with a sleep velocity, after the
    /// equilibrium stage (which brings the model to rest by its own measure).
    pub(super) fn sleeping(&self) -> bool {
        self.stage.is_none()
            && self.params.mode == Mode::Dynamic
            && self.params.sleep_velocity > 0.0
    }

    /// Decides which blocks sleep in the coming step ([`sleep`]), and stops those that fall
    /// asleep now (each slower than the sleep velocity).
    pub(super) fn settle_sleep(&mut self, groups: &ContactGroups) {
        if !self.sleeping() {
            if self.sleep.any_asleep() {
                self.sleep.wake_all();
            }
            return;
        }
        let fixed: Vec<bool> = self.model.blocks.iter().map(|b| b.fixed).collect();
        for i in self
            .sleep
            .settle(&fixed, &groups.pairs, self.params.sleep_time)
        {
            self.model.blocks[i].set_kinematics(Kinematics::at_rest());
        }
    }

    /// Wakes every block: after the parameters, loads or blocks were changed from outside the
    /// solver (the viewer's panel).
    pub fn wake_all(&mut self) {
        self.sleep.wake_all();
    }

    /// Takes `params` in place of its settings, from outside a step (the viewer's panel, a run
    /// started from a checkpoint with other settings). A change of anything but the end time
    /// wakes every block: a sleeping island was at rest under the old settings, not
    /// necessarily under the new.
    pub fn set_params(&mut self, params: SolverParams) {
        let mut ends_apart = params.clone();
        ends_apart.duration = self.params.duration;
        if ends_apart != self.params {
            self.wake_all();
        }
        self.params = params;
    }

    /// Whether block `i` sleeps.
    pub fn is_asleep(&self, i: usize) -> bool {
        self.sleep.is_asleep(i)
    }

    /// The records and closed contacts of pairs of sleeping blocks, carried unchanged from the
    /// last step into this one's (no contact of theirs was searched), and counted in `stats`.
    pub(super) fn carry_sleeping(
        &self,
        held: &[bool],
        records: &mut RecordMap,
        contacts: &mut Vec<ContactSnapshot>,
        stats: &mut StepStats,
    ) {
        for (k, r) in &self.records {
            if held[k.i as usize] && held[k.j as usize] {
                records.insert(*k, *r);
            }
        }
        let first = contacts.len();
        contacts.extend(
            self.contacts
                .iter()
                .filter(|c| held[c.block_i] && held[c.block_j])
                .cloned(),
        );
        let (lock, slide) = commit::lock_and_slide(&contacts[first..]);
        stats.contacts_lock += lock;
        stats.contacts_slide += slide;
        stats.blocks_asleep = held.iter().filter(|&&h| h).count() as u32;
    }

    /// Wakes, for the next step, the island of every sleeping block whose contact with an awake
    /// block (a fixed one: no other touches a sleeping island) changed state or changed its
    /// normal force by more than ε2 of itself in this step: the fixed block moved under it (a
    /// slab shaken by an impact elsewhere), and the held block should follow.
    pub(super) fn wake_disturbed(&mut self, held: &[bool], active: &[Active]) {
        let eps = self.params.contact.eps2;
        for c in active {
            let (i, j) = c.blocks();
            if held[i] == held[j] {
                continue;
            }
            let force = |closed: bool, n: f64| if closed { n } else { 0.0 };
            let before = force(c.start.state.is_closed(), c.start.normal_force);
            let after = force(c.rec.state.is_closed(), c.force);
            let scale = before.abs().max(after.abs());
            if c.start.state != c.rec.state || (after - before).abs() > eps * scale {
                self.sleep.disturb(if held[i] { i } else { j });
            }
        }
    }

    /// A step in which every block sleeps: nothing moves, the contacts keep their records and
    /// forces. Returns the step taken.
    pub(super) fn rest(&mut self, dt: f64, base: f64, predicted: f64) -> f64 {
        self.sleep.resting = Some(predicted);
        let (contacts_lock, contacts_slide) = commit::lock_and_slide(&self.contacts);
        let stats = StepStats {
            time_step: dt,
            contacts_lock,
            contacts_slide,
            blocks_asleep: self.model.blocks.len() as u32,
            ..Default::default()
        };
        self.count(&stats, 0);
        self.last = commit::with_energy(stats, &self.model.blocks, self.params.gravity);
        self.dt = step_control::next_dt(&self.params, base, dt, 0);
        dt
    }
}

/// Which blocks sleep: the movable blocks of every island whose blocks have all been still for
/// `sleep_time`; the fixed blocks near at least one movable block and near no awake one; and
/// the other fixed blocks once every movable block sleeps.
pub(crate) fn sleeping_blocks(
    fixed: &[bool],
    pairs: &[(usize, usize)],
    still: &[f64],
    sleep_time: f64,
) -> Vec<bool> {
    let n = fixed.len();
    let islands = islands(fixed, pairs);
    // An island is ready when its least still block is.
    let mut ready = vec![true; n];
    for i in (0..n).filter(|&i| !fixed[i]) {
        ready[islands[i]] &= still[i] >= sleep_time;
    }
    let mut asleep: Vec<bool> = (0..n).map(|i| !fixed[i] && ready[islands[i]]).collect();
    // A fixed block: asleep if it has a movable neighbour and all of them sleep.
    let mut near_movable = vec![false; n];
    let mut near_awake = vec![false; n];
    for &(a, b) in pairs {
        for (f, m) in [(a, b), (b, a)] {
            if fixed[f] && !fixed[m] {
                near_movable[f] = true;
                near_awake[f] |= !asleep[m];
            }
        }
    }
    // A fixed block near no movable one (a ground slab under a fixed bottom layer) sleeps when
    // every movable block does: nothing it does can then reach a movable block.
    let all_movable_asleep = (0..n).any(|i| !fixed[i]) && (0..n).all(|i| fixed[i] || asleep[i]);
    for i in (0..n).filter(|&i| fixed[i]) {
        asleep[i] = if near_movable[i] {
            !near_awake[i]
        } else {
            all_movable_asleep
        };
    }
    asleep
}

/// Each block's island, named by its smallest member: movable blocks linked by `pairs`
/// (a fixed block is an island of its own and links nothing).
pub(crate) fn islands(fixed: &[bool], pairs: &[(usize, usize)]) -> Vec<usize> {
    let mut parent: Vec<usize> = (0..fixed.len()).collect();
    fn root(parent: &mut [usize], mut k: usize) -> usize {
        while parent[k] != k {
            parent[k] = parent[parent[k]];
            k = parent[k];
        }
        k
    }
    for &(a, b) in pairs {
        if fixed[a] || fixed[b] {
            continue;
        }
        let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
        if ra != rb {
            // The smaller index names the island, whatever the order of the pairs.
            parent[ra.max(rb)] = ra.min(rb);
        }
    }
    (0..fixed.len()).map(|k| root(&mut parent, k)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A cube asleep on its slab stays asleep when only the end time changes, and wakes when
    /// any other setting does ([`Solver::set_params`]: the panel, a run from a checkpoint).
    #[test]
    fn new_settings_wake_the_blocks_and_a_new_end_time_does_not() {
        let s = crate::scene::parse(crate::solver::CUBE_ON_SLAB, "cube.toml", "cube").unwrap();
        let mut solver = Solver::new(s.model, s.params);
        solver.params.duration = 1.0;
        while !solver.is_asleep(1) && !solver.finished() {
            solver.step().unwrap();
        }
        assert!(solver.is_asleep(1), "the cube falls asleep");
        let mut p = solver.params.clone();
        p.duration = 5.0;
        solver.set_params(p.clone());
        assert!(solver.is_asleep(1));
        assert_eq!(solver.params.duration, 5.0);
        p.joint.friction_angle += 1.0;
        solver.set_params(p.clone());
        assert!(!solver.is_asleep(1));
        assert_eq!(solver.params, p);
    }

    /// Blocks 0–2 a chain on the fixed slab 3; block 4 apart on the slab; block 5 alone.
    fn scene() -> (Vec<bool>, Vec<(usize, usize)>) {
        let fixed = vec![false, false, false, true, false, false];
        let pairs = vec![(0, 1), (0, 3), (1, 2), (3, 4)];
        (fixed, pairs)
    }

    #[test]
    fn islands_are_linked_through_movable_blocks_only() {
        let (fixed, pairs) = scene();
        assert_eq!(islands(&fixed, &pairs), vec![0, 0, 0, 3, 4, 5]);
        // The order of the pairs does not matter.
        let mut reversed = pairs.clone();
        reversed.reverse();
        assert_eq!(islands(&fixed, &reversed), islands(&fixed, &pairs));
    }

    #[test]
    fn an_island_sleeps_only_when_all_its_blocks_have_been_still_long_enough() {
        let (fixed, pairs) = scene();
        let t = 0.1;
        // Block 2 not yet still long enough: its whole island stays awake, and so does the slab
        // under it; block 4 sleeps alone; block 5 too.
        let still = [0.2, 0.3, 0.05, 0.0, 0.1, 0.5];
        let asleep = sleeping_blocks(&fixed, &pairs, &still, t);
        assert_eq!(asleep, vec![false, false, false, false, true, true]);
        // All still: everything sleeps, the slab with them.
        let still = [0.2, 0.3, 0.1, 0.0, 0.1, 0.5];
        let asleep = sleeping_blocks(&fixed, &pairs, &still, t);
        assert_eq!(asleep, vec![true; 6]);
    }

    #[test]
    fn a_lone_fixed_block_sleeps_only_when_every_movable_block_does() {
        let asleep = sleeping_blocks(&[true, false], &[], &[0.0, 1.0], 0.1);
        assert_eq!(asleep, vec![true, true]);
        let asleep = sleeping_blocks(&[true, false], &[], &[0.0, 0.0], 0.1);
        assert_eq!(asleep, vec![false, false]);
        // A scene of fixed blocks alone never sleeps.
        let asleep = sleeping_blocks(&[true, true], &[], &[0.0, 0.0], 0.1);
        assert_eq!(asleep, vec![false, false]);
    }

    #[test]
    fn a_block_coming_near_wakes_the_island() {
        let (fixed, mut pairs) = scene();
        let mut sleep = Sleep::new(fixed.len());
        sleep.still = vec![1.0; 6];
        sleep.still[5] = 0.0; // block 5 moves
        let fallen = sleep.settle(&fixed, &pairs, 0.1);
        assert_eq!(fallen, vec![0, 1, 2, 4]);
        assert!(sleep.is_asleep(3) && !sleep.is_asleep(5));
        // Block 5 comes within search distance of block 2: the chain and its slab wake; block 4
        // sleeps on.
        pairs.push((2, 5));
        pairs.sort_unstable();
        assert!(sleep.settle(&fixed, &pairs, 0.1).is_empty());
        assert_eq!(
            sleep.asleep(),
            &[false, false, false, false, true, false][..]
        );
        // The woken blocks kept their still time: once block 5 has been still long enough,
        // they sleep again together.
        sleep.record(&fixed, &[0.0; 6], 0.1, 1e-5);
        assert_eq!(sleep.settle(&fixed, &pairs, 0.1), vec![0, 1, 2, 5]);
    }

    #[test]
    fn recording_counts_still_time_and_restarts_it_on_motion() {
        let fixed = [false, false, true];
        let mut sleep = Sleep::new(3);
        let speeds = [1e-6, 1e-3, 1.0];
        sleep.record(&fixed, &speeds, 0.01, 1e-5);
        sleep.record(&fixed, &speeds, 0.01, 1e-5);
        assert_eq!(sleep.still, vec![0.02, 0.0, 0.0]);
        sleep.record(&fixed, &[1e-4, 0.0, 0.0], 0.01, 1e-5);
        assert_eq!(sleep.still, vec![0.0, 0.01, 0.0]);
        // Sleeping switched off: nothing is ever still.
        sleep.record(&fixed, &[0.0; 3], 0.01, 0.0);
        assert_eq!(sleep.still, vec![0.0; 3]);
        sleep.still = vec![1.0; 3];
        sleep.wake_all();
        assert_eq!(sleep.still, vec![0.0; 3]);
    }
}
