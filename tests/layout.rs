//! The architecture, checked: file and function sizes, and the direction of the data flow
//! scene → model → solver → snapshot → render / output / compare (README "Layout"). A module
//! that reaches against the flow fails here with the file and the import.

use std::fs;
use std::path::{Path, PathBuf};

const MAX_FILE_LINES: usize = 700;
const MAX_FN_LINES: usize = 120;

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

fn sources() -> Vec<(String, String)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    rust_files(&root.join("src"), &mut files);
    // The Python package's extension (python/src, a second crate) keeps the same sizes.
    rust_files(&root.join("python/src"), &mut files);
    files.sort();
    files
        .into_iter()
        .map(|p| {
            let rel = p
                .strip_prefix(root)
                .unwrap()
                .to_string_lossy()
                .replace('\\', "/");
            (rel, fs::read_to_string(&p).unwrap())
        })
        .collect()
}

#[test]
fn no_source_file_is_over_700_lines() {
    let long: Vec<String> = sources()
        .iter()
        .filter(|(_, text)| text.lines().count() > MAX_FILE_LINES)
        .map(|(name, text)| format!("{name}: {} lines", text.lines().count()))
        .collect();
    assert!(
        long.is_empty(),
        "files over {MAX_FILE_LINES} lines: {long:#?}"
    );
}

/// Functions by their lines from `fn` to the closing brace at the same indentation (rustfmt
/// layout), comments included.
fn function_lengths(text: &str) -> Vec<(String, usize)> {
    let lines: Vec<&str> = text.lines().collect();
    let mut out = Vec::new();
    for (k, line) in lines.iter().enumerate() {
        let trimmed = line.trim_start();
        let indent = line.len() - trimmed.len();
        let signature = trimmed
            .trim_start_matches("pub ")
            .trim_start_matches("pub(crate) ")
            .trim_start_matches("pub(super) ")
            .trim_start_matches("const ")
            .trim_start_matches("unsafe ");
        let Some(rest) = signature.strip_prefix("fn ") else {
            continue;
        };
        if line.trim_end().ends_with(';') {
            continue;
        }
        let name: String = rest
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        let closing = " ".repeat(indent) + "}";
        if let Some(end) = lines[k + 1..]
            .iter()
            .position(|l| l.starts_with(&closing) && l.len() - l.trim_start().len() == indent)
        {
            out.push((name, end + 2));
        }
    }
    out
}

#[test]
fn no_function_is_over_120_lines() {
    let mut long = Vec::new();
    for (file, text) in sources() {
        for (name, n) in function_lengths(&text) {
            if n > MAX_FN_LINES {
                long.push(format!("{file}: fn {name}: {n} lines"));
            }
        }
    }
    assert!(
        long.is_empty(),
        "functions over {MAX_FN_LINES} lines: {long:#?}"
    );
}

#[test]
fn the_function_scan_measures_what_it_should() {
    let text = "fn a() {\n    1;\n}\n\nimpl X {\n    pub fn b(&self) {\n        if x {\n        }\n    }\n}\n";
    assert_eq!(
        function_lengths(text),
        vec![("a".to_string(), 3), ("b".to_string(), 4)]
    );
}

/// The front ends: what reads the solver's results or drives it.
const FRONT: &[&str] = &[
    "crate::render",
    "crate::viewer",
    "crate::cli",
    "crate::output",
    "crate::compare",
];
/// The run's machinery, which the snapshot hides from the front ends.
const ENGINE: &[&str] = &[
    "crate::solver",
    "crate::contact",
    "crate::model",
    "crate::physics",
    "crate::scene",
];

/// Modules (paths under src/) and the crate modules they must not use: the front ends they may
/// not reach, and the parts of the engine they may not reach.
const FORBIDDEN: &[(&str, &[&str], &[&str])] = &[
    // The physics knows nothing of the run; contacts are geometry and a law, they do not step
    // time; the model is what the scene builds.
    (
        "src/physics/",
        FRONT,
        &[
            "crate::solver",
            "crate::contact",
            "crate::scene",
            "crate::model",
        ],
    ),
    ("src/contact/", FRONT, &["crate::solver", "crate::scene"]),
    (
        "src/model.rs",
        FRONT,
        &["crate::solver", "crate::contact", "crate::scene"],
    ),
    // The solver knows nothing of the renderer, the viewer, the files or the command line.
    ("src/solver/", FRONT, &["crate::scene"]),
    ("src/scene/", FRONT, &["crate::solver"]),
    // Rock-mass geometry is pure: planes and polyhedra (with physics' polyhedron maths), no
    // blocks, no run.
    (
        "src/rockmass/",
        FRONT,
        &[
            "crate::solver",
            "crate::contact",
            "crate::model",
            "crate::scene",
        ],
    ),
    ("src/params/", FRONT, ENGINE),
    // What leaves the solver is plain data, and output and rendering depend on it alone.
    ("src/snapshot.rs", FRONT, ENGINE),
    (
        "src/output.rs",
        &["crate::render", "crate::viewer", "crate::cli"],
        ENGINE,
    ),
    (
        "src/render/",
        &["crate::viewer", "crate::cli", "crate::output"],
        ENGINE,
    ),
    // Two runs compared: the solver (a model's masses), its snapshots and the parameters, and
    // nothing of the files, the pictures or the command line, so the viewer and `render` can
    // use it as `run` does.
    (
        "src/compare/",
        &[
            "crate::render",
            "crate::viewer",
            "crate::cli",
            "crate::output",
        ],
        &[
            "crate::contact",
            "crate::model",
            "crate::physics",
            "crate::scene",
        ],
    ),
    // The viewer is driven by the command line, never the other way round.
    ("src/viewer/", &["crate::cli"], &[]),
    // A parameter study drives runs as `run` does (scene → solver → outcomes) and writes its
    // tables with output's helpers; the command line drives it, and its plots are its own.
    (
        "src/study/",
        &[
            "crate::render",
            "crate::viewer",
            "crate::cli",
            "crate::compare",
        ],
        &["crate::contact", "crate::model", "crate::physics"],
    ),
    // The study's plots draw columns of numbers: nothing of the runs, the files or the pictures
    // of a run.
    ("src/study/plots", FRONT, ENGINE),
];

#[test]
fn modules_depend_along_the_data_flow() {
    let mut wrong = Vec::new();
    for (file, text) in sources() {
        for (prefix, front, engine) in FORBIDDEN {
            if !file.starts_with(prefix) {
                continue;
            }
            let banned: Vec<&str> = front.iter().chain(engine.iter()).copied().collect();
            // Unit tests may build their fixtures from anywhere (a scene file, say).
            let non_test = text.split("#[cfg(test)]").next().unwrap_or("");
            for (n, line) in non_test.lines().enumerate() {
                let code = line.split("//").next().unwrap_or("");
                for b in &banned {
                    if code.contains(&format!("{b}::")) || code.contains(&format!("{b};")) {
                        wrong.push(format!("{file}:{}: uses {b}", n + 1));
                    }
                }
            }
        }
    }
    assert!(
        wrong.is_empty(),
        "imports against the data flow: {wrong:#?}"
    );
}
