//! The seeded property test: random convex domains (boxes, prisms, two stacked boxes; rotated
//! and shifted) cut by 1–4 random sets of 1–6 planes, with planes forced through vertices and
//! edges of the domain, sets 1e-4 rad apart, and scattered orientations within a set. Every
//! outcome must pass every check of the reference §2.5.

use std::f64::consts::TAU;

use nalgebra::{Rotation3, Unit};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::super::{Plane, Polyhedron, Vec3, cut_all, split};
use super::checks::{box_region, check, direction, moved, options, prism};

/// A convex polygon: 3 to 7 points on a circle, at least 0.2 rad apart.
fn polygon(rng: &mut ChaCha8Rng) -> Vec<(f64, f64)> {
    loop {
        let m = rng.random_range(3..8);
        let mut angles: Vec<f64> = (0..m).map(|_| rng.random_range(0.0..TAU)).collect();
        angles.sort_by(f64::total_cmp);
        let wrap = angles[0] + TAU - angles[m - 1];
        if wrap < 0.2 || angles.windows(2).any(|w| w[1] - w[0] < 0.2) {
            continue;
        }
        let r = rng.random_range(0.5..2.0);
        return angles.iter().map(|a| (r * a.cos(), r * a.sin())).collect();
    }
}

fn domain(rng: &mut ChaCha8Rng) -> Vec<Polyhedron> {
    let size = Vec3::from_fn(|_, _| rng.random_range(0.3..3.0));
    let shapes = match rng.random_range(0..3) {
        0 => vec![box_region(Vec3::zeros(), size)],
        1 => vec![prism(&polygon(rng), size.z)],
        _ => {
            let split_at = Vec3::new(size.x, size.y, size.z * rng.random_range(0.2..0.8));
            vec![
                box_region(Vec3::zeros(), split_at),
                box_region(Vec3::new(0.0, 0.0, split_at.z), size),
            ]
        }
    };
    let rotation = if rng.random_bool(0.7) {
        Rotation3::from_axis_angle(
            &Unit::new_normalize(direction(rng)),
            rng.random_range(0.0..TAU),
        )
    } else {
        Rotation3::identity()
    };
    let shift = Vec3::from_fn(|_, _| rng.random_range(-5.0..5.0));
    shapes.iter().map(|s| moved(s, &rotation, shift)).collect()
}

/// `n` turned by `angle` about a random axis square to it.
fn tilt(n: Vec3, angle: f64, rng: &mut ChaCha8Rng) -> Vec3 {
    let u = n.cross(&direction(rng)).normalize();
    (n * angle.cos() + u * angle.sin()).normalize()
}

/// One plane of a set of normal `n`: through a vertex, through two vertices (an edge or a
/// diagonal), through three, through the case's hub (a point inside the domain that planes of
/// several sets share, so that four or more planes meet in one point), or at a random offset
/// across (and a little beyond) the domain.
fn random_plane(rng: &mut ChaCha8Rng, n: Vec3, scatter: bool, verts: &[Vec3], hub: &Vec3) -> Plane {
    let n = if scatter {
        tilt(n, rng.random_range(0.0..0.3), rng)
    } else {
        n
    };
    let mut pick = || verts[rng.random_range(0..verts.len())];
    let (a, b, c) = (pick(), pick(), pick());
    match rng.random_range(0..10) {
        0 | 1 => Plane::through(n, &a),
        4 | 5 => Plane::through(n, hub),
        2 if a != b => {
            let m = (b - a).cross(&n);
            if m.norm() > 1e-3 * (b - a).norm() {
                Plane::through(m.normalize(), &a)
            } else {
                Plane::through(n, &a)
            }
        }
        3 => {
            let m = (b - a).cross(&(c - a));
            if m.norm() > 1e-3 * (b - a).norm() * (c - a).norm() {
                Plane::through(m.normalize(), &a)
            } else {
                Plane::through(n, &a)
            }
        }
        _ => {
            let t: Vec<f64> = verts.iter().map(|v| n.dot(v)).collect();
            let lo = t.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = t.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let pad = 0.1 * (hi - lo);
            Plane {
                normal: n,
                offset: rng.random_range(lo - pad..hi + pad),
            }
        }
    }
}

/// The sets of a case. Now and then the vertices of the pieces cut by the sets so far join the
/// points that later planes are forced through, so that planes pass exactly through corners made
/// by earlier cuts.
fn sets(rng: &mut ChaCha8Rng, regions: &[Polyhedron]) -> Vec<Vec<Plane>> {
    let mut verts: Vec<Vec3> = regions.iter().flat_map(|r| r.vertices.clone()).collect();
    let weights: Vec<f64> = verts.iter().map(|_| rng.random_range(0.0..1.0)).collect();
    let hub = verts
        .iter()
        .zip(&weights)
        .map(|(v, w)| v * *w)
        .sum::<Vec3>()
        / weights.iter().sum::<f64>();
    let mut sets: Vec<Vec<Plane>> = Vec::new();
    let mut last = direction(rng);
    for _ in 0..rng.random_range(1..=4) {
        if !sets.is_empty() && rng.random_bool(0.4) {
            let out = cut_all(regions, &sets, &options(0.0, f64::INFINITY)).unwrap();
            verts.extend(out.kept.iter().flat_map(|p| p.vertices.iter().copied()));
        }
        // Nearly parallel to the previous set now and then.
        let n = if !sets.is_empty() && rng.random_bool(0.3) {
            tilt(last, 1e-4, rng)
        } else {
            direction(rng)
        };
        let scatter = rng.random_bool(0.3);
        let planes = (0..rng.random_range(1..=6))
            .map(|_| random_plane(rng, n, scatter, &verts, &hub))
            .collect();
        sets.push(planes);
        last = n;
    }
    sets
}

/// Runs `cases` random cases from `seed`; returns (pieces, rejected cuts, dropped pieces, cases
/// without rejections, where the twin faces were checked).
fn run(seed: u64, cases: usize) -> (usize, usize, usize, usize) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (mut pieces, mut rejected, mut dropped, mut conforming) = (0, 0, 0, 0);
    for case in 0..cases {
        let regions = domain(&mut rng);
        let sets = sets(&mut rng, &regions);
        let volume: f64 = regions
            .iter()
            .map(|p| split::volume_centroid(&p.vertices, p.faces.iter().map(Vec::as_slice)).0)
            .sum();
        let min_volume = if rng.random_bool(0.3) {
            1e-3 * volume
        } else {
            0.0
        };
        let max_aspect = [20.0, 100.0, f64::INFINITY][rng.random_range(0..3)];
        let out = cut_all(&regions, &sets, &options(min_volume, max_aspect))
            .unwrap_or_else(|e| panic!("seed {seed}, case {case}: {e}"));
        let mut points = ChaCha8Rng::seed_from_u64(case as u64);
        check(&regions, &sets, &out, &mut points, 2000, 1e-9);
        pieces += out.kept.len() + out.dropped.len();
        rejected += out.report.rejected_cuts;
        dropped += out.report.dropped;
        conforming += usize::from(out.report.rejected_cuts == 0);
    }
    println!(
        "seed {seed}, {cases} cases: {pieces} pieces, {rejected} cuts rejected, {dropped} \
         dropped, {conforming} cases without rejections (twin faces checked)"
    );
    (pieces, rejected, dropped, conforming)
}

#[test]
fn random_cuts_give_closed_convex_conforming_blocks() {
    let (pieces, rejected, dropped, conforming) = run(0x14, 300);
    assert!(pieces > 3000 && rejected > 0 && dropped > 0 && conforming > 100);
}

/// The same on 60 000 cases (about 90 s in release): `cargo test --release -- --ignored`.
#[test]
#[ignore = "long: 60 000 random cases"]
fn many_random_cuts() {
    for seed in 1..=3 {
        run(seed, 20_000);
    }
}
