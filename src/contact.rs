//! Contacts between convex polyhedra: detection (broad phase on bounding boxes, vertex-to-face and
//! edge-to-edge entrance modes), the normal distance and its linearisation (P3)–(P8), and the
//! contact submatrices (P10), (P15), (P20).

use crate::geometry::{Topology, Vec3};
use crate::mechanics::{Mat3x12, Mat12, Vec12, displacement_matrix};
pub use crate::snapshot::{ContactMode, ContactState};

/// Identity of a contact across steps: the blocks and the features that touch.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ContactKey {
    /// Block owning the vertex (V–F) or the first edge (E–E).
    pub i: u32,
    /// Block owning the face (V–F) or the second edge (E–E).
    pub j: u32,
    pub mode: u8,
    /// Vertex index in i (V–F) or edge index in i (E–E).
    pub feature_i: u32,
    /// Face index in j (V–F) or edge index in j (E–E).
    pub feature_j: u32,
}

impl ContactKey {
    pub fn mode(&self) -> ContactMode {
        if self.mode == 0 {
            ContactMode::VertexFace
        } else {
            ContactMode::EdgeEdge
        }
    }
}

/// A block as contact detection sees it at the start of a step.
#[derive(Clone, Debug)]
pub struct Shape<'a> {
    pub vertices: &'a [Vec3],
    pub topo: &'a Topology,
    /// Unit outward face normals.
    pub face_normals: &'a [Vec3],
    pub centroid: Vec3,
    pub lo: Vec3,
    pub hi: Vec3,
    pub fixed: bool,
}

/// Tolerances of the narrow phase (reference §4, §10).
#[derive(Clone, Copy, Debug)]
pub struct DetectionParams {
    /// d_s: contacts are sought up to this gap.
    pub search_distance: f64,
    /// d_pen: deepest penetration still treated as a contact.
    pub max_penetration: f64,
    /// ε_in: slack of the point-in-face test, m.
    pub inside_tolerance: f64,
    /// sin θ_a of the entrance-angle tests (θ_a ≈ 3°).
    pub sin_entrance: f64,
    /// sin θ_p below which two edges count as parallel (θ_p ≈ 3°).
    pub sin_parallel: f64,
    /// ε_e: margin of the edge parameters of an edge-edge contact.
    pub edge_margin: f64,
    /// Contacts of one block pair closer than this are one physical constraint.
    pub merge_distance: f64,
}

impl DetectionParams {
    /// Shi's control lengths for a model of half-extent `w0` and displacement ratio δ.
    pub fn new(w0: f64, delta: f64) -> Self {
        let ds = 2.5 * delta * w0;
        let sin3 = 3f64.to_radians().sin();
        DetectionParams {
            search_distance: ds,
            max_penetration: 0.3 * ds,
            inside_tolerance: 1e-6 * w0,
            sin_entrance: sin3,
            sin_parallel: sin3,
            edge_margin: 1e-3,
            merge_distance: 1e-3 * ds,
        }
    }
}

/// A contact found at the start of a step, with its frozen geometry.
#[derive(Clone, Debug)]
pub struct Candidate {
    pub key: ContactKey,
    /// P1…P4 of (5.1): V–F: the vertex, then three corners of the face; E–E: the edge of i,
    /// then the edge of j.
    pub points: [Vec3; 4],
    /// Unit normal out of block j toward block i.
    pub normal: Vec3,
    /// Signed gap, m (negative when penetrating).
    pub gap: f64,
    /// Contact point on block i (the vertex, or the closest point of edge i).
    pub xa: Vec3,
    /// Closest point of block j to `xa`.
    pub xb: Vec3,
}

impl Candidate {
    pub fn mode(&self) -> ContactMode {
        self.key.mode()
    }
}

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

/// Three well-spread corners of a face for the determinant (5.1).
fn face_triple(face: &[usize]) -> [usize; 3] {
    let k = face.len();
    [face[0], face[k / 3], face[(2 * k) / 3]]
}

/// Vertex-to-face candidates of the vertices of `a` against the faces of `b` (reference §4.3).
/// Per vertex only the face with the largest signed gap is kept (the common-plane rule).
fn vertex_face(
    ia: usize,
    a: &Shape,
    ib: usize,
    b: &Shape,
    p: &DetectionParams,
    out: &mut Vec<Candidate>,
) {
    let lo = b.lo - Vec3::repeat(p.search_distance);
    let hi = b.hi + Vec3::repeat(p.search_distance);
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
        if (0..3).any(|d| pv[d] < lo[d] || pv[d] > hi[d]) {
            continue;
        }
        let mut best: Option<Candidate> = None;
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
            if best.as_ref().is_some_and(|c| c.gap >= gap) {
                continue;
            }
            let [t1, t2, t3] = face_triple(face);
            best = Some(Candidate {
                key: ContactKey {
                    i: ia as u32,
                    j: ib as u32,
                    mode: 0,
                    feature_i: vi as u32,
                    feature_j: fi as u32,
                },
                points: [pv, b.vertices[t1], b.vertices[t2], b.vertices[t3]],
                normal: n,
                gap,
                xa: pv,
                xb: pv - n * gap,
            });
        }
        out.extend(best);
    }
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
    let lo = b.lo - Vec3::repeat(p.search_distance);
    let hi = b.hi + Vec3::repeat(p.search_distance);
    for (ea_i, ea) in a.topo.edges.iter().enumerate() {
        let (p1, p2) = (a.vertices[ea.v[0]], a.vertices[ea.v[1]]);
        if (0..3).any(|d| p1[d].max(p2[d]) < lo[d] || p1[d].min(p2[d]) > hi[d]) {
            continue;
        }
        let e1 = p2 - p1;
        for (eb_i, eb) in b.topo.edges.iter().enumerate() {
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
            if gap0.abs() > p.search_distance.max(p.max_penetration) {
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
    known: &dyn Fn(&ContactKey) -> bool,
) -> Vec<Candidate> {
    let mut all = Vec::new();
    vertex_face(a, sa, b, sb, p, &mut all);
    vertex_face(b, sb, a, sa, p, &mut all);
    edge_edge(a, sa, b, sb, p, &mut all);
    all.sort_by(|x, y| {
        known(&y.key)
            .cmp(&known(&x.key))
            .then(y.gap.total_cmp(&x.gap))
            .then(x.key.cmp(&y.key))
    });
    let mut kept: Vec<Candidate> = Vec::with_capacity(all.len());
    for c in all {
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

/// Linearised normal distance of (5.1)–(5.4): d_n = d0 + G_i D_i + G_j D_j, penetration positive.
#[derive(Clone, Copy, Debug)]
pub struct NormalKinematics {
    pub d0: f64,
    pub g_i: Vec12,
    pub g_j: Vec12,
    /// A0 of (P4), frozen for the step.
    pub a0: f64,
}

/// Cofactor gradients c_r = ∂V0/∂P_r of the determinant (5.1)–(5.2).
fn cofactors(p: &[Vec3; 4]) -> [Vec3; 4] {
    let [p1, p2, p3, p4] = *p;
    [
        -(p3 - p2).cross(&(p4 - p2)),
        (p3 - p1).cross(&(p4 - p1)),
        (p4 - p1).cross(&(p2 - p1)),
        (p2 - p1).cross(&(p3 - p1)),
    ]
}

/// V0 of (5.1).
pub fn determinant(p: &[Vec3; 4]) -> f64 {
    (p[1] - p[0]).dot(&(p[2] - p[0]).cross(&(p[3] - p[0])))
}

/// d0, G_i, G_j of (P6)–(P8) with the sign fixed by (5.3): translating block i along +n must
/// reduce the penetration. `ci`, `cj` are the centroids of the two blocks at the start of the step.
pub fn normal_kinematics(
    mode: ContactMode,
    p: &[Vec3; 4],
    n: &Vec3,
    ci: &Vec3,
    cj: &Vec3,
) -> NormalKinematics {
    let c = cofactors(p);
    let (on_i, a0): (&[usize], f64) = match mode {
        ContactMode::VertexFace => (&[0], (p[2] - p[1]).cross(&(p[3] - p[1])).norm()),
        ContactMode::EdgeEdge => (&[0, 1], (p[1] - p[0]).cross(&(p[3] - p[2])).norm()),
    };
    let sum_i: Vec3 = on_i.iter().map(|&r| c[r]).sum();
    let sigma = if n.dot(&sum_i) > 0.0 { -1.0 } else { 1.0 };
    let mut g_i = Vec12::zeros();
    let mut g_j = Vec12::zeros();
    for r in 0..4 {
        if on_i.contains(&r) {
            g_i += displacement_matrix(&(p[r] - ci)).transpose() * c[r];
        } else {
            g_j += displacement_matrix(&(p[r] - cj)).transpose() * c[r];
        }
    }
    NormalKinematics {
        d0: sigma * determinant(p) / a0,
        g_i: g_i * (sigma / a0),
        g_j: g_j * (sigma / a0),
        a0,
    }
}

/// Stiffness contributions of one contact to the blocks i and j. Kept apart from the forces:
/// the ALM iterations that only update λ rebuild the forces alone, and zeroing and moving these
/// three 12×12 blocks for every contact of every iteration cost more than the forces themselves.
#[derive(Clone, Debug, Default)]
pub struct ContactStiffness {
    pub k_ii: Mat12,
    pub k_ij: Mat12,
    pub k_jj: Mat12,
}

/// Force contributions of one contact to the blocks i and j.
#[derive(Clone, Debug, Default)]
pub struct ContactForces {
    pub f_i: Vec12,
    pub f_j: Vec12,
}

/// Normal stiffness of a closed contact, (P10a)–(P10d).
pub fn add_normal_stiffness(t: &mut ContactStiffness, k: &NormalKinematics, penalty: f64) {
    t.k_ii += k.g_i * k.g_i.transpose() * penalty;
    t.k_ij += k.g_i * k.g_j.transpose() * penalty;
    t.k_jj += k.g_j * k.g_j.transpose() * penalty;
}

/// Normal force terms of a closed contact, (P10e)–(P10f): −(λ_{k−1} + p_n d0) G.
pub fn add_normal_force(t: &mut ContactForces, k: &NormalKinematics, penalty: f64, lambda: f64) {
    let s = lambda + penalty * k.d0;
    t.f_i -= k.g_i * s;
    t.f_j -= k.g_j * s;
}

/// Tangential spring of a locked contact, (P15) as corrected in (5.7): the potential
/// ½ p_τ rᵀ N r with r = Δ + T_a D_i − T_b D_j and N = I − n nᵀ. Its stiffness:
pub fn add_shear_spring_stiffness(
    t: &mut ContactStiffness,
    ta: &Mat3x12,
    tb: &Mat3x12,
    n: &Vec3,
    p_tau: f64,
) {
    let proj = nalgebra::Matrix3::identity() - n * n.transpose();
    let nta = proj * ta;
    let ntb = proj * tb;
    t.k_ii += ta.transpose() * nta * p_tau;
    t.k_ij -= ta.transpose() * ntb * p_tau;
    t.k_jj += tb.transpose() * ntb * p_tau;
}

/// The force of the tangential spring of [`add_shear_spring_stiffness`] at D = 0:
/// −p_τ T_aᵀ N Δ on i and +p_τ T_bᵀ N Δ on j.
pub fn add_shear_spring_force(
    t: &mut ContactForces,
    ta: &Mat3x12,
    tb: &Mat3x12,
    n: &Vec3,
    delta: &Vec3,
    p_tau: f64,
) {
    let nd = (delta - n * n.dot(delta)) * p_tau;
    t.f_i -= ta.transpose() * nd;
    t.f_j += tb.transpose() * nd;
}

/// Sliding friction (P20): a force of magnitude `friction` opposing the slip direction τ of
/// point a relative to point b. Loads only; the stiffness stays symmetric.
pub fn add_friction(t: &mut ContactForces, ta: &Mat3x12, tb: &Mat3x12, tau: &Vec3, friction: f64) {
    t.f_i -= ta.transpose() * tau * friction;
    t.f_j += tb.transpose() * tau * friction;
}

/// Area of the convex hull of points that lie roughly in a plane with normal `n` (used to share
/// a joint's area among its contact points for cohesion).
pub fn planar_hull_area(points: &[Vec3], n: &Vec3) -> f64 {
    if points.len() < 3 {
        return 0.0;
    }
    let u = if n.x.abs() < 0.9 {
        n.cross(&Vec3::x())
    } else {
        n.cross(&Vec3::y())
    }
    .normalize();
    let v = n.cross(&u);
    let mut p: Vec<(f64, f64)> = points.iter().map(|x| (x.dot(&u), x.dot(&v))).collect();
    p.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let cross = |o: (f64, f64), a: (f64, f64), b: (f64, f64)| {
        (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0)
    };
    let mut hull: Vec<(f64, f64)> = Vec::new();
    for &q in &p {
        while hull.len() >= 2 && cross(hull[hull.len() - 2], hull[hull.len() - 1], q) <= 0.0 {
            hull.pop();
        }
        hull.push(q);
    }
    let lower = hull.len() + 1;
    for &q in p.iter().rev().skip(1) {
        while hull.len() >= lower && cross(hull[hull.len() - 2], hull[hull.len() - 1], q) <= 0.0 {
            hull.pop();
        }
        hull.push(q);
    }
    hull.pop();
    let mut area = 0.0;
    for k in 0..hull.len() {
        let (a, b) = (hull[k], hull[(k + 1) % hull.len()]);
        area += a.0 * b.1 - b.0 * a.1;
    }
    area.abs() / 2.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Mat3, box_vertices, convex_hull, newell_normal, rotation_xyz_degrees};

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
        let c = crate::geometry::mass_properties(&v, &t.faces).centroid;
        Owned { v, t, n, c }
    }

    fn shape(o: &Owned) -> Shape<'_> {
        let (lo, hi) = crate::geometry::bounding_box(&o.v);
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
    fn signed_distance_of_a_vertex_above_and_inside_a_face() {
        // Face z = 0 of a unit cube below, CCW from outside (normal +z).
        let face = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        let n = Vec3::z();
        for (h, want) in [(0.001, -0.001), (-0.001, 0.001), (0.3, -0.3), (-0.05, 0.05)] {
            let p1 = Vec3::new(0.4, 0.3, h);
            let p = [p1, face[0], face[1], face[2]];
            // Raw determinant: V0/A0 = −gap (the paper's literal (P3) sign gives the gap).
            let a0 = (face[1] - face[0]).cross(&(face[2] - face[0])).norm();
            assert!((determinant(&p) / a0 + h).abs() < 1e-15);
            let k = normal_kinematics(
                ContactMode::VertexFace,
                &p,
                &n,
                &Vec3::new(0.5, 0.5, 0.5),
                &Vec3::new(0.5, 0.5, -0.5),
            );
            assert!((k.d0 - want).abs() < 1e-15, "h = {h}: d0 = {}", k.d0);
            // Translating the vertex block along +n reduces the penetration one for one.
            assert!((k.g_i[2] + 1.0).abs() < 1e-14);
            assert!((k.g_j[2] - 1.0).abs() < 1e-14);
        }
        // The sign does not depend on the order of the face triple.
        let p = [Vec3::new(0.4, 0.3, -0.002), face[2], face[1], face[0]];
        let k = normal_kinematics(
            ContactMode::VertexFace,
            &p,
            &n,
            &Vec3::zeros(),
            &Vec3::zeros(),
        );
        assert!((k.d0 - 0.002).abs() < 1e-15);
    }

    #[test]
    fn edge_edge_distance() {
        // Edge of i along x at height h above an edge of j along y.
        let h = 0.1;
        let p = [
            Vec3::new(-1.0, 0.0, h),
            Vec3::new(1.0, 0.0, h),
            Vec3::new(0.0, -1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        let k = normal_kinematics(
            ContactMode::EdgeEdge,
            &p,
            &Vec3::z(),
            &Vec3::new(0.0, 0.0, 1.0),
            &Vec3::new(0.0, 0.0, -1.0),
        );
        assert!((k.d0 + h).abs() < 1e-15);
        let k2 = normal_kinematics(
            ContactMode::EdgeEdge,
            &[p[0], p[1], p[3], p[2]],
            &Vec3::z(),
            &Vec3::z(),
            &Vec3::z(),
        );
        assert!((k2.d0 + h).abs() < 1e-15, "independent of edge direction");
    }

    /// G must be the derivative of the exact determinant distance σ V0(P + T D)/A0 (A0 frozen)
    /// for arbitrary increments, including rotations and strains, for both entrance modes.
    #[test]
    fn linearised_distance_matches_finite_differences() {
        let r = rotation_xyz_degrees([10.0, -20.0, 30.0]);
        let ci = Vec3::new(0.3, 0.1, 1.2);
        let cj = Vec3::new(-0.2, 0.4, -0.9);
        let cases = [
            (
                ContactMode::VertexFace,
                [
                    Vec3::new(0.2, 0.1, 0.01),
                    Vec3::new(-1.0, -1.0, 0.0),
                    Vec3::new(1.2, -0.8, 0.0),
                    Vec3::new(0.1, 1.1, 0.0),
                ],
            ),
            (
                ContactMode::EdgeEdge,
                [
                    Vec3::new(-1.0, 0.2, -0.02),
                    Vec3::new(1.0, 0.1, 0.03),
                    Vec3::new(0.1, -1.0, 0.0),
                    Vec3::new(-0.2, 1.0, 0.0),
                ],
            ),
        ];
        for (mode, pts) in cases {
            let pts = pts.map(|x| r * x);
            let n = match mode {
                ContactMode::VertexFace => r * Vec3::z(),
                ContactMode::EdgeEdge => {
                    let m = (pts[1] - pts[0]).cross(&(pts[3] - pts[2])).normalize();
                    if m.dot(&(r * Vec3::z())) > 0.0 { m } else { -m }
                }
            };
            let k = normal_kinematics(mode, &pts, &n, &ci, &cj);
            let on_i = |r: usize| r == 0 || (mode == ContactMode::EdgeEdge && r == 1);
            let sigma = k.d0 / (determinant(&pts) / k.a0);
            let exact = |di: &Vec12, dj: &Vec12| {
                let moved: [Vec3; 4] = std::array::from_fn(|r| {
                    let (c, d) = if on_i(r) { (ci, di) } else { (cj, dj) };
                    pts[r] + displacement_matrix(&(pts[r] - c)) * d
                });
                sigma * determinant(&moved) / k.a0
            };
            let h = 1e-7;
            for a in 0..12 {
                let mut e = Vec12::zeros();
                e[a] = h;
                let z = Vec12::zeros();
                let gi = (exact(&e, &z) - exact(&-e, &z)) / (2.0 * h);
                let gj = (exact(&z, &e) - exact(&z, &-e)) / (2.0 * h);
                assert!(
                    (gi - k.g_i[a]).abs() < 1e-6,
                    "{mode:?} G_i[{a}] {gi} vs {}",
                    k.g_i[a]
                );
                assert!(
                    (gj - k.g_j[a]).abs() < 1e-6,
                    "{mode:?} G_j[{a}] {gj} vs {}",
                    k.g_j[a]
                );
            }
            // Translating i along n reduces the penetration.
            let mut t = Vec12::zeros();
            t.fixed_rows_mut::<3>(0).copy_from(&(n * 1e-3));
            assert!(exact(&t, &Vec12::zeros()) < k.d0);
        }
    }

    /// Each contact submatrix is the Hessian, and its force minus the gradient at D = 0, of the
    /// contact potential: (P2) with the linearised d_n, (P11) with the projected relative
    /// displacement, (P16) for sliding friction.
    #[test]
    fn contact_submatrices_are_derivatives_of_their_potentials() {
        let r = rotation_xyz_degrees([5.0, 12.0, -7.0]);
        let ci = Vec3::new(0.0, 0.2, 0.7);
        let cj = Vec3::new(0.1, -0.3, -1.1);
        let pts = [
            Vec3::new(0.2, 0.1, -0.002),
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.2, -0.8, 0.0),
            Vec3::new(0.1, 1.1, 0.0),
        ]
        .map(|x| r * x);
        let n = r * Vec3::z();
        let k = normal_kinematics(ContactMode::VertexFace, &pts, &n, &ci, &cj);
        let (p, lambda) = (3.0e8, 1.5e4);
        let xa = pts[0];
        let xb = xa - n * 0.0015 + r * Vec3::new(2e-4, -1e-4, 0.0);
        let ta = displacement_matrix(&(xa - ci));
        let tb = displacement_matrix(&(xb - cj));
        let delta = xa - xb;
        let tau = (r * Vec3::new(0.6, 0.8, 0.0)).normalize();
        let (p_tau, fric) = (1.2e8, 7.0e3);
        let mut t = ContactStiffness::default();
        add_normal_stiffness(&mut t, &k, p);
        add_shear_spring_stiffness(&mut t, &ta, &tb, &n, p_tau);
        let mut f = ContactForces::default();
        add_normal_force(&mut f, &k, p, lambda);
        add_shear_spring_force(&mut f, &ta, &tb, &n, &delta, p_tau);
        add_friction(&mut f, &ta, &tb, &tau, fric);
        let proj = Mat3::identity() - n * n.transpose();
        let potential = |d: &[f64; 24]| {
            let di = Vec12::from_column_slice(&d[..12]);
            let dj = Vec12::from_column_slice(&d[12..]);
            let dn = k.d0 + k.g_i.dot(&di) + k.g_j.dot(&dj);
            let rr = delta + ta * di - tb * dj;
            let slip = ta * di - tb * dj;
            lambda * dn
                + 0.5 * p * dn * dn
                + 0.5 * p_tau * rr.dot(&(proj * rr))
                + fric * tau.dot(&slip)
        };
        let h = 1e-6;
        let z = [0.0; 24];
        let grad = |d0: &[f64; 24]| -> [f64; 24] {
            std::array::from_fn(|a| {
                let mut dp = *d0;
                dp[a] += h;
                let mut dm = *d0;
                dm[a] -= h;
                (potential(&dp) - potential(&dm)) / (2.0 * h)
            })
        };
        let g0 = grad(&z);
        let f: Vec<f64> = f.f_i.iter().chain(f.f_j.iter()).copied().collect();
        for a in 0..24 {
            assert!(
                (g0[a] + f[a]).abs() < 1e-6 * f.iter().map(|x| x.abs()).fold(0.0, f64::max),
                "force {a}: {} vs {}",
                -g0[a],
                f[a]
            );
        }
        let mut kfull = nalgebra::DMatrix::<f64>::zeros(24, 24);
        kfull.view_mut((0, 0), (12, 12)).copy_from(&t.k_ii);
        kfull.view_mut((0, 12), (12, 12)).copy_from(&t.k_ij);
        kfull
            .view_mut((12, 0), (12, 12))
            .copy_from(&t.k_ij.transpose());
        kfull.view_mut((12, 12), (12, 12)).copy_from(&t.k_jj);
        let scale = kfull.abs().max();
        for b in 0..24 {
            let mut e = z;
            e[b] = 1e-3;
            let gp = grad(&e);
            for a in 0..24 {
                let fd = (gp[a] - g0[a]) / 1e-3;
                assert!(
                    (fd - kfull[(a, b)]).abs() < 1e-6 * scale,
                    "K[{a},{b}] {fd} vs {}",
                    kfull[(a, b)]
                );
            }
        }
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

    #[test]
    fn hull_area() {
        let pts = [
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(2.0, 0.0, 1.0),
            Vec3::new(2.0, 3.0, 1.0),
            Vec3::new(0.0, 3.0, 1.0),
            Vec3::new(1.0, 1.0, 1.0),
        ];
        assert!((planar_hull_area(&pts, &Vec3::z()) - 6.0).abs() < 1e-12);
    }
}
