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
//!
//! - [`format`]: the TOML tables as serde reads them;
//! - [`build`]: materials checked, shapes turned into blocks, the start checked for overlaps.

mod build;
mod format;

use std::fmt;
use std::path::Path;

use build::{build_block, check_material, check_overlaps};
use format::SceneFile;

use crate::model::Model;
use crate::params::SolverParams;

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
        check_material(name, m.get_ref())
            .map_err(|e| err(Some(line_of(text, m.span().start)), e))?;
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
        blocks.push(build_block(spec, name.clone(), material).map_err(berr)?);
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
