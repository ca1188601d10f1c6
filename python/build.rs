//! Stamps the extension with a hash of the sources it was built from (`dda3d.__build__`), so
//! that `tests/python_package.rs` can tell an installed package built from other sources (a
//! `pip install .` not re-run after a change) from this tree's. `tests/python_package.rs`
//! computes the same hash with the same code (`source_hash.rs`).

use std::path::{Path, PathBuf};

include!("source_hash.rs");

fn main() {
    let crate_dir = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("set by cargo"));
    let root = crate_dir
        .parent()
        .expect("python/ is inside the repository");
    for s in SOURCES {
        println!("cargo:rerun-if-changed={}", root.join(s).display());
    }
    let version = std::env::var("CARGO_PKG_VERSION").expect("set by cargo");
    println!(
        "cargo:rustc-env=DDA3D_BUILD={version}+{:016x}",
        source_hash(root)
    );
}
