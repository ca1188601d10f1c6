//! Which joint a contact lies on. Faces of blocks cut from a rock mass carry the joint plane
//! they were cut along ([`JointFace`]); a contact across such a plane (both blocks touch with
//! faces cut by the same plane) takes the properties of the plane's set. Every other contact
//! (hand-made blocks, a region boundary, a block that has moved onto another joint) takes
//! `[joint]`.

use super::ContactKey;
use crate::model::{Block, JointFace};
use crate::snapshot::ContactMode;

/// The joint set of the contact `key` between blocks `bi` (vertex or first edge) and `bj` (face
/// or second edge), if both touch with faces cut by one plane of that set.
pub fn joint_set(key: &ContactKey, bi: &Block, bj: &Block) -> Option<u16> {
    let (fi, fj) = (key.feature_i as usize, key.feature_j as usize);
    match key.mode() {
        // The face of j and a face of i through the vertex.
        ContactMode::VertexFace => {
            let tag = bj.face_joints[fj]?;
            let at_vertex = bi.topo.vertex_edges[fi]
                .iter()
                .flat_map(|&e| bi.topo.edges[e].faces);
            shared(at_vertex.map(|f| bi.face_joints[f]), tag)
        }
        // A face along each edge.
        ContactMode::EdgeEdge => bj.topo.edges[fj].faces.iter().find_map(|&f| {
            let tag = bj.face_joints[f]?;
            shared(
                bi.topo.edges[fi].faces.iter().map(|&g| bi.face_joints[g]),
                tag,
            )
        }),
    }
}

/// `tag`'s set if one of `tags` is `tag`.
fn shared(mut tags: impl Iterator<Item = Option<JointFace>>, tag: JointFace) -> Option<u16> {
    tags.any(|t| t == Some(tag)).then_some(tag.set)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::geometry::{Vec3, box_vertices, convex_hull};
    use crate::physics::mechanics::Material;

    fn cube(center: [f64; 3]) -> Block {
        let pts = box_vertices(
            [1.0; 3],
            center,
            &crate::physics::geometry::Mat3::identity(),
        );
        let (v, topo) = convex_hull(&pts).unwrap();
        let material = Material {
            density: 2000.0,
            young_modulus: 1e9,
            poisson_ratio: 0.2,
        };
        let z = Vec3::zeros();
        Block::new("c".into(), material, false, v, topo, z, z, Vec::new())
    }

    /// Tags the face of `b` whose outward normal is `n` with `tag`.
    fn tag(b: &mut Block, n: [f64; 3], tag: JointFace) -> usize {
        let f = (0..b.face_normals.len())
            .find(|&f| (b.face_normals[f] - Vec3::from(n)).norm() < 1e-9)
            .unwrap();
        b.face_joints[f] = Some(tag);
        f
    }

    /// A cube on another, across the plane z = 1: vertex–face and edge–edge contacts across the
    /// plane take its set when both faces carry its tag, and `[joint]` otherwise.
    #[test]
    fn contacts_across_one_plane_take_its_set() {
        let (mut top, mut bottom) = (cube([0.5, 0.5, 1.5]), cube([0.5, 0.5, 0.5]));
        let j = JointFace { set: 3, plane: 7 };
        let other = JointFace { set: 3, plane: 8 };
        let fb = tag(&mut bottom, [0.0, 0.0, 1.0], j);
        let v = (0..8).find(|&v| top.vertices[v].z < 1.5).unwrap();
        let vf = ContactKey {
            i: 0,
            j: 1,
            mode: 0,
            feature_i: v as u32,
            feature_j: fb as u32,
        };
        assert_eq!(joint_set(&vf, &top, &bottom), None, "top's face untagged");
        let ft = tag(&mut top, [0.0, 0.0, -1.0], other);
        assert_eq!(joint_set(&vf, &top, &bottom), None, "another plane");
        top.face_joints[ft] = Some(j);
        assert_eq!(joint_set(&vf, &top, &bottom), Some(3));
        // A vertex of the top face of the upper cube is not on the plane.
        let high = (0..8).find(|&v| top.vertices[v].z > 1.5).unwrap();
        let off = ContactKey {
            feature_i: high as u32,
            ..vf
        };
        assert_eq!(joint_set(&off, &top, &bottom), None);
        // Edge–edge: an edge of the bottom face of `top` and of the top face of `bottom`.
        let edge_on = |b: &Block, f: usize| {
            (0..b.topo.edges.len())
                .find(|&e| b.topo.edges[e].faces.contains(&f))
                .unwrap() as u32
        };
        let ee = ContactKey {
            i: 0,
            j: 1,
            mode: 1,
            feature_i: edge_on(&top, ft),
            feature_j: edge_on(&bottom, fb),
        };
        assert_eq!(joint_set(&ee, &top, &bottom), Some(3));
        top.face_joints[ft] = Some(other);
        assert_eq!(joint_set(&ee, &top, &bottom), None);
    }
}
