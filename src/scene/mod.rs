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
//! - [`format`]: the TOML tables as serde reads them; [`tables`]: no list where they are tables;
//! - [`build`]: materials checked, shapes turned into blocks, the start checked for overlaps;
//! - [`locate`]: the line and key of an error, found in the text.
//!
//! Every input is bounded (README, "Input limits"): the file's size ([`MAX_FILE_BYTES`]), the
//! blocks ([`MAX_BLOCKS`]), the points of a block ([`MAX_BLOCK_POINTS`]), and every parameter by
//! the range of its entry in [`crate::params::table`].

mod build;
mod format;
mod locate;
mod read;
mod rock_mass;
mod tables;
mod write;

use std::fmt;
use std::path::Path;

pub use build::{MAX_INERTIA_PER_PENALTY_CAP, check_inertia_scale};
use build::{build_block, check_material, check_overlaps, check_penalty_scale};
use format::SceneFile;
use locate::{LineIndex, key_at, key_line, line_of};
pub(crate) use read::{ReadError, read_utf8};

pub use crate::rockmass::report::RockMassReport;
pub use write::cut_scene;

use crate::model::{Block, Model, RockMassOf};
use crate::params::{JointSetParams, SolverParams, table};
use crate::physics::geometry::convex_hull;
use crate::physics::mechanics::Material;
use crate::text::one_line;
use rock_mass::CutBlock;

/// The largest scene file read, in bytes (16 MiB). The largest generated wall (99 998 blocks)
/// takes 12.8 MB. toml's parse keeps every number with its place in the text, so the memory of a
/// parse grows with the text: 55 times a file of boxes, and 88 times (1.4 GB, 7 s) a file of
/// nothing but `[0,0,0],`. `run /dev/zero` read until memory ran out.
pub const MAX_FILE_BYTES: u64 = 16 << 20;

/// The most blocks a scene may have. The solver's cost grows about linearly with the blocks
/// (README, Performance: a wall of 1000 blocks runs in minutes), so 10⁵ is already a long run;
/// `dda3d generate` writes walls up to this size.
pub const MAX_BLOCKS: usize = 100_000;

/// The most points a block's shape may have (`vertices`, or twice a prism's base): the convex
/// hull of 10⁵ points takes well under a second in O(n log n), and a real block has tens.
pub const MAX_BLOCK_POINTS: usize = 100_000;

/// The most corners a block's convex hull may keep. Contact detection between two blocks
/// tests every corner of each against the other's faces: two hulls of 10⁴ corners took 0.25 s
/// a step, two of 10⁵ (inside the point limit) 50 s. A real block has tens; a scanned boulder
/// is simplified to a few hundred.
pub const MAX_HULL_VERTICES: usize = 4096;

/// A bad scene: one line naming the file, the line when known, and the problem.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneError {
    pub path: String,
    pub line: Option<usize>,
    pub message: String,
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let text = match self.line {
            Some(l) => format!("{}: line {}: {}", self.path, l, self.message),
            None => format!("{}: {}", self.path, self.message),
        };
        // One line, whatever a name or a path in it holds (a block named "a\nb").
        f.write_str(&one_line(&text))
    }
}

impl std::error::Error for SceneError {}

/// A loaded scene.
#[derive(Clone, Debug)]
pub struct Scene {
    pub name: String,
    pub params: SolverParams,
    pub model: Model,
    /// What cutting each `[[rock_masses]]` entry gave.
    pub rock_masses: Vec<RockMassReport>,
    /// The scene's `[output]` table.
    pub output: OutputSettings,
}

/// What `dda3d run` writes besides the CSV files (the scene's `[output]`; `run --vtk` and
/// `--output-interval` override it).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct OutputSettings {
    /// Write the ParaView series into `DIR/vtk/`.
    pub vtk: bool,
    /// Simulated time between outputs (the CSV rows and the VTK series), s (`None`: every
    /// step).
    pub interval: Option<f64>,
}

impl OutputSettings {
    /// A one-line problem with an output interval, if it has one.
    pub fn check_interval(interval: f64) -> Result<(), String> {
        if interval.is_finite() && interval > 0.0 {
            Ok(())
        } else {
            Err(format!(
                "output interval {interval} s: must be a positive number of seconds"
            ))
        }
    }
}

/// Reads and validates a scene file.
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    let (text, shown, default_name) = read_text(path)?;
    parse(&text, &shown, &default_name)
}

/// A scene file's text, with the path as messages show it and the scene's default name (the
/// file's stem): what [`load`] parses, for callers that change the text first.
pub fn read_text(path: &Path) -> Result<(String, String, String), SceneError> {
    let shown = path.display().to_string();
    let err = |line: Option<usize>, message: String| SceneError {
        path: shown.clone(),
        line,
        message,
    };
    let text = read_utf8(path, "a scene file").map_err(|e| match e {
        ReadError::NotUtf8 { line, message } => err(Some(line), message),
        other => err(None, other.to_string()),
    })?;
    let default_name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".into());
    Ok((text, shown, default_name))
}

/// The line and message of a toml error: its line from its offset, and the key of the value it
/// rejects where the message does not name it (`solver.gravity: expected 3 numbers, got 4`).
fn toml_error(text: &str, e: &toml::de::Error) -> (Option<usize>, String) {
    let message = shorten_numbers(&e.message().trim().replace('\n', " "));
    let Some(span) = e.span() else {
        return (None, message);
    };
    let line = Some(line_of(text, span.start));
    if message == "duplicate key" {
        let key = locate::duplicate_key(text, span);
        if !key.is_empty() {
            return (line, format!("{key}: {message}"));
        }
        return (line, message);
    }
    match key_at(text, span.start) {
        Some(key) if !message.contains(&format!("`{key}`")) => (line, format!("{key}: {message}")),
        _ => (line, message),
    }
}

/// The message with every number of more than 12 characters written short: serde prints a
/// float in full, 309 digits for `1e308` where an integer was expected.
pub(crate) fn shorten_numbers(message: &str) -> String {
    let is_num = |c: char| c.is_ascii_digit() || matches!(c, '.' | '-' | '+' | 'e' | 'E');
    let mut out = String::with_capacity(message.len());
    let mut rest = message;
    while let Some(start) = rest.find(|c: char| c.is_ascii_digit()) {
        let len = rest[start..]
            .find(|c: char| !is_num(c))
            .unwrap_or(rest.len() - start);
        let token = &rest[start..start + len];
        out.push_str(&rest[..start]);
        match token.parse::<f64>() {
            Ok(x) if token.len() > 12 => out.push_str(&crate::text::short(x)),
            _ => out.push_str(token),
        }
        rest = &rest[start + len..];
    }
    out.push_str(rest);
    out
}

/// The line of the first of `keys` (`solver.contact.beta`) that the text sets.
fn first_key_line(text: &str, keys: &[&str]) -> Option<usize> {
    keys.iter().find_map(|k| {
        let path: Vec<&str> = k.split('.').collect();
        key_line(text, &path)
    })
}

/// Parses scene text; `path` is used in messages only.
pub fn parse(text: &str, path: &str, default_name: &str) -> Result<Scene, SceneError> {
    parse_cut(text, path, default_name, false, true).map(|(scene, _)| scene)
}

/// [`load`] without the check of Δt_max against the heaviest block
/// ([`check_inertia_scale`]), for a caller that changes the method, the mode or Δt_max before
/// it runs the check itself: the command line, where `--method penalty` on a scene whose
/// Δt_max is too short for DDA-3a was refused for DDA-3a's sake.
pub fn load_deferring_inertia_check(path: &Path) -> Result<Scene, SceneError> {
    let (text, shown, default_name) = read_text(path)?;
    parse_cut(&text, &shown, &default_name, false, false).map(|(scene, _)| scene)
}

/// What the rock masses were cut into, as `dda3d cut` writes it out: the corners each of their
/// blocks was built from (the blocks after the `[[blocks]]`, in order), and their sets.
struct CutOutput {
    points: Vec<Vec<crate::physics::geometry::Vec3>>,
    sets: Vec<rock_mass::CutSet>,
}

/// [`parse`], with what the rock masses were cut into (their blocks' corners only with
/// `keep_points`: a load that does not write them out does not copy them).
fn parse_cut(
    text: &str,
    path: &str,
    default_name: &str,
    keep_points: bool,
    check_inertia: bool,
) -> Result<(Scene, CutOutput), SceneError> {
    let err = |line: Option<usize>, message: String| SceneError {
        path: path.to_string(),
        line,
        message,
    };
    let file: SceneFile = toml::from_str(text).map_err(|e| {
        let (line, message) = toml_error(text, &e);
        err(line, message)
    })?;
    tables::check(text).map_err(|(line, m)| err(Some(line), m))?;
    let mut params = file.solver.clone();
    params.joint = file.joint.clone();
    params
        .check()
        .map_err(|e| err(first_key_line(text, e.keys), e.message))?;
    if let Some(dt) = file.output.interval {
        OutputSettings::check_interval(dt)
            .map_err(|m| err(key_line(text, &["output", "interval"]), m))?;
    }

    check_materials(&file, &params, text).map_err(|(line, m)| err(line, m))?;
    if file.blocks.is_empty() && file.rock_masses.is_empty() {
        return Err(err(
            None,
            "no [[blocks]] and no [[rock_masses]]: a scene needs at least one block".into(),
        ));
    }
    if let Some(extra) = file.blocks.get(MAX_BLOCKS) {
        return Err(err(
            Some(line_of(text, extra.span().start)),
            format!(
                "{} blocks, more than the limit of {MAX_BLOCKS} for a scene",
                file.blocks.len()
            ),
        ));
    }
    let mut masses = MassNames::of(&file).map_err(|(at, m)| err(Some(line_of(text, at)), m))?;
    let (mut blocks, mut lines) = hand_blocks(&file, &mut masses, text, path)?;
    let mut sets = Vec::new();
    for s in &file.joint_sets {
        let line = Some(line_of(text, s.span().start));
        let spec = s.get_ref();
        let index = masses.find(&spec.rock_mass).ok_or_else(|| {
            err(
                line,
                format!(
                    "joint set '{}': no block is of rock mass '{}'",
                    spec.name, spec.rock_mass
                ),
            )
        })?;
        sets.push(rock_mass::planes_set(spec, index, &params.joint).map_err(|m| err(line, m))?);
    }
    let mut reports = Vec::new();
    let mut cut_points = Vec::new();
    let first_cut_set = sets.len();
    for (k, m) in file.rock_masses.iter().enumerate() {
        let line = Some(line_of(text, m.span().start));
        let spec = m.get_ref();
        let merr = |msg: String| err(line, format!("rock mass '{}': {msg}", spec.name));
        let material = material_of(&file, &spec.material).map_err(merr)?;
        let room = MAX_BLOCKS - blocks.len();
        let cut = rock_mass::cut_mass(spec, k as u16, &params.joint, room).map_err(merr)?;
        for b in cut.blocks {
            if keep_points {
                cut_points.push(b.vertices.clone());
            }
            blocks.push(cut_block(b, material).map_err(merr)?);
            lines.push(line);
        }
        sets.extend(cut.sets);
        reports.push(cut.report);
    }
    params.joint_sets = tag_joint_faces(&mut blocks, &sets, &masses);
    // A set, not a scan of the blocks before each: 10⁵ blocks are 5·10⁹ comparisons.
    let mut names = std::collections::HashSet::with_capacity(blocks.len());
    for (k, b) in blocks.iter().enumerate() {
        if !names.insert(b.name.as_str()) {
            return Err(err(
                lines[k],
                format!("block name '{}' is used twice", b.name),
            ));
        }
    }
    check_overlaps(&blocks).map_err(|(k, m)| err(lines[k], m))?;
    if check_inertia {
        check_inertia_scale(&blocks, &params).map_err(|m| {
            let keys = [table::MAX_TIME_STEP.key, table::GAMMA.key];
            err(first_key_line(text, &keys), m)
        })?;
    }
    let name = file.name.unwrap_or_else(|| default_name.to_string());
    let scene = Scene {
        name: name.clone(),
        params,
        model: Model {
            name,
            blocks,
            rock_masses: masses.names,
        },
        rock_masses: reports,
        output: OutputSettings {
            vtk: file.output.vtk,
            interval: file.output.interval,
        },
    };
    let cut = CutOutput {
        points: cut_points,
        sets: sets.split_off(first_cut_set),
    };
    Ok((scene, cut))
}

/// Checks each material's constants, then the initial penalty against the stiffest one; an
/// error comes with the line of the key it concerns.
fn check_materials(
    file: &SceneFile,
    params: &SolverParams,
    text: &str,
) -> Result<(), (Option<usize>, String)> {
    for (name, m) in &file.materials {
        check_material(name, m.get_ref()).map_err(|(key, e)| {
            let line = key_line(text, &["materials", name, key])
                .unwrap_or_else(|| line_of(text, m.span().start));
            (Some(line), e)
        })?;
    }
    let stiffest = file.materials.values().map(|m| m.get_ref().young_modulus);
    if let Some(young) = stiffest.reduce(f64::max) {
        check_penalty_scale(params, young).map_err(|m| {
            let line = first_key_line(text, &[table::INITIAL_PENALTY.key]);
            let keys = [table::INITIAL_PENALTY.key, table::GAMMA.key];
            // A penalty the file does not set is the table's default, 0.01 E of the paper's
            // rock: say so, and what the paper's rule gives for this rock.
            let m = if line.is_none() {
                format!(
                    "{m}; it is the default, the paper's 0.01 E for its E = 2e10 Pa: set it, \
                     e.g. to 0.01 E = {} N/m",
                    crate::text::short(0.01 * young)
                )
            } else {
                m
            };
            (first_key_line(text, &keys), m)
        })?;
    }
    Ok(())
}

/// The rock masses' names, by the index blocks and joint sets carry: those of `[[rock_masses]]`,
/// then those that blocks written by `dda3d cut` name.
struct MassNames {
    names: Vec<String>,
}

impl MassNames {
    /// The `[[rock_masses]]`' names, each once; an error at the offset of a repeated one.
    fn of(file: &SceneFile) -> Result<Self, (usize, String)> {
        let mut names: Vec<String> = Vec::new();
        for m in &file.rock_masses {
            let name = &m.get_ref().name;
            if names.contains(name) || name.is_empty() {
                return Err((
                    m.span().start,
                    format!("rock mass name '{name}' is empty or used twice"),
                ));
            }
            names.push(name.clone());
        }
        Ok(MassNames { names })
    }

    fn find(&self, name: &str) -> Option<u16> {
        self.names.iter().position(|n| n == name).map(|k| k as u16)
    }

    /// The index of `name`, added if new.
    fn index(&mut self, name: &str) -> u16 {
        self.find(name).unwrap_or_else(|| {
            self.names.push(name.to_owned());
            (self.names.len() - 1) as u16
        })
    }
}

/// Tags the faces of every rock mass's blocks that lie on the planes of its sets, and returns
/// the sets' properties by the index the tags carry.
fn tag_joint_faces(
    blocks: &mut [Block],
    sets: &[rock_mass::CutSet],
    masses: &MassNames,
) -> Vec<JointSetParams> {
    for (index, set) in sets.iter().enumerate() {
        for b in blocks.iter_mut() {
            if b.rock_mass.is_some_and(|r| r.mass == set.rock_mass) {
                rock_mass::tag_faces(b, set, index as u16);
            }
        }
    }
    sets.iter()
        .map(|s| JointSetParams {
            name: s.name.clone(),
            rock_mass: masses.names[usize::from(s.rock_mass)].clone(),
            joint: s.joint.clone(),
        })
        .collect()
}

/// A material of the file by name.
fn material_of(file: &SceneFile, name: &str) -> Result<Material, String> {
    file.materials
        .get(name)
        .map(|m| *m.get_ref())
        .ok_or_else(|| format!("material '{name}' is not defined under [materials]"))
}

/// The `[[blocks]]`, built, with their lines.
fn hand_blocks(
    file: &SceneFile,
    masses: &mut MassNames,
    text: &str,
    path: &str,
) -> Result<(Vec<Block>, Vec<Option<usize>>), SceneError> {
    let mut blocks = Vec::with_capacity(file.blocks.len());
    let mut lines = Vec::with_capacity(file.blocks.len());
    let index = LineIndex::new(text);
    for (k, spanned) in file.blocks.iter().enumerate() {
        let line = Some(index.line(spanned.span().start));
        let spec = spanned.get_ref();
        let name = spec.name.clone().unwrap_or_else(|| format!("block{k}"));
        let berr = |m: String| SceneError {
            path: path.to_string(),
            line,
            message: format!("block '{name}': {m}"),
        };
        let material = material_of(file, &spec.material).map_err(berr)?;
        let mut block = build_block(spec, name.clone(), material).map_err(berr)?;
        if let Some(mass) = &spec.rock_mass {
            let region = spec.region.unwrap_or(1);
            if region == 0 {
                return Err(berr("region is numbered from 1".into()));
            }
            block.rock_mass = Some(RockMassOf {
                mass: masses.index(mass),
                region: region - 1,
            });
        }
        blocks.push(block);
        lines.push(line);
    }
    Ok((blocks, lines))
}

/// A block cut from a rock mass, built from its corners.
fn cut_block(b: CutBlock, material: Material) -> Result<Block, String> {
    let (vertices, topo) =
        convex_hull(&b.vertices).map_err(|e| format!("block '{}': {e}", b.name))?;
    let zero = crate::physics::geometry::Vec3::zeros();
    let mut block = Block::new(
        b.name,
        material,
        b.fixed,
        vertices,
        topo,
        zero,
        zero,
        Vec::new(),
    );
    block.rock_mass = Some(b.rock_mass);
    Ok(block)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_numbers_in_messages_are_written_short() {
        let full = format!("invalid type: floating point `{}`, expected u32", 1e308f64);
        assert_eq!(
            shorten_numbers(&full),
            "invalid type: floating point `1e308`, expected u32"
        );
        // Short numbers, line numbers and identifiers with digits stay as they are.
        let kept = "line 12: max_alm_iterations: 20 is not in [1, 1000], x2 0.25";
        assert_eq!(shorten_numbers(kept), kept);
        let tiny = format!("got {:.320}", 1e-308f64);
        assert_eq!(shorten_numbers(&tiny), "got 1e-308");
    }

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

    /// A rock too soft for the default p_n,1 (2·10⁸ N/m, the paper's 0.01 E of 2·10¹⁰ Pa): the
    /// message says the penalty is the default and what 0.01 E gives; set, it is named as set.
    #[test]
    fn a_default_penalty_too_stiff_for_the_rock_says_it_is_the_default() {
        let soft = GOOD.replace("2.0e10", "1.0e6");
        let e = parse_err(&soft);
        assert!(e.message.contains("it is the default"), "{}", e.message);
        assert!(e.message.contains("0.01 E = 10000 N/m"), "{}", e.message);
        let set = soft.replace(
            "[materials",
            "[solver.contact]\ninitial_penalty = 3e8\n[materials",
        );
        let e = parse_err(&set);
        assert!(!e.message.contains("default"), "{}", e.message);
        assert!(e.message.contains("3e8 N/m"), "{}", e.message);
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

    /// Errors found after parsing carry the line of their key too: the table's checks, the
    /// materials' constants, and the step limit at the line of whichever key the file sets.
    #[test]
    fn checks_after_parsing_point_at_their_key() {
        let with = |extra: &str| parse_err(&format!("{GOOD}{extra}"));
        // GOOD ends at line 17; the table added starts at 18.
        for (extra, line, key) in [
            (
                "[joint]\nfriction_angle = 95.0\n",
                19,
                "joint.friction_angle",
            ),
            ("[joint]\n\ncohesion = -1.0\n", 20, "joint.cohesion"),
            ("[solver.contact]\nbeta = 1.0\n", 19, "solver.contact.beta"),
            ("[solver.contact]\neps1 = nan\n", 19, "solver.contact.eps1"),
        ] {
            let e = with(extra);
            assert_eq!(e.line, Some(line), "{e}");
            assert!(e.message.starts_with(key), "{e}");
        }
        // [solver] of GOOD is at line 3, its duration at 4.
        let e = parse_err(&GOOD.replace("duration = 0.5", "duration = 0.5\nmax_time_step = 1e-8"));
        assert_eq!(e.line, Some(5), "{e}");
        let e = parse_err(&GOOD.replace("duration = 0.5", "duration = 1e6"));
        assert_eq!(e.line, Some(4), "{e}");
        assert!(e.message.contains("1e8 steps"), "{e}");
        let e = parse_err(&GOOD.replace("duration = 0.5", "max_time_step = 1e-7"));
        assert_eq!(e.line, Some(4), "the default duration: Δt_max's line: {e}");
        let e = parse_err(&GOOD.replace("poisson_ratio = 0.25", "poisson_ratio = 0.5"));
        assert_eq!(e.line, Some(8), "{e}");
        let e = parse_err(&GOOD.replace("density = 2750.0", "density = -1e308"));
        assert_eq!(
            (e.line, e.message.ends_with("got -1e308")),
            (Some(6), true),
            "{e}"
        );
    }

    /// A message is one line whatever a name holds.
    #[test]
    fn names_with_control_characters_stay_on_one_line() {
        let e = parse_err(&GOOD.replace("name = \"top\"", "name = \"a\\nb\"\nfixed = 3"));
        assert!(!e.to_string().contains('\n'), "{e}");
        let e = parse_err(
            &GOOD
                .replace("\"base\"", "\"x\\ny\"")
                .replace("\"top\"", "\"x\\ny\""),
        );
        assert_eq!(e.to_string().lines().count(), 1, "{e}");
        assert!(e.to_string().contains("'x\\ny' is used twice"), "{e}");
    }

    /// The README's input limits state the numbers of this module.
    #[test]
    fn the_readme_states_the_scene_limits() {
        let readme = include_str!("../../README.md");
        let limits = readme.split("### Input limits").nth(1).unwrap();
        let spaced = |n: usize| {
            let s = n.to_string();
            let (head, tail) = s.split_at(s.len() - 3);
            format!("{head} {tail}")
        };
        for needle in [
            format!("| scene file | {} MiB", MAX_FILE_BYTES >> 20),
            format!("| blocks | {} per scene", spaced(MAX_BLOCKS)),
            format!("| points per block | {}", spaced(MAX_BLOCK_POINTS)),
            format!("1 ≤ N ≤ {}", spaced(crate::generate::MAX_WALL_BLOCKS)),
        ] {
            assert!(limits.contains(&needle), "README lacks {needle}");
        }
    }
}
