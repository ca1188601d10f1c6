//! What the window tests (tests/viewer.rs, tests/compare_view.rs) share: whether `xvfb-run` is
//! there, and the GPU policy for skipping. Without `xvfb-run` or a GPU adapter a window test
//! prints a note and passes, unless `DDA3D_REQUIRE_GPU=1` (set by `.ci/run`) makes that a
//! failure.

use std::process::{Command, Stdio};

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
