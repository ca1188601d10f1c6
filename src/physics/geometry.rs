//! Convex polyhedra: construction from a point cloud, topology, exact mass properties, and the
//! separating-axis overlap test used to validate a scene.

use nalgebra::{Matrix3, Rotation3, Vector3};

use super::hull;
use crate::text::short;

pub type Vec3 = Vector3<f64>;
pub type Mat3 = Matrix3<f64>;

/// Why a point set is not a usable block.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GeometryError {
    #[error("needs at least four vertices, got {0}")]
    TooFewVertices(usize),
    #[error("vertex {0} is not a finite number")]
    NonFinite(usize),
    #[error("vertices are coplanar: the block has no volume")]
    Flat,
    /// After merging the points closer than the hull's tolerance (10⁻⁷ of the block's size),
    /// fewer than four are left: a needle or a sliver.
    #[error(
        "its points merge into {0} distinct corners (points closer than 1e-7 of its size are one): the block has no volume"
    )]
    Merged(usize),
    /// A coordinate beyond [`MAX_COORDINATE`]: squared lengths overflow.
    #[error("a vertex lies {} m out, beyond the {} m a coordinate may reach", short(*.0), short(MAX_COORDINATE))]
    TooFar(f64),
    #[error("the convex hull is not a closed polyhedron")]
    NotClosed,
    /// The block is too small for its distance from the origin: its corners differ in digits
    /// that f64 no longer holds, so its faces (and any motion of it) cannot be resolved.
    #[error(
        "coordinates up to {} m cannot resolve a block {} m across (f64 keeps 16 digits)",
        short(*.reach),
        short(*.size)
    )]
    Unresolved { reach: f64, size: f64 },
}

/// The smallest block size, relative to its largest coordinate, that is simulated. Below it
/// the hull's tolerance (1e-7 of the size) is under one unit in the last place of the
/// coordinates (1.1e-16 of them), so flatness and contact could only be guessed.
const RESOLUTION: f64 = 1e-9;

/// The largest coordinate a vertex may have, m (1000 times the Earth's orbit). A vertex at
/// 10³⁰⁸ m made the block's diagonal infinite and every point merge into one ("needs at least
/// four vertices, got 1").
pub const MAX_COORDINATE: f64 = 1e15;

/// An edge of a polyhedron with the two faces that meet along it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Edge {
    /// Vertex indices, `v[0] < v[1]`.
    pub v: [usize; 2],
    /// The two faces sharing the edge.
    pub faces: [usize; 2],
}

/// Topology of a convex polyhedron. Vertex positions are kept by the owner (they move every
/// step); the topology never changes.
#[derive(Clone, Debug, PartialEq)]
pub struct Topology {
    /// Faces as vertex indices, counter-clockwise seen from outside.
    pub faces: Vec<Vec<usize>>,
    pub edges: Vec<Edge>,
    /// For every vertex, the indices of the edges that meet there.
    pub vertex_edges: Vec<Vec<usize>>,
}

/// Volume, centroid and central second moments S_pq = ∫(x_p − x_c,p)(x_q − x_c,q) dV.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MassProperties {
    pub volume: f64,
    pub centroid: Vec3,
    pub second_moments: Mat3,
}

/// Builds the convex hull of `points`: the extreme points, their faces (coplanar triangles merged
/// into one polygon) and edges.
///
/// Exact about coplanar faces, which is what contact detection needs: a box comes out with six
/// quadrilaterals, not twelve triangles whose diagonals would look like edges to the
/// edge-to-edge test. O(n log n) (see [`super::hull`]): a scanned boulder of 100 000 points
/// takes a fraction of a second.
pub fn convex_hull(points: &[Vec3]) -> Result<(Vec<Vec3>, Topology), GeometryError> {
    for (i, p) in points.iter().enumerate() {
        if !(p.x.is_finite() && p.y.is_finite() && p.z.is_finite()) {
            return Err(GeometryError::NonFinite(i));
        }
    }
    if points.len() < 4 {
        return Err(GeometryError::TooFewVertices(points.len()));
    }
    let reach = points.iter().fold(0.0f64, |m, p| m.max(p.amax()));
    let (lo, hi) = bounding_box(points);
    let size = (hi - lo).max();
    if size == 0.0 {
        return Err(GeometryError::Flat);
    }
    if size < RESOLUTION * reach {
        return Err(GeometryError::Unresolved { reach, size });
    }
    if reach > MAX_COORDINATE {
        return Err(GeometryError::TooFar(reach));
    }
    let diag = (hi - lo).norm();
    // Points closer than this to a plane are on it. Loose enough for coordinates typed with
    // four or five significant digits, tight enough to keep real faces apart.
    let tol = 1e-7 * diag;
    let pts = hull::dedup(points, &lo, tol);
    let n = pts.len();
    if n < 4 {
        return Err(GeometryError::Merged(n));
    }
    let faces = hull::faces(&pts, tol, diag)?;
    corners_only(&pts, faces)
}

/// The polyhedron of `faces` (rings of indices into `pts`): only the points that are corners of
/// some face, numbered in order of first appearance, and the topology.
pub(super) fn corners_only(
    pts: &[Vec3],
    mut faces: Vec<Vec<usize>>,
) -> Result<(Vec<Vec3>, Topology), GeometryError> {
    let n = pts.len();
    let mut used = vec![usize::MAX; n];
    let mut vertices = Vec::new();
    for f in &faces {
        for &m in f {
            if used[m] == usize::MAX {
                used[m] = vertices.len();
                vertices.push(pts[m]);
            }
        }
    }
    for f in &mut faces {
        for m in f.iter_mut() {
            *m = used[*m];
        }
    }
    let topo = Topology::from_faces(vertices.len(), faces)?;
    Ok((vertices, topo))
}

pub(super) fn any_perpendicular(n: &Vec3) -> Vec3 {
    let a = if n.x.abs() < 0.9 {
        Vec3::x()
    } else {
        Vec3::y()
    };
    n.cross(&a).normalize()
}

impl Topology {
    /// Derives edges and vertex adjacency from faces; fails unless every edge has two faces.
    pub fn from_faces(n_vertices: usize, faces: Vec<Vec<usize>>) -> Result<Self, GeometryError> {
        // Sorting (edge, face) keys rather than filling a map of vectors keeps this fast without
        // an allocation per edge: a scanned block has hundreds of thousands of edges. A key is
        // (low vertex, high vertex, face) in 32 bits each, compared as one number.
        let mut sides: Vec<u128> = Vec::new();
        for (fi, f) in faces.iter().enumerate() {
            for k in 0..f.len() {
                let (a, b) = (f[k], f[(k + 1) % f.len()]);
                let key = [a.min(b), a.max(b), fi].map(|x| u128::from(x as u32));
                sides.push(key[0] << 64 | key[1] << 32 | key[2]);
            }
        }
        sides.sort_unstable();
        let mut edges = Vec::with_capacity(sides.len() / 2);
        for run in sides.chunk_by(|x, y| x >> 32 == y >> 32) {
            if run.len() != 2 {
                return Err(GeometryError::NotClosed);
            }
            let part = |x: u128, shift: u32| (x >> shift) as u32 as usize;
            edges.push(Edge {
                v: [part(run[0], 64), part(run[0], 32)],
                faces: [part(run[0], 0), part(run[1], 0)],
            });
        }
        // Euler's formula for a convex polyhedron: V − E + F = 2.
        if n_vertices + faces.len() != edges.len() + 2 {
            return Err(GeometryError::NotClosed);
        }
        let mut vertex_edges = vec![Vec::new(); n_vertices];
        for (ei, e) in edges.iter().enumerate() {
            vertex_edges[e.v[0]].push(ei);
            vertex_edges[e.v[1]].push(ei);
        }
        Ok(Topology {
            faces,
            edges,
            vertex_edges,
        })
    }
}

/// Outward normal of a planar polygon by Newell's method (robust to slight non-planarity),
/// not normalised: its length is twice the polygon's area.
pub fn newell_normal(vertices: &[Vec3], face: &[usize]) -> Vec3 {
    let mut n = Vec3::zeros();
    for k in 0..face.len() {
        let a = vertices[face[k]];
        let b = vertices[face[(k + 1) % face.len()]];
        n.x += (a.y - b.y) * (a.z + b.z);
        n.y += (a.z - b.z) * (a.x + b.x);
        n.z += (a.x - b.x) * (a.y + b.y);
    }
    n
}

/// Exact volume, centroid and central second moments by tetrahedral decomposition
/// (reference (2.1)–(2.2)); the reference point is the first vertex to limit cancellation.
pub fn mass_properties(vertices: &[Vec3], faces: &[Vec<usize>]) -> MassProperties {
    let o = vertices[0];
    let mut vol = 0.0;
    let mut first = Vec3::zeros();
    let mut second = Mat3::zeros();
    for f in faces {
        let a = vertices[f[0]] - o;
        for m in 1..f.len() - 1 {
            let b = vertices[f[m]] - o;
            let c = vertices[f[m + 1]] - o;
            let vt = a.dot(&b.cross(&c)) / 6.0;
            let s = a + b + c;
            vol += vt;
            first += s * (vt / 4.0);
            second +=
                (a * a.transpose() + b * b.transpose() + c * c.transpose() + s * s.transpose())
                    * (vt / 20.0);
        }
    }
    let rel = first / vol;
    MassProperties {
        volume: vol,
        centroid: o + rel,
        second_moments: second - rel * rel.transpose() * vol,
    }
}

/// Axis-aligned bounding box of a point set (lo > hi when there are no points).
pub fn bounding_box<'a>(points: impl IntoIterator<Item = &'a Vec3>) -> (Vec3, Vec3) {
    let mut lo = Vec3::repeat(f64::INFINITY);
    let mut hi = Vec3::repeat(f64::NEG_INFINITY);
    for p in points {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    (lo, hi)
}

/// Depth of overlap of two convex polyhedra by the separating-axis theorem: negative or zero
/// when they are apart or just touch, otherwise the smallest translation that separates them.
pub fn overlap_depth(va: &[Vec3], ta: &Topology, vb: &[Vec3], tb: &Topology) -> f64 {
    let mut axes: Vec<Vec3> = Vec::new();
    for (v, t) in [(va, ta), (vb, tb)] {
        for f in &t.faces {
            let n = newell_normal(v, f);
            if n.norm() > 0.0 {
                axes.push(n.normalize());
            }
        }
    }
    for ea in &ta.edges {
        let da = va[ea.v[1]] - va[ea.v[0]];
        for eb in &tb.edges {
            let db = vb[eb.v[1]] - vb[eb.v[0]];
            let c = da.cross(&db);
            // Near-parallel edge pairs give no new axis (their faces' normals cover them).
            if c.norm() > 1e-9 * da.norm() * db.norm() {
                axes.push(c.normalize());
            }
        }
    }
    let mut depth = f64::INFINITY;
    for axis in axes {
        let (a0, a1) = project(va, &axis);
        let (b0, b1) = project(vb, &axis);
        let d = (a1 - b0).min(b1 - a0);
        depth = depth.min(d);
        if depth < 0.0 {
            return depth;
        }
    }
    depth
}

fn project(v: &[Vec3], axis: &Vec3) -> (f64, f64) {
    v.iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
            let s = p.dot(axis);
            (lo.min(s), hi.max(s))
        })
}

/// Rotation matrix from Euler angles in degrees, applied about x, then y, then z (fixed axes).
pub fn rotation_xyz_degrees(angles: [f64; 3]) -> Mat3 {
    let [rx, ry, rz] = angles.map(f64::to_radians);
    *(Rotation3::from_axis_angle(&Vector3::z_axis(), rz)
        * Rotation3::from_axis_angle(&Vector3::y_axis(), ry)
        * Rotation3::from_axis_angle(&Vector3::x_axis(), rx))
    .matrix()
}

/// Corners of a box of the given edge lengths, centred at `center`, rotated by `rotation`.
pub fn box_vertices(size: [f64; 3], center: [f64; 3], rotation: &Mat3) -> Vec<Vec3> {
    let h = Vec3::from(size) / 2.0;
    let c = Vec3::from(center);
    let mut v = Vec::with_capacity(8);
    for sx in [-1.0, 1.0] {
        for sy in [-1.0, 1.0] {
            for sz in [-1.0, 1.0] {
                v.push(c + rotation * Vec3::new(sx * h.x, sy * h.y, sz * h.z));
            }
        }
    }
    v
}

/// The 20 corners of a regular dodecahedron of edge length `edge`, centred at `center`.
pub fn dodecahedron_vertices(edge: f64, center: [f64; 3], rotation: &Mat3) -> Vec<Vec3> {
    let phi = (1.0 + 5f64.sqrt()) / 2.0;
    let ip = 1.0 / phi;
    // The canonical coordinates have edge 2/φ.
    let s = edge * phi / 2.0;
    let c = Vec3::from(center);
    let mut raw = Vec::with_capacity(20);
    for x in [-1.0, 1.0] {
        for y in [-1.0, 1.0] {
            for z in [-1.0, 1.0] {
                raw.push(Vec3::new(x, y, z));
            }
        }
    }
    for a in [-1.0, 1.0] {
        for b in [-1.0, 1.0] {
            raw.push(Vec3::new(0.0, a * ip, b * phi));
            raw.push(Vec3::new(a * ip, b * phi, 0.0));
            raw.push(Vec3::new(a * phi, 0.0, b * ip));
        }
    }
    raw.into_iter().map(|p| c + rotation * (p * s)).collect()
}

/// A right prism: the polygon `base` (any orientation) swept by `extrude`.
pub fn prism_vertices(base: &[[f64; 3]], extrude: [f64; 3]) -> Vec<Vec3> {
    let e = Vec3::from(extrude);
    base.iter()
        .map(|p| Vec3::from(*p))
        .chain(base.iter().map(|p| Vec3::from(*p) + e))
        .collect()
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

    fn hull(points: &[Vec3]) -> (Vec<Vec3>, Topology) {
        convex_hull(points).expect("valid hull")
    }

    #[test]
    fn box_hull_has_six_quads_and_exact_moments() {
        let pts = box_vertices([2.0, 3.0, 5.0], [11.0, -2.5, 9.5], &Mat3::identity());
        let (v, t) = hull(&pts);
        assert_eq!(v.len(), 8);
        assert_eq!(t.faces.len(), 6);
        assert!(t.faces.iter().all(|f| f.len() == 4));
        assert_eq!(t.edges.len(), 12);
        let mp = mass_properties(&v, &t.faces);
        assert!((mp.volume - 30.0).abs() < 1e-12);
        assert!((mp.centroid - Vec3::new(11.0, -2.5, 9.5)).norm() < 1e-12);
        let s = mp.second_moments;
        // S_xx = V a²/12 for a box of edge a along x.
        assert!((s[(0, 0)] - 10.0).abs() < 1e-10);
        assert!((s[(1, 1)] - 22.5).abs() < 1e-10);
        assert!((s[(2, 2)] - 62.5).abs() < 1e-10);
        for (p, q) in [(0, 1), (1, 2), (0, 2)] {
            assert!(s[(p, q)].abs() < 1e-10);
        }
    }

    #[test]
    fn rotated_box_moments_rotate_as_a_tensor() {
        let r = rotation_xyz_degrees([20.0, -35.0, 50.0]);
        let pts = box_vertices([2.0, 3.0, 5.0], [1.0, 2.0, 3.0], &r);
        let (v, t) = hull(&pts);
        let mp = mass_properties(&v, &t.faces);
        let s0 = Mat3::from_diagonal(&Vec3::new(10.0, 22.5, 62.5));
        assert!((mp.second_moments - r * s0 * r.transpose()).norm() < 1e-9);
        assert!((mp.volume - 30.0).abs() < 1e-10);
    }

    #[test]
    fn dodecahedron_matches_closed_forms() {
        let a = 1.7;
        let pts = dodecahedron_vertices(a, [0.3, -0.2, 4.0], &Mat3::identity());
        let (v, t) = hull(&pts);
        assert_eq!(v.len(), 20);
        assert_eq!(t.faces.len(), 12);
        assert!(t.faces.iter().all(|f| f.len() == 5));
        assert_eq!(t.edges.len(), 30);
        for e in &t.edges {
            assert!(((v[e.v[0]] - v[e.v[1]]).norm() - a).abs() < 1e-12);
        }
        let mp = mass_properties(&v, &t.faces);
        let s5 = 5f64.sqrt();
        let vol = (15.0 + 7.0 * s5) / 4.0 * a.powi(3);
        assert!((mp.volume - vol).abs() < 1e-10 * vol);
        assert!((mp.volume - 37.648903454).abs() < 1e-8);
        let sxx = vol * a * a * (95.0 + 39.0 * s5) / 600.0;
        for p in 0..3 {
            assert!((mp.second_moments[(p, p)] - sxx).abs() < 1e-10 * sxx);
        }
        assert!((sxx - 33.041758304).abs() < 1e-8);
        for (p, q) in [(0, 1), (1, 2), (0, 2)] {
            assert!(mp.second_moments[(p, q)].abs() < 1e-9);
        }
        assert!((mp.centroid - Vec3::new(0.3, -0.2, 4.0)).norm() < 1e-12);
    }

    #[test]
    fn faces_are_counter_clockwise_from_outside() {
        let pts = dodecahedron_vertices(
            1.0,
            [5.0, 5.0, 5.0],
            &rotation_xyz_degrees([10.0, 20.0, 30.0]),
        );
        let (v, t) = hull(&pts);
        let c = mass_properties(&v, &t.faces).centroid;
        for f in &t.faces {
            let n = newell_normal(&v, f);
            assert!(n.dot(&(v[f[0]] - c)) > 0.0);
        }
    }

    #[test]
    fn interior_and_edge_points_are_dropped() {
        let mut pts = box_vertices([1.0, 1.0, 1.0], [0.0; 3], &Mat3::identity());
        pts.push(Vec3::zeros()); // interior
        pts.push(Vec3::new(0.0, -0.5, -0.5)); // mid-edge
        pts.push(Vec3::new(0.1, 0.2, 0.5)); // inside the top face
        pts.push(pts[0]); // duplicate
        let (v, t) = hull(&pts);
        assert_eq!(v.len(), 8);
        assert_eq!(t.faces.len(), 6);
    }

    #[test]
    fn degenerate_inputs_are_rejected() {
        let flat = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
        ];
        assert_eq!(convex_hull(&flat), Err(GeometryError::Flat));
        assert_eq!(
            convex_hull(&flat[..3]),
            Err(GeometryError::TooFewVertices(3))
        );
        let mut nan = flat.clone();
        nan[2].y = f64::NAN;
        assert_eq!(convex_hull(&nan), Err(GeometryError::NonFinite(2)));
    }

    #[test]
    fn triangular_prism_slope() {
        let pts = prism_vertices(
            &[[0.0, 0.0, 0.0], [10.0, 0.0, 0.0], [0.0, 0.0, 5.7735]],
            [0.0, 4.0, 0.0],
        );
        let (v, t) = hull(&pts);
        assert_eq!(v.len(), 6);
        assert_eq!(t.faces.len(), 5);
        let mp = mass_properties(&v, &t.faces);
        assert!((mp.volume - 0.5 * 10.0 * 5.7735 * 4.0).abs() < 1e-9);
    }

    #[test]
    fn separating_axis_overlap() {
        let (va, ta) = hull(&box_vertices([2.0; 3], [0.0; 3], &Mat3::identity()));
        let (vb, tb) = hull(&box_vertices([2.0; 3], [0.0, 0.0, 2.0], &Mat3::identity()));
        assert!(
            overlap_depth(&va, &ta, &vb, &tb).abs() < 1e-12,
            "touching faces"
        );
        let (vc, tc) = hull(&box_vertices([2.0; 3], [0.0, 0.0, 1.9], &Mat3::identity()));
        assert!((overlap_depth(&va, &ta, &vc, &tc) - 0.1).abs() < 1e-12);
        let (vd, td) = hull(&box_vertices([2.0; 3], [3.0, 3.0, 0.0], &Mat3::identity()));
        assert!(overlap_depth(&va, &ta, &vd, &td) < 0.0);
        // Two cubes whose edges cross diagonally: only an edge-edge axis separates them.
        let r = rotation_xyz_degrees([45.0, 0.0, 0.0]);
        let r2 = rotation_xyz_degrees([0.0, 45.0, 0.0]);
        let s = 2f64.sqrt();
        let (ve, te) = hull(&box_vertices([2.0; 3], [0.0, 0.0, 0.0], &r));
        let (vf, tf) = hull(&box_vertices([2.0; 3], [0.0, 0.0, 2.0 * s + 0.01], &r2));
        assert!(overlap_depth(&ve, &te, &vf, &tf) < 0.0);
        let (vg, tg) = hull(&box_vertices([2.0; 3], [0.0, 0.0, 2.0 * s - 0.01], &r2));
        assert!((overlap_depth(&ve, &te, &vg, &tg) - 0.01).abs() < 1e-9);
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
