//! Same input, same output, byte for byte, whatever the thread count (#15). Detection, the block
//! terms and the commit of a step run over pairs, blocks and contacts in parallel (rayon); every
//! parallel result is gathered in index order and every sum is formed in the same order, so the
//! CSV files of a run must not depend on how many threads the pool has.
//!
//! Runs each scene with 1, 2 and 3 threads (`RAYON_NUM_THREADS`) and compares blocks.csv and
//! contacts.csv byte for byte: the rockfall (both methods), a struck wall of 60 blocks, a
//! slice of the jointed slope (rock-mass cutting, joint sets, the equilibrium stage) and a cube
//! jointed in three dimensions, whose factorization runs on the pool.

use std::path::{Path, PathBuf};
use std::process::Command;

fn scene(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name)
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("dda3d-threads-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn dda3d(threads: usize) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_dda3d"));
    c.env("RAYON_NUM_THREADS", threads.to_string());
    c
}

/// Runs `scene` with 1, 2 and 3 threads and checks that the CSV files are identical. Returns
/// the one-thread run's `summary.json`.
fn same_for_any_thread_count(tag: &str, scene: &Path, extra: &[&str]) -> String {
    let dir = tmp(tag);
    let mut outputs: Vec<(Vec<u8>, Vec<u8>)> = Vec::new();
    for threads in 1..=3 {
        let out = dir.join(format!("t{threads}"));
        let status = dda3d(threads)
            .arg("run")
            .arg(scene)
            .args(["--quiet", "--out"])
            .arg(&out)
            .args(extra)
            .status()
            .unwrap();
        assert!(status.success(), "{tag} with {threads} threads: {status}");
        let read = |f: &str| std::fs::read(out.join(f)).unwrap();
        outputs.push((read("blocks.csv"), read("contacts.csv")));
    }
    let (blocks, contacts) = &outputs[0];
    assert!(
        contacts.len() > 1000,
        "{tag}: the run has contacts to compare"
    );
    for (k, (b, c)) in outputs.iter().enumerate().skip(1) {
        assert!(
            b == blocks,
            "{tag}: blocks.csv differs with {} threads",
            k + 1
        );
        assert!(
            c == contacts,
            "{tag}: contacts.csv differs with {} threads",
            k + 1
        );
    }
    let summary = std::fs::read_to_string(dir.join("t1/summary.json")).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    summary
}

#[test]
fn rockfall_is_identical_with_any_thread_count() {
    let rockfall = scene("rock_column_rockfall.toml");
    same_for_any_thread_count("alm", &rockfall, &["--duration", "1.0"]);
    same_for_any_thread_count(
        "penalty",
        &rockfall,
        &["--duration", "1.0", "--method", "penalty"],
    );
}

#[test]
fn struck_wall_is_identical_with_any_thread_count() {
    let dir = tmp("wall");
    let wall = dir.join("wall.toml");
    let status = dda3d(1)
        .args(["generate", "column", "--blocks", "60", "--out"])
        .arg(&wall)
        .status()
        .unwrap();
    assert!(status.success());
    same_for_any_thread_count("wall", &wall, &["--duration", "0.4"]);
}

#[test]
fn a_sleeping_wall_woken_by_a_rock_is_identical_with_any_thread_count() {
    // A standing wall of 20 falls asleep about 0.2 s in; a cube dropped from 6 m above it
    // wakes it at about 1.1 s (`tests/sleeping.rs`).
    let dir = tmp("sleeping");
    let wall = dir.join("wall.toml");
    let mut text = dda3d::generate::column_wall(20, 5, false);
    text += "\n[[blocks]]\nname = \"rock\"\nmaterial = \"rock\"\n\
             box = { size = [0.8, 0.8, 0.8], center = [0.1, 0.3, 16.4] }\n";
    std::fs::write(&wall, text).unwrap();
    let summary = same_for_any_thread_count("sleeping", &wall, &["--duration", "1.6"]);
    let summary: serde_json::Value = serde_json::from_str(&summary).unwrap();
    let asleep = summary["sleeping_steps"].as_u64().unwrap_or(0);
    assert!(
        (50..150).contains(&asleep),
        "the wall sleeps until the rock comes: {asleep} of 160 steps"
    );
}

#[test]
fn jointed_slope_slice_is_identical_with_any_thread_count() {
    // A 4 m slice of the shipped slope (its y extent cut down), with its equilibrium stage.
    let text = std::fs::read_to_string(scene("jointed_slope.toml")).unwrap();
    assert_eq!(
        text.matches("extrude = [0, 20, 0]").count(),
        2,
        "slope layout changed"
    );
    let dir = tmp("slope");
    let slice = dir.join("slice.toml");
    std::fs::write(
        &slice,
        text.replace("extrude = [0, 20, 0]", "extrude = [0, 4, 0]"),
    )
    .unwrap();
    same_for_any_thread_count("slope", &slice, &["--duration", "0.1"]);
}

#[test]
fn jointed_cube_is_identical_with_any_thread_count() {
    // A 6 m cube cut every 1.2 m by three joint sets (about 125 blocks) on a fixed slab: its
    // contact graph is three-dimensional, so the Cholesky fronts are about 600 rows high (the
    // walls': 95), above the height from which faer factorizes on the whole pool
    // (`physics::linear`). Two steps.
    let dir = tmp("cube");
    let cube = dir.join("cube.toml");
    let mut text = String::from(
        r#"name = "Jointed cube"

[solver]
method = "alm"
duration = 0.02
max_time_step = 0.01

[joint]
friction_angle = 40.0

[materials.rock]
density = 2600.0
young_modulus = 1.0e10
poisson_ratio = 0.25

[[blocks]]
name = "ground"
material = "rock"
fixed = true
box = { size = [12, 12, 2], center = [3, 3, -1] }

[[rock_masses]]
name = "cube"
material = "rock"
regions = [ { prism = { base = [[0, 0, 0], [6, 0, 0], [6, 0, 6], [0, 0, 6]], extrude = [0, 6, 0] } } ]
"#,
    );
    for (name, dip, dip_direction) in [("J1", 0.0, 0.0), ("J2", 80.0, 90.0), ("J3", 85.0, 0.0)] {
        text.push_str(&format!(
            "\n[[rock_masses.joint_sets]]\nname = \"{name}\"\ndip = {dip}\n\
             dip_direction = {dip_direction}\nspacing = 1.2\n"
        ));
    }
    std::fs::write(&cube, text).unwrap();
    same_for_any_thread_count("cube", &cube, &[]);
}
