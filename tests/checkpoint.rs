//! `dda3d run --checkpoint-every T` and `dda3d run --resume CHECKPOINT` (issue #16): a run
//! resumed from a checkpoint at t1 writes, from t1 on, the rows of `blocks.csv` and
//! `contacts.csv` that the uninterrupted run wrote, byte for byte, and the checkpoints it takes
//! are those the uninterrupted run took; the same run writes the same checkpoint files every
//! time; and a file that is not a whole checkpoint of this version is refused with one line
//! and exit status 2.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use dda3d::cli::exit::Status;

fn rockfall() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/rock_column_rockfall.toml")
}

fn fresh_dir(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("checkpoint_{name}"));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn dda3d(args: &[&str], paths: &[(&str, &Path)]) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_dda3d"));
    c.arg("run").arg("--quiet").args(args);
    for (flag, p) in paths {
        if !flag.is_empty() {
            c.arg(flag);
        }
        c.arg(p);
    }
    c.output().unwrap()
}

fn succeeded(o: &Output) {
    assert!(
        o.status.success(),
        "status {:?}: {}",
        o.status,
        String::from_utf8_lossy(&o.stderr)
    );
}

/// The checkpoint files in `dir`, in time order (their names have the same width while t < 10).
fn checkpoints(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "ckpt"))
        .collect();
    files.sort();
    files
}

fn read(dir: &Path, file: &str) -> String {
    std::fs::read_to_string(dir.join(file)).unwrap()
}

/// The header and the rows of `csv` at or after `t1`.
fn rows_from(csv: &str, t1: f64) -> String {
    let mut lines = csv.lines();
    let mut out = format!("{}\n", lines.next().unwrap());
    for line in lines {
        let t: f64 = line.split(',').next().unwrap().parse().unwrap();
        if t >= t1 {
            out += line;
            out += "\n";
        }
    }
    out
}

/// Runs `scene` to `duration` with checkpoints every `every` s, resumes from the first, and
/// checks that the resumed run's rows and checkpoints are the uninterrupted run's.
fn resumed_run_matches(name: &str, scene: &Path, flags: &[&str], duration: &str, every: &str) {
    let dir = fresh_dir(name);
    let (full, resumed) = (dir.join("full"), dir.join("resumed"));
    let mut args = flags.to_vec();
    args.extend(["--duration", duration, "--checkpoint-every", every]);
    succeeded(&dda3d(&args, &[("", scene), ("--out", &full)]));
    let saved = checkpoints(&full);
    assert!(saved.len() >= 2, "{name}: checkpoints {saved:?}");
    let from = &saved[0];
    // The checkpoint holds the duration; --checkpoint-every goes on where it was.
    succeeded(&dda3d(
        &["--checkpoint-every", every],
        &[("--resume", from), ("--out", &resumed)],
    ));
    let blocks = read(&resumed, "blocks.csv");
    let first_row = blocks.lines().nth(1).unwrap();
    let t1: f64 = first_row.split(',').next().unwrap().parse().unwrap();
    assert!(t1 > 0.0, "{name}: resumed at t = {t1}");
    for file in ["blocks.csv", "contacts.csv"] {
        let expected = rows_from(&read(&full, file), t1);
        let got = read(&resumed, file);
        assert!(
            got == expected,
            "{name}: {file} of the resumed run differs from the uninterrupted run's after t = {t1}"
        );
    }
    let contacts_after = read(&resumed, "contacts.csv").lines().count() - 1;
    assert!(
        contacts_after > 0,
        "{name}: no contacts after t1 to compare"
    );
    let later: Vec<_> = checkpoints(&resumed);
    assert_eq!(later.len(), saved.len() - 1, "{name}: {later:?}");
    for (a, b) in saved[1..].iter().zip(&later) {
        assert_eq!(a.file_name(), b.file_name());
        assert!(
            std::fs::read(a).unwrap() == std::fs::read(b).unwrap(),
            "{name}: {} differs after the resume",
            b.display()
        );
    }
    println!(
        "{name}: resumed at t = {t1}, {} block rows and {contacts_after} contact rows identical",
        blocks.lines().count() - 1
    );
}

#[test]
fn rockfall_resumed_with_alm_writes_the_same_rows() {
    resumed_run_matches("alm", &rockfall(), &["--method", "alm"], "2.0", "0.5");
}

#[test]
fn rockfall_resumed_with_penalty_writes_the_same_rows() {
    resumed_run_matches(
        "penalty",
        &rockfall(),
        &["--method", "penalty"],
        "2.0",
        "0.5",
    );
}

/// A wall of 40 blocks (8 columns of 5) struck by the rock, as tests/rockfall.rs builds its wall
/// of 80: the resume falls in the impact (at 0.3 s), with many contacts and their records alive.
#[test]
fn struck_wall_resumed_writes_the_same_rows() {
    let dir = fresh_dir("wall_scene");
    let scene = dir.join("wall.toml");
    std::fs::write(&scene, dda3d::generate::column_wall(40, 5, true)).unwrap();
    resumed_run_matches("wall", &scene, &[], "0.8", "0.3");
}

/// A run resumed with a later --duration goes on past the end of the run it continues, from the
/// state that run ended with.
#[test]
fn a_resumed_run_goes_on_to_the_new_duration() {
    let dir = fresh_dir("longer");
    let (first, resumed) = (dir.join("first"), dir.join("resumed"));
    succeeded(&dda3d(
        &["--checkpoint-every", "0.1", "--duration", "0.2"],
        &[("", &rockfall()), ("--out", &first)],
    ));
    let last = checkpoints(&first).pop().unwrap();
    succeeded(&dda3d(
        &["--duration", "0.3"],
        &[("--resume", &last), ("--out", &resumed)],
    ));
    let time = |line: &str| -> f64 { line.split(',').next().unwrap().parse().unwrap() };
    let blocks = read(&resumed, "blocks.csv");
    let t1 = time(blocks.lines().nth(1).unwrap());
    assert!((t1 - 0.2).abs() < 1e-9, "resumed at {t1}");
    // The first rows are the state the first run ended with.
    let ended = rows_from(&read(&first, "blocks.csv"), t1);
    assert!(blocks.starts_with(&ended), "the rows at t = {t1} differ");
    let end = time(blocks.lines().last().unwrap());
    assert!((end - 0.3).abs() < 1e-9, "ends at {end}");
}

#[test]
fn the_same_run_writes_the_same_checkpoint_files() {
    let dir = fresh_dir("twice");
    let (a, b) = (dir.join("a"), dir.join("b"));
    for out in [&a, &b] {
        succeeded(&dda3d(
            &["--duration", "0.3", "--checkpoint-every", "0.1"],
            &[("", &rockfall()), ("--out", out)],
        ));
    }
    let (first, second) = (checkpoints(&a), checkpoints(&b));
    assert_eq!(first.len(), 3, "{first:?}");
    for (x, y) in first.iter().zip(&second) {
        assert_eq!(x.file_name(), y.file_name());
        assert!(
            std::fs::read(x).unwrap() == std::fs::read(y).unwrap(),
            "{} differs between two runs",
            x.display()
        );
    }
}

/// Exit status 2 and one line on stderr naming the file and the problem, and no output written.
fn expect_refused(file: &Path, problem: &str) {
    let out = fresh_dir("refused_out").join("never");
    let o = dda3d(&[], &[("--resume", file), ("--out", &out)]);
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert_eq!(
        o.status.code(),
        Some(i32::from(Status::BadInput.code())),
        "{err}"
    );
    assert_eq!(err.trim_end().lines().count(), 1, "one line: {err}");
    assert!(err.starts_with("error: "), "{err}");
    assert!(
        err.contains(&file.display().to_string()),
        "names the file: {err}"
    );
    assert!(err.contains(problem), "says '{problem}': {err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(!out.exists(), "nothing written for bad input");
}

#[test]
fn bad_checkpoints_exit_2_with_one_line() {
    let dir = fresh_dir("bad");
    let run = dir.join("run");
    succeeded(&dda3d(
        &["--duration", "0.1", "--checkpoint-every", "0.05"],
        &[("", &rockfall()), ("--out", &run)],
    ));
    let good = std::fs::read(&checkpoints(&run)[0]).unwrap();
    let write = |name: &str, bytes: &[u8]| {
        let p = dir.join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    };

    expect_refused(
        &write("truncated.ckpt", &good[..good.len() / 3]),
        "truncated",
    );
    expect_refused(&write("header_only.ckpt", &good[..20]), "truncated");
    let mut corrupt = good.clone();
    let mid = corrupt.len() / 2;
    corrupt[mid] ^= 0x01;
    expect_refused(&write("corrupt.ckpt", &corrupt), "corrupt");
    expect_refused(&rockfall(), "not a dda3d checkpoint");
    expect_refused(&write("empty.ckpt", b""), "not a dda3d checkpoint");
    let mut other = good.clone();
    other[16..20].copy_from_slice(&99u32.to_le_bytes());
    expect_refused(&write("v99.ckpt", &other), "version 99");
    expect_refused(&dir.join("missing.ckpt"), "cannot read");
}

#[test]
fn usage_errors_exit_2() {
    let dir = fresh_dir("usage");
    let status = |o: Output| {
        (
            o.status.code(),
            String::from_utf8_lossy(&o.stderr).to_string(),
        )
    };
    let bad = Some(i32::from(Status::BadInput.code()));
    let out = dir.join("out");
    // A scene and a checkpoint, or a solver setting with a checkpoint (it has its own).
    let ckpt = dir.join("x.ckpt");
    for (args, paths) in [
        (
            vec![],
            vec![("", rockfall().as_path()), ("--resume", &ckpt)],
        ),
        (
            vec!["--method", "penalty"],
            vec![("--resume", ckpt.as_path())],
        ),
        (
            vec!["--checkpoint-every", "0"],
            vec![("", rockfall().as_path())],
        ),
        (
            vec!["--checkpoint-every", "-1"],
            vec![("", rockfall().as_path())],
        ),
        (vec![], vec![]),
    ] {
        let mut paths = paths.clone();
        paths.push(("--out", &out));
        let (code, err) = status(dda3d(&args, &paths));
        assert_eq!(code, bad, "{args:?}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
    }
    // A checkpoint at the end of its run needs a later --duration.
    let run = dir.join("run");
    succeeded(&dda3d(
        &["--duration", "0.1", "--checkpoint-every", "0.1"],
        &[("", &rockfall()), ("--out", &run)],
    ));
    let last = checkpoints(&run).pop().unwrap();
    let (code, err) = status(dda3d(&[], &[("--resume", &last), ("--out", &out)]));
    assert_eq!(code, bad, "{err}");
    assert!(err.contains("later --duration"), "{err}");
}
