//! Fixed-size lists of numbers in a scene file (`[x, y, z]`), read to their exact length.
//!
//! serde reads a Rust array `[f64; 3]` from the first three elements of a list and drops the
//! rest without a word, so `gravity = [0, 0, -9.8, 123]` or a vertex `[0, -1, 0, 99]` was
//! accepted (#13). Every such field of the scene file reads through [`exact`] or [`Exact`]
//! instead: a list of any other length is an error at its line.

use std::fmt;
use std::marker::PhantomData;

use serde::Deserialize;
use serde::de::{self, Deserializer, IgnoredAny, SeqAccess, Visitor};

/// `N` numbers, no more and no fewer: for a list of points (`vertices = [[x, y, z], ...]`),
/// where `deserialize_with` cannot reach the elements.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Exact<const N: usize>(pub [f64; N]);

impl<'de, const N: usize> Deserialize<'de> for Exact<N> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        exact(d).map(Exact)
    }
}

/// Reads a field of `N` numbers (`#[serde(deserialize_with = "exact")]`).
pub fn exact<'de, D: Deserializer<'de>, const N: usize>(d: D) -> Result<[f64; N], D::Error> {
    d.deserialize_seq(ExactVisitor::<N>(PhantomData))
}

struct ExactVisitor<const N: usize>(PhantomData<[f64; N]>);

impl<'de, const N: usize> Visitor<'de> for ExactVisitor<N> {
    type Value = [f64; N];

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "a list of {N} numbers")
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
        let mut out = [0.0; N];
        for (k, slot) in out.iter_mut().enumerate() {
            *slot = seq
                .next_element()?
                .ok_or_else(|| de::Error::custom(wrong_length(N, k)))?;
        }
        // Counted, not collected: the message says how long the list was without keeping it.
        let mut extra = 0usize;
        while seq.next_element::<IgnoredAny>()?.is_some() {
            extra += 1;
        }
        if extra > 0 {
            return Err(de::Error::custom(wrong_length(N, N + extra)));
        }
        Ok(out)
    }
}

fn wrong_length(n: usize, got: usize) -> String {
    format!("expected {n} numbers, got {got}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Deserialize, Debug)]
    struct T {
        #[serde(deserialize_with = "exact")]
        v: [f64; 3],
        #[serde(default)]
        list: Vec<Exact<3>>,
    }

    #[test]
    fn lists_of_any_other_length_are_errors() {
        let t: T = toml::from_str("v = [1, 2.5, -3]\nlist = [[0, 0, 0]]").unwrap();
        assert_eq!(t.v, [1.0, 2.5, -3.0]);
        assert_eq!(t.list, vec![Exact([0.0; 3])]);
        for (text, got) in [
            ("v = [1, 2, 3, 4]", "got 4"),
            ("v = [1, 2]", "got 2"),
            ("v = []", "got 0"),
            ("v = [1, 2, 3]\nlist = [[0, 0, 0], [0, -1, 0, 99]]", "got 4"),
            ("v = [1, 2, 3]\nlist = [[0, 0]]", "got 2"),
        ] {
            let e = toml::from_str::<T>(text).unwrap_err();
            assert!(
                e.message().contains("expected 3 numbers") && e.message().contains(got),
                "{text}: {e}"
            );
            assert!(e.span().is_some(), "{text}: the error has its place");
        }
        let long = format!("v = [{}]", vec!["0"; 100_000].join(","));
        let e = toml::from_str::<T>(&long).unwrap_err();
        assert!(e.message().contains("got 100000"), "{}", e.message());
        assert!(toml::from_str::<T>("v = [1, 2, \"x\"]").is_err());
    }
}
