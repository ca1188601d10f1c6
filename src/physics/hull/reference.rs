//! The former convex hull, O(n⁴), kept to check that the fast one returns the same vertices,
//! faces and numbering (tests only).

use crate::physics::geometry::{GeometryError, Topology, Vec3, any_perpendicular, bounding_box};

/// The hull as `convex_hull` built it before it went through [`super::faces`]: candidate
/// planes through every point triple, the supporting ones kept, each face the 2-D hull of the
/// points on its plane, vertices numbered in order of first appearance.
pub(super) fn convex_hull_reference(
    points: &[Vec3],
) -> Result<(Vec<Vec3>, Topology), GeometryError> {
    for (i, p) in points.iter().enumerate() {
        if !(p.x.is_finite() && p.y.is_finite() && p.z.is_finite()) {
            return Err(GeometryError::NonFinite(i));
        }
    }
    if points.len() < 4 {
        return Err(GeometryError::TooFewVertices(points.len()));
    }
    let (lo, hi) = bounding_box(points);
    let diag = (hi - lo).norm();
    if diag == 0.0 {
        return Err(GeometryError::Flat);
    }
    // Points closer than this to a plane are on it. Loose enough for coordinates typed with
    // four or five significant digits, tight enough to keep real faces apart.
    let tol = 1e-7 * diag;
    let mut pts: Vec<Vec3> = Vec::new();
    for p in points {
        if pts.iter().all(|q| (q - p).norm() > tol) {
            pts.push(*p);
        }
    }
    let n = pts.len();
    if n < 4 {
        return Err(GeometryError::Merged(n));
    }

    // Supporting planes, each with the set of points lying on it.
    let mut planes: Vec<(Vec3, Vec<usize>)> = Vec::new();
    for i in 0..n {
        for j in i + 1..n {
            for k in j + 1..n {
                if planes
                    .iter()
                    .any(|(_, on)| on.contains(&i) && on.contains(&j) && on.contains(&k))
                {
                    continue;
                }
                let nrm = (pts[j] - pts[i]).cross(&(pts[k] - pts[i]));
                let len = nrm.norm();
                if len <= tol * diag {
                    continue; // collinear triple
                }
                let mut nrm = nrm / len;
                let d = nrm.dot(&pts[i]);
                let (mut above, mut below) = (false, false);
                for p in &pts {
                    let s = nrm.dot(p) - d;
                    above |= s > tol;
                    below |= s < -tol;
                }
                if above && below {
                    continue;
                }
                if !above && !below {
                    return Err(GeometryError::Flat);
                }
                if above {
                    nrm = -nrm;
                }
                let on: Vec<usize> = (0..n)
                    .filter(|&m| (nrm.dot(&pts[m]) - nrm.dot(&pts[i])).abs() <= tol)
                    .collect();
                planes.push((nrm, on));
            }
        }
    }
    if planes.len() < 4 {
        return Err(GeometryError::Flat);
    }

    // Order each face counter-clockwise about its outward normal and drop points that are not
    // corners (on an edge or inside the face): a 2-D convex hull in the face plane.
    let mut faces: Vec<Vec<usize>> = Vec::with_capacity(planes.len());
    for (nrm, on) in &planes {
        let u = any_perpendicular(nrm);
        let v = nrm.cross(&u);
        let pts2: Vec<(f64, f64, usize)> = on
            .iter()
            .map(|&m| (pts[m].dot(&u), pts[m].dot(&v), m))
            .collect();
        let ring = convex_hull_2d(pts2, tol);
        if ring.len() >= 3 {
            faces.push(ring);
        }
    }

    super::super::geometry::corners_only(&pts, faces)
}

/// Andrew's monotone chain; returns the labels of the corners in counter-clockwise order.
fn convex_hull_2d(mut p: Vec<(f64, f64, usize)>, tol: f64) -> Vec<usize> {
    p.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let cross = |o: (f64, f64, usize), a: (f64, f64, usize), b: (f64, f64, usize)| {
        (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0)
    };
    // A turn counts as a corner only if the deviation is above tolerance (cross / length).
    let turns_left = |o, a, b| {
        let c = cross(o, a, b);
        let (o, b): ((f64, f64, usize), (f64, f64, usize)) = (o, b);
        let len = ((b.0 - o.0).powi(2) + (b.1 - o.1).powi(2)).sqrt();
        c > tol * len
    };
    let mut hull: Vec<(f64, f64, usize)> = Vec::new();
    // Lower chain left to right, then the upper chain right to left; the upper pass must not
    // pop points of the lower chain.
    for (pass, floor) in [(0, 2), (1, 0)] {
        let floor = if pass == 0 { floor } else { hull.len() + 1 };
        let seq: Box<dyn Iterator<Item = &(f64, f64, usize)>> = if pass == 0 {
            Box::new(p.iter())
        } else {
            Box::new(p.iter().rev().skip(1))
        };
        for &q in seq {
            while hull.len() >= floor.max(2)
                && !turns_left(hull[hull.len() - 2], hull[hull.len() - 1], q)
            {
                hull.pop();
            }
            hull.push(q);
        }
    }
    hull.pop();
    hull.into_iter().map(|q| q.2).collect()
}
