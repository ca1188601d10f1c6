//! `dda3d bench --rock-masses`: a rock-mass scene timed as it is, its equilibrium stage apart.
//! The table's counts must be those of `dda3d run` on the same scene (its `summary.json`).

use std::path::{Path, PathBuf};
use std::process::Command;

fn bin() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_dda3d"));
    // bench's default rockfall scene is relative to the repository.
    c.current_dir(env!("CARGO_MANIFEST_DIR"));
    c
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("dda3d-bench-rm-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A 2 m cube cut by a horizontal and a vertical joint (four blocks) on a fixed slab, with an
/// equilibrium stage of at most `stage_steps` steps, run for two steps of 0.01 s.
fn small_mass(dir: &Path, stage_steps: u32) -> PathBuf {
    let path = dir.join("mass.toml");
    let text = format!(
        r#"name = "Small jointed mass"

[solver]
duration = 0.02
max_time_step = 0.01
initial_equilibrium = true
equilibrium_max_steps = {stage_steps}

[materials.rock]
density = 2600.0
young_modulus = 1.0e10
poisson_ratio = 0.25

[[blocks]]
name = "ground"
material = "rock"
fixed = true
box = {{ size = [6, 6, 1], center = [1, 1, -0.5] }}

[[rock_masses]]
name = "cube"
material = "rock"
regions = [ {{ prism = {{ base = [[0, 0, 0], [2, 0, 0], [2, 0, 2], [0, 0, 2]], extrude = [0, 2, 0] }} }} ]

[[rock_masses.joint_sets]]
name = "bedding"
dip = 0.0
dip_direction = 0.0
spacing = 1.0
origin = [0.0, 0.0, 1.0]

[[rock_masses.joint_sets]]
name = "J2"
dip = 90.0
dip_direction = 90.0
spacing = 5.0
origin = [1.0, 0.0, 0.0]
"#
    );
    std::fs::write(&path, text).unwrap();
    path
}

/// The cells of the table row that names `scene`.
fn row<'a>(stdout: &'a str, scene: &Path) -> Vec<&'a str> {
    let name = scene.display().to_string();
    let line = stdout
        .lines()
        .find(|l| l.starts_with(&format!("| {name} |")))
        .unwrap_or_else(|| panic!("no row for {name} in:\n{stdout}"));
    line.trim_matches('|').split('|').map(str::trim).collect()
}

#[test]
fn the_rock_mass_row_counts_what_run_counts() {
    let dir = tmp("counts");
    let scene = small_mass(&dir, 3);
    let out = bin()
        .args([
            "bench",
            "--sizes",
            "--standing-sizes",
            "--thread-sizes",
            "--method-sizes",
            "--cut-sizes",
        ])
        .args(["--repeat", "1", "--rock-masses"])
        .arg(&scene)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let cells = row(&stdout, &scene);
    assert_eq!(cells.len(), 16, "{cells:?}");

    let run_dir = dir.join("run");
    let status = bin()
        .arg("run")
        .arg(&scene)
        .args(["--quiet", "--out"])
        .arg(&run_dir)
        .status()
        .unwrap();
    assert!(status.success());
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run_dir.join("summary.json")).unwrap())
            .unwrap();
    let eq = &summary["equilibrium"];
    // blocks: the slab and the four cut blocks.
    assert_eq!(cells[1], "5");
    assert_eq!(
        cells[2],
        eq["steps"].as_u64().unwrap().to_string(),
        "stage steps"
    );
    assert!(eq["steps"].as_u64().unwrap() >= 1);
    let converged = if eq["converged"].as_bool().unwrap() {
        "yes"
    } else {
        "no"
    };
    assert_eq!(cells[4], converged);
    assert_eq!(
        cells[5],
        summary["steps"].as_u64().unwrap().to_string(),
        "steps after"
    );
    assert_eq!(cells[6], "0.020");
    let factorizations = summary["factorizations"].as_u64().unwrap() as f64
        / summary["steps"].as_u64().unwrap() as f64;
    assert_eq!(cells[12], format!("{factorizations:.1}"));
}

#[test]
fn a_missing_or_bad_rock_mass_scene_is_bad_input() {
    let dir = tmp("bad");
    let bad = dir.join("bad.toml");
    std::fs::write(&bad, "bogus = 1\n").unwrap();
    for path in [dir.join("missing.toml"), bad] {
        let out = bin()
            .args(["bench", "--rock-masses"])
            .arg(&path)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        assert!(err.contains(&name), "{err}");
        assert!(
            out.stdout.is_empty(),
            "nothing was run: {}",
            String::from_utf8_lossy(&out.stdout)
        );
    }
}
