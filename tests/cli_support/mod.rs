//! Shared by the tests that run the `dda3d` binary: the command, and a fresh scratch directory.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
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
    remove_stale(test, name);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Removes the scratch directories of `test`'s `name` left by earlier runs whose process has
/// ended (a day of test runs left some 1800 in /tmp), so that at most one per live run stays.
/// Where `/proc` is missing (not Linux), nothing is removed.
fn remove_stale(test: &str, name: &str) {
    if !Path::new("/proc/self").exists() {
        return;
    }
    let Ok(entries) = std::fs::read_dir(std::env::temp_dir()) else {
        return;
    };
    let prefix = format!("dda3d-{test}-");
    let suffix = format!("-{name}");
    for e in entries.flatten() {
        let file = e.file_name();
        let Some(pid) = file
            .to_str()
            .and_then(|f| f.strip_prefix(&prefix))
            .and_then(|f| f.strip_suffix(&suffix))
            .and_then(|p| p.parse::<u32>().ok())
        else {
            continue;
        };
        if !Path::new(&format!("/proc/{pid}")).exists() {
            let _ = std::fs::remove_dir_all(e.path());
        }
    }
}

/// The rockfall run to 0.6 s with a checkpoint at its first step past 0.5 s, in `dir/run`:
/// the checkpoint's file and its time (for `render --resume` and `view --resume`).
pub fn rockfall_checkpoint(dir: &Path) -> (PathBuf, f64) {
    let run = dir.join("run");
    let o = bin()
        .arg("run")
        .arg("scenes/rock_column_rockfall.toml")
        .args([
            "--duration",
            "0.6",
            "--checkpoint-every",
            "0.5",
            "-q",
            "--out",
        ])
        .arg(&run)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let ckpt = std::fs::read_dir(&run)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.extension().is_some_and(|x| x == "ckpt"))
        .expect("a checkpoint");
    let t0: f64 = ckpt.file_stem().unwrap().to_str().unwrap()["checkpoint_".len()..]
        .parse()
        .unwrap();
    assert!((0.5..0.6).contains(&t0), "{t0}");
    (ckpt, t0)
}
