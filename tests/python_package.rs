//! The Python package (issue #18, README "Python package"): runs its pytest suite,
//! `python/tests`, with the interpreter `DDA3D_PYTHON` (default `python3`) and `DDA3D_BIN` set
//! to this build's `dda3d`, so that the package's runs are compared with this binary's.
//!
//! The package must be installed in that interpreter (`pip install .` at the repository root).
//! Where `import dda3d` fails, the suite is skipped with a notice, unless
//! `DDA3D_REQUIRE_PYTHON=1` (set by `.ci/run`, which installs it) makes that a failure. An
//! installed package built from other sources than this tree's (a `pip install .` not re-run
//! after a change) fails: `dda3d.__build__` carries a hash of the sources it was built from,
//! computed as `python/build.rs` computes it.

use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

include!("../python/source_hash.rs");

fn python() -> String {
    std::env::var("DDA3D_PYTHON").unwrap_or_else(|_| "python3".into())
}

fn required() -> bool {
    std::env::var("DDA3D_REQUIRE_PYTHON").is_ok_and(|v| v == "1")
}

/// The installed package's build id, or why there is none.
fn installed_build() -> Result<String, String> {
    let o = Command::new(python())
        .args(["-c", "import dda3d; print(dda3d.__build__)"])
        .current_dir(std::env::temp_dir())
        .output()
        .map_err(|e| format!("cannot run {}: {e}", python()))?;
    if !o.status.success() {
        let err = String::from_utf8_lossy(&o.stderr);
        let last = err.trim().lines().last().unwrap_or("").to_string();
        return Err(format!("{} cannot import dda3d: {last}", python()));
    }
    Ok(String::from_utf8_lossy(&o.stdout).trim().to_string())
}

#[test]
fn the_python_package_passes_its_tests() {
    let build = match installed_build() {
        Ok(b) => b,
        Err(why) if !required() => {
            eprintln!("skipping the Python package's tests: {why} (pip install . to run them)");
            return;
        }
        Err(why) => panic!("{why}"),
    };
    let expected = format!("{:016x}", source_hash(root()));
    assert_eq!(
        build.rsplit('+').next().unwrap_or(""),
        expected,
        "the dda3d installed in {} was built from other sources than this tree: run `{} -m pip \
         install .` at the repository root",
        python(),
        python()
    );
    let o = Command::new(python())
        .args([
            "-m",
            "pytest",
            "python/tests",
            "-q",
            "-p",
            "no:cacheprovider",
        ])
        .current_dir(root())
        .env("DDA3D_BIN", env!("CARGO_BIN_EXE_dda3d"))
        .env("RAY_USAGE_STATS_ENABLED", "0")
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    println!("{stdout}");
    assert!(
        o.status.success(),
        "pytest failed:\n{stdout}\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
}
