//! A parameter's value read from text, as `dda3d run --compare-set key=value` (and any later
//! front end that sets a key by name) writes it: `2e9`, `20`, `true`, `penalty`,
//! `[0, 0, -9.8]`. Each [`super::Param`] entry's `set` calls [`assign`] on its own field, so
//! a key set by name goes through the same field, and then the same
//! [`crate::params::SolverParams::check`], as the scene file's key.
//!
//! Reading only checks the kind (a number, a whole number, a flag, a choice, three numbers);
//! ranges are left to `check`, so that a value outside its range gets the scene file's message.

use crate::params::{Method, Mode};

/// A value of one kind read from text; the error says what was expected.
pub trait FromText: Sized {
    fn from_text(text: &str) -> Result<Self, String>;
}

/// Reads `text` into `field`; on failure the field is left as it was.
pub fn assign<T: FromText>(text: &str, field: &mut T) -> Result<(), String> {
    *field = T::from_text(text.trim())?;
    Ok(())
}

/// The text as an error message shows it: quoted, and cut short if it is long (the whole
/// message stays one short line).
fn quoted(text: &str) -> String {
    let cut: String = text.chars().take(40).collect();
    let more = if cut.len() < text.len() { "…" } else { "" };
    format!("'{}{more}'", cut.escape_default())
}

impl FromText for f64 {
    fn from_text(text: &str) -> Result<Self, String> {
        // Rust reads "inf" and "NaN" too; `check` then rejects them as not finite, with the
        // scene file's message.
        text.parse()
            .map_err(|_| format!("expected a number, got {}", quoted(text)))
    }
}

impl FromText for u32 {
    fn from_text(text: &str) -> Result<Self, String> {
        text.parse().map_err(|_| {
            format!(
                "expected a whole number from 0 to {}, got {}",
                u32::MAX,
                quoted(text)
            )
        })
    }
}

impl FromText for bool {
    fn from_text(text: &str) -> Result<Self, String> {
        match text {
            "true" => Ok(true),
            "false" => Ok(false),
            _ => Err(format!("expected true or false, got {}", quoted(text))),
        }
    }
}

impl FromText for [f64; 3] {
    fn from_text(text: &str) -> Result<Self, String> {
        let bad = || format!("expected three numbers [x, y, z], got {}", quoted(text));
        let inner = text
            .strip_prefix('[')
            .and_then(|t| t.strip_suffix(']'))
            .ok_or_else(bad)?;
        let numbers: Vec<f64> = inner
            .split(',')
            .map(|x| x.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|_| bad())?;
        numbers.try_into().map_err(|_| bad())
    }
}

/// A choice among the spellings of `all` (the scene file's, `as_str`).
fn choice<T: Copy>(text: &str, all: &[T], name: fn(T) -> &'static str) -> Result<T, String> {
    all.iter()
        .copied()
        .find(|&v| name(v) == text)
        .ok_or_else(|| {
            let names: Vec<&str> = all.iter().map(|&v| name(v)).collect();
            format!("expected {}, got {}", names.join(" or "), quoted(text))
        })
}

impl FromText for Method {
    fn from_text(text: &str) -> Result<Self, String> {
        choice(text, &[Method::Alm, Method::Penalty], Method::as_str)
    }
}

impl FromText for Mode {
    fn from_text(text: &str) -> Result<Self, String> {
        choice(text, &[Mode::Dynamic, Mode::Static], Mode::as_str)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_kind_reads_its_spelling_and_names_what_it_expected() {
        let mut x = 1.0;
        assign(" 2e9 ", &mut x).unwrap();
        assert_eq!(x, 2e9);
        let e = assign("abc", &mut x).unwrap_err();
        assert_eq!(e, "expected a number, got 'abc'");
        assert_eq!(x, 2e9, "a failed read leaves the field");
        let mut n = 5u32;
        assign("20", &mut n).unwrap();
        assert_eq!(n, 20);
        assert!(assign("2.5", &mut n).unwrap_err().contains("whole number"));
        assert!(assign("-1", &mut n).is_err());
        let mut b = false;
        assign("true", &mut b).unwrap();
        assert!(b);
        assert!(assign("yes", &mut b).is_err());
        let mut g = [0.0; 3];
        assign("[0, 0.5, -9.81]", &mut g).unwrap();
        assert_eq!(g, [0.0, 0.5, -9.81]);
        for bad in ["0,0,-9.8", "[0,0]", "[0,0,1,2]", "[a,0,0]", "[]"] {
            assert!(assign(bad, &mut g).is_err(), "{bad}");
        }
        let mut m = Method::Alm;
        assign("penalty", &mut m).unwrap();
        assert_eq!(m, Method::Penalty);
        assert_eq!(
            assign("lagrange", &mut m).unwrap_err(),
            "expected alm or penalty, got 'lagrange'"
        );
        let mut mode = Mode::Dynamic;
        assign("static", &mut mode).unwrap();
        assert_eq!(mode, Mode::Static);
    }

    #[test]
    fn long_or_odd_text_is_quoted_on_one_short_line() {
        let mut x = 0.0;
        let e = assign(&"x".repeat(500), &mut x).unwrap_err();
        assert!(e.len() < 80, "{e}");
        let e = assign("a\nb", &mut x).unwrap_err();
        assert!(!e.contains('\n'), "{e}");
    }
}
