//! Splitting one convex block by one plane: the vertex/face clipping of the reference §2.2, and
//! the block geometry the cut needs (thickness, volume, centroid).

use std::cmp::Ordering;

use super::{Plane, Vec3};
use crate::physics::geometry::bounding_box;

/// A face of a block being cut: its vertex ring (CCW from outside), its tag, and the plane it
/// lies on (outward unit normal, n·x = offset). Caps copy the cutting plane exactly rather than
/// refitting it, so the aspect rule measures against the true joint plane.
#[derive(Clone, Debug)]
pub(super) struct Face {
    pub ring: Vec<usize>,
    pub tag: Option<(usize, usize)>,
    pub normal: Vec3,
    pub offset: f64,
}

impl Face {
    fn with_ring(&self, ring: Vec<usize>) -> Self {
        Self {
            ring,
            tag: self.tag,
            normal: self.normal,
            offset: self.offset,
        }
    }
}

/// A convex block being cut, with the largest extent of its bounding box for the aspect rule.
#[derive(Clone, Debug)]
pub(super) struct Block {
    pub region: usize,
    pub verts: Vec<Vec3>,
    pub faces: Vec<Face>,
    pub extent: f64,
}

impl Block {
    /// The block of the faces `faces` over `verts`, keeping only the vertices the faces use and
    /// renumbering the rings.
    pub fn compact(region: usize, verts: &[Vec3], mut faces: Vec<Face>) -> Self {
        let mut map = vec![usize::MAX; verts.len()];
        let mut kept = Vec::with_capacity(verts.len());
        for face in &mut faces {
            for v in &mut face.ring {
                if map[*v] == usize::MAX {
                    map[*v] = kept.len();
                    kept.push(verts[*v]);
                }
                *v = map[*v];
            }
        }
        let (lo, hi) = bounding_box(kept.iter());
        Self {
            region,
            verts: kept,
            faces,
            extent: (hi - lo).max(),
        }
    }
}

/// The outcome of offering a plane to a block.
pub(super) enum Split {
    /// The plane leaves no vertex strictly on one side, or one side has no volume: no cut.
    Whole,
    /// The parts on the − side (n·x ≤ offset) and on the + side.
    Two(Block, Block),
    /// The open edges of a side do not form one simple loop on the plane (edges shorter than
    /// the snap band); the block stays whole.
    Inconsistent,
}

/// Side of `x` once snapped: −1 below, 0 on the plane (|n·x − offset| ≤ ε), +1 above.
fn side(plane: &Plane, x: &Vec3, eps: f64) -> i8 {
    let s = plane.signed_distance(x);
    if s > eps {
        1
    } else if s < -eps {
        -1
    } else {
        0
    }
}

/// Splits `block` by `plane`; both caps get `tag`.
pub(super) fn split(block: &Block, plane: &Plane, tag: (usize, usize), eps: f64) -> Split {
    let sides: Vec<i8> = block.verts.iter().map(|v| side(plane, v, eps)).collect();
    if !sides.contains(&1) || !sides.contains(&-1) {
        return Split::Whole;
    }
    let mut cut = Cutting {
        plane,
        verts: block.verts.clone(),
        sides,
        edges: Vec::new(),
    };
    let mut below = Vec::with_capacity(block.faces.len() + 1);
    let mut above = Vec::with_capacity(block.faces.len() + 1);
    for face in &block.faces {
        let (lo, hi) = cut.split_ring(&face.ring);
        if let Some(ring) = clean_ring(lo, &cut.verts, &cut.sides) {
            below.push(face.with_ring(ring));
        }
        if let Some(ring) = clean_ring(hi, &cut.verts, &cut.sides) {
            above.push(face.with_ring(ring));
        }
    }
    let (cap_below, cap_above) = match (cap_ring(&below, &cut.sides), cap_ring(&above, &cut.sides))
    {
        (Cap::Loop(a), Cap::Loop(b)) => (a, b),
        // One side's faces already close up: it is flat (a vertex barely beyond ε whose two
        // faces are nearly parallel), and the plane only grazes the block.
        (Cap::Closed, _) | (_, Cap::Closed) => return Split::Whole,
        _ => return Split::Inconsistent,
    };
    below.push(Face {
        ring: cap_below,
        tag: Some(tag),
        normal: plane.normal,
        offset: plane.offset,
    });
    above.push(Face {
        ring: cap_above,
        tag: Some(tag),
        normal: -plane.normal,
        offset: -plane.offset,
    });
    if below.len() < 4 || above.len() < 4 {
        return Split::Inconsistent;
    }
    Split::Two(
        Block::compact(block.region, &cut.verts, below),
        Block::compact(block.region, &cut.verts, above),
    )
}

/// The state of one split: the block's vertices plus the new edge points, their sides (edge
/// points are on the plane), and the edge points made so far, per undirected edge (a, b, point).
struct Cutting<'a> {
    plane: &'a Plane,
    verts: Vec<Vec3>,
    sides: Vec<i8>,
    edges: Vec<(usize, usize, usize)>,
}

impl Cutting<'_> {
    /// The − and + rings of one face: vertices on or below the plane go to the first, on or
    /// above to the second, and each crossing edge's point to both, in ring order.
    fn split_ring(&mut self, ring: &[usize]) -> (Vec<usize>, Vec<usize>) {
        let mut below = Vec::with_capacity(ring.len() + 2);
        let mut above = Vec::with_capacity(ring.len() + 2);
        for (&a, &b) in ring.iter().zip(ring.iter().cycle().skip(1)) {
            if self.sides[a] <= 0 {
                below.push(a);
            }
            if self.sides[a] >= 0 {
                above.push(a);
            }
            if self.sides[a] * self.sides[b] == -1 {
                let e = self.edge_point(a, b);
                below.push(e);
                above.push(e);
            }
        }
        (below, above)
    }

    /// The index of the point where the plane crosses edge (a, b), made once per edge.
    fn edge_point(&mut self, a: usize, b: usize) -> usize {
        let key = (a.min(b), a.max(b));
        if let Some(&(_, _, e)) = self.edges.iter().find(|e| (e.0, e.1) == key) {
            return e;
        }
        let e = self.verts.len();
        self.verts
            .push(crossing(self.plane, &self.verts[a], &self.verts[b]));
        self.sides.push(0);
        self.edges.push((key.0, key.1, e));
        e
    }
}

/// Where `plane` crosses the segment p–q, with the ends taken in lexicographic order so that the
/// two blocks sharing the edge compute bitwise the same point (from (a, b) and from (b, a) the
/// float results differ in the last bits on over half of all edges, reference §2.2).
fn crossing(plane: &Plane, p: &Vec3, q: &Vec3) -> Vec3 {
    let (a, b) = if lex(q, p) == Ordering::Less {
        (q, p)
    } else {
        (p, q)
    };
    let sa = plane.signed_distance(a);
    let sb = plane.signed_distance(b);
    let t = sa / (sa - sb);
    Vec3::new(
        a.x + t * (b.x - a.x),
        a.y + t * (b.y - a.y),
        a.z + t * (b.z - a.z),
    )
}

fn lex(a: &Vec3, b: &Vec3) -> Ordering {
    a.x.total_cmp(&b.x)
        .then(a.y.total_cmp(&b.y))
        .then(a.z.total_cmp(&b.z))
}

/// The ring without consecutive duplicate points, or None when fewer than 3 distinct points are
/// left or all of them are on the plane (a face lying on the cut only touches it; the cap
/// covers it).
fn clean_ring(mut ring: Vec<usize>, verts: &[Vec3], sides: &[i8]) -> Option<Vec<usize>> {
    ring.dedup_by(|a, b| verts[*a] == verts[*b]);
    while ring.len() > 1 && verts[ring[0]] == verts[ring[ring.len() - 1]] {
        ring.pop();
    }
    if ring.len() < 3 || ring.iter().all(|&v| sides[v] == 0) {
        return None;
    }
    let mut points: Vec<&Vec3> = ring.iter().map(|&v| &verts[v]).collect();
    points.sort_by(|a, b| lex(a, b));
    points.dedup();
    (points.len() >= 3).then_some(ring)
}

/// What closes the open surface of one side's faces.
enum Cap {
    /// Its boundary edges (those whose reverse no face uses), reversed and chained into one
    /// simple loop of points on the plane: the cap.
    Loop(Vec<usize>),
    /// No boundary: the faces already close (a flat side, no volume).
    Closed,
    /// Anything else: a directed edge twice, a boundary that branches, is not one loop, or
    /// leaves the plane.
    Broken,
}

/// The cap that closes the open surface `faces`.
fn cap_ring(faces: &[Face], sides: &[i8]) -> Cap {
    let mut edges: Vec<(usize, usize)> = faces
        .iter()
        .flat_map(|f| {
            f.ring
                .iter()
                .zip(f.ring.iter().cycle().skip(1))
                .map(|(&a, &b)| (a, b))
        })
        .collect();
    edges.sort_unstable();
    if edges.windows(2).any(|w| w[0] == w[1]) {
        return Cap::Broken;
    }
    let mut next: Vec<(usize, usize)> = edges
        .iter()
        .filter(|&&(a, b)| edges.binary_search(&(b, a)).is_err())
        .map(|&(a, b)| (b, a))
        .collect();
    if next.is_empty() {
        return Cap::Closed;
    }
    next.sort_unstable();
    if next.len() < 3
        || next.windows(2).any(|w| w[0].0 == w[1].0)
        || next.iter().any(|&(a, _)| sides[a] != 0)
    {
        return Cap::Broken;
    }
    let start = next[0].0;
    let mut ring = vec![start];
    let mut at = next[0].1;
    while at != start {
        let Ok(k) = next.binary_search_by_key(&at, |e| e.0) else {
            return Cap::Broken;
        };
        if ring.len() >= next.len() {
            return Cap::Broken;
        }
        ring.push(at);
        at = next[k].1;
    }
    if ring.len() == next.len() {
        Cap::Loop(ring)
    } else {
        Cap::Broken
    }
}

/// The block without the points that lie on an edge: vertices that only two faces meet at and
/// that are within ε of the chord between their two neighbours. A snapped cut can leave one: a
/// vertex within ε of the plane whose third face lay on the plane only within ε and went with
/// the cap. It is kept while cutting, where it is a corner of the neighbour across the cap and
/// keeps the two conforming; the output lists only corners. A vertex of two faces that is
/// farther than ε from that chord stays: the two faces are then nearly parallel joint planes
/// whose shared edge bends within the ε band of both (removing it would change the faces' areas
/// by far more than ε × length). A face left with fewer than 3 vertices goes; if that would
/// leave fewer than 4 faces the block is returned as it was.
pub(super) fn corners_only(block: Block, eps: f64) -> Block {
    let mut faces = block.faces.clone();
    let mut changed = false;
    loop {
        let mut count = vec![0usize; block.verts.len()];
        for v in faces.iter().flat_map(|f| &f.ring) {
            count[*v] += 1;
        }
        let mut on_edge = vec![false; block.verts.len()];
        for ring in faces.iter().map(|f| &f.ring) {
            let n = ring.len();
            for (k, &v) in ring.iter().enumerate() {
                let (p, q) = (ring[(k + n - 1) % n], ring[(k + 1) % n]);
                on_edge[v] = count[v] < 3 && chord_distance(&block.verts, v, p, q) <= eps;
            }
        }
        if !on_edge.contains(&true) {
            break;
        }
        for f in &mut faces {
            f.ring.retain(|&v| !on_edge[v]);
        }
        faces.retain(|f| f.ring.len() >= 3);
        changed = true;
        if faces.len() < 4 {
            return block;
        }
    }
    if !changed {
        return block;
    }
    Block::compact(block.region, &block.verts, faces)
}

/// Distance of vertex v from the segment p–q.
fn chord_distance(verts: &[Vec3], v: usize, p: usize, q: usize) -> f64 {
    let (x, a, b) = (verts[v], verts[p], verts[q]);
    let t = ((x - a).dot(&(b - a)) / (b - a).norm_squared().max(f64::MIN_POSITIVE)).clamp(0.0, 1.0);
    (a + (b - a) * t - x).norm()
}

/// The thickness of a block: the least, over its faces, of the largest distance of one of its
/// vertices from that face's plane.
pub(super) fn thickness(block: &Block) -> f64 {
    block
        .faces
        .iter()
        .map(|f| {
            block
                .verts
                .iter()
                .map(|v| f.offset - f.normal.dot(v))
                .fold(0.0, f64::max)
        })
        .fold(f64::INFINITY, f64::min)
}

/// Newell's normal of a ring: twice its vector area, outward for a CCW ring.
pub(super) fn newell(verts: &[Vec3], ring: &[usize]) -> Vec3 {
    let o = verts[ring[0]];
    ring.iter()
        .zip(ring.iter().cycle().skip(1))
        .map(|(&a, &b)| (verts[a] - o).cross(&(verts[b] - o)))
        .sum()
}

/// Volume and centroid of a closed polyhedron with outward rings, by the divergence theorem:
/// faces fanned about their first vertex, tetrahedra closed at the vertex mean.
pub(super) fn volume_centroid<'a>(
    verts: &[Vec3],
    rings: impl Iterator<Item = &'a [usize]>,
) -> (f64, Vec3) {
    let r = verts.iter().sum::<Vec3>() / verts.len().max(1) as f64;
    let mut six_v = 0.0;
    let mut moment = Vec3::zeros();
    for ring in rings {
        let a = verts[ring[0]] - r;
        for (&i, &j) in ring[1..].iter().zip(&ring[2..]) {
            let b = verts[i] - r;
            let c = verts[j] - r;
            let d = a.dot(&b.cross(&c));
            six_v += d;
            moment += (a + b + c) * d;
        }
    }
    (six_v / 6.0, r + moment / (4.0 * six_v))
}
