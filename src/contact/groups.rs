//! Shi's w0 per contact group. Shi scales every control length of a step — the displacement a
//! step may make (δ·w0), the contact search distance (2.5 δ w0), the ALM tolerance
//! (ε1·2δw0), the open and close thresholds — with w0, half the largest extent of the model.
//! Taken over the whole scene, one distant block makes all of them huge: a fixed cube 1 km from
//! the rockfall let every block move metres a step (12 GJ out of 2.7 MJ). Here "the model" is a
//! *contact group*: blocks linked, directly or through others, by being within the search
//! distance of each other. Each group has its own w0, from its own extent; a block that touches
//! nothing is a group of its own. For a model whose blocks are all linked (every shipped scene)
//! that is Shi's w0, and the results are those of the global w0; a block far away changes
//! nothing, and memory and time follow the number of blocks, not the scene's extent.
//!
//! Linking is decided with the larger w0 of the two groups (so that a small rock approaching a
//! column is seen at the column's search distance), and repeated until no group grows: groups
//! only merge, so it ends, in two or three sweeps in practice. Fixed blocks link too (a slab
//! under a column is part of its model), although no contact is sought between two of them.

use crate::model::Block;
use crate::physics::geometry::Vec3;

/// What grouping sees of a block: its bounding box, the box it started in, and whether it is
/// fixed.
#[derive(Clone, Copy, Debug)]
pub struct Bounds {
    pub lo: Vec3,
    pub hi: Vec3,
    /// The block's initial box: a group's w0 is measured on its members' initial boxes, as
    /// Shi's w0 is on the initial model. (On their current boxes, the few nanometres a fixed
    /// block moves on its springs changed w0, and with it every step of a slide, in the 13th
    /// digit; and a group would grow as its blocks spread.)
    pub initial: (Vec3, Vec3),
    pub fixed: bool,
}

impl Bounds {
    /// A block's box as it stands, and as it started.
    pub fn of(b: &Block, initial: (Vec3, Vec3)) -> Self {
        Bounds {
            lo: b.lo,
            hi: b.hi,
            initial,
            fixed: b.fixed,
        }
    }

    /// Half the largest extent of the initial box (a lone block's w0), m.
    fn half_extent(&self) -> f64 {
        0.5 * (self.initial.1 - self.initial.0).max()
    }
}

/// Shi's search distance d_s = 2.5 δ w0 (reference §6.3).
pub fn search_distance(w0: f64, delta: f64) -> f64 {
    2.5 * delta * w0
}

/// The blocks sorted along the axis of the scene's largest extent, for sweeps and range
/// queries: what lies near a box is found among the blocks whose start on that axis is within
/// reach, not among all blocks.
pub struct SweepIndex {
    axis: usize,
    order: Vec<usize>,
    /// For [`SweepIndex::near`]: the blocks no longer along the axis than [`WIDE_RATIO`] times
    /// the median block, and the others (a ground slab under a whole wall), each in sweep order.
    narrow: SweepRange,
    wide: SweepRange,
}

/// Blocks in sweep order, for range queries: `lo[axis]` of each, and the largest extent of
/// their boxes along the axis (how far back a query must reach).
struct SweepRange {
    order: Vec<usize>,
    starts: Vec<f64>,
    widest: f64,
}

impl SweepRange {
    fn of(boxes: &[Bounds], axis: usize, order: Vec<usize>) -> Self {
        let starts = order.iter().map(|&k| boxes[k].lo[axis]).collect();
        let widest = order
            .iter()
            .map(|&k| boxes[k].hi[axis] - boxes[k].lo[axis])
            .fold(0.0, f64::max);
        SweepRange {
            order,
            starts,
            widest,
        }
    }

    /// The blocks whose start on the axis lies within `max_reach` (and their own extent) of
    /// box `b`: a superset of those whose boxes come within `max_reach` of it.
    fn around(&self, b: &Bounds, axis: usize, max_reach: f64) -> &[usize] {
        // A box that starts before this cannot reach `b`; the slack covers round-off.
        let slack = 1e-9 * (b.lo[axis].abs() + self.widest + max_reach);
        let from = self
            .starts
            .partition_point(|&s| s < b.lo[axis] - max_reach - self.widest - slack);
        let to = self
            .starts
            .partition_point(|&s| s <= b.hi[axis] + max_reach);
        &self.order[from..to.max(from)]
    }
}

/// The most block pairs a step searches for contacts: each holds a 12×12 block of K (1.2 kB)
/// and its candidate contacts several kB more. A wall of 10 000 blocks has about 10⁵. Slabs of
/// a joint set spaced 1 mm apart, far thinner than the contact search distance 2.5·δ·w0, made
/// 2·10⁷ pairs among 16 000 blocks, and the run was killed for its memory (24 GB) before its
/// first step. The searches stop just past it ([`SweepIndex::pairs`]): the list itself, at
/// 16 bytes a pair, took 4.7 GB for 20 000 slabs 0.1 mm thick before the count was checked.
pub const MAX_BLOCK_PAIRS: usize = 2_000_000;

/// A box longer along the sweep axis than this many times the median box is kept in a range of
/// its own for [`SweepIndex::near`]. A range query must reach back by the longest box's extent:
/// with a 248 m ground slab under a wall of 1.2 m blocks, every query scanned every block before
/// it, and the step control's queries (one per block, twice a step) took 40 % of a step of a
/// standing wall of 10 000 blocks. Split so, neither range reaches back further than the one
/// range did.
const WIDE_RATIO: f64 = 8.0;

impl SweepIndex {
    pub fn new(boxes: &[Bounds]) -> Self {
        let (mut lo, mut hi) = (Vec3::repeat(f64::INFINITY), Vec3::repeat(f64::NEG_INFINITY));
        for b in boxes {
            lo = lo.inf(&b.lo);
            hi = hi.sup(&b.hi);
        }
        let axis = if boxes.is_empty() {
            0
        } else {
            (hi - lo).imax()
        };
        let mut order: Vec<usize> = (0..boxes.len()).collect();
        order.sort_by(|&a, &b| boxes[a].lo[axis].total_cmp(&boxes[b].lo[axis]));
        let extent = |k: usize| boxes[k].hi[axis] - boxes[k].lo[axis];
        let mut extents: Vec<f64> = (0..boxes.len()).map(extent).collect();
        let limit = if extents.is_empty() {
            f64::INFINITY
        } else {
            let mid = extents.len() / 2;
            WIDE_RATIO * *extents.select_nth_unstable_by(mid, f64::total_cmp).1
        };
        let (narrow, wide): (Vec<usize>, Vec<usize>) =
            order.iter().partition(|&&k| extent(k) <= limit);
        SweepIndex {
            axis,
            order,
            narrow: SweepRange::of(boxes, axis, narrow),
            wide: SweepRange::of(boxes, axis, wide),
        }
    }

    /// Pairs (a, b), a < b, sorted, whose boxes come within `window(a, b)` of each other on
    /// every axis; `window` must not exceed `max_window`. Pairs of two fixed blocks are kept
    /// only if `fixed_pairs`. The search stops once it has found more than `limit` pairs with a
    /// movable block (and returns what it found): the caller refuses the step.
    pub fn pairs(
        &self,
        boxes: &[Bounds],
        max_window: f64,
        fixed_pairs: bool,
        window: impl Fn(usize, usize) -> f64,
        limit: usize,
    ) -> Vec<(usize, usize)> {
        let axis = self.axis;
        let h = max_window / 2.0;
        let mut pairs = Vec::new();
        let mut movable = 0;
        'sweep: for (k, &a) in self.order.iter().enumerate() {
            let sa = &boxes[a];
            for &b in &self.order[k + 1..] {
                let sb = &boxes[b];
                // `within`'s test on the sweep axis at the largest window, negated.
                if sb.lo[axis] - h > sa.hi[axis] + h {
                    break;
                }
                if sa.fixed && sb.fixed && !fixed_pairs {
                    continue;
                }
                if within(sa, sb, window(a, b)) {
                    pairs.push((a.min(b), a.max(b)));
                    movable += usize::from(!(sa.fixed && sb.fixed));
                    if movable > limit {
                        break 'sweep;
                    }
                }
            }
        }
        pairs.sort_unstable();
        pairs
    }

    /// The blocks other than `i` whose boxes come within `reach(k)` of block `i`'s box on every
    /// axis; `reach` must not exceed `max_reach`. The narrow blocks come in sweep order, then
    /// the wide ones.
    pub fn near<'s>(
        &'s self,
        boxes: &'s [Bounds],
        i: usize,
        max_reach: f64,
        reach: impl Fn(usize) -> f64 + 's,
    ) -> impl Iterator<Item = usize> + 's {
        let b = &boxes[i];
        let narrow = self.narrow.around(b, self.axis, max_reach);
        let wide = self.wide.around(b, self.axis, max_reach);
        narrow
            .iter()
            .chain(wide)
            .copied()
            .filter(move |&k| k != i && reaches(b, &boxes[k], reach(k)))
    }
}

/// The test of Shi's broad phase, both boxes grown by half the window: `a` and `b` are within
/// `window` of each other on every axis.
fn within(a: &Bounds, b: &Bounds, window: f64) -> bool {
    let h = window / 2.0;
    (0..3).all(|d| a.lo[d] - h <= b.hi[d] + h && b.lo[d] - h <= a.hi[d] + h)
}

/// `o` comes within `reach` of `b` on every axis (`b` grown by `reach`).
fn reaches(b: &Bounds, o: &Bounds, reach: f64) -> bool {
    let (lo, hi) = (b.lo - Vec3::repeat(reach), b.hi + Vec3::repeat(reach));
    !(0..3).any(|d| o.hi[d] < lo[d] || o.lo[d] > hi[d])
}

/// A block's step and its contact search are measured on at most this many times its own
/// half-extent: in a long chain of touching blocks (a 2 km strip of 1 m cubes) the group's w0 is
/// 1 km, which would let a 1 m cube move 10 m a step and search 25 m around it for contacts
/// (5 GB for 10 000 cubes). With the cap, a step moves a block at most 10 δ of its half-extent
/// (5 % of its size at the paper's δ = 0.01), the search window stays a few centimetres, and
/// memory and time follow the number of blocks. Ten keeps Shi's w0 for every shipped scene (the
/// rockfall's 1 m column blocks on an 18 m slab: min(9 m, 10 × 1 m) = 9 m).
///
/// The contact law's thresholds and the ALM tolerances stay on the group's w0 (Shi's): measured
/// on the capped w0 they were tighter, and a block pushed at 1.2 μmg on a 64 m base slid 5 % too
/// far in its first step (0.1 % at 1 s, against 0.05 %), from the first step's stick iteration.
pub const SIZE_RATIO: f64 = 10.0;

/// The contact groups of a step, with each group's w0 and the block pairs near enough for
/// contact (the broad phase's result).
pub struct ContactGroups {
    /// The group of each block.
    group: Vec<usize>,
    /// Shi's w0 of each group, m (indexed by the group's representative block).
    w0: Vec<f64>,
    /// [`SIZE_RATIO`] times each block's half-extent, m.
    cap: Vec<f64>,
    /// The largest group's w0, m (asked for once per block by the step control: taken over
    /// all blocks each time, it made each step quadratic in the number of blocks).
    largest: f64,
    /// Pairs with a movable block within their search distance, sorted.
    pub pairs: Vec<(usize, usize)>,
    /// The boxes they were found from, and an index over them for range queries.
    pub boxes: Vec<Bounds>,
    pub index: SweepIndex,
    delta: f64,
}

impl ContactGroups {
    /// Groups the blocks with the displacement ratio δ (see the module doc).
    pub fn find(boxes: Vec<Bounds>, delta: f64) -> Self {
        let n = boxes.len();
        let index = SweepIndex::new(&boxes);
        let mut parent: Vec<usize> = (0..n).collect();
        let cap: Vec<f64> = boxes.iter().map(|b| SIZE_RATIO * b.half_extent()).collect();
        let mut w0: Vec<f64> = boxes.iter().map(Bounds::half_extent).collect();
        loop {
            let own: Vec<f64> = (0..n).map(|k| w0[root(&parent, k)].min(cap[k])).collect();
            let widest = own.iter().copied().fold(0.0, f64::max);
            let window = |a: usize, b: usize| search_distance(own[a].max(own[b]), delta);
            let linked = index.pairs(
                &boxes,
                search_distance(widest, delta),
                true,
                window,
                MAX_BLOCK_PAIRS,
            );
            // Past MAX_BLOCK_PAIRS pairs with a movable block the search stopped: the groups
            // found from what it found carry those pairs, and the step is refused on their count.
            let mut merged = false;
            for &(a, b) in &linked {
                let (ra, rb) = (root(&parent, a), root(&parent, b));
                if ra != rb {
                    // The smaller index represents the group: the result does not depend on
                    // the order of the pairs.
                    parent[ra.max(rb)] = ra.min(rb);
                    merged = true;
                }
            }
            if !merged {
                let pairs = linked
                    .into_iter()
                    .filter(|&(a, b)| !(boxes[a].fixed && boxes[b].fixed))
                    .collect();
                let group: Vec<usize> = (0..n).map(|k| root(&parent, k)).collect();
                let largest = group.iter().map(|&g| w0[g]).fold(0.0, f64::max);
                return ContactGroups {
                    group,
                    largest,
                    w0,
                    cap,
                    pairs,
                    boxes,
                    index,
                    delta,
                };
            }
            w0 = group_w0(&boxes, &mut parent);
        }
    }

    /// Shi's w0 of block `i`'s group, m.
    pub fn group_w0(&self, i: usize) -> f64 {
        self.w0[self.group[i]]
    }

    /// The w0 block `i` is measured on by itself: its group's, at most [`SIZE_RATIO`] times its
    /// half-extent, m. Its search distance is Shi's at this w0.
    pub fn own_w0(&self, i: usize) -> f64 {
        self.group_w0(i).min(self.cap[i])
    }

    /// The w0 of a contact between blocks `a` and `b`, m: the larger of their groups' (they are
    /// one group once in contact), at most [`SIZE_RATIO`] times the smaller block's half-extent.
    /// Its search distance and contact window, and the steps of both blocks, are measured on it.
    pub fn pair_w0(&self, a: usize, b: usize) -> f64 {
        self.group_w0(a)
            .max(self.group_w0(b))
            .min(self.cap[a])
            .min(self.cap[b])
    }

    /// The largest group's w0 (the model's, when all its blocks are linked), m.
    pub fn largest_w0(&self) -> f64 {
        self.largest
    }

    /// An upper bound of the w0 block `i`'s step can be measured on, m.
    pub fn max_w0(&self, i: usize) -> f64 {
        self.largest_w0().min(self.cap[i])
    }

    /// The w0 that governs block `i` if it moves up to `motion` in this step: the smallest
    /// [`Self::pair_w0`] with the blocks it may come within their search distance of; `None`
    /// when it comes near no block (free flight).
    pub fn w0_near(&self, i: usize, motion: f64) -> Option<f64> {
        let own = self.own_w0(i);
        let widest = self.largest_w0();
        let reach = |k: usize| motion + search_distance(own.max(self.own_w0(k)), self.delta);
        let max_reach = motion + search_distance(widest, self.delta);
        self.index
            .near(&self.boxes, i, max_reach, reach)
            .map(|k| self.pair_w0(i, k))
            .reduce(f64::min)
    }
}

/// The representative of `k`'s group.
fn root(parent: &[usize], mut k: usize) -> usize {
    while parent[k] != k {
        k = parent[k];
    }
    k
}

/// Each group's w0, half the largest extent of the union of its members' initial boxes, indexed
/// by its representative. Flattens `parent` on the way.
fn group_w0(boxes: &[Bounds], parent: &mut [usize]) -> Vec<f64> {
    let n = boxes.len();
    let mut lo = vec![Vec3::repeat(f64::INFINITY); n];
    let mut hi = vec![Vec3::repeat(f64::NEG_INFINITY); n];
    for k in 0..n {
        let r = root(parent, k);
        parent[k] = r;
        lo[r] = lo[r].inf(&boxes[k].initial.0);
        hi[r] = hi[r].sup(&boxes[k].initial.1);
    }
    (0..n)
        .map(|r| {
            if parent[r] == r {
                0.5 * (hi[r] - lo[r]).max()
            } else {
                0.0
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube(x: f64, y: f64, z: f64, size: f64, fixed: bool) -> Bounds {
        let h = Vec3::repeat(size / 2.0);
        let c = Vec3::new(x, y, z);
        Bounds {
            lo: c - h,
            hi: c + h,
            initial: (c - h, c + h),
            fixed,
        }
    }

    /// A slab with a stack of cubes on it, as the rockfall's column.
    fn stack() -> Vec<Bounds> {
        let (lo, hi) = (Vec3::new(-9.0, -9.0, -1.0), Vec3::new(9.0, 9.0, 0.0));
        let mut b = vec![Bounds {
            lo,
            hi,
            initial: (lo, hi),
            fixed: true,
        }];
        for k in 0..4 {
            b.push(cube(0.0, 0.0, 0.5 + k as f64, 1.0, k == 0));
        }
        b
    }

    #[test]
    fn a_linked_model_has_shis_w0() {
        let g = ContactGroups::find(stack(), 0.01);
        for i in 0..5 {
            assert_eq!(g.group_w0(i), 9.0);
        }
        // Contact pairs: each cube with the next; the slab and the fixed base cube are both
        // fixed, so no contact is sought between them.
        assert_eq!(g.pairs, vec![(1, 2), (2, 3), (3, 4)]);
    }

    #[test]
    fn a_distant_block_is_a_group_of_its_own_and_changes_nothing() {
        let alone = ContactGroups::find(stack(), 0.01);
        for far in [12.0, 1e3, 1e5] {
            let mut boxes = stack();
            boxes.push(cube(far, 0.0, 0.5, 1.0, true));
            let g = ContactGroups::find(boxes, 0.01);
            for i in 0..5 {
                assert_eq!(g.group_w0(i), alone.group_w0(i), "far = {far}");
            }
            assert_eq!(g.group_w0(5), 0.5);
            assert_eq!(g.pairs, alone.pairs);
        }
    }

    #[test]
    fn a_small_block_is_linked_at_the_larger_groups_search_distance() {
        // The cube's own window (2.5 δ · 0.5 = 0.0125 m) would not reach a gap of 0.2 m; the
        // slab group's (2.5 δ · 9 = 0.225 m) does.
        let mut boxes = stack();
        boxes.push(cube(1.7, 0.0, 0.2 + 0.5, 1.0, false));
        let g = ContactGroups::find(boxes.clone(), 0.01);
        assert_eq!(g.group_w0(5), 9.0);
        assert!(g.pairs.contains(&(0, 5)));
        boxes[5] = cube(1.7, 0.0, 0.3 + 0.5, 1.0, false);
        let g = ContactGroups::find(boxes, 0.01);
        assert!((g.group_w0(5) - 0.5).abs() < 1e-12);
        assert!(!g.pairs.contains(&(0, 5)));
        // In free flight 0.3 m above the slab, it is near it once it may move 0.1 m; a contact
        // with the slab is measured on the cube: 10 × its half-extent.
        assert_eq!(g.w0_near(5, 0.0), None);
        let near = g.w0_near(5, 0.1).expect("near the slab");
        assert!((near - 5.0).abs() < 1e-12);
        assert_eq!(near, g.pair_w0(0, 5));
    }

    #[test]
    fn chains_link_through_their_members_whatever_the_order() {
        // A row of cubes 1 cm apart: one group whatever the order they are listed in.
        let n = 30;
        let mut boxes: Vec<Bounds> = (0..n)
            .map(|k| cube(1.01 * k as f64, 0.0, 0.0, 1.0, false))
            .collect();
        let g = ContactGroups::find(boxes.clone(), 0.01);
        let w = 0.5 * (1.01 * (n - 1) as f64 + 1.0);
        assert!((0..n).all(|i| (g.group_w0(i) - w).abs() < 1e-12));
        boxes.reverse();
        let r = ContactGroups::find(boxes, 0.01);
        assert!((0..n).all(|i| r.group_w0(i) == g.group_w0(n - 1 - i)));
        assert_eq!(g.pairs.len(), n - 1);
    }

    #[test]
    fn a_long_chain_is_measured_on_its_blocks_not_its_length() {
        // 10 000 touching 1 m cubes along 10 km: one group of w0 = 5 km, but every block and
        // contact is measured on 10 × 0.5 m, and each cube has only its two neighbours as
        // candidates (on the group's w0 the window would be 125 m: 250 candidates each).
        let n = 10_000;
        let boxes: Vec<Bounds> = (0..n)
            .map(|k| cube(k as f64, 0.0, 0.0, 1.0, false))
            .collect();
        let g = ContactGroups::find(boxes, 0.01);
        assert_eq!(g.group_w0(0), 0.5 * n as f64);
        assert_eq!(g.pairs.len(), n - 1);
        assert!((0..n).all(|i| g.own_w0(i) == 5.0));
        assert_eq!(g.w0_near(n / 2, 0.01), Some(5.0));
    }

    #[test]
    fn range_queries_match_a_scan_of_all_blocks() {
        // A pseudo-random scatter of boxes of mixed sizes; `near` must find exactly what a
        // scan of every block finds.
        let mut seed = 7u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut boxes: Vec<Bounds> = (0..300)
            .map(|_| {
                cube(
                    40.0 * rnd(),
                    10.0 * rnd(),
                    5.0 * rnd(),
                    0.2 + 3.0 * rnd(),
                    false,
                )
            })
            .collect();
        // Slabs far longer along the sweep axis (x) than the median box, among the others: the
        // index keeps them in a sorted range of their own.
        for (k, &(x0, len)) in [(-3.0, 45.0), (5.0, 20.0), (12.0, 30.0)].iter().enumerate() {
            let (lo, hi) = (
                Vec3::new(x0, 2.0 * k as f64, 1.0),
                Vec3::new(x0 + len, 2.0 * k as f64 + 1.5, 1.5),
            );
            boxes.insert(
                40 * k + 7,
                Bounds {
                    lo,
                    hi,
                    initial: (lo, hi),
                    fixed: k == 1,
                },
            );
        }
        let index = SweepIndex::new(&boxes);
        assert_eq!(index.wide.order.len(), 3);
        for i in 0..boxes.len() {
            let reach = |k: usize| 0.1 * (k % 7) as f64;
            let mut fast: Vec<usize> = index.near(&boxes, i, 0.6, reach).collect();
            fast.sort_unstable();
            let slow: Vec<usize> = (0..boxes.len())
                .filter(|&k| k != i && reaches(&boxes[i], &boxes[k], reach(k)))
                .collect();
            assert_eq!(fast, slow, "block {i}");
        }
        let pairs = index.pairs(
            &boxes,
            0.3,
            true,
            |a, b| 0.1 * ((a + b) % 4) as f64,
            MAX_BLOCK_PAIRS,
        );
        let mut slow = Vec::new();
        for a in 0..boxes.len() {
            for b in a + 1..boxes.len() {
                if within(&boxes[a], &boxes[b], 0.1 * ((a + b) % 4) as f64) {
                    slow.push((a, b));
                }
            }
        }
        assert_eq!(pairs, slow);
        // Past its limit the search stops: one pair more than the limit, each a true pair.
        let capped = index.pairs(&boxes, 0.3, true, |a, b| 0.1 * ((a + b) % 4) as f64, 10);
        assert!(slow.len() > 11);
        assert_eq!(capped.len(), 11);
        assert!(capped.iter().all(|p| slow.contains(p)));
    }
}
