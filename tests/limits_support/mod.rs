//! Shared by the tests of bounded inputs (`input_limits.rs`, the scene's keys, and
//! `flag_limits.rs`, the command line's flags): a one-block scene and the one-line error check.

#![allow(dead_code)]

use std::path::Path;
use std::process::Output;

use crate::cli_support::bin;

/// One block on nothing, with `extra` appended to its `[[blocks]]` entry (line 9 onwards).
pub fn scene(extra: &str) -> String {
    format!(
        "[materials.rock]\ndensity = 2750.0\nyoung_modulus = 2.0e10\npoisson_ratio = 0.25\n\
         [[blocks]]\nname = \"a\"\nmaterial = \"rock\"\n\
         box = {{ size = [1, 1, 1], center = [0, 0, 0.5] }}\n{extra}"
    )
}

/// The block of [`scene`] with its shape given by `shape` (line 8) instead of the box.
pub fn shaped(shape: &str) -> String {
    scene("").replace("box = { size = [1, 1, 1], center = [0, 0, 0.5] }", shape)
}

/// stderr of a failed command, checked to be one line with exit status 2 and no panic.
pub fn one_line_error(out: &Output, what: &str) -> String {
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(2), "{what}: {err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{what}: one line: {err}");
    assert!(err.starts_with("error: "), "{what}: {err}");
    assert!(
        !err.contains("panicked") && !err.contains("RUST_BACKTRACE"),
        "{what}: {err}"
    );
    err
}

/// `dda3d run` on `text` written to `NAME.toml`: the one-line error, which names the file.
pub fn run_error(dir: &Path, text: &str, what: &str) -> String {
    let path = dir.join("bad.toml");
    std::fs::write(&path, text).unwrap();
    let out = bin()
        .arg("run")
        .arg(&path)
        .args(["--quiet", "--out"])
        .arg(dir.join("o"))
        .output()
        .unwrap();
    let err = one_line_error(&out, what);
    assert!(err.contains("bad.toml: "), "{what}: names the file: {err}");
    err
}

/// `dda3d run` of `text`, written to `NAME.toml`, for 0.01 s: it must succeed.
pub fn run_briefly(dir: &Path, name: &str, text: &str) {
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, text).unwrap();
    let out = bin()
        .arg("run")
        .arg(&path)
        .args(["--quiet", "--duration", "0.01", "--out"])
        .arg(dir.join(name))
        .output()
        .unwrap();
    assert!(out.status.success(), "{name}: {out:?}");
}
