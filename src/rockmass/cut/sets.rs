//! Applying the planes of one joint set to the blocks: the fixed plane order, the search for the
//! planes that can cross a block, and the rules that accept or reject one cut.

use super::split::{self, Block, Split};
use super::{CutError, CutOptions, Plane, THIN_FLOOR, Vec3};

/// Bounds over the planes of one subtree, with o'ᵢ = offsetᵢ − nᵢ·p₀ (the offset measured from
/// the domain centre p₀): o' in [lo, hi], and |nᵢ − reference| ≤ spread.
#[derive(Clone, Copy, Debug)]
struct Bound {
    lo: f64,
    hi: f64,
    spread: f64,
}

/// The planes of one set in their fixed order (increasing o', ties by normal, then input index)
/// as an implicit balanced binary tree: the node over positions [lo, hi) has the plane at
/// m = (lo + hi) / 2 and children over [lo, m) and [m + 1, hi); node k's children are 2k and
/// 2k + 1, the root is 1.
pub(super) struct PlaneTree<'a> {
    set: usize,
    planes: &'a [Plane],
    order: Vec<usize>,
    bounds: Vec<Bound>,
    reference: Vec3,
    origin: Vec3,
    /// Rounding slack of the pruning test.
    slack: f64,
}

impl<'a> PlaneTree<'a> {
    pub fn new(set: usize, planes: &'a [Plane], origin: Vec3, eps: f64) -> Self {
        let rel = |p: &Plane| p.offset - p.normal.dot(&origin);
        let mut order: Vec<usize> = (0..planes.len()).collect();
        order.sort_by(|&a, &b| {
            let (p, q) = (&planes[a], &planes[b]);
            rel(p)
                .total_cmp(&rel(q))
                .then_with(|| p.normal.x.total_cmp(&q.normal.x))
                .then_with(|| p.normal.y.total_cmp(&q.normal.y))
                .then_with(|| p.normal.z.total_cmp(&q.normal.z))
                .then(a.cmp(&b))
        });
        let empty = Bound {
            lo: f64::INFINITY,
            hi: f64::NEG_INFINITY,
            spread: 0.0,
        };
        let mut tree = Self {
            set,
            planes,
            reference: planes.first().map_or_else(Vec3::zeros, |p| p.normal),
            order,
            bounds: vec![empty; 4 * planes.len() + 4],
            origin,
            slack: 4.0 * eps,
        };
        tree.build(1, 0, planes.len());
        tree
    }

    fn build(&mut self, node: usize, lo: usize, hi: usize) {
        if lo >= hi {
            return;
        }
        let mut b = self.bounds[node];
        for &i in &self.order[lo..hi] {
            let p = &self.planes[i];
            let o = p.offset - p.normal.dot(&self.origin);
            b.lo = b.lo.min(o);
            b.hi = b.hi.max(o);
            b.spread = b.spread.max((p.normal - self.reference).norm());
        }
        self.bounds[node] = b;
        let m = lo + (hi - lo) / 2;
        self.build(2 * node, lo, m);
        self.build(2 * node + 1, m + 1, hi);
    }

    /// True when no plane of the subtree `node` can cross `block`. Plane i crosses only if o'ᵢ
    /// lies strictly between the least and the largest nᵢ·(v − p₀) over the block's vertices v;
    /// nᵢ·(v − p₀) is within spread·|v − p₀| of reference·(v − p₀). (For a set of parallel
    /// planes spread is 0 and the test is exact, however thin the block.)
    fn misses(&self, node: usize, block: &Block) -> bool {
        let b = &self.bounds[node];
        let (mut lo, mut hi, mut far) = (f64::INFINITY, f64::NEG_INFINITY, 0.0_f64);
        for v in &block.verts {
            let v = v - self.origin;
            let t = self.reference.dot(&v);
            lo = lo.min(t);
            hi = hi.max(t);
            far = far.max(v.norm());
        }
        let reach = b.spread * far + self.slack;
        hi + reach < b.lo || lo - reach > b.hi
    }

    /// Cuts `block` by the planes of the set, in the fixed order, and appends the blocks it
    /// ends as to `out`.
    pub fn apply(
        &self,
        cutter: &mut Cutter,
        block: Block,
        out: &mut Vec<Block>,
    ) -> Result<(), CutError> {
        self.visit(cutter, block, 1, (0, self.order.len()), out)
    }

    /// In-order over the subtree: the planes before m, then m, then those after, so every
    /// block meets the planes in the same sequence.
    fn visit(
        &self,
        cutter: &mut Cutter,
        block: Block,
        node: usize,
        (lo, hi): (usize, usize),
        out: &mut Vec<Block>,
    ) -> Result<(), CutError> {
        if lo >= hi || self.misses(node, &block) {
            out.push(block);
            return Ok(());
        }
        let m = lo + (hi - lo) / 2;
        let mut before = Vec::new();
        self.visit(cutter, block, 2 * node, (lo, m), &mut before)?;
        let index = self.order[m];
        for b in before {
            let (first, second) = cutter.cut(b, &self.planes[index], (self.set, index))?;
            self.visit(cutter, first, 2 * node + 1, (m + 1, hi), out)?;
            if let Some(second) = second {
                self.visit(cutter, second, 2 * node + 1, (m + 1, hi), out)?;
            }
        }
        Ok(())
    }
}

/// The rules of one cut, and the counts.
pub(super) struct Cutter {
    pub eps: f64,
    max_aspect: f64,
    aspect_length: f64,
    max_blocks: usize,
    /// Blocks in existence.
    blocks: usize,
    pub rejected: usize,
    pub skipped: usize,
}

impl Cutter {
    pub fn new(eps: f64, opts: &CutOptions) -> Self {
        Self {
            eps,
            max_aspect: opts.max_aspect,
            aspect_length: opts.aspect_length,
            max_blocks: opts.max_blocks,
            blocks: 0,
            rejected: 0,
            skipped: 0,
        }
    }

    /// Counts `n` more blocks; fails once there are more than the limit.
    pub fn count(&mut self, n: usize) -> Result<(), CutError> {
        self.blocks += n;
        if self.blocks > self.max_blocks {
            return Err(CutError::TooManyBlocks {
                limit: self.max_blocks,
            });
        }
        Ok(())
    }

    /// Offers `plane` to `block`: the two children, or the block itself when the plane does
    /// not cut it or the cut is rejected.
    fn cut(
        &mut self,
        block: Block,
        plane: &Plane,
        tag: (usize, usize),
    ) -> Result<(Block, Option<Block>), CutError> {
        match split::split(&block, plane, tag, self.eps) {
            Split::Whole => Ok((block, None)),
            Split::Inconsistent => {
                self.skipped += 1;
                Ok((block, None))
            }
            Split::Two(below, above) => {
                if self.too_thin(&below) || self.too_thin(&above) {
                    self.rejected += 1;
                    return Ok((block, None));
                }
                self.count(1)?;
                Ok((below, Some(above)))
            }
        }
    }

    /// The aspect rule: thinner than its largest extent (at most the aspect length) /
    /// max_aspect, or than the thin floor.
    fn too_thin(&self, block: &Block) -> bool {
        let t = split::thickness(block);
        t < block.extent.min(self.aspect_length) / self.max_aspect || t < THIN_FLOOR * self.eps
    }
}
