//! Shared by the tests that run the `dda3d` binary: the command, and a fresh scratch directory.

#![allow(dead_code)]

use std::path::PathBuf;
use std::process::Command;

/// The `dda3d` binary, run from the repository (where the default scenes of `bench` and the
/// relative paths of the tests lie).
pub fn bin() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_dda3d"));
    c.current_dir(env!("CARGO_MANIFEST_DIR"));
    c
}

/// An empty scratch directory for `name`, unique to this test binary and process, so that test
/// files and concurrent runs never share one.
pub fn tmp(name: &str) -> PathBuf {
    let exe = std::env::current_exe().ok();
    let test = exe
        .as_deref()
        .and_then(|p| p.file_stem())
        .and_then(|s| s.to_str())
        .and_then(|s| s.split('-').next())
        .unwrap_or("test");
    let d = std::env::temp_dir().join(format!("dda3d-{test}-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}
