//! Exit status 1 means a diverged run and nothing else: an output that cannot be created or
//! written is an I/O error, status 74, with one line on stderr naming the path (README "Exit
//! codes", `dda3d::cli::exit`). A full disk keeps the complete rows and says so in
//! summary.json.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use dda3d::cli::exit::Status;
use serde_json::Value;

fn scene() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/slope_sliding.toml")
}

fn fresh_dir(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("exit_codes_{name}"));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn run_to(out: &Path, duration: &str) -> Output {
    Command::new(env!("CARGO_BIN_EXE_dda3d"))
        .arg("run")
        .arg(scene())
        .args(["--quiet", "--duration", duration, "--out"])
        .arg(out)
        .output()
        .unwrap()
}

/// Exit status 74 and one line on stderr that names `path`.
fn expect_io_error(out: &Output, path: &Path) -> String {
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert_eq!(
        out.status.code(),
        Some(i32::from(Status::Io.code())),
        "stderr: {err}"
    );
    assert_eq!(err.trim_end().lines().count(), 1, "one line: {err}");
    assert!(err.starts_with("error: "), "{err}");
    assert!(
        err.contains(&path.display().to_string()),
        "names {path:?}: {err}"
    );
    assert!(!err.contains("panicked"), "{err}");
    err
}

#[test]
fn the_statuses_are_the_documented_ones() {
    assert_eq!(Status::Io.code(), 74);
    assert_eq!(Status::Diverged.code(), 1);
    assert_eq!(Status::BadInput.code(), 2);
}

#[test]
fn out_that_is_a_file_is_an_io_error() {
    let dir = fresh_dir("file");
    let file = dir.join("taken");
    std::fs::write(&file, "not a directory").unwrap();
    expect_io_error(&run_to(&file, "0.05"), &file);
    // A directory cannot be made under a file either.
    let under = file.join("sub");
    expect_io_error(&run_to(&under, "0.05"), &under);
}

/// Every command that makes an output directory says so when a file stands in its way, as
/// `run` does, naming the directory and the file: `generate` and `cut` (the parent of their
/// file), `study` (its directory), `render` (its frames directory and that directory's parents;
/// skipped on a machine without a GPU adapter, which `render` checks first). Before, the system's
/// "File exists (os error 17)" named neither.
#[test]
fn every_command_names_a_file_in_the_way_of_its_output_directory() {
    let dir = fresh_dir("file_in_the_way");
    let file = dir.join("afile");
    std::fs::write(&file, "not a directory").unwrap();
    let f = file.display().to_string();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let study = dir.join("study.toml");
    std::fs::write(
        &study,
        format!(
            "scene = {:?}\n[[parameters]]\nkey = \"solver.duration\"\nvalues = [0.05]\n",
            scene().display().to_string()
        ),
    )
    .unwrap();
    // The two messages: the path itself is a file, or a file lies above it.
    let exists =
        |d: &str| format!("{d}: cannot create the output directory: a file of that name exists");
    let under = |d: &str| {
        format!("{d}: cannot create the output directory: {f} is a file, not a directory")
    };
    let (slope, study) = (scene().display().to_string(), study.display().to_string());
    let cut = root
        .join("scenes/jointed_slope_small.toml")
        .display()
        .to_string();
    let [x, dx, frames, ab] = ["x.toml", "d/x.toml", "frames", "a/b"].map(|p| format!("{f}/{p}"));
    let render = ["render", &slope, "-q", "--duration", "0.05", "--out"];
    let cases: [(Vec<&str>, String); 8] = [
        (vec!["run", &slope, "-q", "--out", &f], exists(&f)),
        (vec!["generate", "column", "--out", &x], exists(&f)),
        (
            vec!["generate", "column", "--out", &dx],
            under(&format!("{f}/d")),
        ),
        (vec!["cut", &cut, "--out", &x], exists(&f)),
        (
            vec!["study", &study, "-q", "--out", &f],
            under(&format!("{f}/cases")),
        ),
        ([&render[..], &[&f]].concat(), exists(&f)),
        ([&render[..], &[&frames]].concat(), under(&frames)),
        (vec!["run", &slope, "-q", "--out", &ab], under(&ab)),
    ];
    for (args, expected) in cases {
        let out = Command::new(env!("CARGO_BIN_EXE_dda3d"))
            .args(&args)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        if args[0] == "render" && err.contains("no GPU adapter") {
            eprintln!("skipping {args:?}: no GPU adapter");
            continue;
        }
        let err = expect_io_error(&out, &file);
        assert_eq!(err.trim_end(), format!("error: {expected}"), "{args:?}");
    }
}

/// Root may write anywhere it has permissions for, so an unwritable place is one no one can
/// create a directory in: /proc.
#[test]
fn out_that_cannot_be_created_is_an_io_error() {
    let path = Path::new("/proc/dda3d-exit-codes/out");
    expect_io_error(&run_to(path, "0.05"), path);
}

#[test]
fn out_with_a_name_too_long_for_the_file_system_is_an_io_error() {
    let dir = fresh_dir("long");
    let path = dir.join("x".repeat(300));
    let out = run_to(&path, "0.05");
    let err = expect_io_error(&out, &path);
    assert!(err.contains("name too long"), "{err}");
}

/// A full disk: blocks.csv leads to /dev/full, where every write fails.
#[test]
fn a_full_disk_is_an_io_error_with_a_summary() {
    let dir = fresh_dir("full");
    std::os::unix::fs::symlink("/dev/full", dir.join("blocks.csv")).unwrap();
    let out = run_to(&dir, "0.05");
    expect_io_error(&out, &dir.join("blocks.csv"));
    let s: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!(s["status"], "io_error");
    assert!(s["error"].as_str().unwrap().contains("blocks.csv"), "{s}");
}

/// A tmpfs of 64 KiB fills up part-way: both CSV files keep complete rows up to the same
/// step, and summary.json says io_error with that step's time. Needs the right to mount
/// (root, outside a container that forbids it); skipped with a note otherwise.
#[test]
fn a_disk_that_fills_up_keeps_complete_rows() {
    let dir = fresh_dir("tmpfs");
    let mount = Command::new("mount")
        .args(["-t", "tmpfs", "-o", "size=64k", "tmpfs"])
        .arg(&dir)
        .output();
    match mount {
        Ok(m) if m.status.success() => {}
        Ok(m) => {
            let why = String::from_utf8_lossy(&m.stderr);
            eprintln!("note: a_disk_that_fills_up_keeps_complete_rows: skipped, mount: {why}");
            return;
        }
        Err(e) => {
            eprintln!("note: a_disk_that_fills_up_keeps_complete_rows: skipped, mount: {e}");
            return;
        }
    }
    struct Unmount(PathBuf);
    impl Drop for Unmount {
        fn drop(&mut self) {
            let _ = Command::new("umount").arg(&self.0).status();
        }
    }
    let _guard = Unmount(dir.clone());
    let out_dir = dir.join("o");
    let out = run_to(&out_dir, "2.0");
    expect_io_error(&out, &out_dir);
    let s: Value =
        serde_json::from_str(&std::fs::read_to_string(out_dir.join("summary.json")).unwrap())
            .unwrap();
    assert_eq!(s["status"], "io_error");
    let written = s["written_time"].as_f64().unwrap();
    let mut last = Vec::new();
    for (file, fields) in [("blocks.csv", 8), ("contacts.csv", 17)] {
        let text = std::fs::read_to_string(out_dir.join(file)).unwrap();
        assert!(text.ends_with('\n'), "{file} ends with a whole row");
        let rows: Vec<csv::StringRecord> = csv::Reader::from_reader(text.as_bytes())
            .records()
            .map(Result::unwrap)
            .collect();
        assert!(rows.iter().all(|r| r.len() == fields));
        last.push(rows.last().unwrap()[0].parse::<f64>().unwrap());
    }
    // To within an ulp: serde_json's fast float parser may read the last digit differently.
    assert!(
        last.iter().all(|t| (t - written).abs() <= 1e-12),
        "both files end at written_time {written}: {last:?}"
    );
    assert!(written < s["simulated_time"].as_f64().unwrap());
}

/// The default output directory comes from the scene's name; a name of any length gives one
/// that can be created.
#[test]
fn a_very_long_scene_name_still_runs() {
    let dir = fresh_dir("name");
    let text = std::fs::read_to_string(scene()).unwrap();
    let name = "A very long scene name ".repeat(30);
    // The top-level name comes before the first table; the blocks' names stay.
    let text = text.replacen(
        "name = \"Block sliding on a 30 degree slope (paper Table 2)\"",
        &format!("name = \"{name}\""),
        1,
    );
    std::fs::write(dir.join("long.toml"), text).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_dda3d"))
        .current_dir(&dir)
        .args(["run", "long.toml", "--quiet", "--duration", "0.02"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let made: Vec<_> = std::fs::read_dir(dir.join("out")).unwrap().collect();
    assert_eq!(made.len(), 1);
    let slug = made[0].as_ref().unwrap().file_name();
    assert!(slug.len() <= dda3d::output::MAX_SLUG, "{slug:?}");
}

/// A model of fixed blocks only (a rock mass cut into slabs, every one held, on a fixed ground)
/// completes: its blocks settle on their vertex springs, and the elastic energy they store
/// (3 µJ) was taken by the energy watchdog for a gain above its 1 µJ floor ("diverged").
#[test]
fn a_model_of_fixed_blocks_only_completes() {
    let dir = fresh_dir("all_fixed");
    let text = "[solver]\nduration = 0.05\n\
        [materials.rock]\ndensity = 2600.0\nyoung_modulus = 1.0e10\npoisson_ratio = 0.25\n\
        [[blocks]]\nname = \"ground\"\nmaterial = \"rock\"\nfixed = true\n\
        box = { size = [20, 20, 2], center = [0, 0, -1] }\n\
        [[rock_masses]]\nname = \"m\"\nmaterial = \"rock\"\n\
        regions = [ { box = { size = [4, 4, 4], center = [0, 0, 2] } } ]\n\
        fixed = { below = 1e9 }\n\
        [[rock_masses.joint_sets]]\nname = \"J1\"\ndip = 45.0\ndip_direction = 90.0\n\
        spacing = 1.0\n";
    let path = dir.join("held.toml");
    std::fs::write(&path, text).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_dda3d"))
        .arg("run")
        .arg(&path)
        .args(["--quiet", "--out"])
        .arg(dir.join("out"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{err}");
    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("out/summary.json")).unwrap())
            .unwrap();
    assert_eq!(summary["status"], "completed");
}

/// A failed write to stdout or stderr (a full disk, a closed pipe) is an I/O error, status 74
/// with one line where stderr takes it, not a panic's report and 101: `cut`'s report to a full
/// stdout, and `generate`'s line to a full stderr.
#[test]
fn a_standard_stream_that_cannot_be_written_is_an_io_error() {
    let full = || {
        std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap()
    };
    let dir = fresh_dir("full_stream");
    let rock_mass = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/jointed_slope_small.toml");
    let out = Command::new(env!("CARGO_BIN_EXE_dda3d"))
        .arg("cut")
        .arg(&rock_mass)
        .arg("--out")
        .arg(dir.join("cut.toml"))
        .stdout(full())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(
        out.status.code(),
        Some(i32::from(Status::Io.code())),
        "{err}"
    );
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains("failed printing to stdout"), "{err}");
    assert!(!err.contains("panicked"), "{err}");

    let out = Command::new(env!("CARGO_BIN_EXE_dda3d"))
        .args(["generate", "column", "--blocks", "5", "--out"])
        .arg(dir.join("column.toml"))
        .stderr(full())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(i32::from(Status::Io.code())));
}

/// `--help` and `--version` to a stream that cannot be written end as every other command's
/// output does: status 74 and one line (clap's own exit ignored the failure and exited 0).
#[test]
fn help_and_version_to_a_full_stdout_are_io_errors() {
    for args in [
        &["--help"][..],
        &["run", "--help"],
        &["--version"],
        &["help"],
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_dda3d"))
            .args(args)
            .stdout(
                std::fs::OpenOptions::new()
                    .write(true)
                    .open("/dev/full")
                    .unwrap(),
            )
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(
            out.status.code(),
            Some(i32::from(Status::Io.code())),
            "{args:?}: {err}"
        );
        assert!(
            err.starts_with("error: failed printing to stdout: No space left on device"),
            "{args:?}: {err}"
        );
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
    }
}
