//! Study keys: a dotted path into the scene's TOML, set in the scene's text with `toml_edit` so
//! that a case's scene keeps the base file's comments and layout.
//!
//! `solver.contact.initial_penalty` walks tables by key; an array of tables (`[[blocks]]`,
//! `[[rock_masses]]`, `[[rock_masses.joint_sets]]`, or an inline array of tables) is entered by
//! the `name` of one of its elements (`blocks.rock.velocity[0]`) or by its index
//! (`rock_masses.slope.regions[0].box.size[1]`); `[i]` at the end indexes a vector, 0-based.
//! A table missing on the way, and the last key, are created when absent: whether the scene
//! format accepts them is for the scene's parse to say.

use toml_edit::{DocumentMut, InlineTable, Item, Table, TableLike, Value};

/// One step of a key: a table key, with the indexes that follow it (`vertices[0][2]`).
#[derive(Clone, Debug, PartialEq)]
struct Segment {
    key: String,
    indexes: Vec<usize>,
}

/// The segments of a key, or why it is not one.
fn segments(key: &str) -> Result<Vec<Segment>, String> {
    let bad = |why: &str| format!("key \"{key}\": {why}");
    let mut out = Vec::new();
    for part in key.split('.') {
        let (name, mut rest) = part.split_at(part.find('[').unwrap_or(part.len()));
        if name.is_empty() {
            return Err(bad(
                "an empty part (a key is a dotted path such as solver.duration)",
            ));
        }
        let mut indexes = Vec::new();
        while !rest.is_empty() {
            let close = rest.find(']').ok_or_else(|| bad("a '[' without its ']'"))?;
            let index = rest[1..close]
                .trim()
                .parse::<usize>()
                .map_err(|_| bad(&format!("[{}] is not an index from 0", &rest[1..close])))?;
            indexes.push(index);
            rest = &rest[close + 1..];
            if !rest.is_empty() && !rest.starts_with('[') {
                return Err(bad("text after an index"));
            }
        }
        out.push(Segment {
            key: name.to_string(),
            indexes,
        });
    }
    Ok(out)
}

/// What an element of an array of tables is called in messages.
fn element_label(array: &str) -> String {
    match array {
        "blocks" => "block".into(),
        "rock_masses" => "rock mass".into(),
        "joint_sets" => "joint set".into(),
        "regions" => "region".into(),
        "loads" => "load".into(),
        other => format!("element of {other}"),
    }
}

/// Sets (or reads) the value at `segs` under `table`: `f` gets the value there (None: absent)
/// and returns the value to put there.
type Visit<'f> = dyn FnMut(Option<&Value>) -> Result<Value, String> + 'f;

fn walk(
    table: &mut dyn TableLike,
    inline: bool,
    segs: &[Segment],
    f: &mut Visit<'_>,
) -> Result<(), String> {
    let (seg, rest) = segs.split_first().ok_or("an empty key")?;
    let key = seg.key.as_str();
    if rest.is_empty() {
        return set_value(table, seg, f);
    }
    if table.get(key).is_none() {
        if !seg.indexes.is_empty() {
            return Err(format!("no {key} in the scene to index"));
        }
        let new = if inline {
            Item::Value(Value::InlineTable(InlineTable::new()))
        } else {
            let mut t = Table::new();
            t.set_implicit(true);
            Item::Table(t)
        };
        table.insert(key, new);
    }
    let child = table.get_mut(key).ok_or("vanished")?;
    // The elements, and whether they are inline tables (for a table created inside one).
    let (mut elements, inline_elements): (Vec<&mut dyn TableLike>, bool) = match child {
        Item::ArrayOfTables(a) => (
            a.iter_mut().map(|t| t as &mut dyn TableLike).collect(),
            false,
        ),
        Item::Value(Value::Array(a)) if a.iter().all(Value::is_inline_table) => (
            a.iter_mut()
                .filter_map(Value::as_inline_table_mut)
                .map(|t| t as &mut dyn TableLike)
                .collect(),
            true,
        ),
        Item::Table(t) if seg.indexes.is_empty() => return walk(t, false, rest, f),
        Item::Value(Value::InlineTable(t)) if seg.indexes.is_empty() => {
            return walk(t, true, rest, f);
        }
        _ if !seg.indexes.is_empty() => {
            return Err(format!("{key} is not a list of tables: index it last"));
        }
        _ => return Err(format!("{key} is a value, not a table")),
    };
    let label = element_label(key);
    let (element, rest) = match seg.indexes.as_slice() {
        [] => {
            let (name, after) = rest.split_first().ok_or("vanished")?;
            if !name.indexes.is_empty() {
                return Err(format!("{}: a {label} is named, not indexed", name.key));
            }
            let found = elements
                .iter()
                .position(|t| t.get("name").and_then(Item::as_str) == Some(name.key.as_str()))
                .ok_or_else(|| format!("no {label} named \"{}\"", name.key))?;
            (found, after)
        }
        [i] => {
            if *i >= elements.len() {
                return Err(format!(
                    "{key}[{i}]: index out of range ({} in the scene)",
                    elements.len()
                ));
            }
            (*i, rest)
        }
        _ => return Err(format!("{key}: one index selects a table")),
    };
    if rest.is_empty() {
        return Err(format!(
            "names a whole {label}: give a key inside it (as in blocks.NAME.velocity[0])"
        ));
    }
    walk(elements.swap_remove(element), inline_elements, rest, f)
}

/// The last segment: a value of `table`, or an element of a vector there.
fn set_value(table: &mut dyn TableLike, seg: &Segment, f: &mut Visit<'_>) -> Result<(), String> {
    let key = seg.key.as_str();
    if seg.indexes.is_empty() {
        let old = match table.get(key) {
            None => None,
            Some(Item::Value(v)) => Some(v.clone()),
            Some(Item::None) => None,
            Some(_) => return Err(format!("{key} is a table, not a value")),
        };
        let mut new = f(old.as_ref())?;
        if let Some(old) = &old {
            *new.decor_mut() = old.decor().clone();
        }
        table.insert(key, Item::Value(new));
        return Ok(());
    }
    let mut slot = match table.get_mut(key) {
        Some(Item::Value(v)) => v,
        Some(_) => return Err(format!("{key} is not a list of values")),
        None => {
            return Err(format!(
                "no {key} in the scene: write it in the base scene to vary one of its elements"
            ));
        }
    };
    let mut path = key.to_string();
    for &i in &seg.indexes {
        let Value::Array(a) = slot else {
            return Err(format!("{path} is not a list"));
        };
        let len = a.len();
        slot = a
            .get_mut(i)
            .ok_or_else(|| format!("{path}[{i}]: index out of range ({len} values)"))?;
        path = format!("{path}[{i}]");
    }
    let mut new = f(Some(&*slot))?;
    *new.decor_mut() = slot.decor().clone();
    *slot = new;
    Ok(())
}

/// A `toml` value as a `toml_edit` one (the formats' two value types).
pub(super) fn edit_value(v: &toml::Value) -> Value {
    match v {
        toml::Value::String(s) => Value::from(s.as_str()),
        toml::Value::Integer(i) => Value::from(*i),
        toml::Value::Float(x) => Value::from(*x),
        toml::Value::Boolean(b) => Value::from(*b),
        toml::Value::Datetime(d) => d
            .to_string()
            .parse::<Value>()
            .unwrap_or_else(|_| Value::from(d.to_string())),
        toml::Value::Array(a) => Value::Array(a.iter().map(edit_value).collect()),
        toml::Value::Table(t) => {
            let mut inline = InlineTable::new();
            for (k, v) in t {
                inline.insert(k, edit_value(v));
            }
            Value::InlineTable(inline)
        }
    }
}

/// A `toml_edit` value as a `toml` one.
pub(super) fn plain_value(v: &Value) -> Option<toml::Value> {
    toml::from_str::<toml::Table>(&format!("v = {}", v.clone().decorated("", "")))
        .ok()
        .and_then(|mut t| t.remove("v"))
}

fn parse_document(text: &str) -> Result<DocumentMut, String> {
    text.parse::<DocumentMut>()
        .map_err(|e| e.message().trim().replace('\n', " "))
}

/// Applies `key = value` overrides (study key syntax, see the module doc) to scene TOML text;
/// the result is scene text with the base's comments kept. Err: one line naming the key.
pub fn override_scene_text(
    text: &str,
    overrides: &[(String, toml::Value)],
) -> Result<String, String> {
    let mut doc = parse_document(text)?;
    for (key, value) in overrides {
        let segs = segments(key)?;
        let new = edit_value(value);
        walk(doc.as_table_mut(), false, &segs, &mut |_| Ok(new.clone()))
            .map_err(|e| format!("key \"{key}\": {e}"))?;
    }
    Ok(doc.to_string())
}

/// The value at `key` in scene text, `None` where the key is absent (and could be created).
/// Err: the key cannot be reached (one line naming it).
pub fn value_at(text: &str, key: &str) -> Result<Option<toml::Value>, String> {
    let mut doc = parse_document(text)?;
    let segs = segments(key)?;
    let mut found = None;
    walk(doc.as_table_mut(), false, &segs, &mut |old| {
        found = old.cloned();
        Ok(old.cloned().unwrap_or(Value::from(0)))
    })
    .map_err(|e| format!("key \"{key}\": {e}"))?;
    Ok(found.as_ref().and_then(plain_value))
}

#[cfg(test)]
mod tests {
    use super::*;

    const SCENE: &str = "\
# a comment kept
[solver]
duration = 2.0  # s

[[blocks]]
name = \"ground\"
box = { size = [1.0, 2.0, 3.0], center = [0.0, 0.0, 0.0] }

[[blocks]]
name = \"rock\"
velocity = [-10.0, 0.0, 0.0]   # toward the column
";

    fn set(key: &str, v: toml::Value) -> Result<String, String> {
        override_scene_text(SCENE, &[(key.to_string(), v)])
    }

    #[test]
    fn values_are_set_and_comments_kept() {
        let t = set("blocks.rock.velocity[0]", toml::Value::Float(-6.5)).unwrap();
        assert!(
            t.contains("velocity = [-6.5, 0.0, 0.0]   # toward the column"),
            "{t}"
        );
        assert!(t.contains("# a comment kept"));
        let t = set("solver.duration", toml::Value::Float(0.5)).unwrap();
        assert!(t.contains("duration = 0.5  # s"), "{t}");
        let t = set("blocks.ground.box.center[2]", toml::Value::Float(-0.5)).unwrap();
        assert!(t.contains("center = [0.0, 0.0, -0.5]"), "{t}");
        let t = set("blocks[1].velocity[1]", toml::Value::Float(2.0)).unwrap();
        assert!(t.contains("velocity = [-10.0, 2.0, 0.0]"), "{t}");
    }

    #[test]
    fn missing_tables_and_keys_are_created() {
        let t = set("solver.contact.initial_penalty", toml::Value::Float(2e9)).unwrap();
        let parsed: toml::Table = toml::from_str(&t).unwrap();
        assert_eq!(
            parsed["solver"]["contact"]["initial_penalty"].as_float(),
            Some(2e9)
        );
        assert_eq!(parsed["solver"]["duration"].as_float(), Some(2.0));
    }

    #[test]
    fn unreachable_keys_say_why() {
        let e = set("blocks.rok.velocity[0]", toml::Value::Float(1.0)).unwrap_err();
        assert_eq!(e, "key \"blocks.rok.velocity[0]\": no block named \"rok\"");
        let e = set("blocks.rock.velocity[3]", toml::Value::Float(1.0)).unwrap_err();
        assert!(
            e.contains("velocity[3]: index out of range (3 values)"),
            "{e}"
        );
        let e = set("blocks.rock", toml::Value::Float(1.0)).unwrap_err();
        assert!(e.contains("names a whole block"), "{e}");
        let e = set("blocks.ground.angular_velocity[0]", toml::Value::Float(1.0)).unwrap_err();
        assert!(e.contains("no angular_velocity in the scene"), "{e}");
        let e = set("solver.duration.x", toml::Value::Float(1.0)).unwrap_err();
        assert!(e.contains("duration is a value, not a table"), "{e}");
        assert!(set("solver..x", toml::Value::Float(1.0)).is_err());
        assert!(set("blocks.rock.velocity[x]", toml::Value::Float(1.0)).is_err());
    }

    #[test]
    fn values_are_read() {
        assert_eq!(
            value_at(SCENE, "blocks.rock.velocity[0]").unwrap(),
            Some(toml::Value::Float(-10.0))
        );
        assert_eq!(value_at(SCENE, "solver.mode").unwrap(), None);
        assert!(value_at(SCENE, "blocks.x.velocity[0]").is_err());
    }
}
