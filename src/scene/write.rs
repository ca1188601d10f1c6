//! `dda3d cut`: a scene with every `[[rock_masses]]` entry replaced by what it was cut into —
//! `[[joint_sets]]` with their planes and `[[blocks]]` with their corners — and the rest of the
//! file (comments included) as it was. The numbers are written in Rust's shortest round-trip
//! form, so the file loads to the same model, bit for bit, as the scene it came from.

use std::path::Path;

use toml_edit::{Array, ArrayOfTables, DocumentMut, Item, Table, value};

use super::{CutOutput, RockMassReport, Scene, SceneError, parse_cut, read_text};

/// The cut scene's text and what each rock mass was cut into.
pub fn cut_scene(path: &Path) -> Result<(String, Vec<RockMassReport>), SceneError> {
    let (text, shown, default_name) = read_text(path)?;
    let (scene, cut) = parse_cut(&text, &shown, &default_name, true, true)?;
    let mut doc: DocumentMut = text.parse().map_err(|e: toml_edit::TomlError| SceneError {
        path: shown.clone(),
        line: None,
        message: e.message().to_string(),
    })?;
    let masses = doc.remove("rock_masses");
    let materials: Vec<String> = masses
        .as_ref()
        .and_then(Item::as_array_of_tables)
        .map(|a| {
            a.iter()
                .map(|t| t["material"].as_str().unwrap_or_default().to_owned())
                .collect()
        })
        .unwrap_or_default();
    let err = |what: &str| SceneError {
        path: shown.clone(),
        line: None,
        message: format!("{what} is not written as [[{what}]] tables: cannot add the cut ones"),
    };
    let sets = tables(&mut doc, "joint_sets").ok_or_else(|| err("joint_sets"))?;
    for s in &cut.sets {
        sets.push(set_table(s, &scene));
    }
    let blocks = tables(&mut doc, "blocks").ok_or_else(|| err("blocks"))?;
    write_blocks(blocks, &scene, &cut, &materials);
    let header = format!(
        "# Cut by `dda3d cut` from {shown}: its [[rock_masses]] are the [[joint_sets]] and \
         [[blocks]] at the end.\n"
    );
    Ok((header + &doc.to_string(), scene.rock_masses))
}

/// The array of tables `key`, created if absent; `None` if `key` holds something else.
fn tables<'a>(doc: &'a mut DocumentMut, key: &str) -> Option<&'a mut ArrayOfTables> {
    doc.entry(key)
        .or_insert(Item::ArrayOfTables(ArrayOfTables::new()))
        .as_array_of_tables_mut()
}

/// A `[[joint_sets]]` table for a set of a rock mass.
fn set_table(s: &super::rock_mass::CutSet, scene: &Scene) -> Table {
    let mut t = Table::new();
    t["name"] = value(s.name.as_str());
    t["rock_mass"] = value(scene.model.rock_masses[usize::from(s.rock_mass)].as_str());
    t["friction_angle"] = value(s.joint.friction_angle);
    t["cohesion"] = value(s.joint.cohesion);
    let planes: Array = s
        .planes
        .iter()
        .map(|p| {
            let row: Array = [p.normal.x, p.normal.y, p.normal.z, p.offset]
                .into_iter()
                .collect();
            row
        })
        .collect();
    t["planes"] = value(planes);
    t
}

/// The `[[blocks]]` of the rock masses: the blocks after the file's own, with the corners they
/// were built from.
fn write_blocks(blocks: &mut ArrayOfTables, scene: &Scene, cut: &CutOutput, materials: &[String]) {
    let first = scene.model.blocks.len() - cut.points.len();
    for (b, points) in scene.model.blocks[first..].iter().zip(&cut.points) {
        let of = b.rock_mass.expect("a block cut from a rock mass");
        let mut t = Table::new();
        t["name"] = value(b.name.as_str());
        t["material"] = value(materials[usize::from(of.mass)].as_str());
        if b.fixed {
            t["fixed"] = value(true);
        }
        t["rock_mass"] = value(scene.model.rock_masses[usize::from(of.mass)].as_str());
        t["region"] = value(i64::from(of.region) + 1);
        let vertices: Array = points
            .iter()
            .map(|p| {
                let row: Array = [p.x, p.y, p.z].into_iter().collect();
                row
            })
            .collect();
        t["vertices"] = value(vertices);
        blocks.push(t);
    }
}
