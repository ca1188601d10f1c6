//! `dda3d bench --method-sizes`: the struck walls run with both methods. Each row must count what
//! `dda3d run` counts on the same generated wall with that method (its `summary.json`), and the
//! ratio row must be the quotient of the two rows' times.

use std::path::{Path, PathBuf};
use std::process::Command;

fn bin() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_dda3d"));
    // bench's default rockfall scene is relative to the repository.
    c.current_dir(env!("CARGO_MANIFEST_DIR"));
    c
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("dda3d-bench-m-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The cells of the table row of the wall of `n` blocks whose second cell is `label`.
fn row<'a>(stdout: &'a str, n: usize, label: &str) -> Vec<&'a str> {
    let line = stdout
        .lines()
        .find(|l| l.starts_with(&format!("| {n} | {label} |")))
        .unwrap_or_else(|| panic!("no row for {n} / {label} in:\n{stdout}"));
    line.trim_matches('|').split('|').map(str::trim).collect()
}

/// `dda3d run` on `scene` with `method` for `duration` s: its `summary.json`.
fn run_summary(scene: &Path, method: &str, duration: &str, out: &Path) -> serde_json::Value {
    let status = bin()
        .arg("run")
        .arg(scene)
        .args([
            "--method",
            method,
            "--duration",
            duration,
            "--quiet",
            "--out",
        ])
        .arg(out)
        .status()
        .unwrap();
    assert!(status.success());
    serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap()
}

#[test]
fn each_method_row_counts_what_run_counts() {
    let dir = tmp("counts");
    let n = 10;
    let duration = "0.3";
    let out = bin()
        .args([
            "bench",
            "--sizes",
            "--standing-sizes",
            "--thread-sizes",
            "--cut-sizes",
            "--repeat",
            "1",
            "--scaling-duration",
            duration,
            "--method-sizes",
            &n.to_string(),
        ])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let wall = dir.join("wall.toml");
    let status = bin()
        .args(["generate", "column", "--blocks", &n.to_string(), "--out"])
        .arg(&wall)
        .status()
        .unwrap();
    assert!(status.success());
    let mut times = Vec::new();
    for (method, label) in [("alm", "ALM (DDA-3a)"), ("penalty", "penalty (DDA-3p)")] {
        let cells = row(&stdout, n, label);
        assert_eq!(cells.len(), 10, "{cells:?}");
        let s = run_summary(&wall, method, duration, &dir.join(method));
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
    let (alm, penalty) = (
        row(&stdout, n, "ALM (DDA-3a)"),
        row(&stdout, n, "penalty (DDA-3p)"),
    );
    assert_eq!(penalty[5], penalty[6], "one solve a pass: {penalty:?}");
    assert_ne!(alm[9], penalty[9], "the two rows ran different methods");
    let ratio = row(&stdout, n, "ALM / penalty");
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
