//! Issue #13, the input half, on the command line: a flag's absurd value, a bad usage or a
//! bench scene that does not load is one line on stderr naming the flag, exit status 2, no
//! panic. The scene file's keys: `input_limits.rs`.

use std::path::Path;

mod cli_support;
mod limits_support;
use cli_support::{bin, tmp};
use limits_support::{one_line_error, scene};

/// The scene's time controls overridden on the command line: the same bounds, and the message
/// names the flag.
#[test]
fn absurd_overrides_are_rejected_naming_the_flag() {
    let dir = tmp("flags");
    let path = dir.join("ok.toml");
    std::fs::write(&path, scene("")).unwrap();
    let run = |flag: &str, value: &str| {
        bin()
            .arg("run")
            .arg(&path)
            .args([flag, value, "--quiet", "--out"])
            .arg(dir.join("o"))
            .output()
            .unwrap()
    };
    for (flag, values) in [
        (
            "--duration",
            &["-1", "0", "1e-300", "1e-12", "1e308", "1e6", "inf", "nan"][..],
        ),
        (
            "--max-time-step",
            &["-1", "0", "1e-15", "1.5", "3e9", "1e308"],
        ),
        ("--spectral-radius", &["-1", "0", "0.3", "1.01", "1e308"]),
        // A negative number is a value, not a flag ("unexpected argument '-1'" before).
        ("--output-interval", &["-1", "0", "nan"]),
    ] {
        for value in values {
            let what = format!("{flag} {value}");
            let err = one_line_error(&run(flag, value), &what);
            assert!(err.starts_with(&format!("error: {flag}")), "{what}: {err}");
            assert!(err.len() < 160, "{what}: {err}");
        }
    }
    // Messages that were already good keep their words.
    let err = one_line_error(&run("--duration", "-1"), "-1");
    assert_eq!(
        err,
        "error: --duration must be a positive number of seconds, got -1\n"
    );
    let err = one_line_error(&run("--duration", "1e308"), "1e308");
    assert_eq!(
        err,
        "error: --duration: solver.duration must lie in [1e-7, 1e7] s, got 1e308 s\n"
    );
    let err = one_line_error(&run("--duration", "1e6"), "steps");
    assert!(
        err.contains("1e8 steps, more than the limit of 1e7"),
        "{err}"
    );
    // The shortest Δt_max is too short for this 2750 kg block: its inertia would dwarf every
    // penalty the ALM may reach, and the message says which Δt_max would do.
    let short_run = bin()
        .arg("run")
        .arg(&path)
        .args([
            "--max-time-step",
            "1e-7",
            "--duration",
            "1e-6",
            "--quiet",
            "--out",
        ])
        .arg(dir.join("o"))
        .output()
        .unwrap();
    let err = one_line_error(&short_run, "1e-7");
    assert!(
        err.starts_with("error: --max-time-step: ") && err.contains("max_time_step ≥ 1.18"),
        "{err}"
    );
    assert!(err.len() < 240, "{err}");
    // At the ends of the ranges a run goes: ten steps of the shortest Δt_max (for a 4 cm
    // block), one of the longest.
    let pebble = dir.join("pebble.toml");
    let small = "size = [0.04, 0.04, 0.04], center = [0, 0, 0.02]";
    std::fs::write(
        &pebble,
        scene("").replace("size = [1, 1, 1], center = [0, 0, 0.5]", small),
    )
    .unwrap();
    for (scene_path, args) in [
        (&pebble, ["--max-time-step", "1e-7", "--duration", "1e-6"]),
        (&path, ["--max-time-step", "1", "--duration", "1e-7"]),
    ] {
        let out = bin()
            .arg("run")
            .arg(scene_path)
            .args(args)
            .args(["--quiet", "--out"])
            .arg(dir.join("o"))
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let summary = std::fs::read_to_string(dir.join("o/summary.json")).unwrap();
        assert!(!summary.contains("\"steps\": 0,"), "{args:?}: {summary}");
    }
}

/// `generate` writes only scenes that load, and `bench` checks its sizes before it builds any.
#[test]
fn generate_and_bench_options_are_bounded() {
    let dir = tmp("gen");
    let out = dir.join("w.toml");
    for blocks in ["0", "99999", "1000000", "-5", "18446744073709551615"] {
        let o = bin()
            .args(["generate", "column", "--blocks", blocks, "--out"])
            .arg(&out)
            .output()
            .unwrap();
        let err = one_line_error(&o, blocks);
        assert!(err.contains("--blocks"), "{err}");
    }
    let o = bin()
        .args(["generate", "column", "--layers", "0", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    one_line_error(&o, "layers 0");
    assert!(!out.exists(), "nothing written");
    for (flag, value) in [
        ("--sizes", "0"),
        ("--sizes", "10,0"),
        ("--sizes", "1000000000"),
        ("--sizes", "99999"),
        ("--sizes", "-1"),
        ("--standing-sizes", "0"),
        ("--standing-sizes", "100000"),
        ("--method-sizes", "0"),
        ("--method-sizes", "100000"),
        ("--method-penalties", "0"),
        ("--method-penalties", "-1"),
        ("--method-penalties", "10,20000"),
        ("--method-penalties", "inf"),
        ("--method-penalties", "NaN"),
        ("--repeat", "0"),
        ("--repeat", "101"),
        ("--repeat", "-1"),
        ("--scaling-duration", "-1"),
        ("--scaling-duration", "0"),
        ("--scaling-duration", "1e308"),
        ("--scaling-duration", "1e6"),
    ] {
        let o = bin().args(["bench", flag, value]).output().unwrap();
        let err = one_line_error(&o, &format!("{flag} {value}"));
        assert!(err.contains(flag), "{flag} {value}: {err}");
        assert!(o.stdout.is_empty(), "{flag} {value}: nothing run");
    }
}

/// The argument parser's own errors are one line too.
#[test]
fn usage_errors_are_one_line() {
    for args in [
        &["run", "x.toml", "--durration", "5"][..],
        &["run", "x.toml", "--duration", "abc"],
        &["run", "x.toml", "--duration"],
        &["run", "x.toml", "--method", "magic"],
        &["run"],
        &["frobnicate"],
        &["generate", "column", "--blocks", "many"],
        &["bench", "--sizes", "1,x"],
    ] {
        let o = bin().args(args).output().unwrap();
        one_line_error(&o, &format!("{args:?}"));
    }
    let o = bin()
        .args(["run", "x.toml", "--durration", "5"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("(tip: a similar argument exists: '--duration')"),
        "{err}"
    );
    // Help is still help.
    let o = bin().args(["run", "--help"]).output().unwrap();
    assert!(o.status.success());
    assert!(String::from_utf8_lossy(&o.stdout).contains("--max-time-step"));
}

#[test]
fn a_bench_scene_that_does_not_load_is_bad_input() {
    let dir = tmp("bench-scene");
    let path = dir.join("bad.toml");
    for text in ["bogus = 1\n", &scene("fixed = 3\n")] {
        std::fs::write(&path, text).unwrap();
        let out = bin()
            .arg("bench")
            .arg("--scene")
            .arg(&path)
            .output()
            .unwrap();
        let err = one_line_error(&out, text);
        assert!(err.contains("bad.toml"), "{err}");
    }
}

/// `render`'s frame count, duration × fps, is bounded before anything is drawn (no GPU needed).
#[test]
fn render_frames_are_bounded() {
    let dir = tmp("render-frames");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/slope_stable.toml");
    for (duration, fps) in [("0.05", "1e9"), ("1000", "1000"), ("5000", "30")] {
        let out = bin()
            .arg("render")
            .arg(&scene)
            .args(["--quiet", "--duration", duration, "--fps", fps, "--out"])
            .arg(dir.join("o"))
            .output()
            .unwrap();
        let err = one_line_error(&out, fps);
        assert!(
            err.contains("frames, more than 100000"),
            "{duration} s at {fps}: {err}"
        );
    }
}
