//! Where things sit in the scene text, for messages: the line of an offset, the line of a key
//! that a check after parsing rejects (`solver.contact.beta`, `materials.rock.density`), and the
//! key of a value that serde rejected. serde's own errors carry an offset but not always the key;
//! the checks after parsing know the key but not the offset. Both are found in toml's
//! span-keeping parse of the text, made again only on the way to an error.

use toml::de::{DeTable, DeValue};

/// The 1-based line of a byte offset.
pub(super) fn line_of(text: &str, offset: usize) -> usize {
    let end = offset.min(text.len());
    text.as_bytes()[..end]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

/// The lines of a text, for the line of many offsets: a scene of 10 000 blocks asked
/// [`line_of`] for each block's line, and each call counted the newlines from the start (1.5 s
/// of its 2.7 s load).
pub(super) struct LineIndex {
    /// Byte offsets of the text's newlines, ascending.
    newlines: Vec<usize>,
    len: usize,
}

impl LineIndex {
    pub fn new(text: &str) -> Self {
        let newlines = text
            .bytes()
            .enumerate()
            .filter_map(|(k, b)| (b == b'\n').then_some(k))
            .collect();
        LineIndex {
            newlines,
            len: text.len(),
        }
    }

    /// The 1-based line of a byte offset, as [`line_of`] gives it.
    pub fn line(&self, offset: usize) -> usize {
        let end = offset.min(self.len);
        self.newlines.partition_point(|&k| k < end) + 1
    }
}

/// The line of the value of `path` (`["solver", "contact", "beta"]`), if the text sets it.
pub(super) fn key_line(text: &str, path: &[&str]) -> Option<usize> {
    let doc = DeTable::parse(text).ok()?;
    let (first, rest) = path.split_first()?;
    let mut value = doc.get_ref().get(*first)?;
    for part in rest {
        value = value.get_ref().get(*part)?;
    }
    Some(line_of(text, value.span().start))
}

/// The dotted key of the value, not a table, whose text contains `offset`: the key of a value
/// serde rejected (`solver.gravity`, `blocks[2].velocity`). None where the offset lies in no such
/// value (a key serde did not expect, a table that lacks a key): those messages name the key
/// themselves.
pub(super) fn key_at(text: &str, offset: usize) -> Option<String> {
    let doc = DeTable::parse(text).ok()?;
    find_value(doc.get_ref(), offset, "")
}

/// Depth first through the tables and arrays of tables: a table's span is its header alone.
fn find_value(table: &DeTable<'_>, offset: usize, prefix: &str) -> Option<String> {
    for (name, value) in table.iter() {
        let key = format!("{prefix}{}", name.get_ref());
        let found = match value.get_ref() {
            // A table's own span (an inline table's text, a header) names it where no value
            // inside it holds the offset: `density = { a = 1 }`, a block without `material`.
            DeValue::Table(t) => find_value(t, offset, &format!("{key}."))
                .or_else(|| value.span().contains(&offset).then(|| key.clone())),
            DeValue::Array(items)
                if !items.is_empty() && items.iter().all(|i| i.get_ref().is_table()) =>
            {
                items.iter().enumerate().find_map(|(k, item)| {
                    let t = item.get_ref().as_table()?;
                    find_value(t, offset, &format!("{key}[{k}]."))
                        .or_else(|| item.span().contains(&offset).then(|| format!("{key}[{k}]")))
                })
            }
            _ => value.span().contains(&offset).then_some(key),
        };
        if found.is_some() {
            return found;
        }
    }
    None
}

/// The key that stands in for the repeated one in [`duplicate_key`]'s probe.
const PROBE: &str = "dda3d_duplicate_key_probe";

/// The dotted key of a "duplicate key" error, whose span is the repeated name as written:
/// `solver.duration`, `blocks[1].name`, `a.b` for a dotted key, `solver.contact` for a table
/// header given twice. toml's message names no key. The text up to the repeated line, with a
/// probe key in place of that line's key, parses (the repetition is not in it) and says which
/// table the line is in; where it does not (a key repeated inside an inline table), the name
/// as written.
pub(super) fn duplicate_key(text: &str, span: std::ops::Range<usize>) -> String {
    let Some(written) = text.get(span.clone()) else {
        return String::new();
    };
    let written = written.trim().trim_matches(['"', '\'']);
    let line_start = text[..span.start].rfind('\n').map_or(0, |k| k + 1);
    let before = &text[line_start..span.start];
    if let Some(header) = before.trim_start().strip_prefix('[') {
        return format!("{}{written}", header.trim_start_matches('[').trim_start());
    }
    let dotted_prefix = before
        .chars()
        .all(|c| c.is_alphanumeric() || "_-. \t".contains(c));
    let table = dotted_prefix
        .then(|| format!("{}{before}{PROBE} = 0\n", &text[..line_start]))
        .and_then(|probe| probe_table(DeTable::parse(&probe).ok()?.get_ref(), ""));
    format!("{}{written}", table.unwrap_or_default())
}

/// The dotted prefix (`solver.`, `blocks[1].`) of the table that holds [`PROBE`]: the probe is
/// the last key of its text, so in an array of tables it is in the last one.
fn probe_table(table: &DeTable<'_>, prefix: &str) -> Option<String> {
    table.iter().find_map(|(name, value)| {
        let key = name.get_ref();
        if key == PROBE {
            return Some(prefix.to_owned());
        }
        match value.get_ref() {
            DeValue::Table(t) => probe_table(t, &format!("{prefix}{key}.")),
            DeValue::Array(items) => {
                let k = items.len().checked_sub(1)?;
                let t = items[k].get_ref().as_table()?;
                probe_table(t, &format!("{prefix}{key}[{k}]."))
            }
            _ => None,
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEXT: &str = "name = \"x\"\n[solver]\nduration = 2.0\ngravity = [0, 0, -9.8, 1]\n\
                        [solver.contact]\nbeta = 0.25\n[materials.rock]\ndensity = 1.0\n\
                        [[blocks]]\nname = \"a\"\n[[blocks]]\nname = \"b\"\nvelocity = [1, 2, 3, 4]\n";

    #[test]
    fn keys_have_lines_and_values_have_keys() {
        assert_eq!(key_line(TEXT, &["solver", "duration"]), Some(3));
        assert_eq!(key_line(TEXT, &["solver", "contact", "beta"]), Some(6));
        assert_eq!(key_line(TEXT, &["materials", "rock", "density"]), Some(8));
        assert_eq!(key_line(TEXT, &["solver", "max_time_step"]), None);
        assert_eq!(key_line(TEXT, &["joint", "cohesion"]), None);
        let at = |needle: &str| key_at(TEXT, TEXT.find(needle).unwrap());
        assert_eq!(at("-9.8").as_deref(), Some("solver.gravity"));
        assert_eq!(at("2.0").as_deref(), Some("solver.duration"));
        assert_eq!(at("[1, 2, 3, 4]").as_deref(), Some("blocks[1].velocity"));
        assert_eq!(at("\"b\"").as_deref(), Some("blocks[1].name"));
        // Dotted keys and inline tables are the same tables.
        let inline = "solver.contact = { beta = 7 }\n";
        assert_eq!(
            key_at(inline, inline.find('7').unwrap()).as_deref(),
            Some("solver.contact.beta")
        );
        let map = "[materials.rock]\ndensity = { a = 1 }\n";
        assert_eq!(
            key_at(map, map.find('{').unwrap()).as_deref(),
            Some("materials.rock.density")
        );
        let header = "[[blocks]]\nname = \"a\"\n[[blocks]]\nname = \"b\"\n";
        assert_eq!(
            key_at(header, header.rfind("[[").unwrap()).as_deref(),
            Some("blocks[1]")
        );
        let dup = |text: &str| {
            let e = toml::from_str::<toml::Table>(text).unwrap_err();
            assert_eq!(e.message(), "duplicate key", "{text}");
            duplicate_key(text, e.span().unwrap())
        };
        assert_eq!(
            dup("[solver]\nduration = 1\nduration = 2\n"),
            "solver.duration"
        );
        assert_eq!(
            dup("[solver]\nduration = 1\n\"duration\" = 2\n"),
            "solver.duration"
        );
        assert_eq!(
            dup("[[blocks]]\nname = \"a\"\n[[blocks]]\nname = \"b\"\nname = \"c\"\n"),
            "blocks[1].name"
        );
        assert_eq!(dup("x = 1\na.b = 1\na.b = 2\n"), "a.b");
        assert_eq!(
            dup("[solver.contact]\nbeta = 1\n[solver.contact]\n"),
            "solver.contact"
        );
        assert_eq!(dup("[solver]\nx = { y = 1, y = 2 }\n"), "y");
        assert_eq!(line_of("a\nb\nc", 4), 3);
        assert_eq!(line_of("a", 99), 1);
        let text = "a\nbb\n\nccc\n";
        let index = LineIndex::new(text);
        for offset in 0..text.len() + 3 {
            assert_eq!(index.line(offset), line_of(text, offset), "offset {offset}");
        }
    }
}
