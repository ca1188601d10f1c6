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
