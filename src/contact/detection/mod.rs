//! Contact detection at the start of a step (reference §4): the broad phase on bounding boxes,
//! and the narrow phase's two entrance modes, vertex-to-face and edge-to-edge, with the merging
//! of candidates that are one physical constraint.

use super::groups::{Bounds, SweepIndex};
use super::{Alternative, Candidate, ContactKey, DetectionParams, Shape};
use crate::physics::geometry::Vec3;

/// Candidate block pairs by sort-and-sweep on the enlarged bounding boxes (the sweep of
/// [`SweepIndex::pairs`], every box grown by `margin / 2`). Pairs of two fixed blocks are
/// skipped. Returns pairs (a, b) with a < b; the sweep stops once it has found more than
/// `limit` (see [`crate::contact::groups::MAX_BLOCK_PAIRS`]).
pub fn broad_phase(shapes: &[Shape], margin: f64, limit: usize) -> Vec<(usize, usize)> {
    let boxes: Vec<Bounds> = shapes
        .iter()
        .map(|s| Bounds {
            lo: s.lo,
            hi: s.hi,
            initial: (s.lo, s.hi),
            fixed: s.fixed,
        })
        .collect();
    SweepIndex::new(&boxes).pairs(&boxes, margin, false, |_, _| margin, limit)
}

/// The bounding box of a block grown by the search distance: the cull that opens both
/// narrow-phase tests. A feature (a vertex, or an edge's two ends) whose own box misses it cannot
/// come within the search distance of the block.
struct Reach {
    lo: Vec3,
    hi: Vec3,
}

impl Reach {
    fn around(b: &Shape, margin: f64) -> Reach {
        Reach {
            lo: b.lo - Vec3::repeat(margin),
            hi: b.hi + Vec3::repeat(margin),
        }
    }

    /// True when the box of the segment p–q (a point when p = q) meets the grown box.
    fn holds(&self, p: &Vec3, q: &Vec3) -> bool {
        !(0..3).any(|d| p[d].max(q[d]) < self.lo[d] || p[d].min(q[d]) > self.hi[d])
    }
}

/// Three well-spread corners of a face for the determinant (5.1).
fn face_triple(face: &[usize]) -> [usize; 3] {
    let k = face.len();
    [face[0], face[k / 3], face[(2 * k) / 3]]
}

/// Vertex-to-face candidates of the vertices of `a` against the faces of `b` (reference §4.3).
/// Per vertex one candidate, on the face with the largest signed gap (the common-plane rule);
/// among faces tied with it (a vertex on an edge of `b`), a face the vertex had a contact with
/// in the last step, so that the contact keeps its history. The other faces in reach go with it
/// as alternatives.
fn vertex_face(
    ia: usize,
    a: &Shape,
    ib: usize,
    b: &Shape,
    p: &DetectionParams,
    known: &(dyn Fn(&ContactKey) -> bool + Sync),
    out: &mut Vec<Candidate>,
) {
    let reach = Reach::around(b, p.search_distance);
    // Longest edge of each face of b, for the slack of the point-in-face test below.
    let face_edges = &b.edges.face_longest;
    for (vi, &pv) in a.vertices.iter().enumerate() {
        if !reach.holds(&pv, &pv) {
            continue;
        }
        let mut passing: Vec<Alternative> = Vec::new();
        // How far the vertex is outside b's face planes, at most (over all faces of b), and
        // the widest slack a passing face allowed it.
        let mut outside = f64::NEG_INFINITY;
        let mut widest_slack = 0.0f64;
        let vertex_edge = a.edges.vertex_longest[vi];
        for (fi, face) in b.topo.faces.iter().enumerate() {
            let n = b.face_normals[fi];
            let q0 = b.vertices[face[0]];
            let gap = (pv - q0).dot(&n);
            outside = outside.max(gap);
            if gap < -p.max_penetration || gap > p.search_distance {
                continue;
            }
            let slack = outline_slack(p, face_edges[fi], vertex_edge);
            if !faces_vertex(a, vi, b, fi, slack, p) {
                continue;
            }
            passing.push(alternative(b, fi, gap));
            widest_slack = widest_slack.max(slack);
        }
        // Block b is convex: a vertex outside the plane of any one of its faces is outside b,
        // however deep it is behind the faces whose tests it passed. Within the slack of a face's
        // outline it stands for the edge of its own block against that face (two equal faces
        // stacked with a little twist have no vertex inside the other block, and their edges
        // are parallel), but farther out it claims a depth that is not there: beside an acute
        // edge of b (a 35° joint meeting an 80° one) a vertex sat 6 cm behind one face, within
        // its outline, and as far outside the plane of the other; taken as a contact that deep
        // it pushed two slabs of a jointed slope apart until the run diverged.
        let top = passing
            .iter()
            .map(|f| f.gap)
            .fold(f64::NEG_INFINITY, f64::max);
        if top < -p.tie_distance && outside > widest_slack.max(p.tie_distance) {
            continue;
        }
        if top < -p.tie_distance && -top > DEPTH_RATIO * outside + p.tie_distance {
            // Outside b within the slack, yet behind every passing face by far more: the vertex
            // slid past the edge of the face it lies on by a little more than that face's slack
            // allows, and only a far face of b still passed. See `face_beside`. (Without such a
            // face the claim stands: dropped, the vertex could sink into b unseen.)
            if let Some(f) = face_beside(a, vi, b, (face_edges, vertex_edge), outside, p) {
                passing = vec![f];
            }
        }
        out.extend(choose_face(
            (ia, vi, pv),
            ib,
            passing,
            p.tie_distance,
            known,
        ));
    }
}

/// The face of `b` that separates vertex `vi` of `a` from it, for a vertex that lies `outside` b
/// by less than the point-in-face slack but passed only faces far behind it: of the faces whose
/// outline test (widened by `outside`) and entrance test it passes, the one whose plane it is
/// farthest outside of (for a convex block, the separating plane; its gap is at most
/// `outside`). Where J1 (35°) meets an 80° joint, a corner of one slab slid 1.02 cm past the
/// side edge of the J1 face it rested on (slack 1.00 cm), and the only face it still passed was
/// the far steep face 13 cm behind: taken as a contact that deep, it was held as a 13 cm overlap
/// and pressed with 16 MN for a step. Another corner, 1 cm above a J1 face and 1 cm past its
/// side, was taken 11 cm deep the same way. Dropping such vertices instead (a depth-claim check)
/// made the slope diverge at 2 s: here they keep a contact, at their true gap.
fn face_beside(
    a: &Shape,
    vi: usize,
    b: &Shape,
    (face_edges, vertex_edge): (&[f64], f64),
    outside: f64,
    p: &DetectionParams,
) -> Option<Alternative> {
    let pv = a.vertices[vi];
    let mut best: Option<Alternative> = None;
    for (fi, face) in b.topo.faces.iter().enumerate() {
        let gap = (pv - b.vertices[face[0]]).dot(&b.face_normals[fi]);
        if best.as_ref().is_some_and(|f| f.gap >= gap) {
            continue;
        }
        let slack = outline_slack(p, face_edges[fi], vertex_edge) + outside;
        if faces_vertex(a, vi, b, fi, slack, p) {
            best = Some(alternative(b, fi, gap));
        }
    }
    // Not a face far behind: that is the phantom depth again.
    best.filter(|f| -f.gap <= DEPTH_RATIO * outside + p.tie_distance)
}

/// The slack of the point-in-face test for a face whose longest edge is `face_edge` and a
/// vertex whose longest edge is `vertex_edge`. It covers the blind spot the edge–edge test
/// leaves near edge ends (closest points within ε_e of an end are refused there): a vertex a
/// few millimetres outside a face, beside the face's edge, is caught by the vertex–face test,
/// against the face's plane. Without it a corner of one block near a corner of another (every
/// joint of a wall of aligned blocks) is seen by neither test, can move into the neighbour
/// unseen within a step, and the next step pushes it out with a burst of energy.
fn outline_slack(p: &DetectionParams, face_edge: f64, vertex_edge: f64) -> f64 {
    p.inside_tolerance
        .max(2.0 * p.edge_margin * face_edge.max(vertex_edge))
}

/// Whether vertex `vi` of `a` faces face `fi` of `b`: it lies within the face's outline, up to
/// `slack`, and passes the entrance test (block a lies locally outside the face plane; an edge
/// diving into the face means the contact is really edge–face or face–face, found by other
/// features).
fn faces_vertex(
    a: &Shape,
    vi: usize,
    b: &Shape,
    fi: usize,
    slack: f64,
    p: &DetectionParams,
) -> bool {
    let (face, n, pv) = (&b.topo.faces[fi], b.face_normals[fi], a.vertices[vi]);
    let inward = b.edges.inward(fi, face.len());
    let inside = face
        .iter()
        .zip(inward)
        .all(|(&q, across)| (pv - b.vertices[q]).dot(across) >= -slack);
    inside
        && a.topo.vertex_edges[vi].iter().all(|&ei| {
            let e = a.topo.edges[ei];
            let other = if e.v[0] == vi { e.v[1] } else { e.v[0] };
            let t = a.vertices[other] - pv;
            t.dot(&n) >= -t.norm() * p.sin_entrance
        })
}

/// Face `fi` of `b` as a contact face at `gap`.
fn alternative(b: &Shape, fi: usize, gap: f64) -> Alternative {
    let [t1, t2, t3] = face_triple(&b.topo.faces[fi]);
    Alternative {
        face: fi as u32,
        corners: [b.vertices[t1], b.vertices[t2], b.vertices[t3]],
        normal: b.face_normals[fi],
        gap,
    }
}

/// The candidate of vertex `vi` (at `xa`) of block `ia` among the faces of block `ib` it passed
/// the tests with: the largest gap wins; among faces tied with it, a known contact's face, else
/// the first.
fn choose_face(
    (ia, vi, xa): (usize, usize, Vec3),
    ib: usize,
    mut passing: Vec<Alternative>,
    tie: f64,
    known: &(dyn Fn(&ContactKey) -> bool + Sync),
) -> Option<Candidate> {
    let key = |face: u32| ContactKey {
        i: ia as u32,
        j: ib as u32,
        mode: 0,
        feature_i: vi as u32,
        feature_j: face,
    };
    let top = passing
        .iter()
        .map(|f| f.gap)
        .fold(f64::NEG_INFINITY, f64::max);
    let largest = passing.iter().position(|f| f.gap == top)?;
    let chosen = passing
        .iter()
        .position(|f| f.gap >= top - tie && known(&key(f.face)))
        .unwrap_or(largest);
    let f = passing.remove(chosen);
    Some(Candidate {
        key: key(f.face),
        points: [xa, f.corners[0], f.corners[1], f.corners[2]],
        normal: f.normal,
        gap: f.gap,
        xa,
        xb: xa - f.normal * f.gap,
        tied: passing.iter().any(|a| a.gap >= f.gap - tie),
        alternatives: passing,
    })
}

/// The largest signed distance of `x` from the face planes of the convex block `b`: positive
/// when `x` is outside `b`, a lower bound of its distance from `b`.
fn farthest_outside(b: &Shape, x: &Vec3) -> f64 {
    b.topo
        .faces
        .iter()
        .zip(b.face_normals)
        .map(|(face, n)| (x - b.vertices[face[0]]).dot(n))
        .fold(f64::NEG_INFINITY, f64::max)
}

/// How much deeper a contact may claim a point to be, along its normal, than the point lies inside
/// the other block: two edges crossing in their middles, along the bisector of an edge whose
/// faces meet at 30° (the sharpest a joint set cuts against another here), cross 1 / cos 75° ≈
/// 3.9 times deeper than their closest points lie behind the nearest face plane.
const DEPTH_RATIO: f64 = 4.0;

/// Edges crossing within this fraction of an end of one of them cross where a third face of
/// that block meets the edge, and may cross deeper than the blocks overlap
/// ([`crossing_is_overlap`]). Elsewhere the closest points lie on the planes of the faces at
/// the other edge, and the crossing depth is the overlap's.
const NEAR_END: f64 = 0.05;

/// True when edges crossed by `−gap` along their common normal (closest points `xa` on `a`'s
/// edge, `xb` on `b`'s) are an overlap of the blocks that the common normal resolves. Each
/// closest point must lie inside the other block, and not far shallower than the crossing: a
/// point inside a convex block is as far from its boundary as from the nearest face plane. Near
/// an end of an edge, where other faces of its block meet, lines crossing 5 cm deep had their
/// closest points 0.5–3.5 mm inside; pushed apart along the common normal, nearly in the plane
/// of a face, the blocks of a jointed slope gained energy until the run diverged. The vertex at
/// that end is in contact with a face instead (`vertex_face`).
fn crossing_is_overlap(a: &Shape, b: &Shape, xa: &Vec3, xb: &Vec3, gap: f64, tie: f64) -> bool {
    let depth = -farthest_outside(b, xa).max(farthest_outside(a, xb));
    -gap <= DEPTH_RATIO * depth.max(0.0) + tie
}

/// Unit vector in the plane of `face` (of a block with these vertices), perpendicular to the
/// edge p→q and pointing into the face.
fn into_face(vertices: &[Vec3], face: &[usize], p: Vec3, q: Vec3) -> Vec3 {
    let c = face.iter().map(|&k| vertices[k]).sum::<Vec3>() / face.len() as f64;
    let e = (q - p).normalize();
    let w = (c - p) - e * (c - p).dot(&e);
    w.normalize()
}

/// Edge-to-edge candidates between the edges of `a` and of `b` (reference §4.3).
fn edge_edge(
    ia: usize,
    a: &Shape,
    ib: usize,
    b: &Shape,
    p: &DetectionParams,
    out: &mut Vec<Candidate>,
) {
    let reach = Reach::around(b, p.search_distance);
    // The edges of b that can come within |gap| ≤ max(d_s, d_max) of an edge of a: the closest
    // point on b's edge then lies in a's box grown by that much (grown a little more here, so
    // that rounding never culls an edge the test below would keep).
    let limit = p.search_distance.max(p.max_penetration);
    let reach_a = Reach::around(a, limit * (1.0 + 1e-6) + 1e-12);
    let near_b: Vec<usize> = (0..b.topo.edges.len())
        .filter(|&k| {
            let eb = &b.topo.edges[k];
            reach_a.holds(&b.vertices[eb.v[0]], &b.vertices[eb.v[1]])
        })
        .collect();
    for (ea_i, ea) in a.topo.edges.iter().enumerate() {
        let (p1, p2) = (a.vertices[ea.v[0]], a.vertices[ea.v[1]]);
        if !reach.holds(&p1, &p2) {
            continue;
        }
        let e1 = p2 - p1;
        for &eb_i in &near_b {
            let eb = &b.topo.edges[eb_i];
            let (p3, p4) = (b.vertices[eb.v[0]], b.vertices[eb.v[1]]);
            let e2 = p4 - p3;
            let c = e1.cross(&e2);
            let cn = c.norm();
            if cn < p.sin_parallel * e1.norm() * e2.norm() {
                continue; // near-parallel: the endpoints give vertex–face contacts
            }
            // Closest points of the two lines.
            let r = p1 - p3;
            let (aa, bb, ee) = (e1.dot(&e1), e1.dot(&e2), e2.dot(&e2));
            let (dd, ff) = (e1.dot(&r), e2.dot(&r));
            let den = aa * ee - bb * bb;
            let s = (bb * ff - dd * ee) / den;
            let t = (aa * ff - bb * dd) / den;
            let m = p.edge_margin;
            if !(s > m && s < 1.0 - m && t > m && t < 1.0 - m) {
                continue; // closest points at an end: a vertex contact
            }
            let xa = p1 + e1 * s;
            let xb = p3 + e2 * t;
            let mut normal = c / cn;
            let gap0 = (xa - xb).dot(&normal);
            if gap0.abs() > limit {
                continue;
            }
            // Orientation: the faces of b at its edge on the −n side, those of a on the +n side.
            let wa: Vec<Vec3> = ea
                .faces
                .iter()
                .map(|&f| into_face(a.vertices, &a.topo.faces[f], p1, p2))
                .collect();
            let wb: Vec<Vec3> = eb
                .faces
                .iter()
                .map(|&f| into_face(b.vertices, &b.topo.faces[f], p3, p4))
                .collect();
            let fits = |n: &Vec3| -> f64 {
                // Margin of the worst face; ≥ −sin θ_a means the entrance holds.
                let ma = wa.iter().map(|w| w.dot(n)).fold(f64::INFINITY, f64::min);
                let mb = wb.iter().map(|w| -w.dot(n)).fold(f64::INFINITY, f64::min);
                ma.min(mb)
            };
            let (plus, minus) = (fits(&normal), fits(&-normal));
            if plus.max(minus) < -p.sin_entrance {
                continue;
            }
            if minus > plus {
                normal = -normal;
            }
            let gap = (xa - xb).dot(&normal);
            if gap < -p.max_penetration || gap > p.search_distance {
                continue;
            }
            let near_end = s.min(1.0 - s).min(t.min(1.0 - t)) < NEAR_END;
            if p.check_crossing_depth
                && near_end
                && gap < 0.0
                && !crossing_is_overlap(a, b, &xa, &xb, gap, p.tie_distance)
            {
                continue;
            }
            out.push(Candidate {
                key: ContactKey {
                    i: ia as u32,
                    j: ib as u32,
                    mode: 1,
                    feature_i: ea_i as u32,
                    feature_j: eb_i as u32,
                },
                points: [p1, p2, p3, p4],
                normal,
                gap,
                xa,
                xb,
                alternatives: Vec::new(),
                tied: false,
            });
        }
    }
}

/// Two candidates of one block pair at one place whose normals oppose (an angle beyond 90°):
/// two convex blocks touching there have one separating direction, and the pair would clamp
/// them. At the acute edges of a jointed slope two edge–edge contacts of lower/41 and
/// upper/137 met at one point of the slower block's edge, normals 140° apart, one of them
/// 6 cm deep; their multipliers pressed the blocks together with 2–3·10⁸ N each, which
/// grew step by step, and when one of them let go the block left at 24 m/s. "One place":
/// their points on block j closer than the deeper one's depth (or the merge distance). The
/// one kept is the one the de-duplication prefers (known, then the larger gap).
///
/// Anywhere in the pair, two candidates whose normals, taken toward the same block, are more
/// than [`OPPOSED_ANYWHERE`] apart clamp it as well: two convex blocks whose interiors do not
/// overlap cannot touch at two places with such normals (the segment between the two points
/// would run through one of them). In a cube cut by joint sets 23° apart a 130 g sliver held a
/// 26 kg neighbour by two such contacts, normals 157° apart, 2.6·10⁸ N each, until a solve
/// moved the neighbour 3.4 mm in 0.1 ms and the run stopped as diverged.
fn opposed(k: &Candidate, c: &Candidate, p: &DetectionParams) -> bool {
    let reach = p.merge_distance.max(-k.gap).max(-c.gap);
    let block = k.key.i as usize;
    let (nk, nc) = (
        toward(&k.key, &k.normal, block),
        toward(&c.key, &c.normal, block),
    );
    nk.dot(&nc) < OPPOSED_ANYWHERE.cos()
        || k.normal.dot(&c.normal) < 0.0 && (k.xb - c.xb).norm() <= reach
}

/// A contact's normal `n` (which points toward its block i) taken toward `block`, one of its
/// two blocks.
fn toward(key: &ContactKey, n: &Vec3, block: usize) -> Vec3 {
    if key.i as usize == block { *n } else { -*n }
}

/// The angle between two contact normals of one block pair (taken toward the same block)
/// beyond which the two cannot both hold, wherever they are ([`opposed`]). Not 90°: the
/// contacts at the corners of a wall's aligned boxes have normals at right angles, and their
/// cosines come out at ±10⁻¹⁷.
const OPPOSED_ANYWHERE: f64 = 120.0 * std::f64::consts::PI / 180.0;

/// Drops from each vertex–face candidate of the pair of `a` the alternative faces whose normal
/// opposes another kept candidate's ([`opposed`]): moved to such a face within a step
/// (`Active::reconsider_face`), the contact would clamp the pair as well.
fn drop_opposed_alternatives(a: usize, kept: &mut [Candidate]) {
    let normals: Vec<(ContactKey, Vec3)> = kept
        .iter()
        .map(|c| (c.key, toward(&c.key, &c.normal, a)))
        .collect();
    for c in kept.iter_mut().filter(|c| !c.alternatives.is_empty()) {
        let key = c.key;
        c.alternatives.retain(|alt| {
            let n = toward(&key, &alt.normal, a);
            normals
                .iter()
                .all(|(k, m)| *k == key || n.dot(m) >= OPPOSED_ANYWHERE.cos())
        });
    }
}

/// All contacts of one block pair, de-duplicated: candidates whose contact points coincide are
/// one physical constraint (typically the i→j and j→i vertex–face contacts at the corners of two
/// equal stacked faces). `known` tells which keys existed in the previous step: those win, so a
/// contact keeps its history; otherwise the candidate with the larger gap wins.
pub fn detect_pair(
    a: usize,
    sa: &Shape,
    b: usize,
    sb: &Shape,
    p: &DetectionParams,
    known: &(dyn Fn(&ContactKey) -> bool + Sync),
) -> Vec<Candidate> {
    let mut all = Vec::new();
    vertex_face(a, sa, b, sb, p, known, &mut all);
    vertex_face(b, sb, a, sa, p, known, &mut all);
    edge_edge(a, sa, b, sb, p, &mut all);
    // Looked up once per candidate, not once per comparison.
    let mut all: Vec<(bool, Candidate)> = all.into_iter().map(|c| (known(&c.key), c)).collect();
    all.sort_by(|(kx, x), (ky, y)| {
        ky.cmp(kx)
            .then(y.gap.total_cmp(&x.gap))
            .then(x.key.cmp(&y.key))
    });
    let mut kept: Vec<Candidate> = Vec::with_capacity(all.len());
    for (_, c) in all {
        let mid = (c.xa + c.xb) / 2.0;
        if kept
            .iter()
            .all(|k| ((k.xa + k.xb) / 2.0 - mid).norm() > p.merge_distance && !opposed(k, &c, p))
        {
            kept.push(c);
        }
    }
    if kept.len() > 1 {
        drop_opposed_alternatives(a, &mut kept);
    }
    kept.sort_by_key(|c| c.key);
    kept
}

#[cfg(test)]
mod tests;
