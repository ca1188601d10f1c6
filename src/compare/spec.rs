//! What run B changes of run A: `--compare alm|penalty` (B's method) and `--compare-set
//! key=value,...` (any key of the parameter table, by the name the scene file uses). A spec is
//! read whole before anything runs, and B's settings go through
//! [`SolverParams::check`], the scene file's own validation: a bad spec is one line that
//! names the key, never a run that fails later.

use std::fmt;

use crate::params::table::{self, FromText, Param};
use crate::params::{Method, SolverParams};

/// The flag of `--compare`, for messages.
pub const COMPARE_FLAG: &str = "--compare";
/// The flag of `--compare-set`, for messages.
pub const COMPARE_SET_FLAG: &str = "--compare-set";

/// B's settings as changes to A's.
#[derive(Clone, Debug, PartialEq)]
pub struct CompareSpec {
    /// `--compare`: B's contact method.
    pub method: Option<Method>,
    /// `--compare-set`: each key's entry and its value as given, in the order given.
    pub set: Vec<(&'static Param, String)>,
}

/// A spec that cannot be read or gives B invalid settings: the flag and a one-line message
/// naming the key.
#[derive(Clone, Debug, PartialEq)]
pub struct SpecError {
    pub flag: &'static str,
    pub message: String,
}

impl fmt::Display for SpecError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.flag, self.message)
    }
}

impl std::error::Error for SpecError {}

fn set_error(message: String) -> SpecError {
    SpecError {
        flag: COMPARE_SET_FLAG,
        message,
    }
}

/// Text as a message quotes it: escaped to one line and cut short.
fn quoted(text: &str) -> String {
    let cut: String = text.chars().take(40).collect();
    let more = if cut.len() < text.len() { "…" } else { "" };
    format!("'{}{more}'", cut.escape_default())
}

/// `k=v,k=v` split at the commas outside brackets, so that `gravity=[0, 0, -9.8]` stays whole.
fn entries(text: &str) -> Vec<&str> {
    let (mut depth, mut start, mut out) = (0i32, 0, Vec::new());
    for (i, c) in text.char_indices() {
        match c {
            '[' => depth += 1,
            ']' => depth -= 1,
            ',' if depth == 0 => {
                out.push(&text[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    out.push(&text[start..]);
    out
}

impl CompareSpec {
    /// The spec of `--compare` and `--compare-set` as given (`None` for a flag left out);
    /// `Ok(None)` when neither is given. Every key and the kind of every value is checked here;
    /// ranges are checked by [`CompareSpec::derive`] against A's settings.
    pub fn parse(compare: Option<&str>, set: Option<&str>) -> Result<Option<Self>, SpecError> {
        if compare.is_none() && set.is_none() {
            return Ok(None);
        }
        let method = compare
            .map(|m| Method::from_text(m.trim()))
            .transpose()
            .map_err(|message| SpecError {
                flag: COMPARE_FLAG,
                message,
            })?;
        let mut spec = CompareSpec {
            method,
            set: Vec::new(),
        };
        if let Some(text) = set {
            spec.read_set(text)?;
        }
        Ok(Some(spec))
    }

    fn read_set(&mut self, text: &str) -> Result<(), SpecError> {
        if text.trim().is_empty() {
            return Err(set_error(
                "empty: give key=value[,key=value...] with the scene file's keys (e.g. \
                 initial_penalty=2e9,eps1=0.001)"
                    .into(),
            ));
        }
        for entry in entries(text) {
            let entry = entry.trim();
            if entry.is_empty() {
                return Err(set_error(format!(
                    "an empty entry in {} (a comma too many)",
                    quoted(text)
                )));
            }
            let Some((name, value)) = entry.split_once('=') else {
                return Err(set_error(format!("{}: expected key=value", quoted(entry))));
            };
            let (name, value) = (name.trim(), value.trim());
            let param = table::find(name).ok_or_else(|| {
                let names: Vec<&str> = table::ALL.iter().map(|p| p.name()).collect();
                set_error(format!(
                    "unknown key {} (the keys of the scene's [solver], [solver.contact] and \
                     [joint]: {})",
                    quoted(name),
                    names.join(", ")
                ))
            })?;
            if value.is_empty() {
                return Err(set_error(format!("{}: no value", param.name())));
            }
            if self.set.iter().any(|(p, _)| p.key == param.key) {
                return Err(set_error(format!("{} is given twice", param.name())));
            }
            if self.method.is_some() && param.key == table::METHOD.key {
                return Err(set_error(format!(
                    "method is already set by {COMPARE_FLAG}; give it once"
                )));
            }
            // The kind of the value now, so that a typo fails before anything runs.
            (param.set)(&mut SolverParams::default(), value)
                .map_err(|e| set_error(format!("{}: {e}", param.name())))?;
            self.set.push((param, value.to_owned()));
        }
        Ok(())
    }

    /// B's settings: A's, with the spec's changes, checked as a scene file's are.
    pub fn derive(&self, a: &SolverParams) -> Result<SolverParams, SpecError> {
        let mut b = a.clone();
        if let Some(m) = self.method {
            b.method = m;
        }
        for (param, value) in &self.set {
            (param.set)(&mut b, value).map_err(|e| set_error(format!("{}: {e}", param.name())))?;
        }
        b.check().map_err(|e| {
            // A was valid, so a key the spec set is to blame; `--compare` alone sets only the
            // method, which has no range.
            let flag = if self.set.is_empty() {
                COMPARE_FLAG
            } else {
                COMPARE_SET_FLAG
            };
            SpecError {
                flag,
                message: e.message,
            }
        })?;
        Ok(b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::Mode;

    fn parse(compare: Option<&str>, set: Option<&str>) -> Result<CompareSpec, SpecError> {
        CompareSpec::parse(compare, set).map(|s| s.expect("a spec"))
    }

    #[test]
    fn method_and_set_change_b_only_where_they_say() {
        let a = SolverParams::default();
        let spec = parse(Some("penalty"), Some("initial_penalty=2e9, eps1=0.001")).unwrap();
        let b = spec.derive(&a).unwrap();
        assert_eq!(b.method, Method::Penalty);
        assert_eq!(b.contact.initial_penalty, 2e9);
        assert_eq!(b.contact.eps1, 0.001);
        let mut back = b.clone();
        back.method = a.method;
        back.contact.initial_penalty = a.contact.initial_penalty;
        back.contact.eps1 = a.contact.eps1;
        assert_eq!(back, a, "nothing else changed");
        assert_eq!(a, SolverParams::default(), "A is untouched");
    }

    #[test]
    fn keys_take_every_spelling_and_every_kind() {
        let spec = parse(
            None,
            Some(
                "solver.mode=static,max-time-step=0.005,gravity=[0, 0, -9.81],\
                 warm_start=false,max_alm_iterations=5,friction_angle=20",
            ),
        )
        .unwrap();
        let b = spec.derive(&SolverParams::default()).unwrap();
        assert_eq!(b.mode, Mode::Static);
        assert_eq!(b.max_time_step, 0.005);
        assert_eq!(b.gravity, [0.0, 0.0, -9.81]);
        assert!(!b.contact.warm_start);
        assert_eq!(b.contact.max_alm_iterations, 5);
        assert_eq!(b.joint.friction_angle, 20.0);
        assert_eq!(CompareSpec::parse(None, None), Ok(None));
    }

    #[test]
    fn bad_specs_are_one_line_naming_the_key() {
        let a = SolverParams::default();
        let err = |c: Option<&str>, s: Option<&str>| match parse(c, s) {
            Ok(spec) => spec.derive(&a).unwrap_err().to_string(),
            Err(e) => e.to_string(),
        };
        let cases = [
            (Some("lagrange"), None, "--compare: expected alm or penalty"),
            (Some(""), None, "--compare: expected alm or penalty, got ''"),
            (None, Some(""), "--compare-set: empty"),
            (None, Some("  "), "--compare-set: empty"),
            (None, Some("bogus=1"), "--compare-set: unknown key 'bogus'"),
            (
                None,
                Some("eps1"),
                "--compare-set: 'eps1': expected key=value",
            ),
            (None, Some("eps1="), "--compare-set: eps1: no value"),
            (
                None,
                Some("eps1=abc"),
                "--compare-set: eps1: expected a number",
            ),
            (None, Some("eps1=0.1,,beta=0.5"), "an empty entry"),
            (None, Some("eps1=0.1,eps1=0.2"), "eps1 is given twice"),
            (
                Some("alm"),
                Some("method=penalty"),
                "already set by --compare",
            ),
            (
                None,
                Some("eps1=2"),
                "solver.contact.eps1 must lie in (0, 1), got 2",
            ),
            (
                None,
                Some("eps1=nan"),
                "solver.contact.eps1 must be a finite number",
            ),
            (None, Some("max_alm_iterations=2.5"), "whole number"),
            (None, Some("max_time_step=1e-7"), "more than the limit"),
            (
                None,
                Some("gravity=[0,0]"),
                "gravity: expected three numbers",
            ),
        ];
        for (c, s, want) in cases {
            let e = err(c, s);
            assert!(e.contains(want), "{c:?} {s:?}: {e}");
            assert!(!e.contains('\n'), "{e}");
        }
        assert!(err(None, Some("bogus=1")).contains("initial_penalty, alpha"));
    }

    #[test]
    fn brackets_keep_a_vector_whole() {
        assert_eq!(
            entries("a=1,g=[0, 0, -9.8],b=2"),
            ["a=1", "g=[0, 0, -9.8]", "b=2"]
        );
        assert_eq!(entries(""), [""]);
    }
}
