//! What the window tests (tests/viewer.rs, tests/compare_view.rs) share: whether `xvfb-run` is
//! there, the GPU policy for skipping, and waiting for the window's process. Without `xvfb-run` or a GPU adapter a window test
//! prints a note and passes, unless `DDA3D_REQUIRE_GPU=1` (set by `.ci/run`) makes that a
//! failure.

use std::ffi::OsStr;
use std::path::Path;
use std::process::{Child, Command, ExitStatus, Stdio};
use std::time::{Duration, Instant};

use dda3d::render::gpu_required_by_env;

/// Skips (returns false with a note naming `test`) or fails, as the GPU policy says.
pub fn skip_or_fail(test: &str, why: &str) -> bool {
    if gpu_required_by_env() {
        panic!("{why} (DDA3D_REQUIRE_GPU is set, so the {test} test may not be skipped)");
    }
    eprintln!("note: {test} test skipped: {why}");
    false
}

pub fn have_xvfb_run() -> bool {
    Command::new("sh")
        .args(["-c", "command -v xvfb-run"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// `dda3d view ARGS --screenshot PNG --out DIR/out` under `xvfb-run` on a 1600×900 screen, with
/// its own `XDG_RUNTIME_DIR` in `dir`, run to its end: its stderr. `None` where the window
/// cannot open here (no `xvfb-run`, no GPU adapter): the `test` is skipped with a note, or
/// fails, as the GPU policy says ([`skip_or_fail`]). A window that fails otherwise panics with
/// its stderr.
pub fn view_under_xvfb(test: &str, dir: &Path, png: &Path, args: &[&OsStr]) -> Option<String> {
    if !have_xvfb_run() {
        skip_or_fail(
            test,
            "xvfb-run is not installed (Debian: apt-get install xvfb xauth)",
        );
        return None;
    }
    let runtime = dir.join("xdg");
    std::fs::create_dir_all(&runtime).unwrap();
    let child = Command::new("xvfb-run")
        // -a: a free display number, so parallel runs do not collide.
        .args(["-a", "-s", "-screen 0 1600x900x24"])
        .arg(env!("CARGO_BIN_EXE_dda3d"))
        .arg("view")
        .args(args)
        .arg("--screenshot")
        .arg(png)
        .arg("--out")
        .arg(dir.join("out"))
        .env("XDG_RUNTIME_DIR", &runtime)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start xvfb-run");
    let (status, stderr) = finish(child);
    if !status.success() {
        if stderr.contains("no GPU adapter") {
            skip_or_fail(
                test,
                "no GPU adapter (Debian: apt-get install libvulkan1 mesa-vulkan-drivers)",
            );
            return None;
        }
        panic!("viewer failed ({status}):\n{stderr}");
    }
    Some(stderr)
}

/// Runs a command to its end (at most 300 s); its status and stderr.
pub fn finish(mut child: Child) -> (ExitStatus, String) {
    let deadline = Instant::now() + Duration::from_secs(300);
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            panic!("the command did not exit within 300 s");
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    let out = child.wait_with_output().unwrap();
    (status, String::from_utf8_lossy(&out.stderr).into_owned())
}

/// Fraction of pixels in the rectangle that differ clearly from its first pixel.
pub fn variation(img: &image::RgbImage, [x0, y0, x1, y1]: [u32; 4]) -> f64 {
    let first = *img.get_pixel(x0, y0);
    let mut differ = 0usize;
    for y in y0..y1 {
        for x in x0..x1 {
            if distance(img.get_pixel(x, y), &first) > 24 {
                differ += 1;
            }
        }
    }
    differ as f64 / ((x1 - x0) * (y1 - y0)) as f64
}

/// The sum of the channels' absolute differences of two pixels.
pub fn distance(p: &image::Rgb<u8>, q: &image::Rgb<u8>) -> i32 {
    (0..3).map(|k| (p[k] as i32 - q[k] as i32).abs()).sum()
}
