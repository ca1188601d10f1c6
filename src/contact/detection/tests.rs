//! Unit tests of the narrow phase (`super`).

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
        edges: crate::contact::EdgeMeasures::of(&o.v, &o.t, &o.n),
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
    assert_eq!(broad_phase(&shapes, 0.125, 10), vec![(0, 2)]);
    let c = detect_pair(0, &shapes[0], 2, &shapes[2], &params(), &|_| false);
    assert_eq!(c.len(), 4, "gap 5 cm < d_s = 12.5 cm");
}

#[test]
fn a_vertex_just_past_a_face_edge_is_taken_on_the_face_that_separates_it() {
    // b: the unit cube. A corner of a lies 3 mm above b's top plane, 5 mm beyond the side face
    // y = 0: outside b by 5 mm, the side face's plane separates it. `face_beside` gives that
    // face at its true gap, not the far faces behind the vertex; 5 mm above the top and 3 mm
    // beyond the side it gives the top. A vertex deep inside b gets none.
    let b = owned(box_vertices([1.0; 3], [0.5, 0.5, 0.5], &Mat3::identity()));
    let tip = |x: Vec3| {
        owned(vec![
            x,
            x + Vec3::new(0.2, -0.1, 0.5),
            x + Vec3::new(-0.2, -0.1, 0.5),
            x + Vec3::new(0.0, -0.3, 0.2),
        ])
    };
    let p = params();
    let faces: Vec<f64> = vec![1.0; b.t.faces.len()];
    let beside = |x: Vec3, outside: f64| {
        let a = tip(x);
        let vi = a.v.iter().position(|v| (v - x).norm() < 1e-12).unwrap();
        let sa = shape(&a);
        let longest = sa.edges.vertex_longest[vi];
        face_beside(&sa, vi, &shape(&b), (&faces, longest), outside, &p)
    };
    let f = beside(Vec3::new(0.5, -0.005, 1.003), 0.005).expect("the side face");
    assert!(
        (f.normal + Vec3::y()).norm() < 1e-12 && (f.gap - 0.005).abs() < 1e-12,
        "{f:?}"
    );
    let f = beside(Vec3::new(0.5, -0.003, 1.005), 0.005).expect("the top face");
    assert!(
        (f.normal - Vec3::z()).norm() < 1e-12 && (f.gap - 0.005).abs() < 1e-12,
        "{f:?}"
    );
    assert!(beside(Vec3::new(0.5, 0.5, 0.5), -0.5).is_none());
    // On the top's plane, 2 cm beyond the side: both faces pass the widened outline test, and
    // the side's plane, 2 cm away, is the one that separates it (the top's gap is 0).
    let f = beside(Vec3::new(0.5, -0.02, 1.0), 0.02).expect("the side face");
    assert!((f.normal + Vec3::y()).norm() < 1e-12 && (f.gap - 0.02).abs() < 1e-12);
}

/// One candidate at `xb` with this normal and gap (an edge–edge key of its own).
fn candidate_at(xb: Vec3, normal: Vec3, gap: f64, feature: u32) -> Candidate {
    Candidate {
        key: ContactKey {
            i: 0,
            j: 1,
            mode: 1,
            feature_i: feature,
            feature_j: feature,
        },
        points: [xb; 4],
        normal,
        gap,
        xa: xb + normal * gap,
        xb,
        alternatives: Vec::new(),
        tied: false,
    }
}

#[test]
fn opposed_normals_at_one_place_are_one_contact() {
    let p = params();
    let at = Vec3::new(3.0, 2.0, 5.0);
    let n1 = Vec3::new(0.86, 0.0, -0.51).normalize();
    let n2 = Vec3::new(-0.98, 0.02, -0.18).normalize();
    let shallow = candidate_at(at, n1, -1e-9, 0);
    // The slope's pair: 140° apart, one 6 cm deep, at one point of block j.
    let deep = candidate_at(at, n2, -0.06, 1);
    assert!(opposed(&shallow, &deep, &p));
    assert!(opposed(&deep, &shallow, &p));
    // Within the deeper one's depth of each other: still one place.
    let near = candidate_at(at + Vec3::new(0.0, 0.05, 0.0), n2, -0.06, 1);
    assert!(opposed(&shallow, &near, &p));
    // Farther apart than the depth, two places: at 140° still one contact (see the next
    // test), at 100° both kept.
    let far = candidate_at(at + Vec3::new(0.0, 0.1, 0.0), n2, -0.06, 1);
    assert!(opposed(&shallow, &far, &p));
    let n_100 = Vec3::new(-0.985, 0.0, -0.174).normalize();
    let far_100 = candidate_at(at + Vec3::new(0.0, 0.1, 0.0), n_100, -0.06, 1);
    assert!(!opposed(
        &candidate_at(at, Vec3::z(), -1e-9, 0),
        &far_100,
        &p
    ));
    // At one place but less than 90° apart (a vertex at a right-angled edge): both kept.
    let square = candidate_at(at, Vec3::x(), -1e-9, 1);
    assert!(!opposed(
        &candidate_at(at, Vec3::z(), -1e-9, 0),
        &square,
        &p
    ));
    // 80° apart: both kept; 100° apart: one.
    let up = candidate_at(at, Vec3::z(), -1e-9, 0);
    let at_80 = candidate_at(at, Vec3::new(-0.985, 0.0, 0.174).normalize(), -1e-9, 1);
    assert!(!opposed(&up, &at_80, &p));
    let at_100 = candidate_at(at, Vec3::new(-0.985, 0.0, -0.174).normalize(), -1e-9, 1);
    assert!(opposed(&up, &at_100, &p));
}

/// Two contacts of one pair at two places whose normals, taken toward the same block, are more
/// than 120° apart are one too (two convex blocks cannot touch so without overlapping), the
/// normal of a candidate keyed j→i counting reversed; and a vertex–face candidate loses the
/// alternative faces that would oppose another contact of its pair.
#[test]
fn normals_opposed_anywhere_in_a_pair_are_one_contact() {
    let p = params();
    let at = Vec3::new(0.0, 0.0, 0.0);
    let elsewhere = Vec3::new(0.3, 0.2, 0.0);
    let up = candidate_at(at, Vec3::z(), -1e-9, 0);
    // A J0/J1 sliver's two sides, 157° apart, 0.36 m from each other.
    let n_157 = Vec3::new(0.39, 0.0, -0.92).normalize();
    assert!(opposed(&up, &candidate_at(elsewhere, n_157, -2e-4, 1), &p));
    // Keyed j→i, its normal points toward j: the same physical normal as `up` is not opposed
    // (though its raw normal is −z), and one that is opposed toward i is caught.
    let mut swapped = candidate_at(elsewhere, -Vec3::z(), -1e-9, 1);
    swapped.key = ContactKey {
        i: 1,
        j: 0,
        mode: 0,
        feature_i: 1,
        feature_j: 1,
    };
    assert!(!opposed(&up, &swapped, &p));
    swapped.normal = -n_157;
    assert!(opposed(&up, &swapped, &p));
    // Alternatives: the face at 157° goes, the one at 90° stays.
    let mut vertex = candidate_at(elsewhere, Vec3::x(), -1e-9, 2);
    vertex.key.mode = 0;
    let alt = |face: u32, normal: Vec3| Alternative {
        face,
        corners: [elsewhere; 3],
        normal,
        gap: 0.0,
    };
    vertex.alternatives = vec![alt(7, n_157), alt(8, Vec3::y())];
    let mut kept = vec![up, vertex];
    drop_opposed_alternatives(0, &mut kept);
    let faces: Vec<u32> = kept[1].alternatives.iter().map(|a| a.face).collect();
    assert_eq!(faces, vec![8]);
}
