//! The scene file's TOML format, as serde reads it. Every table denies unknown keys, so a typo is
//! an error with its line, not a silently ignored setting, and every list of numbers takes
//! exactly its length ([`exact`]: `[0, -1, 0, 99]` is not a point). The shapes of `[[blocks]]`
//! are built into blocks by [`super::build`].

use std::collections::BTreeMap;

use serde::Deserialize;
use toml::Spanned;

use crate::params::numbers::{Exact, exact};
use crate::params::{JointParams, SolverParams};
use crate::physics::mechanics::Material;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SceneFile {
    pub(super) name: Option<String>,
    #[serde(default, deserialize_with = "table")]
    pub(super) solver: SolverParams,
    #[serde(default, deserialize_with = "table")]
    pub(super) joint: JointParams,
    #[serde(default)]
    pub(super) materials: BTreeMap<String, Spanned<Material>>,
    #[serde(default)]
    pub(super) blocks: Vec<Spanned<BlockSpec>>,
    /// Domains cut into blocks by joint sets (`super::rock_mass`).
    #[serde(default)]
    pub(super) rock_masses: Vec<Spanned<RockMassSpec>>,
    /// Joint sets given by their planes, for blocks given by their vertices: what `dda3d cut`
    /// writes for the sets of a rock mass it has cut.
    #[serde(default)]
    pub(super) joint_sets: Vec<Spanned<PlanesSpec>>,
    /// What `dda3d run` writes besides the CSV files.
    #[serde(default, deserialize_with = "table")]
    pub(super) output: OutputSpec,
}

/// `[output]`: the ParaView series (`crate::output::vtk`) and the output interval.
#[derive(Deserialize, Default, Clone, Copy)]
#[serde(deny_unknown_fields)]
pub(super) struct OutputSpec {
    /// Write `DIR/vtk/` as `run --vtk` does.
    #[serde(default)]
    pub(super) vtk: bool,
    /// Simulated time between outputs, s: the CSV rows and the VTK series alike (default: every
    /// step), as `run --output-interval`.
    pub(super) interval: Option<f64>,
}

/// Reads a field that must be a table. serde lets a struct be read from a list of its fields in
/// order, so `solver = []` was a solver with every default, silently (#13's fuzz test).
fn table<'de, D, T>(d: D) -> Result<T, D::Error>
where
    D: serde::Deserializer<'de>,
    T: Deserialize<'de>,
{
    struct OnlyTable<T>(std::marker::PhantomData<T>);
    impl<'de, T: Deserialize<'de>> serde::de::Visitor<'de> for OnlyTable<T> {
        type Value = T;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str("a table")
        }
        fn visit_map<A: serde::de::MapAccess<'de>>(self, map: A) -> Result<T, A::Error> {
            T::deserialize(serde::de::value::MapAccessDeserializer::new(map))
        }
    }
    d.deserialize_map(OnlyTable(std::marker::PhantomData))
}

/// One `[[blocks]]` entry. Exactly one of `vertices`, `box`, `dodecahedron`, `prism`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct BlockSpec {
    pub(super) name: Option<String>,
    pub(super) material: String,
    #[serde(default)]
    pub(super) fixed: bool,
    /// Initial centroid velocity, m/s.
    #[serde(default, deserialize_with = "exact")]
    pub(super) velocity: [f64; 3],
    /// Initial angular velocity, rad/s.
    #[serde(default, deserialize_with = "exact")]
    pub(super) angular_velocity: [f64; 3],
    pub(super) vertices: Option<Vec<Exact<3>>>,
    #[serde(rename = "box")]
    pub(super) box_: Option<BoxSpec>,
    pub(super) dodecahedron: Option<DodecahedronSpec>,
    pub(super) prism: Option<PrismSpec>,
    /// Point loads moving with the block.
    #[serde(default)]
    pub(super) loads: Vec<LoadSpec>,
    /// The rock mass a block written by `dda3d cut` was cut from: its faces on the planes of the
    /// rock mass's `[[joint_sets]]` are joints of those sets.
    pub(super) rock_mass: Option<String>,
    /// The region of that rock mass's domain, from 1.
    pub(super) region: Option<u16>,
}

impl BlockSpec {
    pub(super) fn shape(&self) -> ShapeSpec<'_> {
        ShapeSpec {
            vertices: self.vertices.as_deref(),
            box_: self.box_.as_ref(),
            dodecahedron: self.dodecahedron.as_ref(),
            prism: self.prism.as_ref(),
        }
    }
}

/// The shape of a block or a region: exactly one of these is given.
pub(super) struct ShapeSpec<'a> {
    pub(super) vertices: Option<&'a [Exact<3>]>,
    pub(super) box_: Option<&'a BoxSpec>,
    pub(super) dodecahedron: Option<&'a DodecahedronSpec>,
    pub(super) prism: Option<&'a PrismSpec>,
}

/// One `[[rock_masses]]` entry: a domain, the joint sets that cut it, and which blocks are held.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RockMassSpec {
    pub(super) name: String,
    pub(super) material: String,
    /// Convex pieces whose union is the domain.
    pub(super) regions: Vec<Spanned<RegionSpec>>,
    #[serde(default)]
    pub(super) fixed: FixedSpec,
    /// m³: blocks smaller than this after cutting are dropped (default: 10⁻³ of the median
    /// block's volume).
    pub(super) min_volume: Option<f64>,
    /// A cut is not made where a piece would be thinner than its extent (at most the smallest
    /// joint spacing) over this (default 30).
    pub(super) max_aspect: Option<f64>,
    #[serde(default)]
    pub(super) joint_sets: Vec<Spanned<JointSetSpec>>,
}

/// A region of a rock mass's domain, in the shape syntax of `[[blocks]]`. The shape keys are
/// repeated from [`BlockSpec`] rather than shared by `#[serde(flatten)]`, which serde does not
/// support together with `deny_unknown_fields`; [`ShapeSpec`] is what both hand on.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RegionSpec {
    pub(super) vertices: Option<Vec<Exact<3>>>,
    #[serde(rename = "box")]
    pub(super) box_: Option<BoxSpec>,
    pub(super) dodecahedron: Option<DodecahedronSpec>,
    pub(super) prism: Option<PrismSpec>,
}

impl RegionSpec {
    pub(super) fn shape(&self) -> ShapeSpec<'_> {
        ShapeSpec {
            vertices: self.vertices.as_deref(),
            box_: self.box_.as_ref(),
            dodecahedron: self.dodecahedron.as_ref(),
            prism: self.prism.as_ref(),
        }
    }
}

/// Which blocks of a rock mass are held: a block is fixed when its centroid meets any of these.
#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct FixedSpec {
    /// z below this, m.
    pub(super) below: Option<f64>,
    /// z above this, m.
    pub(super) above: Option<f64>,
    pub(super) x_below: Option<f64>,
    pub(super) x_above: Option<f64>,
    pub(super) y_below: Option<f64>,
    pub(super) y_above: Option<f64>,
    /// Every block of these regions (numbered from 1).
    #[serde(default)]
    pub(super) regions: Vec<u16>,
}

/// One `[[rock_masses.joint_sets]]` entry.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct JointSetSpec {
    pub(super) name: String,
    /// Degrees below horizontal.
    pub(super) dip: f64,
    /// Degrees clockwise from north (+y).
    pub(super) dip_direction: f64,
    /// m, normal distance between planes.
    pub(super) spacing: f64,
    #[serde(default, deserialize_with = "exact")]
    pub(super) origin: [f64; 3],
    pub(super) friction_angle: Option<f64>,
    pub(super) cohesion: Option<f64>,
    /// m: standard deviation of each spacing.
    #[serde(default)]
    pub(super) spacing_deviation: f64,
    /// Degrees: standard deviation of each plane's tilt, in each of two directions.
    #[serde(default)]
    pub(super) orientation_deviation: f64,
    #[serde(default)]
    pub(super) seed: u64,
}

/// One top-level `[[joint_sets]]` entry: a set by its planes.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct PlanesSpec {
    pub(super) name: String,
    /// The rock mass whose blocks the planes cut.
    pub(super) rock_mass: String,
    pub(super) friction_angle: Option<f64>,
    pub(super) cohesion: Option<f64>,
    /// Each plane as [n_x, n_y, n_z, d]: the points x with n·x = d (n a unit normal).
    pub(super) planes: Vec<Exact<4>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct BoxSpec {
    /// Edge lengths along the block's own x, y, z, m.
    #[serde(deserialize_with = "exact")]
    pub(super) size: [f64; 3],
    #[serde(deserialize_with = "exact")]
    pub(super) center: [f64; 3],
    /// Rotation about x, then y, then z (fixed axes), degrees.
    #[serde(default, deserialize_with = "exact")]
    pub(super) rotation: [f64; 3],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct DodecahedronSpec {
    /// Edge length, m.
    pub(super) edge: f64,
    #[serde(deserialize_with = "exact")]
    pub(super) center: [f64; 3],
    #[serde(default, deserialize_with = "exact")]
    pub(super) rotation: [f64; 3],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct PrismSpec {
    /// A convex polygon.
    pub(super) base: Vec<Exact<3>>,
    /// The sweep vector from the base to the top face.
    #[serde(deserialize_with = "exact")]
    pub(super) extrude: [f64; 3],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct LoadSpec {
    #[serde(deserialize_with = "exact")]
    pub(super) point: [f64; 3],
    #[serde(deserialize_with = "exact")]
    pub(super) force: [f64; 3],
}
