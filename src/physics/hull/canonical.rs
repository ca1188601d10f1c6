//! The order of the hull's faces and of each face's corners, as the former O(n⁴) enumeration
//! of vertex triples produced it: vertex numbers follow from it, and every result downstream
//! (block CSV columns, contact lists) depends on them.
//!
//! That enumeration knew a face by all the points on its plane, corners or not (a point in the
//! middle of a face or on an edge could be what it met first), so those are found here too,
//! with a tree of boxes over the faces: a point that is not a corner looks only at the few
//! faces whose box it is in.

use crate::physics::geometry::{Vec3, any_perpendicular, newell_normal};

/// Orders the faces and picks each ring's first vertex as the former enumeration did. It found
/// a face at the first triple of its points (i < j < k, in input order) not collinear within
/// `tol`, so faces come in the order of that triple; it then wrote the face's corners by a 2-D
/// hull in a basis (u, v) built from that triple's normal, which starts at the smallest (u, v).
/// Both are recomputed here with the same arithmetic, on the original coordinates.
pub(super) fn order(pts: &[Vec3], rings: Vec<Vec<usize>>, tol: f64, diag: f64) -> Vec<Vec<usize>> {
    let planes: Vec<(Vec3, f64)> = rings
        .iter()
        .map(|ring| {
            let n = newell_normal(pts, ring).normalize();
            let d = ring.iter().map(|&m| n.dot(&pts[m])).sum::<f64>() / ring.len() as f64;
            (n, d)
        })
        .collect();
    let extra = points_on_faces(pts, &rings, &planes, tol);
    let mut on = Vec::new();
    let mut keyed: Vec<([usize; 4], Vec<usize>)> = rings
        .into_iter()
        .enumerate()
        .map(|(at, ring)| {
            // A face with no such triple (degenerate; the former code dropped it) goes last.
            let n = planes[at].0;
            on.clear();
            on.extend_from_slice(&ring);
            on.extend_from_slice(&extra[at]);
            on.sort_unstable();
            let Some(([i, j, k], mut nrm)) = discovery(pts, &on, tol, diag) else {
                return ([usize::MAX, usize::MAX, usize::MAX, at], ring);
            };
            if nrm.dot(&n) < 0.0 {
                nrm = -nrm;
            }
            let u = any_perpendicular(&nrm);
            let v = nrm.cross(&u);
            let uv = |m: usize| (pts[m].dot(&u), pts[m].dot(&v));
            let first = (0..ring.len())
                .min_by(|&a, &b| {
                    let (pa, pb) = (uv(ring[a]), uv(ring[b]));
                    pa.0.total_cmp(&pb.0).then(pa.1.total_cmp(&pb.1))
                })
                .unwrap_or(0);
            let mut ring = ring;
            ring.rotate_left(first);
            ([i, j, k, at], ring)
        })
        .collect();
    keyed.sort_unstable_by_key(|(key, _)| *key);
    keyed.into_iter().map(|(_, ring)| ring).collect()
}

/// The first triple of a face's points (`on`, sorted), in index order, that the former
/// enumeration accepted as spanning a plane, with that plane's unit normal as it computed it.
fn discovery(pts: &[Vec3], on: &[usize], tol: f64, diag: f64) -> Option<([usize; 3], Vec3)> {
    for (x, &i) in on.iter().enumerate() {
        for (y, &j) in on.iter().enumerate().skip(x + 1) {
            for &k in &on[y + 1..] {
                let nrm = (pts[j] - pts[i]).cross(&(pts[k] - pts[i]));
                let len = nrm.norm();
                if len > tol * diag {
                    return Some(([i, j, k], nrm / len));
                }
            }
        }
    }
    None
}

/// For each face, the points that are not corners of any face but lie on it: within `tol` of
/// its plane, inside its bounding box grown by `tol`. (A point off the polygon but on its plane
/// extended, which the former code also counted, lies on a neighbouring face almost coplanar
/// with it; then only the order can differ, never the hull.)
fn points_on_faces(
    pts: &[Vec3],
    rings: &[Vec<usize>],
    planes: &[(Vec3, f64)],
    tol: f64,
) -> Vec<Vec<usize>> {
    let mut corner = vec![false; pts.len()];
    for &m in rings.iter().flatten() {
        corner[m] = true;
    }
    let mut extra = vec![Vec::new(); rings.len()];
    let others: Vec<usize> = (0..pts.len()).filter(|&m| !corner[m]).collect();
    if others.is_empty() {
        return extra;
    }
    let boxes: Vec<(Vec3, Vec3)> = rings
        .iter()
        .map(|ring| {
            let t = Vec3::repeat(tol);
            ring.iter()
                .fold((pts[ring[0]] - t, pts[ring[0]] + t), |(lo, hi), &m| {
                    (lo.inf(&(pts[m] - t)), hi.sup(&(pts[m] + t)))
                })
        })
        .collect();
    let mut test = |m: usize, f: usize| {
        let (p, (n, d), (lo, hi)) = (&pts[m], planes[f], boxes[f]);
        if within(p, &lo, &hi) && (n.dot(p) - d).abs() <= tol {
            extra[f].push(m);
        }
    };
    // A handful of points (a scanned surface has hardly any that are not corners) are cheaper
    // to test against every face than a tree is to build; both find the same.
    if others.len() <= 16 {
        for &m in &others {
            (0..rings.len()).for_each(|f| test(m, f));
        }
        return extra;
    }
    let tree = Tree::new(&boxes);
    let mut stack = Vec::new();
    for &m in &others {
        tree.visit(&pts[m], &mut stack, |f| test(m, f));
    }
    extra
}

fn within(p: &Vec3, lo: &Vec3, hi: &Vec3) -> bool {
    (0..3).all(|a| lo[a] <= p[a] && p[a] <= hi[a])
}

/// Items per leaf of a [`Tree`].
const LEAF: usize = 4;

/// A bounding-box tree over items (faces) in Morton order of their boxes' centres, implicit:
/// node 1 is the root, node k has children 2k and 2k + 1, and the leaves start at
/// `first_leaf`, each over `LEAF` consecutive items of `order`.
struct Tree {
    order: Vec<usize>,
    lo: Vec<Vec3>,
    hi: Vec<Vec3>,
    first_leaf: usize,
}

impl Tree {
    fn new(boxes: &[(Vec3, Vec3)]) -> Self {
        let centres: Vec<Vec3> = boxes.iter().map(|(lo, hi)| (lo + hi) / 2.0).collect();
        let order = super::morton_order(&centres);
        let first_leaf = order.len().div_ceil(LEAF).next_power_of_two();
        let mut lo = vec![Vec3::repeat(f64::INFINITY); 2 * first_leaf];
        let mut hi = vec![Vec3::repeat(f64::NEG_INFINITY); 2 * first_leaf];
        for (l, run) in order.chunks(LEAF).enumerate() {
            for &i in run {
                lo[first_leaf + l] = lo[first_leaf + l].inf(&boxes[i].0);
                hi[first_leaf + l] = hi[first_leaf + l].sup(&boxes[i].1);
            }
        }
        for k in (1..first_leaf).rev() {
            lo[k] = lo[2 * k].inf(&lo[2 * k + 1]);
            hi[k] = hi[2 * k].sup(&hi[2 * k + 1]);
        }
        Tree {
            order,
            lo,
            hi,
            first_leaf,
        }
    }

    /// Calls `f` on every item in a leaf whose box holds `p`.
    fn visit(&self, p: &Vec3, stack: &mut Vec<usize>, mut f: impl FnMut(usize)) {
        stack.clear();
        stack.push(1);
        while let Some(k) = stack.pop() {
            if !within(p, &self.lo[k], &self.hi[k]) {
                continue;
            }
            if k < self.first_leaf {
                stack.extend([2 * k, 2 * k + 1]);
            } else {
                let l = (k - self.first_leaf) * LEAF;
                self.order[l..(l + LEAF).min(self.order.len())]
                    .iter()
                    .for_each(|&i| f(i));
            }
        }
    }
}
