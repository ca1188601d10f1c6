//! The model: the blocks a scene builds and the solver steps. A [`Block`] holds its geometry,
//! material, the 12-DOF velocity carried between steps, and its accumulated stress and strain;
//! everything derived from the vertex positions is refreshed by [`Block::refresh`] after each
//! step's finite-rotation update.

use std::sync::Arc;

use nalgebra::{Matrix6, Vector6};

use crate::physics::geometry::{
    MassProperties, Topology, Vec3, bounding_box, mass_properties, newell_normal,
};
use crate::physics::integrator::Kinematics;
use crate::physics::mechanics::{Mat12, Material, Vec12, elasticity_matrix, mass_matrix};

/// A face of a block that lies on a joint plane of a rock mass: the set (an index of
/// [`crate::params::SolverParams::joint_sets`]) and the plane within it. Two blocks touching
/// across faces with the same tag touch across that joint, and take its set's properties.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct JointFace {
    pub set: u16,
    pub plane: u32,
}

/// Where a block cut from a rock mass came from: the rock mass (an index of
/// [`Model::rock_masses`]) and the region of its domain.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RockMassOf {
    pub mass: u16,
    pub region: u16,
}

/// One deformable block and its state carried between steps.
#[derive(Clone, Debug)]
pub struct Block {
    pub name: String,
    pub material: Material,
    /// Held at every vertex by springs of `fixed_spring_factor · E`.
    pub fixed: bool,
    pub vertices: Vec<Vec3>,
    pub topo: Arc<Topology>,
    /// Unit outward normals, refreshed with the vertices.
    pub face_normals: Vec<Vec3>,
    pub mp: MassProperties,
    /// Constant mass; the density follows the volume so that mass is conserved (§1.3).
    pub mass: f64,
    pub density: f64,
    pub mass_matrix: Mat12,
    pub elasticity: Matrix6<f64>,
    /// 12-vector of DOF rates carried between steps (§3.2).
    pub velocity: Vec12,
    /// DOF accelerations of the last step (a dissipative step carries them; rock-mass
    /// reference §4.3).
    pub acceleration: Vec12,
    /// Accumulated stress [σx, σy, σz, τyz, τzx, τxy], Pa.
    pub stress: Vector6<f64>,
    pub strain: Vector6<f64>,
    /// Spring anchors of a fixed block: the initial vertex positions.
    pub anchors: Vec<Vec3>,
    /// Point loads: (material point, force N).
    pub loads: Vec<(Vec3, Vec3)>,
    pub initial_centroid: Vec3,
    pub lo: Vec3,
    pub hi: Vec3,
    /// The joint plane each face lies on, if any (faces of blocks cut from a rock mass).
    pub face_joints: Vec<Option<JointFace>>,
    /// The rock mass the block was cut from, if any.
    pub rock_mass: Option<RockMassOf>,
}

impl Block {
    /// A block from its hull; `velocity` is the initial centroid velocity and `spin` the initial
    /// angular velocity (rad/s).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        name: String,
        material: Material,
        fixed: bool,
        vertices: Vec<Vec3>,
        topo: Topology,
        velocity: Vec3,
        spin: Vec3,
        loads: Vec<(Vec3, Vec3)>,
    ) -> Self {
        let mp = mass_properties(&vertices, &topo.faces);
        let mut v = Vec12::zeros();
        v.fixed_rows_mut::<3>(0).copy_from(&velocity);
        v.fixed_rows_mut::<3>(3).copy_from(&spin);
        let mut b = Block {
            name,
            material,
            fixed,
            anchors: if fixed { vertices.clone() } else { Vec::new() },
            vertices,
            topo: Arc::new(topo),
            face_normals: Vec::new(),
            mp,
            mass: material.density * mp.volume,
            density: material.density,
            mass_matrix: Mat12::zeros(),
            elasticity: elasticity_matrix(material.young_modulus, material.poisson_ratio),
            velocity: v,
            acceleration: Vec12::zeros(),
            stress: Vector6::zeros(),
            strain: Vector6::zeros(),
            loads,
            initial_centroid: mp.centroid,
            lo: Vec3::zeros(),
            hi: Vec3::zeros(),
            face_joints: Vec::new(),
            rock_mass: None,
        };
        b.face_joints = vec![None; b.topo.faces.len()];
        b.refresh();
        b
    }

    /// Recomputes everything derived from the vertex positions.
    pub fn refresh(&mut self) {
        self.face_normals = self
            .topo
            .faces
            .iter()
            .map(|f| newell_normal(&self.vertices, f).normalize())
            .collect();
        self.mp = mass_properties(&self.vertices, &self.topo.faces);
        self.density = self.mass / self.mp.volume;
        self.mass_matrix = mass_matrix(self.density, &self.mp);
        let (lo, hi) = bounding_box(&self.vertices);
        self.lo = lo;
        self.hi = hi;
    }

    /// What the time integrator carries for this block.
    pub fn kinematics(&self) -> Kinematics {
        Kinematics {
            velocity: self.velocity,
            acceleration: self.acceleration,
        }
    }

    pub fn set_kinematics(&mut self, k: Kinematics) {
        self.velocity = k.velocity;
        self.acceleration = k.acceleration;
    }

    /// ½ vᵀ M v.
    pub fn kinetic_energy(&self) -> f64 {
        self.kinetic_energy_at(&self.velocity)
    }

    /// ½ vᵀ M v at the DOF rates `v` (M of the block as it is).
    pub fn kinetic_energy_at(&self, v: &Vec12) -> f64 {
        0.5 * (v.transpose() * self.mass_matrix * v)[0]
    }

    /// A bound of the speed of its fastest vertex, m/s: the translation's speed plus the
    /// rotation's and the strain rate's at the block's radius.
    pub fn peak_speed(&self) -> f64 {
        let v = &self.velocity;
        let r = self.radius();
        Vec3::new(v[0], v[1], v[2]).norm()
            + Vec3::new(v[3], v[4], v[5]).norm() * r
            + v.fixed_rows::<6>(6).norm() * r
    }

    /// Largest distance from the centroid to a vertex.
    pub fn radius(&self) -> f64 {
        self.vertices
            .iter()
            .map(|v| (v - self.mp.centroid).norm())
            .fold(0.0, f64::max)
    }
}

/// The blocks of a scene.
#[derive(Clone, Debug)]
pub struct Model {
    pub name: String,
    pub blocks: Vec<Block>,
    /// The names of the rock masses the blocks were cut from ([`Block::rock_mass`]).
    pub rock_masses: Vec<String>,
}

impl Model {
    /// A model of hand-made blocks (no rock masses).
    pub fn new(name: impl Into<String>, blocks: Vec<Block>) -> Self {
        Model {
            name: name.into(),
            blocks,
            rock_masses: Vec::new(),
        }
    }
}
