//! Tests of the cut: the orthogonal cube, the degenerate planes of the reference §2.2, the slivers,
//! the Hoek–Bray wedge and the domain of §2.5, the block limit, bad input, and (in `random`) a
//! seeded property test.

mod checks;
mod random;

use std::time::Instant;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::{CutError, CutOptions, Piece, Plane, Polyhedron, Vec3, cut, cut_all};
use checks::{box_region, check, options, plane, pole, unit_cube};

fn rng() -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(14)
}

/// The cube [0, 10]³ by x = k, y = k, z = k, k = 0..=10 (the planes on the faces must not cut).
fn cube_sets() -> Vec<Vec<Plane>> {
    (0..3)
        .map(|axis| {
            (0..=10)
                .map(|k| Plane {
                    normal: Vec3::ith(axis, 1.0),
                    offset: f64::from(k),
                })
                .collect()
        })
        .collect()
}

#[test]
fn a_cube_cut_by_three_orthogonal_sets_gives_1000_unit_cubes_in_order() {
    let region = [box_region(Vec3::zeros(), Vec3::repeat(10.0))];
    let sets = cube_sets();
    let out = cut_all(&region, &sets, &options(0.0, 20.0)).unwrap();
    assert_eq!(out.kept.len(), 1000);
    assert_eq!(out.report.rejected_cuts, 0);
    for (k, p) in out.kept.iter().enumerate() {
        assert_eq!(p.vertices.len(), 8);
        assert_eq!(p.faces.len(), 6);
        assert!(p.faces.iter().all(|f| f.len() == 4));
        assert!((p.volume - 1.0).abs() <= 1e-12, "volume {}", p.volume);
        // Slab by slab along x, row by row along y, then along z.
        let expect = Vec3::new((k / 100) as f64, (k / 10 % 10) as f64, (k % 10) as f64);
        assert!((p.centroid - expect - Vec3::repeat(0.5)).norm() <= 1e-12);
        // Faces on the cube's boundary carry no tag, the others their plane.
        for (ring, tag) in p.faces.iter().zip(&p.face_planes) {
            let mean = ring.iter().map(|&i| p.vertices[i]).sum::<Vec3>() / 4.0;
            let on_boundary = mean
                .iter()
                .any(|&c| c.abs() < 1e-9 || (c - 10.0).abs() < 1e-9);
            match tag {
                None => assert!(on_boundary),
                Some((s, k)) => assert!((mean[*s] - *k as f64).abs() < 1e-12),
            }
        }
    }
    assert_eq!(out.kept[0].sides, vec![1, 1, 1]);
    assert!((out.kept[999].centroid - Vec3::repeat(9.5)).norm() <= 1e-12);
    check(&region, &sets, &out, &mut rng(), 2000, 1e-12);
}

#[test]
fn the_planes_of_a_set_may_come_in_any_order() {
    let region = [box_region(Vec3::zeros(), Vec3::new(5.0, 4.0, 3.0))];
    let mut sets = domain_sets();
    let (a, _) = cut(&region, &sets, &options(1e-3, 20.0)).unwrap();
    for set in &mut sets {
        set.reverse();
        let third = set.len() / 3;
        set.rotate_left(third);
    }
    let (b, _) = cut(&region, &sets, &options(1e-3, 20.0)).unwrap();
    assert_eq!(a.len(), b.len());
    for (p, q) in a.iter().zip(&b) {
        assert_eq!(p.vertices, q.vertices);
        assert_eq!(p.faces, q.faces);
        assert_eq!(p.volume, q.volume);
    }
}

/// Cuts the unit cube by one plane (set 0) with the aspect rule off.
fn cube_by(p: Plane) -> Vec<Piece> {
    let out = cut_all(&[unit_cube()], &[vec![p]], &options(0.0, f64::INFINITY)).unwrap();
    check(&[unit_cube()], &[vec![p]], &out, &mut rng(), 500, 1e-14);
    out.kept
}

#[test]
fn degenerate_planes_on_the_unit_cube() {
    let d = Vec3::repeat(1.0);
    // A generic cut: two 7-face halves of 0.5.
    let halves = cube_by(plane(d, 1.5));
    assert_eq!(halves.len(), 2);
    for h in &halves {
        assert_eq!(h.faces.len(), 7);
        assert!((h.volume - 0.5).abs() <= 1e-15);
    }
    // Touching a vertex, lying on a face, 1e-13 inside a face: no cut.
    for p in [
        plane(d, 0.0),
        plane(Vec3::z(), 1.0),
        plane(Vec3::z(), 1.0 - 1e-13),
        plane(Vec3::z(), 1e-13),
        plane(-Vec3::x(), 0.0),
    ] {
        let whole = cube_by(p);
        assert_eq!(whole.len(), 1, "{p:?}");
        assert_eq!(whole[0].vertices.len(), 8);
        assert!(whole[0].face_planes.iter().all(Option::is_none));
    }
    // Through three vertices: a tetrahedron of 1/6 on existing vertices, and 5/6.
    let corner = cube_by(plane(d, 1.0));
    assert_eq!(corner.len(), 2);
    let (tet, rest) = (&corner[0], &corner[1]);
    assert_eq!(tet.vertices.len(), 4);
    assert_eq!(tet.faces.len(), 4);
    assert!((tet.volume - 1.0 / 6.0).abs() <= 1e-15);
    assert!((rest.volume - 5.0 / 6.0).abs() <= 1e-15);
    assert_eq!((rest.vertices.len(), rest.faces.len()), (7, 7));
    let corners = unit_cube().vertices;
    for v in tet.vertices.iter().chain(&rest.vertices) {
        assert!(corners.contains(v), "a new vertex {v:?}");
    }
    // Through two opposite edges: two prisms, the cap on 4 existing vertices.
    let prisms = cube_by(plane(Vec3::new(1.0, -1.0, 0.0), 0.0));
    assert_eq!(prisms.len(), 2);
    for p in &prisms {
        assert_eq!((p.vertices.len(), p.faces.len()), (6, 5));
        assert!((p.volume - 0.5).abs() <= 1e-15);
        assert!(p.vertices.iter().all(|v| corners.contains(v)));
    }
}

#[test]
fn a_rotated_cube_cut_through_three_float_vertices_is_clean() {
    let rotation = nalgebra::Rotation3::from_euler_angles(0.3, -0.7, 1.1);
    let cube = checks::moved(&unit_cube(), &rotation, Vec3::new(2.0, -1.0, 0.5));
    let v = &cube.vertices;
    // The plane through vertices 1, 2, 4 (x + y + z = 1 before the rotation), in floats.
    let n = (v[2] - v[1]).cross(&(v[4] - v[1])).normalize();
    let p = Plane::through(n, &v[1]);
    let region = [cube];
    let out = cut_all(&region, &[vec![p]], &options(0.0, 20.0)).unwrap();
    assert_eq!(out.kept.len(), 2);
    let mut counts: Vec<usize> = out.kept.iter().map(|p| p.vertices.len()).collect();
    counts.sort_unstable();
    assert_eq!(counts, [4, 7]);
    check(&region, &[vec![p]], &out, &mut rng(), 500, 1e-14);
}

#[test]
fn slivers_are_rejected_or_dropped() {
    let cube = [unit_cube()];
    // A slab of 1e-6: rejected at aspect 20 (the cube stays whole), kept without the rule, then
    // dropped by min_volume.
    let slab = vec![vec![plane(Vec3::z(), 1.0 - 1e-6)]];
    let out = cut_all(&cube, &slab, &options(0.0, 20.0)).unwrap();
    assert_eq!((out.kept.len(), out.report.rejected_cuts), (1, 1));
    assert_eq!(out.kept[0].vertices.len(), 8);
    let out = cut_all(&cube, &slab, &options(1e-3, f64::INFINITY)).unwrap();
    assert_eq!((out.kept.len(), out.report.dropped), (1, 1));
    assert!((out.report.dropped_volume - 1e-6).abs() <= 1e-15);
    assert!((out.report.volume + out.report.dropped_volume - 1.0).abs() <= 1e-15);
    check(&cube, &slab, &out, &mut rng(), 500, 1e-14);
    // A corner tetrahedron of 4.5e-12 m³ is not thin, so only min_volume removes it.
    let corner = vec![vec![plane(Vec3::repeat(1.0), 3e-4)]];
    let out = cut_all(&cube, &corner, &options(1e-9, 20.0)).unwrap();
    assert_eq!((out.kept.len(), out.report.dropped), (1, 1));
    assert!((out.report.dropped_volume - 4.5e-12).abs() <= 1e-20);
    assert_eq!(out.report.smallest, out.kept[0].volume);
    // Two planes 1e-4 rad apart crossing at mid-height: the wedge slivers are rejected.
    let tilt = 1e-4_f64;
    let wedges = vec![
        vec![plane(Vec3::z(), 0.5)],
        vec![Plane::through(
            Vec3::new(tilt.sin(), 0.0, tilt.cos()),
            &Vec3::new(0.5, 0.5, 0.5),
        )],
    ];
    let out = cut_all(&cube, &wedges, &options(0.0, 20.0)).unwrap();
    assert_eq!((out.kept.len(), out.report.rejected_cuts), (2, 2));
    check(&cube, &wedges, &out, &mut rng(), 500, 1e-14);
    // Without the rule they are cut: four pieces, two of 1.25e-5 m³.
    let out = cut_all(&cube, &wedges, &options(0.0, 1e6)).unwrap();
    assert_eq!(out.kept.len(), 4);
    let slivers = out
        .kept
        .iter()
        .filter(|p| (p.volume - 1.25e-5).abs() < 1e-9);
    assert_eq!(slivers.count(), 2);
    check(&cube, &wedges, &out, &mut rng(), 500, 1e-14);
}

/// The wedge of the reference §3.4: A 45/105, B 70/235 and the slope face F 65/185 through the
/// origin, and the top z = 1, each its own set.
fn wedge_sets() -> Vec<Vec<Plane>> {
    vec![
        vec![Plane::through(pole(45.0, 105.0), &Vec3::zeros())],
        vec![Plane::through(pole(70.0, 235.0), &Vec3::zeros())],
        vec![Plane::through(pole(65.0, 185.0), &Vec3::zeros())],
        vec![plane(Vec3::z(), 1.0)],
    ]
}

#[test]
fn the_hoek_bray_wedge_is_cut_out_of_a_box() {
    let region = [box_region(
        Vec3::new(-2.0, -1.0, -0.5),
        Vec3::new(2.0, 3.0, 1.5),
    )];
    let sets = wedge_sets();
    let out = cut_all(&region, &sets, &options(0.0, f64::INFINITY)).unwrap();
    assert_eq!(out.kept.len(), 15);
    // Above A and B, behind (below) the face, below the top.
    let wedge: Vec<&Piece> = out
        .kept
        .iter()
        .filter(|p| p.sides == [1, 1, 0, 0])
        .collect();
    assert_eq!(wedge.len(), 1);
    let w = wedge[0];
    let mut tags = w.face_planes.clone();
    tags.sort_unstable();
    assert_eq!(
        tags,
        [Some((0, 0)), Some((1, 0)), Some((2, 0)), Some((3, 0))]
    );
    assert_eq!(w.vertices.len(), 4);
    let expected = 0.169780934267878;
    assert!(
        (w.volume - expected).abs() <= 1e-12 * expected,
        "{}",
        w.volume
    );
    check(&region, &sets, &out, &mut rng(), 2000, 1e-12);
}

/// The three sets of the domain example of §2.5 over the box [0,5]×[0,4]×[0,3]: each from one
/// plane below the box to one above (those do not cut).
fn domain_sets() -> Vec<Vec<Plane>> {
    let sets = [
        (60.0, 30.0, 0.7, Vec3::new(0.3, 0.1, 0.2)),
        (80.0, 140.0, 0.9, Vec3::new(1.0, 1.0, 1.0)),
        (10.0, 250.0, 0.6, Vec3::new(0.0, 0.0, 0.25)),
    ];
    let corners = box_region(Vec3::zeros(), Vec3::new(5.0, 4.0, 3.0)).vertices;
    sets.iter()
        .map(|&(dip, dd, s, o)| {
            let n = pole(dip, dd);
            let t: Vec<f64> = corners.iter().map(|c| n.dot(&(c - o)) / s).collect();
            let lo = t.iter().copied().fold(f64::INFINITY, f64::min).floor() as i32 - 1;
            let hi = t.iter().copied().fold(f64::NEG_INFINITY, f64::max).ceil() as i32 + 1;
            (lo..=hi)
                .map(|k| Plane {
                    normal: n,
                    offset: n.dot(&o) + f64::from(k) * s,
                })
                .collect()
        })
        .collect()
}

#[test]
fn the_domain_example_conserves_volume_and_passes_every_check() {
    let region = [box_region(Vec3::zeros(), Vec3::new(5.0, 4.0, 3.0))];
    let sets = domain_sets();
    // k = 0..9 cut (reference §1), and two more planes each side that do not.
    assert_eq!(sets[0].len(), 14);
    for (min_volume, max_aspect) in [(0.0, 20.0), (1e-3, 20.0), (0.0, f64::INFINITY)] {
        let out = cut_all(&region, &sets, &options(min_volume, max_aspect)).unwrap();
        let r = &out.report;
        assert!((r.volume + r.dropped_volume - 60.0).abs() <= 60.0 * 1e-12);
        if min_volume > 0.0 {
            assert!(r.smallest >= 1e-3 && r.dropped > 0);
        }
        check(&region, &sets, &out, &mut rng(), 2000, 1e-12);
        println!(
            "domain, min_volume {min_volume}, max_aspect {max_aspect}: {} blocks ({} dropped, \
             {} cuts rejected), volume {} + {}, smallest {:.3e}",
            out.kept.len(),
            r.dropped,
            r.rejected_cuts,
            r.volume,
            r.dropped_volume,
            r.smallest
        );
    }
}

#[test]
fn two_regions_sharing_a_face_are_cut_by_the_same_planes() {
    let regions = [
        box_region(Vec3::zeros(), Vec3::new(4.0, 3.0, 1.0)),
        box_region(Vec3::new(0.0, 0.0, 1.0), Vec3::new(4.0, 3.0, 2.5)),
    ];
    let sets = domain_sets();
    let out = cut_all(&regions, &sets, &options(0.0, f64::INFINITY)).unwrap();
    assert!(out.kept.iter().any(|p| p.region == 1));
    assert_eq!(out.kept[0].region, 0);
    check(&regions, &sets, &out, &mut rng(), 2000, 1e-12);
    // The pieces on either side of z = 1 meet on the same points.
    let on_top = |p: &Piece, z: f64| -> Vec<[u64; 3]> {
        p.vertices
            .iter()
            .filter(|v| v.z == z)
            .map(|v| v.map(f64::to_bits).into())
            .collect()
    };
    let mut below: Vec<_> = out
        .kept
        .iter()
        .filter(|p| p.region == 0)
        .flat_map(|p| on_top(p, 1.0))
        .collect();
    let mut above: Vec<_> = out
        .kept
        .iter()
        .filter(|p| p.region == 1)
        .flat_map(|p| on_top(p, 1.0))
        .collect();
    below.sort_unstable();
    below.dedup();
    above.sort_unstable();
    above.dedup();
    assert_eq!(below, above);
}

#[test]
fn a_domain_far_from_the_origin_is_cut_as_well() {
    let shift = Vec3::new(4.5e5, 5.2e6, 310.0);
    let region = [box_region(shift, shift + Vec3::new(5.0, 4.0, 3.0))];
    // Map coordinates (UTM-like): for a 7 m box at 5.2e6 m the rounding floor sets ε, 7.4e-8 m.
    let eps = super::snap_tolerance(&region);
    assert_eq!(eps, super::SNAP_ROUNDING * (5.2e6 + 4.0));
    assert!(eps > 1e-9 * 50f64.sqrt());
    let sets: Vec<Vec<Plane>> = domain_sets()
        .into_iter()
        .map(|set| {
            set.iter()
                .map(|p| Plane {
                    normal: p.normal,
                    offset: p.offset + p.normal.dot(&shift),
                })
                .collect()
        })
        .collect();
    let out = cut_all(&region, &sets, &options(0.0, f64::INFINITY)).unwrap();
    let near = cut_all(
        &[box_region(Vec3::zeros(), Vec3::new(5.0, 4.0, 3.0))],
        &domain_sets(),
        &options(0.0, f64::INFINITY),
    )
    .unwrap();
    assert_eq!(out.kept.len(), near.kept.len());
    for (p, q) in out.kept.iter().zip(&near.kept) {
        // Coordinates near 5.2e6 m are rounded to 1e-9 m: volumes agree to that × the surface.
        assert!(
            (p.volume - q.volume).abs() <= 1e-8,
            "{} vs {}",
            p.volume,
            q.volume
        );
        assert!((p.centroid - shift - q.centroid).norm() <= 1e-8);
    }
    check(&region, &sets, &out, &mut rng(), 2000, 1e-9);
}

#[test]
fn too_many_blocks_fails_early() {
    let cube = [box_region(Vec3::zeros(), Vec3::repeat(10.0))];
    let sets: Vec<Vec<Plane>> = (0..3)
        .map(|axis| {
            (0..10_000)
                .map(|k| Plane {
                    normal: Vec3::ith(axis, 1.0),
                    offset: f64::from(k) * 1e-3,
                })
                .collect()
        })
        .collect();
    let start = Instant::now();
    let opts = CutOptions {
        min_volume: 0.0,
        max_aspect: f64::INFINITY,
        aspect_length: f64::INFINITY,
        max_blocks: 1000,
    };
    let err = cut(&cube, &sets, &opts).unwrap_err();
    assert_eq!(err, CutError::TooManyBlocks { limit: 1000 });
    assert!(start.elapsed().as_secs_f64() < 1.0);
    assert_eq!(
        err.to_string(),
        "the joint sets cut more than 1000 blocks (the limit of a scene): increase the spacing"
    );
    // A scene of exactly the limit passes.
    let opts = CutOptions {
        max_blocks: 1000,
        ..opts
    };
    let (pieces, _) = cut(&cube, &cube_sets(), &opts).unwrap();
    assert_eq!(pieces.len(), 1000);
    let opts = CutOptions {
        max_blocks: 999,
        ..opts
    };
    assert!(cut(&cube, &cube_sets(), &opts).is_err());
}

#[test]
fn bad_input_is_an_error() {
    let opts = options(0.0, 20.0);
    let mut inverted = unit_cube();
    inverted.faces.iter_mut().for_each(|f| f.reverse());
    let mut open = unit_cube();
    open.faces.pop();
    let mut dented = unit_cube();
    dented.vertices[7] = Vec3::repeat(0.8);
    let bad_region = |r: Polyhedron| match cut(&[r], &[], &opts) {
        Err(CutError::InvalidRegion { region: 0, reason }) => reason,
        other => panic!("{other:?}"),
    };
    assert!(bad_region(inverted).contains("clockwise"));
    assert!(bad_region(open).contains("closed"));
    assert!(bad_region(dented).contains("convex"));
    let long = vec![vec![Plane {
        normal: Vec3::new(1.0, 1.0, 0.0),
        offset: 0.5,
    }]];
    assert_eq!(
        cut(&[unit_cube()], &long, &opts).unwrap_err(),
        CutError::InvalidPlane { set: 0, plane: 0 }
    );
    for o in [
        options(-1.0, 20.0),
        options(0.0, 0.0),
        options(0.0, f64::NAN),
    ] {
        assert!(matches!(
            cut(&[unit_cube()], &[], &o),
            Err(CutError::InvalidOptions { .. })
        ));
    }
    // No regions: nothing to cut.
    let (pieces, report) = cut(&[], &cube_sets(), &opts).unwrap();
    assert!(pieces.is_empty() && report.domain_volume == 0.0);
}
