//! Shapes for the tests, and the checks every cut must pass (reference §2.5): closed, convex,
//! outward pieces; volume conserved; no gap and no overlap; joint faces in balanced pairs.

use std::collections::HashMap;

use nalgebra::Rotation3;
use rand::Rng;
use rand_chacha::ChaCha8Rng;

use super::super::{CutOptions, CutOutcome, Piece, Plane, Polyhedron, Vec3};
use super::super::{piece_order, snap_tolerance, split};

/// The box [lo, hi]; vertex k has x from bit 0, y from bit 1, z from bit 2.
pub(super) fn box_region(lo: Vec3, hi: Vec3) -> Polyhedron {
    let vertices = (0..8)
        .map(|k| {
            Vec3::new(
                if k & 1 == 0 { lo.x } else { hi.x },
                if k & 2 == 0 { lo.y } else { hi.y },
                if k & 4 == 0 { lo.z } else { hi.z },
            )
        })
        .collect();
    let faces = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
    ];
    Polyhedron {
        vertices,
        faces: faces.iter().map(|f| f.to_vec()).collect(),
    }
}

pub(super) fn unit_cube() -> Polyhedron {
    box_region(Vec3::zeros(), Vec3::repeat(1.0))
}

/// The prism of height `h` over the convex polygon `base` (CCW seen from +z, at z = 0).
pub(super) fn prism(base: &[(f64, f64)], h: f64) -> Polyhedron {
    let m = base.len();
    let mut vertices: Vec<Vec3> = base.iter().map(|&(x, y)| Vec3::new(x, y, 0.0)).collect();
    vertices.extend(base.iter().map(|&(x, y)| Vec3::new(x, y, h)));
    let mut faces = vec![(0..m).rev().collect::<Vec<_>>(), (m..2 * m).collect()];
    faces.extend((0..m).map(|i| vec![i, (i + 1) % m, m + (i + 1) % m, m + i]));
    Polyhedron { vertices, faces }
}

/// `p` rotated about the origin, then shifted.
pub(super) fn moved(p: &Polyhedron, rotation: &Rotation3<f64>, shift: Vec3) -> Polyhedron {
    Polyhedron {
        vertices: p.vertices.iter().map(|v| rotation * v + shift).collect(),
        faces: p.faces.clone(),
    }
}

/// The plane n·x = offset for a normal of any length.
pub(super) fn plane(n: Vec3, offset: f64) -> Plane {
    let len = n.norm();
    Plane {
        normal: n / len,
        offset: offset / len,
    }
}

/// The upward unit normal of a plane of dip / dip direction in degrees, (R1.1).
pub(super) fn pole(dip: f64, dip_direction: f64) -> Vec3 {
    let (sd, cd) = dip.to_radians().sin_cos();
    let (sa, ca) = dip_direction.to_radians().sin_cos();
    Vec3::new(sa * sd, ca * sd, cd)
}

pub(super) fn options(min_volume: f64, max_aspect: f64) -> CutOptions {
    CutOptions {
        min_volume,
        max_aspect,
        aspect_length: f64::INFINITY,
        max_blocks: 100_000,
    }
}

/// A uniformly random unit vector.
pub(super) fn direction(rng: &mut ChaCha8Rng) -> Vec3 {
    loop {
        let v = Vec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        );
        let n = v.norm();
        if n > 0.1 && n < 1.0 {
            return v / n;
        }
    }
}

/// Outward face planes (unit normal, offset) of a region, by Newell's normal.
fn region_planes(r: &Polyhedron) -> Vec<(Vec3, f64)> {
    r.faces
        .iter()
        .map(|f| {
            let n = split::newell(&r.vertices, f).normalize();
            let d = f.iter().map(|&i| n.dot(&r.vertices[i])).sum::<f64>() / f.len() as f64;
            (n, d)
        })
        .collect()
}

/// Outward face planes of a piece, exact where known: a tagged face's joint plane (signed by the
/// face's orientation), else the plane of the region face it lies on.
fn piece_planes(p: &Piece, sets: &[Vec<Plane>], region: &[(Vec3, f64)]) -> Vec<(Vec3, f64)> {
    p.faces
        .iter()
        .zip(&p.face_planes)
        .map(|(ring, tag)| {
            let n = split::newell(&p.vertices, ring);
            match tag {
                Some((s, k)) => {
                    let q = sets[*s][*k];
                    if n.dot(&q.normal) > 0.0 {
                        (q.normal, q.offset)
                    } else {
                        (-q.normal, -q.offset)
                    }
                }
                None => *region
                    .iter()
                    .max_by(|a, b| n.dot(&a.0).total_cmp(&n.dot(&b.0)))
                    .unwrap(),
            }
        })
        .collect()
}

/// Every check of the reference §2.5 on one outcome. `volume_tol`: relative tolerance of
/// kept + dropped = domain volume; `points`: random points for the gap/overlap test.
pub(super) fn check(
    regions: &[Polyhedron],
    sets: &[Vec<Plane>],
    out: &CutOutcome,
    rng: &mut ChaCha8Rng,
    points: usize,
    volume_tol: f64,
) {
    let eps = snap_tolerance(regions);
    let region: Vec<Vec<(Vec3, f64)>> = regions.iter().map(region_planes).collect();
    let all: Vec<&Piece> = out.kept.iter().chain(&out.dropped).collect();
    let planes: Vec<Vec<(Vec3, f64)>> = all
        .iter()
        .map(|p| piece_planes(p, sets, &region[p.region]))
        .collect();
    for (p, pl) in all.iter().zip(&planes) {
        check_piece(p, pl, sets, eps);
    }
    let r = &out.report;
    let kept: f64 = out.kept.iter().map(|p| p.volume).sum();
    let dropped: f64 = out.dropped.iter().map(|p| p.volume).sum();
    assert_eq!(r.volume, kept);
    assert_eq!(r.dropped_volume, dropped);
    assert_eq!(r.dropped, out.dropped.len());
    let domain: f64 = regions
        .iter()
        .map(|p| split::volume_centroid(&p.vertices, p.faces.iter().map(Vec::as_slice)).0)
        .sum();
    assert!((r.domain_volume - domain).abs() <= 1e-12 * domain);
    let err = (kept + dropped - domain).abs() / domain;
    assert!(err <= volume_tol, "volume error {err:e}");
    assert_eq!(r.skipped_cuts, 0);
    for list in [&out.kept, &out.dropped] {
        assert!(list.windows(2).all(|w| piece_order(&w[0], &w[1]).is_le()));
    }
    check_cover(regions, &region, &all, &planes, rng, points);
    check_areas(sets, &all);
    if r.rejected_cuts == 0 {
        check_twins(&all, eps);
    }
}

/// One piece: a closed, Euler-valid, convex polyhedron with outward faces, its vertices all
/// corners within ε of the inner side of every face plane, its joint faces on their planes.
fn check_piece(p: &Piece, planes: &[(Vec3, f64)], sets: &[Vec<Plane>], eps: f64) {
    let tol = 1.01 * eps;
    assert_eq!(p.faces.len(), p.face_planes.len());
    assert!(p.faces.len() >= 4);
    let mut used = vec![0usize; p.vertices.len()];
    let mut edges = Vec::new();
    for ring in &p.faces {
        assert!(ring.len() >= 3);
        let mut sorted = ring.clone();
        sorted.sort_unstable();
        sorted.dedup();
        assert_eq!(sorted.len(), ring.len(), "a vertex twice in a ring");
        for (&a, &b) in ring.iter().zip(ring.iter().cycle().skip(1)) {
            used[a] += 1;
            edges.push((a, b));
        }
    }
    // A corner has at least three faces, or two nearly parallel ones whose shared edge bends
    // there by more than ε (split::corners_only); never a point on a straight edge.
    for ring in &p.faces {
        for (k, &v) in ring.iter().enumerate() {
            let a = p.vertices[ring[(k + ring.len() - 1) % ring.len()]];
            let b = p.vertices[ring[(k + 1) % ring.len()]];
            let x = p.vertices[v];
            let t = ((x - a).dot(&(b - a)) / (b - a).norm_squared()).clamp(0.0, 1.0);
            let off = (a + (b - a) * t - x).norm();
            assert!(
                used[v] >= 3 || (used[v] == 2 && off > eps),
                "not a corner: {p:?}"
            );
        }
    }
    let mut coords: Vec<[u64; 3]> = p
        .vertices
        .iter()
        .map(|v| v.map(f64::to_bits).into())
        .collect();
    coords.sort_unstable();
    coords.dedup();
    assert_eq!(coords.len(), p.vertices.len(), "duplicate vertices");
    edges.sort_unstable();
    assert!(
        edges.windows(2).all(|w| w[0] != w[1]),
        "a directed edge twice"
    );
    for &(a, b) in &edges {
        assert!(edges.binary_search(&(b, a)).is_ok(), "an open edge");
    }
    let (v, e, f) = (p.vertices.len(), edges.len() / 2, p.faces.len());
    assert_eq!(v + f, e + 2, "Euler");
    assert!(p.volume > 0.0);
    for ((ring, (n, d)), tag) in p.faces.iter().zip(planes).zip(&p.face_planes) {
        for x in &p.vertices {
            assert!(n.dot(x) - d <= tol, "not convex by {:e}", n.dot(x) - d);
        }
        assert!(n.dot(&p.centroid) < *d, "centroid outside");
        let newell = split::newell(&p.vertices, ring);
        let mean = ring.iter().map(|&i| p.vertices[i]).sum::<Vec3>() / ring.len() as f64;
        assert!(newell.dot(&(mean - p.centroid)) > 0.0, "an inward face");
        if let Some((s, k)) = tag {
            let q = sets[*s][*k];
            assert!(
                ring.iter()
                    .all(|&i| q.signed_distance(&p.vertices[i]).abs() <= tol)
            );
        }
    }
    for (set, count) in sets.iter().zip(&p.sides) {
        let above = set.iter().filter(|q| q.normal.dot(&p.centroid) > q.offset);
        assert_eq!(above.count() as u32, *count);
    }
}

/// Random points of the domain (away from region faces) lie in at least one piece when the
/// faces are pushed out by a band, and in at most one when pulled in by it.
fn check_cover(
    regions: &[Polyhedron],
    region: &[Vec<(Vec3, f64)>],
    pieces: &[&Piece],
    planes: &[Vec<(Vec3, f64)>],
    rng: &mut ChaCha8Rng,
    points: usize,
) {
    let all = regions.iter().flat_map(|r| r.vertices.iter());
    let (lo, hi) = crate::physics::geometry::bounding_box(all);
    let band = 1e-7 * (hi - lo).norm();
    let boxes: Vec<(Vec3, Vec3)> = pieces
        .iter()
        .map(|p| crate::physics::geometry::bounding_box(p.vertices.iter()))
        .collect();
    let mut found = 0;
    let mut tries = 0;
    while found < points {
        tries += 1;
        assert!(tries < 1000 * points, "cannot sample the domain");
        let x = Vec3::from_fn(|k, _| rng.random_range(lo[k]..hi[k]));
        let inside =
            |pl: &[(Vec3, f64)], margin: f64| pl.iter().all(|(n, d)| n.dot(&x) - d <= margin);
        if !region.iter().any(|pl| inside(pl, -band)) {
            continue;
        }
        found += 1;
        let near = |k: &usize| {
            let (a, b) = boxes[*k];
            (0..3).all(|i| x[i] >= a[i] - band && x[i] <= b[i] + band)
        };
        let candidates: Vec<usize> = (0..pieces.len()).filter(near).collect();
        let loose = candidates
            .iter()
            .filter(|&&k| inside(&planes[k], band))
            .count();
        let strict = candidates
            .iter()
            .filter(|&&k| inside(&planes[k], -band))
            .count();
        assert!(loose >= 1, "a gap at {x:?}");
        assert!(strict <= 1, "an overlap at {x:?}");
    }
}

/// On every joint plane the faces on its + side and on its − side have the same area.
fn check_areas(sets: &[Vec<Plane>], pieces: &[&Piece]) {
    let mut area: HashMap<(usize, usize), (f64, f64)> = HashMap::new();
    for p in pieces {
        for (ring, tag) in p.faces.iter().zip(&p.face_planes) {
            let Some((s, k)) = tag else { continue };
            let n = split::newell(&p.vertices, ring);
            let e = area.entry((*s, *k)).or_default();
            if n.dot(&sets[*s][*k].normal) > 0.0 {
                e.0 += n.norm() / 2.0;
            } else {
                e.1 += n.norm() / 2.0;
            }
        }
    }
    for (tag, (a, b)) in area {
        assert!(
            (a - b).abs() <= 1e-9 * a.max(b),
            "plane {tag:?}: {a} vs {b}"
        );
    }
}

/// Conforming faces: every joint face has exactly one twin in another piece, facing the other
/// way, with bitwise the same points, or, where the output dropped a vertex that was a corner on
/// one side only (`split::corners_only`), with each point of one that the other lacks within
/// 4ε of the other's boundary.
fn check_twins(pieces: &[&Piece], eps: f64) {
    type Key = Vec<[u64; 3]>;
    let mut faces: HashMap<Key, Vec<(usize, Vec3)>> = HashMap::new();
    let mut rings: HashMap<Key, (usize, Vec<Vec3>)> = HashMap::new();
    for (k, p) in pieces.iter().enumerate() {
        for (ring, tag) in p.faces.iter().zip(&p.face_planes) {
            if tag.is_none() {
                continue;
            }
            let mut key: Key = ring
                .iter()
                .map(|&i| p.vertices[i].map(f64::to_bits).into())
                .collect();
            key.sort_unstable();
            let n = split::newell(&p.vertices, ring);
            faces.entry(key.clone()).or_default().push((k, n));
            rings.insert(key, (k, ring.iter().map(|&i| p.vertices[i]).collect()));
        }
    }
    let mut single: Vec<(usize, Vec<Vec3>, Vec3)> = Vec::new();
    for (key, found) in &faces {
        match found.as_slice() {
            [(a, n), (b, m)] => assert!(a != b && n.dot(m) < 0.0),
            [(_, n)] => single.push((rings[key].0, rings[key].1.clone(), *n)),
            _ => panic!("a joint face {} times", found.len()),
        }
    }
    let near = |x: &Vec3, ring: &[Vec3]| {
        ring.iter().any(|y| y == x)
            || ring.iter().zip(ring.iter().cycle().skip(1)).any(|(a, b)| {
                let t = ((x - a).dot(&(b - a)) / (b - a).norm_squared()).clamp(0.0, 1.0);
                (a + (b - a) * t - x).norm() <= 4.0 * eps
            })
    };
    for (k, ring, n) in &single {
        let twins = single.iter().filter(|(j, other, m)| {
            j != k
                && n.dot(m) < 0.0
                && ring.iter().all(|x| near(x, other))
                && other.iter().all(|x| near(x, ring))
        });
        assert_eq!(twins.count(), 1, "a joint face without its twin: {ring:?}");
    }
}
