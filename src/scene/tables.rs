//! Where the scene format has a table, a list is refused. serde reads a struct from a list of its
//! fields in order, so `contact = []` under `[solver]` was a `[solver.contact]` of defaults,
//! `rock = [2750.0, 2.0e10, 0.25]` under `[materials]` a material by the order of its keys, and
//! `box = [[1, 1, 1], [0, 0, 5]]` a box, all silently (found by `tests/fuzz_scenes.rs` with
//! another seed). The format's tables are listed here, and [`check`] walks the text's tables
//! against the list once serde has read it (toml's span-keeping parse, for the line).

use toml::de::{DeTable, DeValue};

use super::locate::line_of;

/// What the format holds at a key.
enum Shape {
    /// A table whose keys are checked as listed (the keys not listed are not tables).
    Table(&'static [(&'static str, Shape)]),
    /// A table whose every key holds a table (`[materials]`).
    EachTable,
    /// A list of tables (`[[blocks]]`), each checked as listed.
    Tables(&'static [(&'static str, Shape)]),
}

/// The shape keys of a block and of a rock mass's region.
const SHAPES: &[(&str, Shape)] = &[
    ("box", Shape::Table(&[])),
    ("dodecahedron", Shape::Table(&[])),
    ("prism", Shape::Table(&[])),
];

const BLOCK: &[(&str, Shape)] = &[
    ("box", Shape::Table(&[])),
    ("dodecahedron", Shape::Table(&[])),
    ("prism", Shape::Table(&[])),
    ("loads", Shape::Tables(&[])),
];

const ROCK_MASS: &[(&str, Shape)] = &[
    ("regions", Shape::Tables(SHAPES)),
    ("fixed", Shape::Table(&[])),
    ("joint_sets", Shape::Tables(&[])),
];

/// The scene file (`super::format::SceneFile`).
const SCENE: &[(&str, Shape)] = &[
    ("solver", Shape::Table(&[("contact", Shape::Table(&[]))])),
    ("joint", Shape::Table(&[])),
    ("output", Shape::Table(&[])),
    ("materials", Shape::EachTable),
    ("blocks", Shape::Tables(BLOCK)),
    ("rock_masses", Shape::Tables(ROCK_MASS)),
    ("joint_sets", Shape::Tables(&[])),
];

/// The line and the message of the first list where the format has a table. Text that toml
/// cannot parse passes: serde's own message names that.
pub(super) fn check(text: &str) -> Result<(), (usize, String)> {
    let Ok(doc) = DeTable::parse(text) else {
        return Ok(());
    };
    walk(doc.get_ref(), SCENE, "").map_err(|(offset, m)| (line_of(text, offset), m))
}

/// Checks the keys of `table` that `shape` lists; `prefix` is the dotted path to it.
fn walk(table: &DeTable<'_>, shape: &[(&str, Shape)], prefix: &str) -> Result<(), (usize, String)> {
    for (key, inner) in shape {
        let Some(value) = table.get(*key) else {
            continue;
        };
        let path = format!("{prefix}{key}");
        let offset = value.span().start;
        match (inner, value.get_ref()) {
            (Shape::Table(keys), DeValue::Table(t)) => walk(t, keys, &format!("{path}."))?,
            (Shape::EachTable, DeValue::Table(t)) => {
                for (name, v) in t.iter() {
                    if v.get_ref().is_array() {
                        let path = format!("{path}.{}", name.get_ref());
                        return Err((v.span().start, not_a_list(&path)));
                    }
                }
            }
            (Shape::Table(_) | Shape::EachTable, DeValue::Array(_)) => {
                return Err((offset, not_a_list(&path)));
            }
            (Shape::Tables(keys), DeValue::Array(items)) => {
                for (k, item) in items.iter().enumerate() {
                    match item.get_ref() {
                        DeValue::Table(t) => walk(t, keys, &format!("{path}[{k}]."))?,
                        _ => {
                            // A header names the list without the entries' indices.
                            let header: String = path
                                .split('.')
                                .map(|k| k.split('[').next().unwrap_or(k))
                                .collect::<Vec<_>>()
                                .join(".");
                            return Err((
                                item.span().start,
                                format!(
                                    "{path}: each entry must be a table ([[{header}]] or {{ key = value, ... }})"
                                ),
                            ));
                        }
                    }
                }
            }
            // Any other type is serde's to refuse, with its own message.
            _ => {}
        }
    }
    Ok(())
}

fn not_a_list(path: &str) -> String {
    let key = path.rsplit('.').next().unwrap_or(path);
    let section = if path.contains('[') {
        String::new()
    } else {
        format!("a [{path}] section or ")
    };
    format!(
        "{path} must be a table, not a list: write it as {section}{key} = {{ key = value, ... }}"
    )
}

#[cfg(test)]
mod tests {
    use super::check;

    fn refused(text: &str) -> (usize, String) {
        check(text).expect_err(text)
    }

    #[test]
    fn lists_where_the_format_has_tables_are_refused_with_their_line() {
        let (line, m) = refused("[solver]\nduration = 1.0\ncontact = []\n");
        assert_eq!(line, 3);
        assert!(m.starts_with("solver.contact must be a table"), "{m}");
        let (line, m) = refused("[materials]\nrock = [2750.0, 2.0e10, 0.25]\n");
        assert_eq!(
            (line, m.starts_with("materials.rock must")),
            (2, true),
            "{m}"
        );
        let (_, m) = refused("[[blocks]]\nmaterial = \"rock\"\nbox = [[1, 1, 1], [0, 0, 5]]\n");
        assert!(m.starts_with("blocks[0].box must be a table"), "{m}");
        let (_, m) = refused("[[blocks]]\nmaterial = \"r\"\nloads = [[[0, 0, 0], [1, 0, 0]]]\n");
        assert!(m.starts_with("blocks[0].loads: each entry"), "{m}");
        assert!(m.contains("([[blocks.loads]] or"), "{m}");
        let (_, m) = refused("joint = []\n");
        assert!(m.starts_with("joint must be a table"), "{m}");
        let (_, m) = refused("blocks = [[1, 2, 3]]\n");
        assert!(m.starts_with("blocks: each entry"), "{m}");
        let (_, m) = refused(
            "[[rock_masses]]\nname = \"m\"\nfixed = []\n[[rock_masses.regions]]\nbox = {}\n",
        );
        assert!(m.starts_with("rock_masses[0].fixed must"), "{m}");
        let (_, m) = refused("[[rock_masses]]\nname = \"m\"\nregions = [[[0, 0, 0]]]\n");
        assert!(m.starts_with("rock_masses[0].regions: each entry"), "{m}");
    }

    #[test]
    fn tables_and_lists_of_numbers_pass() {
        let text = "[solver]\ngravity = [0.0, 0.0, -9.8]\n[solver.contact]\nalpha = 10.0\n\
                    [materials.rock]\ndensity = 1.0\n[[blocks]]\nmaterial = \"rock\"\n\
                    vertices = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]\n\
                    velocity = [1, 0, 0]\nbox = { size = [1, 1, 1] }\n\
                    loads = [{ point = [0, 0, 0], force = [1, 0, 0] }]\n\
                    [[rock_masses]]\nname = \"m\"\nregions = [{ box = { size = [1, 1, 1] } }]\n\
                    [rock_masses.fixed]\nregions = [1, 2]\n";
        assert_eq!(check(text), Ok(()));
        // Text toml cannot parse is left to serde's message.
        assert_eq!(check("[solver\n"), Ok(()));
    }
}
