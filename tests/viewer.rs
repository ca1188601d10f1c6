//! The interactive viewer as CI sees it: `dda3d view SCENE --screenshot FILE --exit-after-frames N`
//! under Xvfb, and its one-line errors for bad input.
//!
//! Without `xvfb-run` or a GPU adapter (hardware or Mesa's software Vulkan driver) the window
//! test prints a note and passes, unless `DDA3D_REQUIRE_GPU=1` (set by `.ci/run`) makes that a
//! failure.

use std::path::{Path, PathBuf};

mod window_support;

use window_support::{variation, view_under_xvfb};

mod cli_support;
use cli_support::{bin, rockfall_checkpoint, tmp};

const WIDTH: u32 = 1280;
const HEIGHT: u32 = 720;

fn scene(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name)
}

/// Whether any pixel of the rectangle is within `tol` (per channel) of `rgb`.
fn contains_color(img: &image::RgbImage, rect: [u32; 4], rgb: [u8; 3], tol: i32) -> bool {
    let [x0, y0, x1, y1] = rect;
    (y0..y1).any(|y| {
        (x0..x1).any(|x| {
            let p = img.get_pixel(x, y);
            (0..3).all(|k| (p[k] as i32 - rgb[k] as i32).abs() <= tol)
        })
    })
}

#[test]
fn window_screenshot_under_xvfb() {
    let dir = tmp("shot");
    let png = dir.join("window.png");
    let rockfall = scene("rock_column_rockfall.toml");
    let size = format!("{WIDTH}x{HEIGHT}");
    let args = [
        rockfall.as_os_str(),
        "--size".as_ref(),
        size.as_ref(),
        "--exit-after-frames".as_ref(),
        "40".as_ref(),
    ];
    let Some(stderr) = view_under_xvfb("viewer window", &dir, &png, &args) else {
        return;
    };
    assert!(png.exists(), "no screenshot written; stderr:\n{stderr}");
    let img = image::open(&png).expect("a readable PNG").to_rgb8();
    assert_eq!(
        (img.width(), img.height()),
        (WIDTH, HEIGHT),
        "the screenshot has the window's size"
    );

    // Left panel (parameters) and the 3-D view to its right, away from the toolbar and plots.
    let panel = [8, 50, 290, 480];
    let view = [480, 60, 1270, 500];
    let pv = variation(&img, panel);
    let vv = variation(&img, view);
    assert!(
        pv > 0.02,
        "panel region is uniform ({pv:.4} of pixels differ)"
    );
    assert!(
        vv > 0.02,
        "3-D region is uniform ({vv:.4} of pixels differ)"
    );
    // The 3-D view shows its light-grey background (so it was drawn, with the right sRGB
    // handling), and the panel its own fill.
    assert!(
        contains_color(&img, view, [0xF4, 0xF4, 0xF1], 3),
        "3-D background colour not found in the view region"
    );
    assert!(
        contains_color(&img, panel, [0xFA, 0xFA, 0xF8], 3),
        "panel colour not found in the panel region"
    );
    assert!(
        stderr.contains("frames in"),
        "the exit report is printed:\n{stderr}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_scene_is_a_one_line_error_with_status_2() {
    let dir = tmp("bad");
    let bad = dir.join("bad.toml");
    std::fs::write(&bad, "name = \"x\"\n[[blocks]]\nmaterial = \"granite\"\nbox = { size = [1.0, 1.0, 1.0], center = [0.0, 0.0, 0.0] }\n").unwrap();
    for args in [
        vec!["view".to_string(), bad.display().to_string()],
        // The shortcut `dda3d SCENE.toml`.
        vec![bad.display().to_string()],
        vec![
            "view".to_string(),
            dir.join("missing.toml").display().to_string(),
        ],
    ] {
        // No display is needed: the scene is read before any window opens.
        let out = bin()
            .args(&args)
            .env_remove("DISPLAY")
            .env_remove("WAYLAND_DISPLAY")
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(err.trim_end().lines().count(), 1, "one line: {err}");
        assert!(err.starts_with("error: "), "{err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_options_are_rejected_before_opening_a_window() {
    let rock = scene("rock_column_rockfall.toml");
    for extra in [
        vec!["--size", "12x7"],
        vec!["--speed", "-2"],
        vec!["--msaa", "3"],
        vec!["--exit-after-frames", "0"],
    ] {
        let out = bin()
            .arg("view")
            .arg(&rock)
            .args(&extra)
            .env_remove("DISPLAY")
            .env_remove("WAYLAND_DISPLAY")
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2), "{extra:?}");
    }
}

/// `view --resume CHECKPOINT`: the window opens at a checkpoint of `run` (a large rock mass's
/// equilibrium stage computed once, headless); bad uses are one line and exit 2 before any
/// window opens.
#[test]
fn the_viewer_opens_at_a_checkpoint() {
    let dir = tmp("resume");
    let (ckpt, t0) = rockfall_checkpoint(&dir);
    let run = dir.join("run");

    let summary = run.join("summary.json");
    let stable = scene("slope_stable.toml");
    let bad: [(Vec<&std::ffi::OsStr>, &str); 4] = [
        (
            vec![ckpt.as_ref(), "--method".as_ref(), "penalty".as_ref()],
            "cannot be used with",
        ),
        (
            vec![ckpt.as_ref(), "--duration".as_ref(), "0.2".as_ref()],
            "give a later --duration",
        ),
        (
            vec![summary.as_ref()],
            "summary.json: not a dda3d checkpoint",
        ),
        (vec![ckpt.as_ref(), stable.as_ref()], "cannot be used with"),
    ];
    for (extra, want) in bad {
        let out = bin()
            .args(["view", "--resume"])
            .args(&extra)
            .env_remove("DISPLAY")
            .env_remove("WAYLAND_DISPLAY")
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{extra:?}: {err}");
        assert!(err.contains(want), "{extra:?}: {err}");
    }

    let png = dir.join("window.png");
    let args = [
        "--resume".as_ref(),
        ckpt.as_os_str(),
        "--paused".as_ref(),
        "--exit-after-frames".as_ref(),
        "10".as_ref(),
    ];
    let Some(stderr) = view_under_xvfb("viewer at a checkpoint", &dir, &png, &args) else {
        return;
    };
    assert!(png.exists(), "no screenshot written; stderr:\n{stderr}");
    // The window opened at the checkpoint's time (src/viewer/sim has the run going on from
    // there, and Reset going back to it).
    assert!(stderr.contains(&format!("to t = {t0:.3} s")), "{stderr}");
    let _ = std::fs::remove_dir_all(&dir);
}
