//! The order of the hull's faces and of each face's corners, as the former O(n⁴) enumeration
//! of vertex triples produced it: vertex numbers follow from it, and every result downstream
//! (block CSV columns, contact lists) depends on them.

use crate::physics::geometry::{Vec3, any_perpendicular, newell_normal};

/// Orders the faces and picks each ring's first vertex as the former enumeration did. It found
/// a face at the first triple of its points (i < j < k, in input order) not collinear within
/// `tol`, so faces come in the order of that triple; it then wrote the face's corners by a 2-D
/// hull in a basis (u, v) built from that triple's normal, which starts at the smallest (u, v).
/// Both are recomputed here with the same arithmetic, on the original coordinates.
pub(super) fn order(pts: &[Vec3], rings: Vec<Vec<usize>>, tol: f64, diag: f64) -> Vec<Vec<usize>> {
    let mut keyed: Vec<([usize; 4], Vec<usize>)> = rings
        .into_iter()
        .enumerate()
        .map(|(at, ring)| {
            // A face with no such triple (degenerate; the former code dropped it) goes last.
            let Some(([i, j, k], mut nrm)) = discovery(pts, &ring, tol, diag) else {
                return ([usize::MAX, usize::MAX, usize::MAX, at], ring);
            };
            if nrm.dot(&newell_normal(pts, &ring)) < 0.0 {
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

/// The first triple of a face's corners, in index order, that the former enumeration accepted
/// as spanning a plane, with that plane's unit normal as it computed it.
fn discovery(pts: &[Vec3], ring: &[usize], tol: f64, diag: f64) -> Option<([usize; 3], Vec3)> {
    // Most faces are small: sort them on the stack.
    let mut buf = [0usize; 16];
    let mut heap = Vec::new();
    let c: &mut [usize] = if ring.len() <= buf.len() {
        buf[..ring.len()].copy_from_slice(ring);
        &mut buf[..ring.len()]
    } else {
        heap.extend_from_slice(ring);
        &mut heap
    };
    c.sort_unstable();
    for (x, &i) in c.iter().enumerate() {
        for (y, &j) in c.iter().enumerate().skip(x + 1) {
            for &k in &c[y + 1..] {
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
