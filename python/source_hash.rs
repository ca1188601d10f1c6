// The source hash shared by python/build.rs (which stamps it into `dda3d.__build__`) and
// tests/python_package.rs (which checks an installed package against this tree); both
// `include!` this file, so the two cannot drift apart.

/// What the package is built from, relative to the repository root: the library and this crate,
/// and the Python sources `pip install .` copies beside the extension.
const SOURCES: &[&str] = &[
    "Cargo.toml",
    "src",
    "python/Cargo.toml",
    "python/src",
    "python/dda3d",
];

fn files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        out.push(dir.to_path_buf());
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        // Not sources: Python's caches, and an extension `maturin develop` put beside them.
        let name = path.file_name().unwrap_or_default().to_string_lossy();
        if name == "__pycache__" || [".so", ".pyd", ".pyc"].iter().any(|e| name.ends_with(e)) {
            continue;
        }
        if path.is_dir() {
            files(&path, out);
        } else {
            out.push(path);
        }
    }
}

/// FNV-1a over each file's path (relative to the root, with `/`) and bytes, in path order.
fn source_hash(root: &Path) -> u64 {
    let mut all = Vec::new();
    for s in SOURCES {
        files(&root.join(s), &mut all);
    }
    let mut named: Vec<(String, PathBuf)> = all
        .into_iter()
        .map(|p| {
            let rel = p.strip_prefix(root).unwrap_or(&p).to_string_lossy();
            (rel.replace('\\', "/"), p)
        })
        .collect();
    named.sort();
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for (name, path) in named {
        let bytes = std::fs::read(&path).unwrap_or_default();
        for b in name.bytes().chain([0]).chain(bytes).chain([0]) {
            h = (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
    }
    h
}
