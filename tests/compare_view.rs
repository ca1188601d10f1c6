//! Two runs side by side as CI sees them: `dda3d view SCENE --compare penalty --screenshot FILE
//! --exit-after-frames N` under Xvfb shows two panes that both show the model and differ after
//! the rock strikes the column; `dda3d render SCENE --compare penalty` writes frames whose
//! halves do the same; bad specs are one-line errors with status 2 before any window opens.
//!
//! As tests/viewer.rs: without `xvfb-run` or a GPU adapter (hardware or Mesa's software Vulkan
//! driver) the window and render tests print a note and pass, unless `DDA3D_REQUIRE_GPU=1`
//! (set by `.ci/run`) makes that a failure.

use std::path::{Path, PathBuf};

mod window_support;

use window_support::{distance, skip_or_fail, variation, view_under_xvfb};

mod cli_support;
use cli_support::{bin, tmp};

fn rockfall() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join("rock_column_rockfall.toml")
}

/// Fraction of pixels that differ clearly between two rectangles of one size.
fn difference(img: &image::RgbImage, a: [u32; 4], b: [u32; 2]) -> f64 {
    let [x0, y0, x1, y1] = a;
    let mut differ = 0usize;
    for y in 0..y1 - y0 {
        for x in 0..x1 - x0 {
            let p = img.get_pixel(x0 + x, y0 + y);
            let q = img.get_pixel(b[0] + x, b[1] + y);
            if distance(p, q) > 24 {
                differ += 1;
            }
        }
    }
    differ as f64 / ((x1 - x0) * (y1 - y0)) as f64
}

/// The simulated time of the exit report's line `… solver N steps to t = T s …`.
fn reported_time(line: &str) -> Option<f64> {
    let rest = line.split("steps to t = ").nth(1)?;
    rest.split_whitespace().next()?.parse().ok()
}

#[test]
fn compare_window_shows_two_different_panes_after_the_impact() {
    let dir = tmp("view");
    let png = dir.join("window.png");
    let rockfall = rockfall();
    let args = [
        rockfall.as_os_str(),
        "--compare".as_ref(),
        "penalty".as_ref(),
        "--speed".as_ref(),
        "max".as_ref(),
        "--size".as_ref(),
        "1280x720".as_ref(),
        "--exit-after-frames".as_ref(),
        "80".as_ref(),
    ];
    let Some(stderr) = view_under_xvfb("compare view", &dir, &png, &args) else {
        return;
    };
    // Both solvers report, at the same simulated time, after the strike (about 0.2 s).
    let times: Vec<f64> = stderr.lines().filter_map(reported_time).collect();
    assert_eq!(times.len(), 2, "A's and B's report lines:\n{stderr}");
    assert_eq!(times[0], times[1], "lock-step:\n{stderr}");
    assert!(
        times[0] >= 0.3,
        "the screenshot is after the impact:\n{stderr}"
    );
    assert!(stderr.contains("compare run B (penalty)"), "{stderr}");

    let img = image::open(&png).expect("a readable PNG").to_rgb8();
    assert_eq!((img.width(), img.height()), (1280, 720));
    // The two panes right of the panel, below their captions, above the legends.
    let (a, b) = ([430, 110, 840, 450], [860, 110, 1270, 450]);
    let (va, vb) = (variation(&img, a), variation(&img, b));
    assert!(va > 0.02, "pane A is uniform ({va:.4} of pixels differ)");
    assert!(vb > 0.02, "pane B is uniform ({vb:.4} of pixels differ)");
    let d = difference(&img, a, [b[0], b[1]]);
    assert!(
        d > 0.005,
        "the panes show the same picture ({d:.4} of pixels differ)"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_compare_specs_are_one_line_errors_with_status_2() {
    for extra in [
        vec!["--compare", "fastest"],
        vec!["--compare-set", "no_such_key=1"],
        vec!["--compare-set", "alpha=0.5"],
    ] {
        for cmd in ["view", "render"] {
            // No display is needed: the spec is read before any window opens.
            let out = bin()
                .arg(cmd)
                .arg(rockfall())
                .args(&extra)
                .env_remove("DISPLAY")
                .env_remove("WAYLAND_DISPLAY")
                .output()
                .unwrap();
            assert_eq!(out.status.code(), Some(2), "{cmd} {extra:?}");
            let err = String::from_utf8_lossy(&out.stderr);
            assert_eq!(err.trim_end().lines().count(), 1, "one line: {err}");
            assert!(err.starts_with("error: --compare"), "{err}");
        }
    }
    // A block to select that the scene does not have, likewise.
    let out = bin()
        .arg("view")
        .arg(rockfall())
        .args(["--compare", "penalty", "--select", "no such block"])
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.trim_end().lines().count(), 1, "one line: {err}");
    assert!(err.starts_with("error: --select"), "{err}");
}

#[test]
fn compare_render_writes_side_by_side_frames_that_differ_after_the_impact() {
    let dir = tmp("render");
    let out = bin()
        .arg("render")
        .arg(rockfall())
        .args([
            "--compare",
            "penalty",
            "--fps",
            "10",
            "--msaa",
            "1",
            "--gif",
            "--quiet",
        ])
        .args(["--width", "640", "--height", "360", "--duration", "0.5"])
        .arg("--out")
        .arg(&dir)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    if !out.status.success() {
        if stderr.contains("no GPU adapter") {
            skip_or_fail(
                "compare view",
                "no GPU adapter (Debian: apt-get install libvulkan1 mesa-vulkan-drivers)",
            );
            return;
        }
        panic!("render --compare failed ({}):\n{stderr}", out.status);
    }
    // Both sides' times, equal on every row.
    let csv = std::fs::read_to_string(dir.join("frames.csv")).unwrap();
    let mut rows = csv.lines();
    assert_eq!(rows.next(), Some("frame,time,step,file,time_b,step_b"));
    let rows: Vec<Vec<&str>> = rows.map(|r| r.split(',').collect()).collect();
    assert_eq!(rows.len(), 6, "frames at 0, 0.1, …, 0.5 s:\n{csv}");
    for r in &rows {
        let (ta, tb): (f64, f64) = (r[1].parse().unwrap(), r[4].parse().unwrap());
        assert!((ta - tb).abs() < 1e-12, "A at {ta}, B at {tb}");
    }
    assert!(dir.join("animation.gif").exists());
    // At 0.4 s, after the strike: both halves show the model, and not the same picture.
    let img = image::open(dir.join("frame_00004.png")).unwrap().to_rgb8();
    assert_eq!((img.width(), img.height()), (640, 360));
    // Below the captions, above the legends.
    let (a, b) = ([0, 60, 320, 300], [320, 60, 640, 300]);
    let (va, vb) = (variation(&img, a), variation(&img, b));
    assert!(va > 0.02, "half A is uniform ({va:.4})");
    assert!(vb > 0.02, "half B is uniform ({vb:.4})");
    let d = difference(&img, a, [b[0], b[1]]);
    assert!(
        d > 0.003,
        "the halves show the same picture ({d:.4} of pixels differ)"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
