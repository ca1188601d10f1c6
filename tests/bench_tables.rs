//! `dda3d bench`'s tables against `dda3d run`: each row's counts must be those of `run` on the
//! same scene (its `summary.json`). `--rock-masses`: a rock-mass scene timed as it is, its
//! equilibrium stage apart; `--method-sizes`: the struck walls with both methods.

use std::path::{Path, PathBuf};

mod cli_support;
use cli_support::{bin, tmp};

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

/// `dda3d bench ARGS`, which must succeed: its standard output.
fn bench_stdout(args: &[&str]) -> String {
    let out = bin().arg("bench").args(args).output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    stdout
}

/// `dda3d run SCENE ARGS --quiet --out OUT`, which must succeed: its `summary.json`.
fn run_summary(scene: &Path, args: &[&str], out: &Path) -> serde_json::Value {
    let status = bin()
        .arg("run")
        .arg(scene)
        .args(args)
        .args(["--quiet", "--out"])
        .arg(out)
        .status()
        .unwrap();
    assert!(status.success());
    serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap()
}

/// The cells of the table row that begins with the cells `first`.
fn row<'a>(stdout: &'a str, first: &[&str]) -> Vec<&'a str> {
    let start = format!("| {} |", first.join(" | "));
    let line = stdout
        .lines()
        .find(|l| l.starts_with(&start))
        .unwrap_or_else(|| panic!("no row {start} in:\n{stdout}"));
    line.trim_matches('|').split('|').map(str::trim).collect()
}

#[test]
fn the_rock_mass_row_counts_what_run_counts() {
    let dir = tmp("counts");
    let scene = small_mass(&dir, 3);
    let scene_name = scene.display().to_string();
    let stdout = bench_stdout(&[
        "--sizes",
        "--standing-sizes",
        "--thread-sizes",
        "--method-sizes",
        "--cut-sizes",
        "--repeat",
        "1",
        "--rock-masses",
        &scene_name,
    ]);
    let cells = row(&stdout, &[&scene_name]);
    assert_eq!(cells.len(), 16, "{cells:?}");

    let summary = run_summary(&scene, &[], &dir.join("run"));
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

#[test]
fn each_method_row_of_the_struck_walls_counts_what_run_counts() {
    let dir = tmp("methods");
    let n = 10;
    let size = n.to_string();
    let duration = "0.3";
    let stdout = bench_stdout(&[
        "--sizes",
        "--standing-sizes",
        "--thread-sizes",
        "--cut-sizes",
        "--repeat",
        "1",
        "--scaling-duration",
        duration,
        "--method-sizes",
        &size,
        "--method-penalties",
        "10",
    ]);
    let wall = dir.join("wall.toml");
    let status = bin()
        .args(["generate", "column", "--blocks", &n.to_string(), "--out"])
        .arg(&wall)
        .status()
        .unwrap();
    assert!(status.success());
    // The same wall with DDA-3p's penalty ten times p_n,1.
    let text = std::fs::read_to_string(&wall).unwrap();
    assert!(text.contains("initial_penalty = 2.0e8\n"), "{text}");
    let stiff = dir.join("stiff.toml");
    std::fs::write(
        &stiff,
        text.replace("initial_penalty = 2.0e8\n", "initial_penalty = 2.0e9\n"),
    )
    .unwrap();
    let mut times = Vec::new();
    for (k, (scene, method, label)) in [
        (&wall, "alm", "ALM (DDA-3a)"),
        (&wall, "penalty", "penalty (DDA-3p)"),
        (&stiff, "penalty", "penalty (DDA-3p), p_n × 10"),
    ]
    .into_iter()
    .enumerate()
    {
        let cells = row(&stdout, &[&size, label]);
        assert_eq!(cells.len(), 10, "{cells:?}");
        let args = ["--method", method, "--duration", duration];
        let s = run_summary(scene, &args, &dir.join(format!("run{k}")));
        let steps = s["steps"].as_u64().unwrap();
        let per_step = |key: &str| format!("{:.2}", s[key].as_u64().unwrap() as f64 / steps as f64);
        assert_eq!(cells[4], steps.to_string(), "{label}: steps");
        assert_eq!(cells[5], per_step("open_close_iterations"), "{label}");
        assert_eq!(cells[6], per_step("alm_iterations"), "{label}");
        assert_eq!(cells[7], per_step("factorizations"), "{label}");
        assert_eq!(cells[8], s["unconverged_steps"].to_string(), "{label}");
        let pen = s["max_penetration"].as_f64().unwrap();
        assert_eq!(cells[9], format!("{pen:.2e}"), "{label}");
        times.push(cells[2].parse::<f64>().unwrap());
    }
    // DDA-3p solves once a pass; DDA-3a's ALM iterates.
    let alm = row(&stdout, &[&size, "ALM (DDA-3a)"]);
    let penalty = row(&stdout, &[&size, "penalty (DDA-3p)"]);
    assert_eq!(penalty[5], penalty[6], "one solve a pass: {penalty:?}");
    assert_ne!(alm[9], penalty[9], "the two rows ran different methods");
    let stiff = row(&stdout, &[&size, "penalty (DDA-3p), p_n × 10"]);
    assert_ne!(
        stiff[9], penalty[9],
        "the stiffer penalty ran with its own p_n"
    );
    let stiff_ratio = row(&stdout, &[&size, "ALM / penalty, p_n × 10"]);
    assert_eq!(stiff_ratio.len(), 10, "{stiff_ratio:?}");
    let ratio = row(&stdout, &[&size, "ALM / penalty"]);
    let printed: f64 = ratio[2].parse().unwrap();
    // Both times are printed to the millisecond and the ratio to two decimals: the printed
    // ratio must lie within what the rounded times allow.
    let (a, p, ms) = (times[0], times[1], 0.0005);
    let (least, most) = ((a - ms) / (p + ms) - 0.005, (a + ms) / (p - ms) + 0.005);
    assert!(
        (least..=most).contains(&printed),
        "ratio {printed} outside {least}..{most} ({a} s / {p} s)"
    );
}
