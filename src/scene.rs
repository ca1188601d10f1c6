//! Scene files (TOML): format, validation, and the model and parameters they describe.
//!
//! ```toml
//! name = "Block sliding on a 30 degree slope"
//! [solver]                  # everything optional: see params::SolverParams
//! method = "alm"
//! [solver.contact]          # params::ContactParams
//! [joint]                   # params::JointParams
//! [materials.rock]
//! density = 2750.0
//! young_modulus = 2.0e10
//! poisson_ratio = 0.25
//! [[blocks]]
//! name = "block"
//! material = "rock"
//! vertices = [[0,0,0], ...]           # or box = {...}, dodecahedron = {...}, prism = {...}
//! ```

use std::collections::BTreeMap;
use std::fmt;
use std::path::Path;

use serde::Deserialize;
use toml::Spanned;

use crate::contact::Shape;
use crate::contact::detection::broad_phase;
use crate::model::{Block, Model};
use crate::params::{JointParams, SolverParams};
use crate::physics::geometry::{
    Vec3, box_vertices, convex_hull, dodecahedron_vertices, overlap_depth, prism_vertices,
    rotation_xyz_degrees,
};
use crate::physics::mechanics::Material;

/// A bad scene: one line naming the file, the line when known, and the problem.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneError {
    pub path: String,
    pub line: Option<usize>,
    pub message: String,
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line {
            Some(l) => write!(f, "{}: line {}: {}", self.path, l, self.message),
            None => write!(f, "{}: {}", self.path, self.message),
        }
    }
}

impl std::error::Error for SceneError {}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    name: Option<String>,
    #[serde(default)]
    solver: SolverParams,
    #[serde(default)]
    joint: JointParams,
    #[serde(default)]
    materials: BTreeMap<String, Spanned<Material>>,
    #[serde(default)]
    blocks: Vec<Spanned<BlockSpec>>,
}

/// One `[[blocks]]` entry. Exactly one of `vertices`, `box`, `dodecahedron`, `prism`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BlockSpec {
    name: Option<String>,
    material: String,
    #[serde(default)]
    fixed: bool,
    /// Initial centroid velocity, m/s.
    #[serde(default)]
    velocity: [f64; 3],
    /// Initial angular velocity, rad/s.
    #[serde(default)]
    angular_velocity: [f64; 3],
    vertices: Option<Vec<[f64; 3]>>,
    #[serde(rename = "box")]
    box_: Option<BoxSpec>,
    dodecahedron: Option<DodecahedronSpec>,
    prism: Option<PrismSpec>,
    /// Point loads moving with the block.
    #[serde(default)]
    loads: Vec<LoadSpec>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BoxSpec {
    /// Edge lengths along the block's own x, y, z, m.
    size: [f64; 3],
    center: [f64; 3],
    /// Rotation about x, then y, then z (fixed axes), degrees.
    #[serde(default)]
    rotation: [f64; 3],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct DodecahedronSpec {
    /// Edge length, m.
    edge: f64,
    center: [f64; 3],
    #[serde(default)]
    rotation: [f64; 3],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PrismSpec {
    /// A convex polygon.
    base: Vec<[f64; 3]>,
    /// The sweep vector from the base to the top face.
    extrude: [f64; 3],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LoadSpec {
    point: [f64; 3],
    force: [f64; 3],
}

/// A loaded scene.
#[derive(Clone, Debug)]
pub struct Scene {
    pub name: String,
    pub params: SolverParams,
    pub model: Model,
}

/// Reads and validates a scene file.
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    let shown = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| SceneError {
        path: shown.clone(),
        line: None,
        message: format!("cannot read: {e}"),
    })?;
    let default_name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".into());
    parse(&text, &shown, &default_name)
}

fn line_of(text: &str, offset: usize) -> usize {
    text[..offset.min(text.len())].matches('\n').count() + 1
}

/// Parses scene text; `path` is used in messages only.
pub fn parse(text: &str, path: &str, default_name: &str) -> Result<Scene, SceneError> {
    let err = |line: Option<usize>, message: String| SceneError {
        path: path.to_string(),
        line,
        message,
    };
    let file: SceneFile = toml::from_str(text).map_err(|e| {
        let line = e.span().map(|s| line_of(text, s.start));
        err(line, e.message().trim().replace('\n', " "))
    })?;
    let mut params = file.solver;
    params.joint = file.joint;
    params.validate().map_err(|m| err(None, m))?;

    for (name, m) in &file.materials {
        let line = Some(line_of(text, m.span().start));
        let m = m.get_ref();
        for (key, v) in [
            ("density", m.density),
            ("young_modulus", m.young_modulus),
            ("poisson_ratio", m.poisson_ratio),
        ] {
            if !v.is_finite() {
                return Err(err(
                    line,
                    format!("material '{name}': {key} is not a finite number"),
                ));
            }
        }
        if m.density <= 0.0 {
            return Err(err(
                line,
                format!(
                    "material '{name}': density must be positive, got {}",
                    m.density
                ),
            ));
        }
        if m.young_modulus <= 0.0 {
            return Err(err(
                line,
                format!(
                    "material '{name}': young_modulus must be positive, got {}",
                    m.young_modulus
                ),
            ));
        }
        if !(m.poisson_ratio > -1.0 && m.poisson_ratio < 0.5) {
            return Err(err(
                line,
                format!(
                    "material '{name}': poisson_ratio must lie in (-1, 0.5), got {}",
                    m.poisson_ratio
                ),
            ));
        }
    }
    if file.blocks.is_empty() {
        return Err(err(
            None,
            "no [[blocks]]: a scene needs at least one block".into(),
        ));
    }

    let mut blocks = Vec::with_capacity(file.blocks.len());
    let mut lines = Vec::with_capacity(file.blocks.len());
    for (k, spanned) in file.blocks.iter().enumerate() {
        let line = Some(line_of(text, spanned.span().start));
        let spec = spanned.get_ref();
        let name = spec.name.clone().unwrap_or_else(|| format!("block{k}"));
        let berr = |m: String| err(line, format!("block '{name}': {m}"));
        let material = file
            .materials
            .get(&spec.material)
            .map(|m| *m.get_ref())
            .ok_or_else(|| {
                berr(format!(
                    "material '{}' is not defined under [materials]",
                    spec.material
                ))
            })?;
        let given = [
            spec.vertices.is_some(),
            spec.box_.is_some(),
            spec.dodecahedron.is_some(),
            spec.prism.is_some(),
        ]
        .iter()
        .filter(|&&b| b)
        .count();
        if given != 1 {
            return Err(berr(
                "give exactly one of vertices, box, dodecahedron or prism".into(),
            ));
        }
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        let points: Vec<Vec3> = if let Some(v) = &spec.vertices {
            v.iter().map(|p| Vec3::from(*p)).collect()
        } else if let Some(b) = &spec.box_ {
            if !finite(&b.size) || !finite(&b.center) || !finite(&b.rotation) {
                return Err(berr("box has a non-finite number".into()));
            }
            if b.size.iter().any(|&s| s <= 0.0) {
                return Err(berr("box size must be positive".into()));
            }
            box_vertices(b.size, b.center, &rotation_xyz_degrees(b.rotation))
        } else if let Some(d) = &spec.dodecahedron {
            if !d.edge.is_finite() || !finite(&d.center) || !finite(&d.rotation) {
                return Err(berr("dodecahedron has a non-finite number".into()));
            }
            if d.edge <= 0.0 {
                return Err(berr("dodecahedron edge must be positive".into()));
            }
            dodecahedron_vertices(d.edge, d.center, &rotation_xyz_degrees(d.rotation))
        } else {
            let p = spec.prism.as_ref().expect("one shape given");
            if !finite(&p.extrude) || p.base.iter().any(|b| !finite(b)) {
                return Err(berr("prism has a non-finite number".into()));
            }
            prism_vertices(&p.base, p.extrude)
        };
        let (vertices, topo) = convex_hull(&points).map_err(|e| berr(e.to_string()))?;
        if !finite(&spec.velocity) || !finite(&spec.angular_velocity) {
            return Err(berr("velocity is not finite".into()));
        }
        let mut loads = Vec::new();
        for l in &spec.loads {
            if !finite(&l.point) || !finite(&l.force) {
                return Err(berr("load has a non-finite number".into()));
            }
            loads.push((Vec3::from(l.point), Vec3::from(l.force)));
        }
        blocks.push(Block::new(
            name,
            material,
            spec.fixed,
            vertices,
            topo,
            Vec3::from(spec.velocity),
            Vec3::from(spec.angular_velocity),
            loads,
        ));
        lines.push(line);
    }
    for (k, b) in blocks.iter().enumerate() {
        if blocks[..k].iter().any(|o| o.name == b.name) {
            return Err(err(
                lines[k],
                format!("block name '{}' is used twice", b.name),
            ));
        }
    }
    check_overlaps(&blocks).map_err(|(k, m)| err(lines[k], m))?;
    let name = file.name.unwrap_or_else(|| default_name.to_string());
    Ok(Scene {
        name: name.clone(),
        params,
        model: Model { name, blocks },
    })
}

/// Blocks may touch at the start but not overlap: the separating-axis depth of every nearby
/// pair must stay below a small tolerance (10⁻⁴ of the model half-size, for coordinates typed
/// with a few decimals).
fn check_overlaps(blocks: &[Block]) -> Result<(), (usize, String)> {
    let all: Vec<Vec3> = blocks
        .iter()
        .flat_map(|b| b.vertices.iter().copied())
        .collect();
    let (lo, hi) = crate::physics::geometry::bounding_box(&all);
    let tol = 1e-4 * 0.5 * (hi - lo).max();
    let shapes: Vec<Shape> = blocks
        .iter()
        .map(|b| Shape {
            vertices: &b.vertices,
            topo: &b.topo,
            face_normals: &b.face_normals,
            centroid: b.mp.centroid,
            lo: b.lo,
            hi: b.hi,
            fixed: false,
        })
        .collect();
    for (a, b) in broad_phase(&shapes, 0.0) {
        let depth = overlap_depth(
            &blocks[a].vertices,
            &blocks[a].topo,
            &blocks[b].vertices,
            &blocks[b].topo,
        );
        if depth > tol {
            return Err((
                b,
                format!(
                    "blocks '{}' and '{}' overlap by {:.3e} m at the start (touching is fine)",
                    blocks[a].name, blocks[b].name, depth
                ),
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = r#"
name = "two cubes"
[solver]
duration = 0.5
[materials.rock]
density = 2750.0
young_modulus = 2.0e10
poisson_ratio = 0.25
[[blocks]]
name = "base"
material = "rock"
fixed = true
box = { size = [2, 2, 2], center = [0, 0, 1] }
[[blocks]]
name = "top"
material = "rock"
vertices = [[-1,-1,2],[1,-1,2],[1,1,2],[-1,1,2],[-1,-1,4],[1,-1,4],[1,1,4],[-1,1,4]]
"#;

    fn parse_err(text: &str) -> SceneError {
        parse(text, "s.toml", "s").expect_err("should fail")
    }

    #[test]
    fn good_scene_parses_with_defaults() {
        let s = parse(GOOD, "s.toml", "s").unwrap();
        assert_eq!(s.name, "two cubes");
        assert_eq!(s.model.blocks.len(), 2);
        assert_eq!(s.params.duration, 0.5);
        assert_eq!(s.params.contact.alpha, 10.0);
        assert_eq!(s.params.joint.friction_angle, 35.0);
        assert!((s.model.blocks[1].mp.volume - 8.0).abs() < 1e-12);
    }

    #[test]
    fn errors_name_the_file_line_and_problem() {
        let e = parse_err(&GOOD.replace("duration = 0.5", "duration = 0.5\nbogus = 1"));
        assert!(e.to_string().starts_with("s.toml: line "), "{e}");
        assert!(e.message.contains("bogus"), "{e}");
        let e = parse_err(&GOOD.replace(
            "material = \"rock\"\nvertices",
            "material = \"granite\"\nvertices",
        ));
        assert!(e.message.contains("granite") && e.line == Some(14), "{e}");
        let e = parse_err(&GOOD.replace("poisson_ratio = 0.25", "poisson_ratio = 0.5"));
        assert!(e.message.contains("poisson_ratio"), "{e}");
        let e = parse_err(&GOOD.replace("density = 2750.0", "density = -1.0"));
        assert!(e.message.contains("density"), "{e}");
        let e = parse_err(&GOOD.replace("young_modulus = 2.0e10", "young_modulus = nan"));
        assert!(e.message.contains("finite"), "{e}");
        let e = parse_err(&GOOD.replace("[-1,-1,4],[1,-1,4],[1,1,4],[-1,1,4]]", "[-1,-1,2]]"));
        assert!(
            e.message.contains("coplanar") || e.message.contains("four"),
            "{e}"
        );
        let e = parse_err(&GOOD.replace("center = [0, 0, 1]", "center = [0, 0, 1.5]"));
        assert!(e.message.contains("overlap"), "{e}");
        let e = parse_err("name = \"x\"\n[solver\n");
        assert_eq!(e.line, Some(2), "{e}");
        let e = parse_err(&GOOD.replace("duration = 0.5", "duration = inf"));
        assert!(e.message.contains("finite"), "{e}");
        let e = parse_err(&GOOD.replace("duration = 0.5", "method = \"lagrange\""));
        assert!(
            e.message.contains("lagrange") || e.message.contains("variant"),
            "{e}"
        );
        assert!(!e.to_string().contains('\n'));
    }
}
