//! Contact detection at the start of a step (reference §4): the broad phase on bounding boxes,
//! and the narrow phase's two entrance modes, vertex-to-face and edge-to-edge, with the merging
//! of candidates that are one physical constraint.

use super::{Alternative, Candidate, ContactKey, DetectionParams, Shape};
use crate::physics::geometry::Vec3;

/// Candidate block pairs by sort-and-sweep on the x extent of the enlarged bounding boxes.
/// Pairs of two fixed blocks are skipped. Returns pairs (a, b) with a < b.
pub fn broad_phase(shapes: &[Shape], margin: f64) -> Vec<(usize, usize)> {
    let mut order: Vec<usize> = (0..shapes.len()).collect();
    // Sweep along the longest axis of the model.
    let (mut lo, mut hi) = (Vec3::repeat(f64::INFINITY), Vec3::repeat(f64::NEG_INFINITY));
    for s in shapes {
        lo = lo.inf(&s.lo);
        hi = hi.sup(&s.hi);
    }
    let axis = (hi - lo).imax();
    order.sort_by(|&a, &b| shapes[a].lo[axis].total_cmp(&shapes[b].lo[axis]));
    let h = margin / 2.0;
    let mut pairs = Vec::new();
    for (k, &a) in order.iter().enumerate() {
        let sa = &shapes[a];
        for &b in &order[k + 1..] {
            let sb = &shapes[b];
            if sb.lo[axis] - h > sa.hi[axis] + h {
                break;
            }
            if sa.fixed && sb.fixed {
                continue;
            }
            let overlap =
                (0..3).all(|d| sa.lo[d] - h <= sb.hi[d] + h && sb.lo[d] - h <= sa.hi[d] + h);
            if overlap {
                pairs.push((a.min(b), a.max(b)));
            }
        }
    }
    pairs.sort_unstable();
    pairs
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
    let face_edges: Vec<f64> = b
        .topo
        .faces
        .iter()
        .map(|face| {
            (0..face.len())
                .map(|m| (b.vertices[face[(m + 1) % face.len()]] - b.vertices[face[m]]).norm())
                .fold(0.0, f64::max)
        })
        .collect();
    for (vi, &pv) in a.vertices.iter().enumerate() {
        if !reach.holds(&pv, &pv) {
            continue;
        }
        let mut passing: Vec<Alternative> = Vec::new();
        // How far the vertex is outside b's face planes, at most (over all faces of b), and
        // the widest slack a passing face allowed it.
        let mut outside = f64::NEG_INFINITY;
        let mut widest_slack = 0.0f64;
        let vertex_edge = a.topo.vertex_edges[vi]
            .iter()
            .map(|&ei| {
                let e = a.topo.edges[ei];
                (a.vertices[e.v[1]] - a.vertices[e.v[0]]).norm()
            })
            .fold(0.0, f64::max);
        for (fi, face) in b.topo.faces.iter().enumerate() {
            let n = b.face_normals[fi];
            let q0 = b.vertices[face[0]];
            let gap = (pv - q0).dot(&n);
            outside = outside.max(gap);
            if gap < -p.max_penetration || gap > p.search_distance {
                continue;
            }
            // The slack covers the blind spot the edge–edge test leaves near edge ends (closest
            // points within ε_e of an end are refused there): a vertex a few millimetres
            // outside a face, beside the face's edge, is caught here, against the face's plane.
            // Without it a corner of one block near a corner of another (every joint of a
            // wall of aligned blocks) is seen by neither test, can move into the neighbour
            // unseen within a step, and the next step pushes it out with a burst of energy.
            let slack = p
                .inside_tolerance
                .max(2.0 * p.edge_margin * face_edges[fi].max(vertex_edge));
            let inside = (0..face.len()).all(|m| {
                let qm = b.vertices[face[m]];
                let e = b.vertices[face[(m + 1) % face.len()]] - qm;
                (pv - qm).dot(&n.cross(&e.normalize())) >= -slack
            });
            if !inside {
                continue;
            }
            // Entrance: block a lies locally outside the face plane; an edge diving into the
            // face means the contact is really edge–face or face–face, found by other features.
            let enters = a.topo.vertex_edges[vi].iter().all(|&ei| {
                let e = a.topo.edges[ei];
                let other = if e.v[0] == vi { e.v[1] } else { e.v[0] };
                let t = a.vertices[other] - pv;
                t.dot(&n) >= -t.norm() * p.sin_entrance
            });
            if !enters {
                continue;
            }
            let [t1, t2, t3] = face_triple(face);
            passing.push(Alternative {
                face: fi as u32,
                corners: [b.vertices[t1], b.vertices[t2], b.vertices[t3]],
                normal: n,
                gap,
            });
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
        out.extend(choose_face(
            (ia, vi, pv),
            ib,
            passing,
            p.tie_distance,
            known,
        ));
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
            .all(|k| ((k.xa + k.xb) / 2.0 - mid).norm() > p.merge_distance)
        {
            kept.push(c);
        }
    }
    kept.sort_by_key(|c| c.key);
    kept
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::ContactMode;
    use crate::physics::geometry::{
        Mat3, Topology, box_vertices, convex_hull, newell_normal, rotation_xyz_degrees,
    };

    struct Owned {
        v: Vec<Vec3>,
        t: Topology,
        n: Vec<Vec3>,
        c: Vec3,
    }

    fn owned(points: Vec<Vec3>) -> Owned {
        let (v, t) = convex_hull(&points).unwrap();
        let n = t
            .faces
            .iter()
            .map(|f| newell_normal(&v, f).normalize())
            .collect();
        let c = crate::physics::geometry::mass_properties(&v, &t.faces).centroid;
        Owned { v, t, n, c }
    }

    fn shape(o: &Owned) -> Shape<'_> {
        let (lo, hi) = crate::physics::geometry::bounding_box(&o.v);
        Shape {
            vertices: &o.v,
            topo: &o.t,
            face_normals: &o.n,
            centroid: o.c,
            lo,
            hi,
            fixed: false,
        }
    }

    fn params() -> DetectionParams {
        DetectionParams::new(5.0, 0.01)
    }

    #[test]
    fn stacked_equal_cubes_give_four_corner_contacts() {
        let lower = owned(box_vertices([2.0; 3], [0.0, 0.0, 1.0], &Mat3::identity()));
        let upper = owned(box_vertices([2.0; 3], [0.0, 0.0, 3.0], &Mat3::identity()));
        let c = detect_pair(0, &shape(&lower), 1, &shape(&upper), &params(), &|_| false);
        assert_eq!(c.len(), 4, "{c:#?}");
        for k in &c {
            assert_eq!(k.mode(), ContactMode::VertexFace);
            assert!(k.gap.abs() < 1e-12);
            // Normal out of the face block toward the vertex block.
            let towards_i = if k.key.i == 1 { Vec3::z() } else { -Vec3::z() };
            assert!((k.normal - towards_i).norm() < 1e-12);
        }
    }

    #[test]
    fn shifted_cubes_give_two_vertex_face_and_two_edge_edge_contacts() {
        let lower = owned(box_vertices([2.0; 3], [0.0, 0.0, 1.0], &Mat3::identity()));
        let upper = owned(box_vertices([2.0; 3], [0.5, 0.7, 2.999], &Mat3::identity()));
        let c = detect_pair(0, &shape(&lower), 1, &shape(&upper), &params(), &|_| false);
        let vf = c
            .iter()
            .filter(|k| k.mode() == ContactMode::VertexFace)
            .count();
        let ee = c
            .iter()
            .filter(|k| k.mode() == ContactMode::EdgeEdge)
            .count();
        assert_eq!((vf, ee), (2, 2), "{c:#?}");
        for k in &c {
            assert!((k.gap + 0.001).abs() < 1e-12, "penetration 1 mm: {}", k.gap);
            assert!(k.normal.z.abs() > 0.999);
        }
    }

    #[test]
    fn a_corner_just_beside_a_face_edge_is_still_a_vertex_face_contact() {
        // The upper cube's corner hangs 0.5 mm beyond the lower cube's top edge, 0.1 mm above
        // its top plane. Its edges run parallel to, or end at, the lower cube's edges, so the
        // edge–edge test refuses them all; before the slack of the point-in-face test nothing
        // saw this corner, and a small move took it into the lower cube unseen.
        let lower = owned(box_vertices([1.0; 3], [0.5, 0.5, 0.5], &Mat3::identity()));
        let upper = owned(box_vertices(
            [1.0; 3],
            [1.5005, 0.8, 1.5001],
            &Mat3::identity(),
        ));
        let c = detect_pair(0, &shape(&lower), 1, &shape(&upper), &params(), &|_| false);
        assert!(
            c.iter().all(|k| k.mode() == ContactMode::VertexFace),
            "{c:#?}"
        );
        let corner = c
            .iter()
            .find(|k| k.key.i == 1 && (k.xa - Vec3::new(1.0005, 0.3, 1.0001)).norm() < 1e-9)
            .unwrap_or_else(|| panic!("the corner is a contact: {c:#?}"));
        // Of the two faces at the edge, the common-plane rule keeps the one with the larger
        // gap: the side face x = 1, 0.5 mm away.
        assert!((corner.gap - 5e-4).abs() < 1e-12, "{corner:#?}");
        assert!((corner.normal - Vec3::x()).norm() < 1e-12);
        // 5 mm beyond the edge and 5 mm above (more than the slack, 2 ε_e × 1 m) it is not.
        let far = owned(box_vertices(
            [1.0; 3],
            [1.505, 0.8, 1.505],
            &Mat3::identity(),
        ));
        let c = detect_pair(0, &shape(&lower), 1, &shape(&far), &params(), &|_| false);
        assert!(c.iter().all(|k| k.key.i != 1), "{c:#?}");
    }

    #[test]
    fn a_vertex_beside_an_acute_edge_is_not_deep_in_the_block() {
        // b: a blade, its sloping top meeting its base at 30° along the edge x = 4, z = 0. The
        // vertex p is 3.2 cm behind the slope, within its outline, but 2 cm below the base's
        // plane (more than the slack, 2 ε_e × 4 m), so outside b. Its block's edges run up
        // along the slope's normal: the base, which it is outside of, fails the entrance test.
        let (s30, c30) = (0.5, 3f64.sqrt() / 2.0);
        let blade = owned(vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(4.0, 0.0, 0.0),
            Vec3::new(0.0, 0.0, 4.0 * s30 / c30),
            Vec3::new(0.0, 2.0, 0.0),
            Vec3::new(4.0, 2.0, 0.0),
            Vec3::new(0.0, 2.0, 4.0 * s30 / c30),
        ]);
        let n = Vec3::new(s30, 0.0, c30);
        let p = Vec3::new(4.0 - 0.03, 1.0, -0.02);
        let (u, w) = (Vec3::y(), n.cross(&Vec3::y()));
        let tip_at = |x: Vec3| {
            owned(vec![
                x,
                x + n + u * 0.3,
                x + n - u * 0.3 + w * 0.3,
                x + n - w * 0.3,
            ])
        };
        let tip = tip_at(p);
        let gap = (p - Vec3::new(4.0, 0.0, 0.0)).dot(&n);
        assert!(gap < -0.03 && gap > -params().max_penetration, "{gap}");
        let c = detect_pair(0, &shape(&blade), 1, &shape(&tip), &params(), &|_| false);
        assert!(c.iter().all(|k| (k.xa - p).norm() > 1e-9), "{c:#?}");
        // Moved up by 2.5 cm, p is inside b, 5 mm from the base: a contact 7.5 mm deep.
        let q = p + Vec3::z() * 0.025;
        let tip = tip_at(q);
        let c = detect_pair(0, &shape(&blade), 1, &shape(&tip), &params(), &|_| false);
        let k = c
            .iter()
            .find(|k| (k.xa - q).norm() < 1e-9)
            .expect("q is a contact");
        assert!((k.gap - (gap + 0.025 * c30)).abs() < 1e-12, "{k:#?}");
    }

    #[test]
    fn a_corner_overhanging_a_face_edge_within_the_slack_bears_on_the_face() {
        // The upper cube sits 1 mm into the lower one and 0.5 mm past its edge x = 1: its
        // corners there are outside the lower cube (beyond the side face's plane, which their
        // edges along −x dive through), yet they stand for the upper cube's bottom edge on the
        // top face, 1 mm deep (no edge of the upper cube crosses one of the lower's).
        let lower = owned(box_vertices([1.0; 3], [0.5, 0.5, 0.5], &Mat3::identity()));
        let upper = owned(box_vertices(
            [1.0; 3],
            [0.5005, 0.5, 1.499],
            &Mat3::identity(),
        ));
        let c = detect_pair(0, &shape(&lower), 1, &shape(&upper), &params(), &|_| false);
        for y in [0.0, 1.0] {
            let k = c
                .iter()
                .find(|k| (k.xa - Vec3::new(1.0005, y, 0.999)).norm() < 1e-9)
                .unwrap_or_else(|| panic!("the corner at y = {y} is a contact: {c:#?}"));
            assert!((k.gap + 1e-3).abs() < 1e-12 && (k.normal - Vec3::z()).norm() < 1e-12);
        }
    }

    #[test]
    fn crossed_edges_are_an_overlap_only_as_deep_as_their_points_lie_inside() {
        // A point 1 mm under the top of a unit cube, near its corner: edges crossing there
        // 3 mm deep along a slanted normal are an overlap; 5 cm deep, they are not.
        let cube = owned(box_vertices([1.0; 3], [0.5, 0.5, 0.5], &Mat3::identity()));
        let b = shape(&cube);
        let tie = params().tie_distance;
        let xa = Vec3::new(0.9, 0.9, 0.999);
        let xb = Vec3::new(0.5, 0.5, 0.5);
        assert!(crossing_is_overlap(&b, &b, &xa, &xb, -0.003, tie));
        assert!(!crossing_is_overlap(&b, &b, &xa, &xb, -0.05, tie));
        // Outside the block, no depth at all is.
        let out = Vec3::new(1.01, 0.5, 0.5);
        assert!(!crossing_is_overlap(&b, &b, &out, &xb, -0.003, tie));
    }

    #[test]
    fn the_diagonal_blocks_of_a_joint_junction_touch_on_tied_faces() {
        // Four unit cubes meeting along the line x = 0, z = 1 (a bedding joint crossed by a
        // vertical one): the lower-right and upper-left cubes touch along that line only. Each
        // corner of one on that line is as close to the other's top (or bottom) face as to its
        // side face: the candidate is tied and carries the other face as its alternative.
        let lower_right = owned(box_vertices([1.0; 3], [0.5, 0.5, 0.5], &Mat3::identity()));
        let upper_left = owned(box_vertices([1.0; 3], [-0.5, 0.5, 1.5], &Mat3::identity()));
        let c = detect_pair(
            0,
            &shape(&lower_right),
            1,
            &shape(&upper_left),
            &params(),
            &|_| false,
        );
        assert!(!c.is_empty(), "they touch along the line");
        for k in &c {
            assert_eq!(k.mode(), ContactMode::VertexFace, "{k:#?}");
            assert!(k.tied, "{k:#?}");
            assert_eq!(k.alternatives.len(), 1, "{k:#?}");
            let a = k.alternatives[0];
            assert!(a.gap.abs() < 1e-12 && k.gap.abs() < 1e-12);
            // One face is horizontal, the other vertical.
            let crossed = k.normal.z.abs() * a.normal.x.abs() + k.normal.x.abs() * a.normal.z.abs();
            assert!(crossed > 0.99, "{k:#?}");
            // Switching makes the alternative the face, and back.
            let mut s = k.clone();
            s.switch_face(0);
            assert!(
                (s.normal - a.normal).norm() < 1e-15
                    && (s.alternatives[0].normal - k.normal).norm() < 1e-15
            );
            assert!(
                (s.xb - k.xa).norm() < 1e-12,
                "the vertex touches both faces"
            );
        }
        // A corner of a stacked cube in the middle of the face below is not tied.
        let lower = owned(box_vertices([2.0; 3], [0.0, 0.0, 1.0], &Mat3::identity()));
        let upper = owned(box_vertices([1.0; 3], [0.0, 0.0, 2.5], &Mat3::identity()));
        let c = detect_pair(0, &shape(&lower), 1, &shape(&upper), &params(), &|_| false);
        assert_eq!(c.len(), 4);
        assert!(
            c.iter().all(|k| !k.tied && k.alternatives.is_empty()),
            "{c:#?}"
        );
    }

    #[test]
    fn crossed_edges_give_one_edge_edge_contact() {
        let r1 = rotation_xyz_degrees([45.0, 0.0, 0.0]);
        let r2 = rotation_xyz_degrees([0.0, 45.0, 0.0]);
        let s = 2f64.sqrt();
        let a = owned(box_vertices([2.0; 3], [0.0; 3], &r1));
        let b = owned(box_vertices([2.0; 3], [0.0, 0.0, 2.0 * s + 0.01], &r2));
        let c = detect_pair(0, &shape(&a), 1, &shape(&b), &params(), &|_| false);
        assert_eq!(c.len(), 1, "{c:#?}");
        assert_eq!(c[0].mode(), ContactMode::EdgeEdge);
        assert!((c[0].gap - 0.01).abs() < 1e-12);
        // The normal points from j toward i.
        let dir = if c[0].key.i == 1 {
            Vec3::z()
        } else {
            -Vec3::z()
        };
        assert!((c[0].normal - dir).norm() < 1e-12);
    }

    #[test]
    fn far_blocks_have_no_contacts_and_broad_phase_skips_them() {
        let a = owned(box_vertices([1.0; 3], [0.0; 3], &Mat3::identity()));
        let b = owned(box_vertices([1.0; 3], [3.0, 0.0, 0.0], &Mat3::identity()));
        let d = owned(box_vertices([1.0; 3], [0.0, 0.0, 1.05], &Mat3::identity()));
        let shapes = [shape(&a), shape(&b), shape(&d)];
        assert_eq!(broad_phase(&shapes, 0.125), vec![(0, 2)]);
        let c = detect_pair(0, &shapes[0], 2, &shapes[2], &params(), &|_| false);
        assert_eq!(c.len(), 4, "gap 5 cm < d_s = 12.5 cm");
    }
}
