//! Contacts between convex polyhedral blocks.
//!
//! - [`detection`]: which features of which block pairs may touch in this step;
//! - [`kinematics`]: the linearised normal distance and the contact submatrices;
//! - [`joint`]: which joint set a contact lies on (its friction and cohesion);
//! - [`law`]: the contact law as a pure state classification (open / lock / slide, hysteresis,
//!   friction reversal, cohesion);
//! - [`record`]: what a contact carries from one step to the next.
//!
//! The types below name a contact ([`ContactKey`]), what detection sees of a block ([`Shape`])
//! and what it finds ([`Candidate`]).

pub mod detection;
pub mod groups;
pub mod joint;
pub mod kinematics;
pub mod law;
pub mod record;

use crate::model::Block;
use crate::physics::geometry::{Topology, Vec3};
pub use crate::snapshot::{ContactMode, ContactState};

/// Identity of a contact across steps: the blocks and the features that touch.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize,
)]
pub struct ContactKey {
    /// Block owning the vertex (V–F) or the first edge (E–E).
    pub i: u32,
    /// Block owning the face (V–F) or the second edge (E–E).
    pub j: u32,
    pub mode: u8,
    /// Vertex index in i (V–F) or edge index in i (E–E).
    pub feature_i: u32,
    /// Face index in j (V–F) or edge index in j (E–E).
    pub feature_j: u32,
}

impl ContactKey {
    pub fn mode(&self) -> ContactMode {
        if self.mode == 0 {
            ContactMode::VertexFace
        } else {
            ContactMode::EdgeEdge
        }
    }
}

/// A block as contact detection sees it at the start of a step.
#[derive(Clone, Debug)]
pub struct Shape<'a> {
    pub vertices: &'a [Vec3],
    pub topo: &'a Topology,
    /// Unit outward face normals.
    pub face_normals: &'a [Vec3],
    pub centroid: Vec3,
    pub lo: Vec3,
    pub hi: Vec3,
    pub fixed: bool,
    /// What the narrow phase measures on the block's edges, once a step.
    pub edges: EdgeMeasures,
}

/// What the narrow phase measures on a block's edges, taken once a step rather than in every
/// test of every pair the block is in (each of a wall's blocks is in about eight): the same
/// numbers, by the same operations.
#[derive(Clone, Debug)]
pub struct EdgeMeasures {
    /// The longest edge of each face, m.
    pub face_longest: Vec<f64>,
    /// The longest edge at each vertex, m.
    pub vertex_longest: Vec<f64>,
    /// Per face, from `face_start[f]`, per corner m: n × ê of the edge from corner m to m + 1,
    /// the unit vector in the face's plane across that edge, into the face.
    pub inward: Vec<Vec3>,
    pub face_start: Vec<usize>,
}

impl EdgeMeasures {
    pub fn of(vertices: &[Vec3], topo: &Topology, face_normals: &[Vec3]) -> Self {
        let edge =
            |face: &[usize], m: usize| vertices[face[(m + 1) % face.len()]] - vertices[face[m]];
        let face_longest = topo
            .faces
            .iter()
            .map(|face| {
                (0..face.len())
                    .map(|m| edge(face, m).norm())
                    .fold(0.0, f64::max)
            })
            .collect();
        let vertex_longest = topo
            .vertex_edges
            .iter()
            .map(|edges| {
                edges
                    .iter()
                    .map(|&ei| {
                        let e = topo.edges[ei];
                        (vertices[e.v[1]] - vertices[e.v[0]]).norm()
                    })
                    .fold(0.0, f64::max)
            })
            .collect();
        let mut face_start = Vec::with_capacity(topo.faces.len());
        let mut inward = Vec::new();
        for (face, n) in topo.faces.iter().zip(face_normals) {
            face_start.push(inward.len());
            inward.extend((0..face.len()).map(|m| n.cross(&edge(face, m).normalize())));
        }
        EdgeMeasures {
            face_longest,
            vertex_longest,
            inward,
            face_start,
        }
    }

    /// n × ê of each edge of face `f`, in the face's corner order.
    pub fn inward(&self, f: usize, corners: usize) -> &[Vec3] {
        &self.inward[self.face_start[f]..self.face_start[f] + corners]
    }
}

/// Tolerances of the narrow phase (reference §4, §10).
#[derive(Clone, Copy, Debug)]
pub struct DetectionParams {
    /// d_s: contacts are sought up to this gap.
    pub search_distance: f64,
    /// d_pen: deepest penetration still treated as a contact.
    pub max_penetration: f64,
    /// ε_in: slack of the point-in-face test, m.
    pub inside_tolerance: f64,
    /// sin θ_a of the entrance-angle tests (θ_a ≈ 3°).
    pub sin_entrance: f64,
    /// sin θ_p below which two edges count as parallel (θ_p ≈ 3°).
    pub sin_parallel: f64,
    /// ε_e: margin of the edge parameters of an edge-edge contact.
    pub edge_margin: f64,
    /// Contacts of one block pair closer than this are one physical constraint.
    pub merge_distance: f64,
    /// Faces whose gaps to a vertex differ by less than this are tied: the vertex sits on their
    /// common edge (see [`Candidate::tied`]).
    pub tie_distance: f64,
    /// Edges crossed near an end must not cross much deeper than their points lie inside the
    /// other block (see `detection::crossing_is_overlap`). DDA-3a only: under DDA-3p's fixed
    /// penalty a contact sinks N/p_n, centimetres at an impact, and the check then dropped
    /// corner crossings that held the rockfall's column, whose kept overlaps grew from 3 mm to
    /// 4.5 cm.
    pub check_crossing_depth: bool,
}

impl DetectionParams {
    /// Shi's control lengths for a model of half-extent `w0` and displacement ratio δ.
    pub fn new(w0: f64, delta: f64) -> Self {
        let ds = groups::search_distance(w0, delta);
        let sin3 = 3f64.to_radians().sin();
        DetectionParams {
            search_distance: ds,
            max_penetration: 0.3 * ds,
            inside_tolerance: 1e-6 * w0,
            sin_entrance: sin3,
            sin_parallel: sin3,
            edge_margin: 1e-3,
            merge_distance: 1e-3 * ds,
            tie_distance: 1e-3 * ds,
            check_crossing_depth: true,
        }
    }
}

/// A contact found at the start of a step, with its frozen geometry.
#[derive(Clone, Debug)]
pub struct Candidate {
    pub key: ContactKey,
    /// P1…P4 of (5.1): V–F: the vertex, then three corners of the face; E–E: the edge of i,
    /// then the edge of j.
    pub points: [Vec3; 4],
    /// Unit normal out of block j toward block i.
    pub normal: Vec3,
    /// Signed gap, m (negative when penetrating).
    pub gap: f64,
    /// Contact point on block i (the vertex, or the closest point of edge i).
    pub xa: Vec3,
    /// Closest point of block j to `xa`.
    pub xb: Vec3,
    /// V–F: the other faces of j the vertex is within reach of (they pass the point-in-face and
    /// entrance tests); empty for E–E. The open–close check closes the contact on whichever
    /// face the solution leaves the vertex least deep behind (see `Active::reconsider_face`).
    pub alternatives: Vec<Alternative>,
    /// V–F: the vertex sits on an edge or corner of block j, another face being as close as the
    /// chosen one (within [`DetectionParams::tie_distance`]). Which face it would cross, the one
    /// whose plane gives the larger gap after the motion (the common-plane rule), the motion
    /// decides, and at rest it is unknown: at a junction of two persistent joints (four blocks
    /// meeting along a line) the diagonal blocks touch along that line only, and a slab sliding
    /// on one joint read the other joint's plane as a wall and stood.
    pub tied: bool,
}

/// Another face of block j for a vertex–face candidate: the same vertex, its own plane.
#[derive(Clone, Copy, Debug)]
pub struct Alternative {
    /// The face's index in block j.
    pub face: u32,
    /// P2…P4 of (5.1): three corners of the face.
    pub corners: [Vec3; 3],
    pub normal: Vec3,
    pub gap: f64,
}

impl Candidate {
    pub fn mode(&self) -> ContactMode {
        self.key.mode()
    }

    /// Makes `alt` the candidate's face; the chosen face becomes an alternative.
    pub fn switch_face(&mut self, alt: usize) {
        let a = self.alternatives[alt];
        let old = Alternative {
            face: self.key.feature_j,
            corners: [self.points[1], self.points[2], self.points[3]],
            normal: self.normal,
            gap: self.gap,
        };
        self.key.feature_j = a.face;
        self.points = [self.points[0], a.corners[0], a.corners[1], a.corners[2]];
        self.normal = a.normal;
        self.gap = a.gap;
        self.xb = self.xa - a.normal * a.gap;
        self.alternatives[alt] = old;
    }
}

impl<'a> Shape<'a> {
    /// What detection sees of `block` now.
    pub fn of(block: &'a Block) -> Self {
        Shape {
            vertices: &block.vertices,
            topo: &block.topo,
            face_normals: &block.face_normals,
            centroid: block.mp.centroid,
            lo: block.lo,
            hi: block.hi,
            fixed: block.fixed,
            edges: EdgeMeasures::of(&block.vertices, &block.topo, &block.face_normals),
        }
    }
}
