//! The command line as a user meets it: outputs of `dda3d run`, and one-line errors with exit
//! status 2 for bad input.

use std::path::{Path, PathBuf};

mod cli_support;
use cli_support::{bin, tmp};

/// `dda3d run SCENE --out OUT`, its output captured.
fn run_scene(scene: &Path, out: &Path) -> std::process::Output {
    bin()
        .arg("run")
        .arg(scene)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap()
}

fn scenes() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

#[test]
fn run_writes_the_three_outputs() {
    let out = tmp("run");
    let st = bin()
        .args([
            "run",
            scenes().join("slope_sliding.toml").to_str().unwrap(),
            "--duration",
            "0.2",
            "--out",
        ])
        .arg(&out)
        .status()
        .unwrap();
    assert!(st.success());
    let blocks = std::fs::read_to_string(out.join("blocks.csv")).unwrap();
    let mut lines = blocks.lines();
    assert_eq!(lines.next(), Some("time,block,x,y,z,vx,vy,vz"));
    let rows: Vec<&str> = lines.collect();
    // Two blocks, time 0 included, one row per block per step.
    assert!(
        rows.len() >= 2 * 21 && rows.len().is_multiple_of(2),
        "{} rows",
        rows.len()
    );
    assert!(rows[0].starts_with("0,slope,") && rows[1].starts_with("0,block,"));
    let contacts = std::fs::read_to_string(out.join("contacts.csv")).unwrap();
    let mut lines = contacts.lines();
    assert_eq!(
        lines.next(),
        Some(
            "time,block_i,block_j,mode,state,px,py,pz,nx,ny,nz,normal_force,shear_force,penetration,penalty,lambda,joint"
        )
    );
    let last: Vec<&str> = lines.last().unwrap().split(',').collect();
    assert_eq!(&last[1..5], &["block", "slope", "vertex-face", "slide"]);
    let n: f64 = last[11].parse().unwrap();
    assert!(n > 1e4, "compressive normal force is positive: {n}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    for key in [
        "steps",
        "simulated_time",
        "wall_seconds",
        "max_penetration",
        "open_close_iterations",
        "alm_iterations",
        "time_step_cuts",
    ] {
        assert!(summary.get(key).is_some(), "summary.json lacks {key}");
    }
    assert!((summary["simulated_time"].as_f64().unwrap() - 0.2).abs() < 1e-12);
}

fn expect_input_error(text: &str, needle: &str) {
    let dir = tmp("bad");
    let path = dir.join("bad.toml");
    std::fs::write(&path, text).unwrap();
    let out = run_scene(&path, &dir.join("o"));
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "stderr: {err}");
    assert_eq!(err.trim_end().lines().count(), 1, "one line: {err}");
    assert!(err.contains("bad.toml"), "names the file: {err}");
    assert!(err.contains(needle), "mentions {needle}: {err}");
    assert!(!err.contains("panicked") && !err.contains("RUST_BACKTRACE"));
}

const GOOD: &str = r#"
[materials.rock]
density = 2750.0
young_modulus = 2.0e10
poisson_ratio = 0.25
[[blocks]]
name = "a"
material = "rock"
box = { size = [1, 1, 1], center = [0, 0, 0.5] }
"#;

#[test]
fn bad_input_is_one_line_and_exit_status_2() {
    expect_input_error("name = \"x\"\n[solver\nmethod = \"alm\"", "line 2");
    expect_input_error(&format!("{GOOD}colour = \"red\"\n"), "colour");
    expect_input_error(
        &GOOD.replace("material = \"rock\"", "material = \"basalt\""),
        "basalt",
    );
    expect_input_error(
        &GOOD.replace(
            "box = { size = [1, 1, 1], center = [0, 0, 0.5] }",
            "vertices = [[0,0,0],[1,0,0],[0,1,0]]",
        ),
        "four",
    );
    expect_input_error(&GOOD.replace("2750.0", "0.0"), "density");
    expect_input_error(&GOOD.replace("2.0e10", "-2.0e10"), "young_modulus");
    expect_input_error(&GOOD.replace("0.25", "0.7"), "poisson_ratio");
    expect_input_error(&GOOD.replace("2750.0", "nan"), "finite");
    expect_input_error(
        &format!(
            "{GOOD}[[blocks]]\nname = \"b\"\nmaterial = \"rock\"\nbox = {{ size = [1, 1, 1], center = [0.5, 0, 0.5] }}\n"
        ),
        "overlap",
    );
    expect_input_error("[solver]\nmethod = \"lagrange\"\n", "lagrange");
}

#[test]
fn missing_file_and_bad_flags_exit_2() {
    let out = bin()
        .args(["run", "/nonexistent/scene.toml"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("/nonexistent/scene.toml"));
    let out = bin()
        .args(["run", "x.toml", "--method", "magic"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
}

/// A first argument that is no subcommand but a path, as a mistyped scene file of the shorthand
/// `dda3d SCENE.toml` is, says what is wrong with the file (before: clap's "unrecognized
/// subcommand"); a word that is no path is still clap's usage error.
#[test]
fn a_mistyped_scene_path_is_named() {
    for (arg, expected) in [
        (
            "scenes/slope_sliding.tom",
            "error: scenes/slope_sliding.tom: no such scene file",
        ),
        ("scenes/", "error: scenes/: not a file"),
        (
            "Cargo.lock",
            "error: Cargo.lock: not a scene file (a scene file's name ends in .toml; `dda3d view \
             Cargo.lock` opens it as one)",
        ),
        ("frobnicate", "error: unrecognized subcommand 'frobnicate'"),
    ] {
        let out = bin().arg(arg).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{arg}: {err}");
        assert_eq!(err.trim_end(), expected, "{arg}");
    }
}

/// A study file that cannot be read is named once (before: "nosuch.toml: cannot read
/// nosuch.toml: …").
#[test]
fn a_missing_study_file_is_named_once() {
    let out = bin().args(["study", "nosuch.toml"]).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.starts_with("error: nosuch.toml: cannot read: No such file"),
        "{err}"
    );
    assert_eq!(err.matches("nosuch.toml").count(), 1, "{err}");
}

#[test]
fn touching_blocks_are_accepted() {
    let dir = tmp("touch");
    let path = dir.join("touch.toml");
    let on_top = "[[blocks]]\nname = \"b\"\nmaterial = \"rock\"\nbox = { size = [1, 1, 1], center = [0, 0, 1.5] }\n";
    std::fs::write(&path, format!("{GOOD}{on_top}")).unwrap();
    let st = bin()
        .arg("run")
        .arg(&path)
        .args(["--quiet", "--duration", "0.02", "--out"])
        .arg(dir.join("o"))
        .status()
        .unwrap();
    assert!(st.success());
    let summary = std::fs::read_to_string(dir.join("o/summary.json")).unwrap();
    assert!(summary.contains("\"status\": \"completed\""));
}

/// A run that cannot go on stops with a message, exit status 1, and keeps what it wrote.
#[test]
fn diverging_run_keeps_its_output() {
    let dir = tmp("diverge");
    let path = dir.join("fast.toml");
    // 1 km/s toward a fixed block 3 m away: even the smallest step (Δt_max/100) moves the
    // block far beyond δ·w0. (Alone in open space it would just fly: free flight is exact.)
    let wall = "[[blocks]]\nname = \"wall\"\nmaterial = \"rock\"\nfixed = true\nbox = { size = [1, 1, 1], center = [4, 0, 0.5] }\n";
    std::fs::write(
        &path,
        format!(
            "{}{wall}",
            GOOD.replace("box = {", "velocity = [1000.0, 0.0, 0.0]\nbox = {")
        ),
    )
    .unwrap();
    let out = run_scene(&path, &dir.join("o"));
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("diverged") && err.contains("fast.toml"),
        "{err}"
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("o/summary.json")).unwrap())
            .unwrap();
    assert_eq!(summary["status"], "diverged");
    let blocks = std::fs::read_to_string(dir.join("o/blocks.csv")).unwrap();
    assert!(blocks.lines().count() >= 2, "the initial state was written");
}
