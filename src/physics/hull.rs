//! The convex hull behind [`convex_hull`](super::geometry::convex_hull), in O(n log n).
//!
//! Three stages, each with one job:
//! 1. Quickhull on exact orientation predicates (`robust::orient3d`, Shewchuk's adaptive
//!    arithmetic). Every "is this point above that triangle" is answered exactly, so the
//!    triangulated hull is always a closed convex surface, whatever the rounding: the visible
//!    region from a new point is a disc and its horizon a single loop. A float distance answers
//!    instead only where a proven error bound says its sign is the exact one (nearly always),
//!    and ranks points (which is farthest), where an error costs time, never validity.
//! 2. Triangles that lie within the tolerance of one plane are merged into one polygon face (a
//!    box comes out as six quads), growing each face from its largest triangle so that it stays
//!    a disc with a simple boundary. Vertices left on the boundary between only two faces are
//!    points on an edge, and are dropped.
//! 3. The faces are put in the order, and each starts at the vertex, that the former O(n⁴)
//!    enumeration of vertex triples produced ([`canonical`]), so that vertex numbering, and every
//!    result that depends on it, is unchanged: the tests compare the two on boxes, dodecahedra,
//!    prisms, the scenes' blocks and thousands of random and gridded clouds.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

use super::geometry::{GeometryError, Vec3};

/// No triangle: the end of a list, or a missing neighbour.
const NONE: u32 = u32::MAX;

/// A triangle of the hull under construction, counter-clockwise seen from outside.
struct Tri {
    v: [u32; 3],
    /// `adj[e]` is the triangle across the edge `v[e] -> v[e + 1]`.
    adj: [u32; 3],
    /// Unit outward normal and area, in floating point: they rank points and seed faces.
    n: Vec3,
    area: f64,
    /// A bound on the rounding error of `n · (x − v[0])` for any point x of the (scaled) cloud:
    /// beyond it the float sign is the exact one, and orient3d is not needed.
    sure: f64,
    /// Points strictly above this triangle (exactly), and which of them is farthest.
    outside: Vec<u32>,
    far: u32,
    far_d: f64,
    alive: bool,
    /// Stamps of the last search that found this triangle visible, or tested it and not.
    seen: u32,
    hidden: u32,
}

/// Removes points closer than `tol` to a point kept before them, keeping the first of each
/// cluster in input order (what the former pairwise scan did), with a grid so that the scan
/// costs O(n) rather than O(n²).
pub(super) fn dedup(points: &[Vec3], lo: &Vec3, tol: f64) -> Vec<Vec3> {
    // Cells 8·tol wide: a ball of radius tol crosses into a neighbouring cell along an axis only
    // a quarter of the time, so most points look into one or two cells. The bounding box is at
    // most 1/(8e-7) = 1.25e6 cells across, so a cell's coordinates (shifted by one for the
    // neighbours below the box) pack into 21 bits each.
    let cell = 8.0 * tol;
    let key =
        |i: i64, j: i64, k: i64| ((i + 1) as u64) | ((j + 1) as u64) << 21 | ((k + 1) as u64) << 42;
    let mut heads: HashMap<u64, u32, BuildHasherDefault<CellHasher>> = HashMap::default();
    let mut next: Vec<u32> = Vec::new();
    let mut kept: Vec<Vec3> = Vec::new();
    for p in points {
        let f = (p - lo) / cell;
        // A neighbour within tol is at most an eighth of a cell away; the margin covers the
        // rounding of the cell coordinates, so no cell that may hold one is skipped.
        let span = |x: f64| (x - 0.125 - 1e-6).floor() as i64..=(x + 0.125 + 1e-6).floor() as i64;
        let mut near = false;
        'search: for i in span(f.x) {
            for j in span(f.y) {
                for k in span(f.z) {
                    let mut m = heads.get(&key(i, j, k)).copied().unwrap_or(NONE);
                    while m != NONE {
                        if (kept[m as usize] - p).norm() <= tol {
                            near = true;
                            break 'search;
                        }
                        m = next[m as usize];
                    }
                }
            }
        }
        if !near {
            let home = key(f.x.floor() as i64, f.y.floor() as i64, f.z.floor() as i64);
            let head = heads.entry(home).or_insert(NONE);
            next.push(*head);
            *head = kept.len() as u32;
            kept.push(*p);
        }
    }
    kept
}

/// A multiplicative hash for packed cell keys: SipHash's resistance to crafted keys buys
/// nothing here and costs a third of the scan.
#[derive(Default)]
struct CellHasher(u64);

impl Hasher for CellHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for b in bytes {
            self.write_u64(u64::from(*b));
        }
    }
    fn write_u64(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(5) ^ x).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
}

/// The faces of the hull of `pts` (distinct points, at least four), as counter-clockwise rings
/// of indices into `pts`, in the former enumeration's order. `tol` is the distance under which a
/// point is on a plane and `diag` the size of the point set.
pub(super) fn faces(pts: &[Vec3], tol: f64, diag: f64) -> Result<Vec<Vec<usize>>, GeometryError> {
    // Scaling by a power of two is exact and keeps every product in orient3d far from overflow
    // and underflow, where its arithmetic would stop being exact.
    let reach = pts.iter().fold(0.0f64, |m, p| m.max(p.amax()));
    let scale = 2f64.powi(-(reach.log2().ceil() as i32));
    // The points in Morton order: points near in space are near in memory, so the outside
    // sets, which hold points near each other, are read with fewer cache misses. The order
    // changes nothing in the result: `order[k]` is the index in `pts` of the k-th point hulled.
    let order = morton_order(pts);
    let q: Vec<Vec3> = order.iter().map(|&i| pts[i] * scale).collect();
    let mut hull = Quickhull::new(&q, tol * scale)?;
    hull.run()?;
    let mut rings = merge_coplanar(&hull, tol * scale)?;
    drop_edge_points(&mut rings, pts.len());
    for v in rings.iter_mut().flatten() {
        *v = order[*v];
    }
    Ok(canonical::order(pts, rings, tol, diag))
}

/// Indices of `pts` sorted along a Z-order curve through their bounding box.
fn morton_order(pts: &[Vec3]) -> Vec<usize> {
    // Spreads the low 21 bits of x so that two zero bits follow each.
    fn spread(x: u64) -> u64 {
        let mut x = x & 0x1f_ffff;
        x = (x | x << 32) & 0x1f_0000_0000_ffff;
        x = (x | x << 16) & 0x1f_0000_ff00_00ff;
        x = (x | x << 8) & 0x100f_00f0_0f00_f00f;
        x = (x | x << 4) & 0x10c3_0c30_c30c_30c3;
        (x | x << 2) & 0x1249_2492_4924_9249
    }
    let (lo, hi) = super::geometry::bounding_box(pts);
    let cells = ((1u64 << 21) - 1) as f64;
    let side = (hi - lo).map(|s| if s > 0.0 { cells / s } else { 0.0 });
    let mut keyed: Vec<(u64, usize)> = pts
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let c = (p - lo).component_mul(&side).map(|x| x as u64);
            (spread(c.x) | spread(c.y) << 1 | spread(c.z) << 2, i)
        })
        .collect();
    keyed.sort_unstable();
    keyed.into_iter().map(|(_, i)| i).collect()
}

struct Quickhull<'a> {
    p: &'a [Vec3],
    tris: Vec<Tri>,
    free: Vec<u32>,
    stack: Vec<u32>,
    stamp: u32,
}

impl<'a> Quickhull<'a> {
    /// The starting tetrahedron with every other point in the outside set of a face, or `Flat`
    /// if the points lie within `tol` of a line or a plane.
    fn new(p: &'a [Vec3], tol: f64) -> Result<Self, GeometryError> {
        let s = initial_simplex(p, tol)?;
        let mut hull = Quickhull {
            p,
            tris: Vec::new(),
            free: Vec::new(),
            stack: Vec::new(),
            stamp: 0,
        };
        for (i, j, k, o) in [(0, 1, 2, 3), (0, 3, 1, 2), (1, 3, 2, 0), (2, 3, 0, 1)] {
            let mut v = [s[i], s[j], s[k]];
            if hull.above(&v, s[o]) {
                v.swap(1, 2);
            }
            hull.add(v, [NONE; 3]);
        }
        for f in 0..4 {
            for e in 0..3 {
                let (a, b) = (hull.tris[f].v[e], hull.tris[f].v[(e + 1) % 3]);
                let g = (0..4)
                    .find(|&g| {
                        (0..3).any(|x| hull.tris[g].v[x] == b && hull.tris[g].v[(x + 1) % 3] == a)
                    })
                    .expect("a tetrahedron is closed");
                hull.tris[f].adj[e] = g as u32;
            }
        }
        let rest = (0..p.len() as u32).filter(|i| !s.contains(i));
        hull.assign(rest, &[0, 1, 2, 3]);
        Ok(hull)
    }

    /// Exactly: is point `i` strictly above triangle `t`? The float distance decides where it
    /// is larger than its error bound, orient3d where it is not.
    fn sees(&self, t: &Tri, i: u32) -> bool {
        let d = t.n.dot(&(self.p[i as usize] - self.p[t.v[0] as usize]));
        if d.abs() > t.sure {
            return d > 0.0;
        }
        self.above(&t.v, i)
    }

    /// Exactly: is point `i` strictly above the plane of the counter-clockwise triangle `v`?
    fn above(&self, v: &[u32; 3], i: u32) -> bool {
        let c = |k: u32| {
            let x = self.p[k as usize];
            robust::Coord3D {
                x: x.x,
                y: x.y,
                z: x.z,
            }
        };
        robust::orient3d(c(v[0]), c(v[1]), c(v[2]), c(i)) < 0.0
    }

    fn add(&mut self, v: [u32; 3], adj: [u32; 3]) -> u32 {
        let [a, b, c] = v.map(|k| self.p[k as usize]);
        let cross = (b - a).cross(&(c - a));
        let len = cross.norm();
        // A freed slot's point list keeps its capacity: no allocation per triangle.
        let mut outside = match self.free.last() {
            Some(&f) => std::mem::take(&mut self.tris[f as usize].outside),
            None => Vec::new(),
        };
        outside.clear();
        // Rounding of the differences, the cross product and the dot product, for coordinates
        // within [-1, 1] (so |x − a| < 4): at most ε (88 |b − a| |c − a| / |cross| + 32); twice
        // that, to be sure. A degenerate triangle (len = 0) always goes to orient3d.
        let sure = 256.0 * f64::EPSILON * (b - a).norm() * (c - a).norm() / len;
        let tri = Tri {
            v,
            adj,
            n: if len > 0.0 { cross / len } else { cross },
            area: len / 2.0,
            sure: if len > 0.0 { sure } else { f64::INFINITY },
            outside,
            far: NONE,
            far_d: f64::NEG_INFINITY,
            alive: true,
            seen: 0,
            hidden: 0,
        };
        match self.free.pop() {
            Some(f) => {
                self.tris[f as usize] = tri;
                f
            }
            None => {
                self.tris.push(tri);
                self.tris.len() as u32 - 1
            }
        }
    }

    /// Gives each point to the triangle among `cands` it is farthest above, if it is above any;
    /// a point above none is inside the hull and is dropped for good.
    fn assign(&mut self, points: impl Iterator<Item = u32>, cands: &[u32]) {
        for i in points {
            let x = self.p[i as usize];
            let (mut best, mut best_d) = (NONE, f64::NEG_INFINITY);
            for &f in cands {
                let t = &self.tris[f as usize];
                let d = t.n.dot(&(x - self.p[t.v[0] as usize]));
                if d > best_d && (d > t.sure || (d >= -t.sure && self.above(&t.v, i))) {
                    (best, best_d) = (f, d);
                }
            }
            if best != NONE {
                let t = &mut self.tris[best as usize];
                t.outside.push(i);
                if best_d > t.far_d {
                    (t.far, t.far_d) = (i, best_d);
                }
            }
        }
        for &f in cands {
            if !self.tris[f as usize].outside.is_empty() {
                self.stack.push(f);
            }
        }
    }

    fn run(&mut self) -> Result<(), GeometryError> {
        let mut visible: Vec<u32> = Vec::new();
        let mut horizon: Vec<(u32, u32, u32, u32)> = Vec::new();
        let mut orphans: Vec<u32> = Vec::new();
        let mut cone: Vec<u32> = Vec::new();
        while let Some(f) = self.stack.pop() {
            let t = &self.tris[f as usize];
            if !t.alive || t.outside.is_empty() {
                continue;
            }
            let apex = t.far;
            self.stamp += 1;
            let stamp = self.stamp;
            // The triangles the apex sees, and the horizon: their edges (a, b) to triangles it
            // does not see, each with that neighbour h and h's index of the edge.
            visible.clear();
            horizon.clear();
            visible.push(f);
            self.tris[f as usize].seen = stamp;
            let mut k = 0;
            while k < visible.len() {
                let g = visible[k] as usize;
                for e in 0..3 {
                    let h = self.tris[g].adj[e];
                    let th = &self.tris[h as usize];
                    if th.seen == stamp {
                        continue;
                    }
                    if th.hidden != stamp && self.sees(th, apex) {
                        self.tris[h as usize].seen = stamp;
                        visible.push(h);
                    } else {
                        self.tris[h as usize].hidden = stamp;
                        let (a, b) = (self.tris[g].v[e], self.tris[g].v[(e + 1) % 3]);
                        let th = &self.tris[h as usize];
                        let eh = (0..3)
                            .find(|&x| th.v[x] == b)
                            .ok_or(GeometryError::NotClosed)?;
                        horizon.push((a, b, h, eh as u32));
                    }
                }
                k += 1;
            }
            orphans.clear();
            for &g in &visible {
                let t = &mut self.tris[g as usize];
                t.alive = false;
                orphans.extend(t.outside.drain(..).filter(|&i| i != apex));
                self.free.push(g);
            }
            let ring = chain(&mut horizon)?;
            cone.clear();
            for &(a, b, h, eh) in &ring {
                let t = self.add([a, b, apex], [h, NONE, NONE]);
                self.tris[h as usize].adj[eh as usize] = t;
                cone.push(t);
            }
            let m = cone.len();
            for j in 0..m {
                self.tris[cone[j] as usize].adj[1] = cone[(j + 1) % m];
                self.tris[cone[j] as usize].adj[2] = cone[(j + m - 1) % m];
            }
            self.assign(orphans.iter().copied(), &cone);
        }
        Ok(())
    }
}

/// Orders the horizon edges into one loop, each edge's end the next one's start. Exact
/// predicates make the horizon a single simple loop; anything else is reported, not built on.
fn chain(edges: &mut [(u32, u32, u32, u32)]) -> Result<Vec<(u32, u32, u32, u32)>, GeometryError> {
    edges.sort_unstable_by_key(|e| e.0);
    if edges.len() < 3 || edges.windows(2).any(|w| w[0].0 == w[1].0) {
        return Err(GeometryError::NotClosed);
    }
    let mut ring = Vec::with_capacity(edges.len());
    let mut e = edges[0];
    for _ in 0..edges.len() {
        ring.push(e);
        let k = edges
            .binary_search_by_key(&e.1, |x| x.0)
            .map_err(|_| GeometryError::NotClosed)?;
        e = edges[k];
    }
    if e != edges[0] {
        return Err(GeometryError::NotClosed);
    }
    Ok(ring)
}

/// Four points spanning a tetrahedron: the two farthest apart of the six axis-extreme points,
/// the point farthest from their line and the point farthest from the plane of the three.
fn initial_simplex(p: &[Vec3], tol: f64) -> Result<[u32; 4], GeometryError> {
    let mut ext = Vec::with_capacity(6);
    for axis in 0..3 {
        let key = |&i: &usize| p[i][axis];
        ext.push(
            (0..p.len())
                .min_by(|a, b| key(a).total_cmp(&key(b)))
                .unwrap_or(0),
        );
        ext.push(
            (0..p.len())
                .max_by(|a, b| key(a).total_cmp(&key(b)))
                .unwrap_or(0),
        );
    }
    let (mut a, mut b, mut best) = (0, 0, -1.0);
    for &i in &ext {
        for &j in &ext {
            let d = (p[i] - p[j]).norm();
            if d > best {
                (a, b, best) = (i, j, d);
            }
        }
    }
    let farthest = |dist: &dyn Fn(&Vec3) -> f64| {
        (0..p.len())
            .map(|i| (dist(&p[i]), i))
            .fold((-1.0, 0), |m, x| if x.0 > m.0 { x } else { m })
    };
    let u = (p[b] - p[a]).normalize();
    let (dc, c) = farthest(&|x| (x - p[a]).cross(&u).norm());
    if dc <= tol {
        return Err(GeometryError::Flat);
    }
    let n = (p[b] - p[a]).cross(&(p[c] - p[a])).normalize();
    let (dd, d) = farthest(&|x| n.dot(&(x - p[a])).abs());
    if dd <= tol {
        return Err(GeometryError::Flat);
    }
    Ok([a, b, c, d].map(|i| i as u32))
}

/// Grows polygon faces over the triangulated hull: from the largest triangle not yet in a face,
/// adds neighbouring triangles whose corners all lie within `tol` of the face's plane, as long
/// as the face stays a disc. The plane is the seed's at first, then the area-weighted mean plane
/// of what was gathered, and the face is grown again: the plane of one small triangle of a
/// noisy face may be tilted by the noise, the mean of many is not. Returns each face's
/// boundary, counter-clockwise.
fn merge_coplanar(h: &Quickhull, tol: f64) -> Result<Vec<Vec<usize>>, GeometryError> {
    let live: Vec<u32> = (0..h.tris.len() as u32)
        .filter(|&t| h.tris[t as usize].alive)
        .collect();
    // Largest first; a positive float's bits order as the float does.
    let mut seeds: Vec<(std::cmp::Reverse<u64>, u32)> = live
        .iter()
        .map(|&t| (std::cmp::Reverse(h.tris[t as usize].area.to_bits()), t))
        .collect();
    seeds.sort_unstable();
    let mut g = Grower {
        h,
        tol,
        face: vec![NONE; h.tris.len()],
        on_rim: vec![0; h.p.len()],
        members: Vec::new(),
        queue: Vec::new(),
    };
    let mut n_faces = 0;
    for &(_, s) in &seeds {
        if g.face[s as usize] != NONE {
            continue;
        }
        let r = n_faces;
        n_faces += 1;
        let seed = &h.tris[s as usize];
        // A sliver thinner than the tolerance has a normal that rounding may have turned
        // anywhere: it stays a face of its own rather than gather neighbours by it.
        let longest = (0..3)
            .map(|e| (h.p[seed.v[e] as usize] - h.p[seed.v[(e + 1) % 3] as usize]).norm())
            .fold(0.0, f64::max);
        let trusted = 2.0 * seed.area > tol * longest;
        let mut plane = (seed.n, h.p[seed.v[0] as usize]);
        let mut size = 0;
        g.members.clear();
        for _ in 0..4 {
            g.grow(s, r, plane, trusted);
            // One triangle is its own mean plane: nothing to refit.
            if g.members.len() == size || g.members.len() == 1 || !trusted {
                break;
            }
            size = g.members.len();
            plane = g.mean_plane();
        }
    }
    boundaries(h, &live, &g.face, n_faces)
}

/// The state of [`merge_coplanar`]: the face of each triangle, and the face being grown.
struct Grower<'h, 'p> {
    h: &'h Quickhull<'p>,
    tol: f64,
    face: Vec<u32>,
    /// Boundary edges of the face being grown that meet at each vertex.
    on_rim: Vec<u32>,
    members: Vec<u32>,
    queue: Vec<u32>,
}

impl Grower<'_, '_> {
    /// Face `r` afresh from triangle `s` (what `members` held of it is undone first): every triangle reachable across its edges whose
    /// corners are within tol of `plane` (normal, point), and that joins without making the
    /// face other than a disc: along one edge with its third corner off the face's boundary
    /// (else the boundary would touch itself there), or along two.
    fn grow(&mut self, s: u32, r: u32, plane: (Vec3, Vec3), spread: bool) {
        let h = self.h;
        for t in self.members.drain(..) {
            self.face[t as usize] = NONE;
        }
        self.queue.clear();
        self.queue.push(s);
        let (n, o) = plane;
        while let Some(t) = self.queue.pop() {
            let tri = &h.tris[t as usize];
            let off = |&v: &u32| n.dot(&(h.p[v as usize] - o)).abs() > self.tol;
            if self.face[t as usize] != NONE || (t != s && tri.v.iter().any(off)) {
                continue;
            }
            let shared = tri.adj.map(|a| self.face[a as usize] == r);
            let fits = match shared.iter().filter(|&&x| x).count() {
                0 => t == s,
                1 => {
                    let e = shared.iter().position(|&x| x).unwrap_or(0);
                    self.on_rim[tri.v[(e + 2) % 3] as usize] == 0
                }
                2 => true,
                _ => false,
            };
            if !fits {
                continue;
            }
            self.face[t as usize] = r;
            self.members.push(t);
            for (e, &inner) in shared.iter().enumerate() {
                for v in [tri.v[e], tri.v[(e + 1) % 3]] {
                    let c = &mut self.on_rim[v as usize];
                    *c = if inner { *c - 1 } else { *c + 1 };
                }
                if !inner && spread {
                    self.queue.push(tri.adj[e]);
                }
            }
        }
        for &t in &self.members {
            for v in h.tris[t as usize].v {
                self.on_rim[v as usize] = 0;
            }
        }
    }

    /// The area-weighted mean plane of the face's triangles: normal and centroid.
    fn mean_plane(&self) -> (Vec3, Vec3) {
        let (mut n, mut c, mut a) = (Vec3::zeros(), Vec3::zeros(), 0.0);
        for &t in &self.members {
            let tri = &self.h.tris[t as usize];
            let centroid = tri.v.iter().map(|&v| self.h.p[v as usize]).sum::<Vec3>() / 3.0;
            n += tri.n * tri.area;
            c += centroid * tri.area;
            a += tri.area;
        }
        (n.normalize(), c / a)
    }
}

/// The boundary loop of each face: the triangle edges whose neighbour is in another face,
/// chained end to start.
fn boundaries(
    h: &Quickhull,
    live: &[u32],
    face: &[u32],
    n_faces: u32,
) -> Result<Vec<Vec<usize>>, GeometryError> {
    let mut rim: Vec<(u32, u32, u32)> = Vec::new();
    for &t in live {
        let tri = &h.tris[t as usize];
        for e in 0..3 {
            if face[tri.adj[e] as usize] != face[t as usize] {
                rim.push((face[t as usize], tri.v[e], tri.v[(e + 1) % 3]));
            }
        }
    }
    rim.sort_unstable();
    let mut rings = Vec::with_capacity(n_faces as usize);
    let mut start = 0;
    while start < rim.len() {
        let r = rim[start].0;
        let end = start + rim[start..].partition_point(|x| x.0 == r);
        let edges = &rim[start..end];
        if edges.windows(2).any(|w| w[0].1 == w[1].1) {
            return Err(GeometryError::NotClosed);
        }
        let mut ring = Vec::with_capacity(edges.len());
        let mut v = edges[0].1;
        for _ in 0..edges.len() {
            ring.push(v as usize);
            let k = edges
                .binary_search_by_key(&v, |x| x.1)
                .map_err(|_| GeometryError::NotClosed)?;
            v = edges[k].2;
        }
        if v != edges[0].1 {
            return Err(GeometryError::NotClosed);
        }
        rings.push(ring);
        start = end;
    }
    Ok(rings)
}

/// Drops the vertices that only two faces share: points on an edge between two corners. A
/// face that would keep fewer than three corners keeps all of its own, and so does its
/// neighbour, so that the two always agree about the edge.
fn drop_edge_points(rings: &mut [Vec<usize>], n_points: usize) {
    let mut count = vec![0u32; n_points];
    for &v in rings.iter().flatten() {
        count[v] += 1;
    }
    let mut drop: Vec<bool> = count.iter().map(|&c| c == 2).collect();
    loop {
        let mut changed = false;
        for ring in rings.iter() {
            let gone = ring.iter().filter(|&&v| drop[v]).count();
            if gone > 0 && ring.len() - gone < 3 {
                for &v in ring {
                    changed |= drop[v];
                    drop[v] = false;
                }
            }
        }
        if !changed {
            break;
        }
    }
    for ring in rings {
        ring.retain(|&v| !drop[v]);
    }
}

mod canonical;
#[cfg(test)]
mod reference;
#[cfg(test)]
mod tests;
