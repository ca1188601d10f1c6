//! Cutting convex rock domains into convex blocks by joint planes (issue #14), after
//! `shared/docs/rock-mass-reference.md` §2.
//!
//! **Input.** Convex, non-overlapping regions (faces listed counter-clockwise seen from outside)
//! and joint sets, each a list of planes n·x = offset with |n| = 1. Planes of one set may have
//! different normals (scattered orientations).
//!
//! **Algorithm.** The regions are cut set by set, in the order given. Within a set the planes are
//! applied in one fixed order, the same for every block: increasing offset measured from the
//! centre p₀ of the domain's bounding box (offset − n·p₀), ties by normal. So the input order of a
//! set's planes does not matter, and two neighbours meet the same sequence of cuts, which keeps
//! their shared faces identical. A block is only offered the planes that can cross it: the
//! planes of a set sit in a balanced tree whose nodes bound their offsets and the spread of their
//! normals, and a subtree is skipped when the block's extent along the set's first normal,
//! widened by that spread, misses its offsets. A column crossed by k parallel planes thus costs
//! O(k log k) tests, not O(k²).
//!
//! One plane splits one block by the vertex/face clipping of §2.2: vertices within the snap
//! tolerance ε of the plane count as on it; every edge with one end strictly on each side gets
//! one new point, computed with the edge's ends in lexicographic order so two blocks sharing the
//! edge get bitwise the same point; each face ring is split in two (a ring left with fewer than
//! 3 distinct points, or lying on the plane within ε, goes); and each child's cap is the loop of
//! boundary edges its split faces leave open on the plane, reversed. A plane that leaves no
//! vertex strictly on one side (through a vertex, along an edge, in a face, or within ε of one)
//! does not cut; nor does one whose far side has no volume (its faces already close: a vertex
//! barely beyond ε between two nearly parallel faces). Caps carry the plane's `(set, plane)` tag,
//! faces keep their tags through later cuts, and region faces carry none. If the open edges of a
//! side do not form one simple loop on the plane, the cut is not made and is counted in
//! [`CutReport::skipped_cuts`]. That was never seen in the tests; a stress test whose planes
//! cross at 1e-6 to 1e-8 rad through one shared point met it about once in 3 000 cases, where
//! vertices a few ε apart made a face's edge shorter than the snap band.
//!
//! **Tolerance.** ε is one value for a whole call, [`snap_tolerance`]: [`SNAP_RELATIVE`] × the
//! bounding-box diagonal of all regions, but at least [`SNAP_ROUNDING`] × the largest coordinate
//! magnitude. "Near the plane" is |n·x − offset| ≤ ε with the float value, and the side is its
//! sign, summed in one fixed order ([`Plane::signed_distance`]). Outside the snap band that sign
//! is exact for the given float plane: with |n| = 1 the rounding error of the sum is at most
//! 4u(Σ|nᵢxᵢ| + |offset|) ≤ 16 u·max|x| for a plane that reaches the domain (u = 2⁻⁵³; every
//! vertex lies in the domain's hull), and the floor keeps ε above 128 u·max|x|. Inside the band
//! the vertex is snapped onto the plane anyway. Since a vertex shared by two blocks is the same
//! f64 triple in both, both classify it the same way, so faces stay conforming without exact
//! predicates (`robust::orient3d` is not needed).
//!
//! **Slivers.** A cut of one block is rejected (the block stays whole for that plane; counted in
//! [`CutReport::rejected_cuts`]) when either child is thinner than its largest bounding-box extent
//! (at most [`CutOptions::aspect_length`]) / `max_aspect`, or thinner than [`THIN_FLOOR`] × ε (no
//! block that thin can be told from its own faces under the snap). The **thickness** of a block is the least, over its faces, of the
//! largest distance of one of its vertices from that face's plane: the width of the thinnest slab
//! between a face's plane and a parallel plane that holds the block. The rule judges the pieces
//! as they are when the cut is made: without `aspect_length` the first set of a domain more than
//! `max_aspect` × spacing across makes slabs that fail it (a 22 m box and 1 m spacing pass at
//! `max_aspect` 30, not at 20); the scene sets it to the smallest joint spacing. A rejected cut leaves T-junctions: the neighbours' faces no longer match one to
//! one, though they still cover each other. After all cuts, blocks of volume below `min_volume`
//! are dropped and counted.
//!
//! **Output.** Each piece lists only its corners: a point that only two faces meet at and that
//! lies within ε of the straight edge between its neighbours (a snap can leave one, when a third
//! face went with a cap) is dropped from the output rings; it is kept while cutting, where the
//! neighbour across the cap has it as a corner. Where two joint planes coincide within ε over a
//! whole face yet cross the block elsewhere (possible only for planes within about 1e-6 rad of
//! each other), the face is covered by the later plane's cap on one side and may keep the earlier
//! plane's tag on the other: the geometry still conforms, the tags do not.
//!
//! **Order of the pieces** (a contract: blocks are named mass/1, mass/2, … in this order): by
//! region index, then by [`Piece::sides`] compared lexicographically (set 0 first), then by
//! centroid x, then y, then z (`f64::total_cmp`). For a box cut by three orthogonal sets this
//! runs through the blocks slab by slab along set 0, row by row along set 1, then along set 2.
//!
//! **Volume and centroid** by the divergence theorem: each face fanned into triangles about its
//! first vertex, each triangle closed into a tetrahedron with the vertex mean (a point inside, so
//! the terms are small and rounding stays small).
//!
//! **Cost.** Cutting a 22 × 22 × 21 m box by three orthogonal sets at 1 m (10 164 blocks) took
//! 0.05–0.07 s in a release build (one thread, median of 3), three oblique sets at 1 m (11 205
//! blocks) 0.06–0.1 s. [`cut`] is the entry point a benchmark calls.

mod input;
mod sets;
mod split;
#[cfg(test)]
mod tests;

use std::cmp::Ordering;
use std::fmt;

use crate::physics::geometry::bounding_box;
use sets::{Cutter, PlaneTree};
use split::Block;

pub use crate::physics::geometry::Vec3;

/// ε = `SNAP_RELATIVE` × the bounding-box diagonal of all regions (the ε_g of the main reference
/// §10): vertices closer than that to a plane are on it.
pub const SNAP_RELATIVE: f64 = 1e-9;
/// Floor of ε, × the largest coordinate magnitude of the regions: keeps ε above the rounding
/// error of n·x − offset (≤ 16 u·max|x|, u = 2⁻⁵³ = f64::EPSILON / 2) for a domain far from
/// the origin.
pub const SNAP_ROUNDING: f64 = 64.0 * f64::EPSILON;
/// A child thinner than `THIN_FLOOR` × ε is a sliver whatever `max_aspect` says.
pub const THIN_FLOOR: f64 = 16.0;
/// Input regions must be convex and their faces planar to `REGION_TOLERANCE` × their
/// bounding-box diagonal (the tolerance of a convex hull of rounded points).
pub const REGION_TOLERANCE: f64 = 1e-6;
/// Plane normals must have unit length to this tolerance.
pub const NORMAL_TOLERANCE: f64 = 1e-6;

/// The plane n·x = offset, |n| = 1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    pub normal: Vec3,
    pub offset: f64,
}

/// A joint set's plane as the cut takes it.
impl From<&super::orientation::JointPlane> for Plane {
    fn from(p: &super::orientation::JointPlane) -> Self {
        Plane {
            normal: p.normal,
            offset: p.offset,
        }
    }
}

impl Plane {
    /// The plane with unit normal `normal` through `point`; `point` gets a signed distance of
    /// exactly 0 (the same arithmetic as [`Plane::signed_distance`]).
    pub fn through(normal: Vec3, point: &Vec3) -> Self {
        let offset = normal.x * point.x + normal.y * point.y + normal.z * point.z;
        Self { normal, offset }
    }

    /// n·x − offset, always summed in the same order, so that one vertex (one f64 triple) gets
    /// the same value in every block that holds it.
    pub fn signed_distance(&self, x: &Vec3) -> f64 {
        self.normal.x * x.x + self.normal.y * x.y + self.normal.z * x.z - self.offset
    }
}

/// A convex polyhedron: faces CCW from outside.
#[derive(Clone, Debug)]
pub struct Polyhedron {
    pub vertices: Vec<Vec3>,
    pub faces: Vec<Vec<usize>>,
}

/// The rules of a cut.
#[derive(Clone, Copy, Debug)]
pub struct CutOptions {
    /// Blocks smaller than this after all cuts are dropped (counted in the report), m³.
    pub min_volume: f64,
    /// A cut of one block is rejected (the block stays whole for that plane; counted) when a
    /// child would be thinner than its largest bounding-box extent (at most `aspect_length`) /
    /// max_aspect.
    pub max_aspect: f64,
    /// The longest extent the aspect rule measures against, m: the joint spacing, so that the
    /// slabs the first set leaves across a wide domain are not taken for slivers (∞: the
    /// piece's own extent alone).
    pub aspect_length: f64,
    /// The cut fails with [`CutError::TooManyBlocks`] as soon as more blocks than this exist
    /// (the regions count as the first blocks; dropped pieces count until the end).
    pub max_blocks: usize,
}

/// One block of the cut.
#[derive(Clone, Debug)]
pub struct Piece {
    /// Index of the region it came from.
    pub region: usize,
    /// Only the corners, no duplicates (module doc, **Output**).
    pub vertices: Vec<Vec3>,
    /// CCW from outside.
    pub faces: Vec<Vec<usize>>,
    /// For each face: the (set, plane) it lies on, or None for a region boundary face.
    pub face_planes: Vec<Option<(usize, usize)>>,
    pub volume: f64,
    pub centroid: Vec3,
    /// Per set: how many planes of that set have the centroid on their positive side
    /// (n·x > offset).
    pub sides: Vec<u32>,
}

/// What the cut did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CutReport {
    /// The regions' total volume.
    pub domain_volume: f64,
    /// The kept pieces' total volume.
    pub volume: f64,
    /// Pieces dropped for `min_volume`, and their volume.
    pub dropped: usize,
    pub dropped_volume: f64,
    /// Cuts rejected by the aspect rule (or the [`THIN_FLOOR`]).
    pub rejected_cuts: usize,
    /// Cuts not made because the open edges of a side did not form one simple loop on the
    /// plane (module doc); the block stays whole for that plane. Never seen in the tests.
    pub skipped_cuts: usize,
    /// Smallest kept volume (infinite when nothing is kept).
    pub smallest: f64,
}

#[derive(Debug, Clone, PartialEq)]
pub enum CutError {
    /// More blocks than `CutOptions::max_blocks` exist.
    TooManyBlocks { limit: usize },
    /// A region is not a closed convex polyhedron with outward faces.
    InvalidRegion { region: usize, reason: &'static str },
    /// A plane has a non-unit or non-finite normal, or a non-finite offset.
    InvalidPlane { set: usize, plane: usize },
    /// `min_volume` is negative or not finite, or `max_aspect` is not positive.
    InvalidOptions { reason: &'static str },
}

impl fmt::Display for CutError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::TooManyBlocks { limit } => write!(
                f,
                "the joint sets cut more than {limit} blocks (the limit of a scene): increase \
                 the spacing"
            ),
            Self::InvalidRegion { region, reason } => {
                write!(f, "region {}: {reason}", region + 1)
            }
            Self::InvalidPlane { set, plane } => write!(
                f,
                "joint set {}, plane {}: the normal must be a finite unit vector and the offset \
                 finite",
                set + 1,
                plane + 1
            ),
            Self::InvalidOptions { reason } => write!(f, "cut options: {reason}"),
        }
    }
}

impl std::error::Error for CutError {}

/// Cuts `regions` by the planes of `sets`. `sets[s]` are the planes of joint set s (any order
/// within a set; planes of one set may have different normals when orientations vary). Regions
/// are convex and do not overlap. Returns the kept pieces in the documented order (module doc)
/// and the report.
pub fn cut(
    regions: &[Polyhedron],
    sets: &[Vec<Plane>],
    opts: &CutOptions,
) -> Result<(Vec<Piece>, CutReport), CutError> {
    cut_all(regions, sets, opts).map(|out| (out.kept, out.report))
}

/// The snap tolerance ε of a call on `regions` (module doc).
pub fn snap_tolerance(regions: &[Polyhedron]) -> f64 {
    let (lo, hi) = bounding_box(regions.iter().flat_map(|r| r.vertices.iter()));
    if lo.x > hi.x {
        return 0.0;
    }
    let magnitude = lo.abs().max().max(hi.abs().max());
    (SNAP_RELATIVE * (hi - lo).norm()).max(SNAP_ROUNDING * magnitude)
}

/// What [`cut_all`] returns: the kept and the dropped pieces, both in the documented order, and
/// the report.
#[derive(Clone, Debug)]
pub struct CutOutcome {
    pub kept: Vec<Piece>,
    /// The pieces below `min_volume` (the voids they leave, for checks or display).
    pub dropped: Vec<Piece>,
    pub report: CutReport,
}

/// [`cut`], also returning the dropped pieces.
pub fn cut_all(
    regions: &[Polyhedron],
    sets: &[Vec<Plane>],
    opts: &CutOptions,
) -> Result<CutOutcome, CutError> {
    input::check_options(opts)?;
    input::check_planes(sets)?;
    let eps = snap_tolerance(regions);
    let (lo, hi) = bounding_box(regions.iter().flat_map(|r| r.vertices.iter()));
    let origin = if regions.is_empty() {
        Vec3::zeros()
    } else {
        (lo + hi) / 2.0
    };
    let mut blocks = Vec::with_capacity(regions.len());
    let mut domain_volume = 0.0;
    for (k, region) in regions.iter().enumerate() {
        let (block, volume) = input::region_block(k, region, eps)?;
        blocks.push(block);
        domain_volume += volume;
    }
    let mut cutter = Cutter::new(eps, opts);
    cutter.count(blocks.len())?;
    for (s, set) in sets.iter().enumerate() {
        let tree = PlaneTree::new(s, set, origin, eps);
        let mut next = Vec::with_capacity(blocks.len());
        for block in blocks {
            tree.apply(&mut cutter, block, &mut next)?;
        }
        blocks = next;
    }
    Ok(finish(blocks, sets, domain_volume, opts, &cutter))
}

/// Volumes, centroids and sides; the `min_volume` filter; the order; the report.
fn finish(
    blocks: Vec<Block>,
    sets: &[Vec<Plane>],
    domain_volume: f64,
    opts: &CutOptions,
    cutter: &Cutter,
) -> CutOutcome {
    let (mut kept, mut dropped): (Vec<Piece>, Vec<Piece>) = blocks
        .into_iter()
        .map(|b| piece(b, sets, cutter.eps))
        .partition(|p| p.volume >= opts.min_volume);
    kept.sort_by(piece_order);
    dropped.sort_by(piece_order);
    let report = CutReport {
        domain_volume,
        // fold from +0: an empty f64 sum is −0.
        volume: kept.iter().fold(0.0, |v, p| v + p.volume),
        dropped: dropped.len(),
        dropped_volume: dropped.iter().fold(0.0, |v, p| v + p.volume),
        rejected_cuts: cutter.rejected,
        skipped_cuts: cutter.skipped,
        smallest: kept.iter().map(|p| p.volume).fold(f64::INFINITY, f64::min),
    };
    CutOutcome {
        kept,
        dropped,
        report,
    }
}

fn piece(block: Block, sets: &[Vec<Plane>], eps: f64) -> Piece {
    let block = split::corners_only(block, eps);
    let (volume, centroid) =
        split::volume_centroid(&block.verts, block.faces.iter().map(|f| f.ring.as_slice()));
    let sides = sets
        .iter()
        .map(|set| {
            let above = set
                .iter()
                .filter(|p| p.normal.dot(&centroid) > p.offset)
                .count();
            u32::try_from(above).unwrap_or(u32::MAX)
        })
        .collect();
    let face_planes = block.faces.iter().map(|f| f.tag).collect();
    Piece {
        region: block.region,
        faces: block.faces.into_iter().map(|f| f.ring).collect(),
        vertices: block.verts,
        face_planes,
        volume,
        centroid,
        sides,
    }
}

/// The documented order: region, sides (lexicographic, set 0 first), centroid x, y, z.
fn piece_order(a: &Piece, b: &Piece) -> Ordering {
    a.region
        .cmp(&b.region)
        .then_with(|| a.sides.cmp(&b.sides))
        .then_with(|| a.centroid.x.total_cmp(&b.centroid.x))
        .then_with(|| a.centroid.y.total_cmp(&b.centroid.y))
        .then_with(|| a.centroid.z.total_cmp(&b.centroid.z))
}
