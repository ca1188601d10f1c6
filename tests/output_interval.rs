//! `dda3d run --output-interval T` and the scene's `[output] interval` (issue #15): the CSV
//! files then hold the first state, the first step at or past each multiple of T and the final
//! state, each of them byte for byte the rows the every-step run wrote for that step; a resumed
//! run goes on writing the uninterrupted run's rows.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

fn rockfall() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/rock_column_rockfall.toml")
}

fn fresh_dir(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("output_interval_{name}"));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// `dda3d run --quiet ARGS --out OUT`, which must succeed.
fn run(args: &[&str], out: &Path) {
    let o = Command::new(env!("CARGO_BIN_EXE_dda3d"))
        .arg("run")
        .arg("--quiet")
        .args(args)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// The rows of a CSV file by their time column (the text of the time, as written), in order.
fn rows_by_time(dir: &Path, file: &str) -> (String, BTreeMap<String, Vec<String>>, Vec<String>) {
    let text = std::fs::read_to_string(dir.join(file)).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().to_string();
    let mut rows: BTreeMap<String, Vec<String>> = BTreeMap::new();
    let mut order = Vec::new();
    for line in lines {
        let t = line.split(',').next().unwrap().to_string();
        if order.last() != Some(&t) {
            order.push(t.clone());
        }
        rows.entry(t).or_default().push(line.to_string());
    }
    (header, rows, order)
}

/// The steps an interval of `dt` takes from the every-step times: the first, the first at or
/// past each multiple of `dt` (a step a rounding error short of one counting as on it), and
/// the last. Written from the documented rule, not from the program's code.
fn expected_times(all: &[String], dt: f64) -> Vec<String> {
    let times: Vec<f64> = all.iter().map(|t| t.parse().unwrap()).collect();
    let mut keep = vec![0];
    let end = *times.last().unwrap();
    let mut k = 1.0;
    while k * dt <= end * (1.0 + 1e-12) {
        let m = k * dt * (1.0 - 1e-9);
        if let Some(i) = times.iter().position(|&t| t >= m)
            && keep.last() != Some(&i)
        {
            keep.push(i);
        }
        k += 1.0;
    }
    if keep.last() != Some(&(times.len() - 1)) {
        keep.push(times.len() - 1);
    }
    keep.into_iter().map(|i| all[i].clone()).collect()
}

#[test]
fn rows_at_an_interval_are_the_every_step_rows_of_the_steps_it_takes() {
    let dir = fresh_dir("family");
    let every = dir.join("every");
    run(&[rockfall().to_str().unwrap()], &every);
    let (bh, blocks, times) = rows_by_time(&every, "blocks.csv");
    let (ch, contacts, _) = rows_by_time(&every, "contacts.csv");
    assert!(times.len() > 200, "{} steps", times.len());
    // Intervals that divide the 2 s run and ones that do not, one shorter than most steps and
    // one longer than the run.
    for dt in ["0.005", "0.05", "0.1", "0.25", "0.3", "0.7", "5"] {
        let out = dir.join(format!("dt{dt}"));
        run(
            &[rockfall().to_str().unwrap(), "--output-interval", dt],
            &out,
        );
        let want = expected_times(&times, dt.parse().unwrap());
        let (h, got, order) = rows_by_time(&out, "blocks.csv");
        assert_eq!(h, bh);
        assert_eq!(order, want, "--output-interval {dt}: the steps written");
        for t in &order {
            assert_eq!(
                got[t], blocks[t],
                "--output-interval {dt}: block rows at t = {t}"
            );
        }
        let (h, got, _) = rows_by_time(&out, "contacts.csv");
        assert_eq!(h, ch);
        for t in &want {
            assert_eq!(
                got.get(t),
                contacts.get(t),
                "--output-interval {dt}: contact rows at t = {t}"
            );
        }
        assert!(
            got.keys().all(|t| want.contains(t)),
            "--output-interval {dt}"
        );
        println!(
            "--output-interval {dt}: {} of {} steps",
            want.len(),
            times.len()
        );
    }
}

#[test]
fn the_scenes_output_interval_thins_the_rows_and_the_flag_overrides_it() {
    let dir = fresh_dir("scene");
    let text = std::fs::read_to_string(rockfall()).unwrap() + "\n[output]\ninterval = 0.5\n";
    let scene = dir.join("rockfall.toml");
    std::fs::write(&scene, text).unwrap();
    let scene = scene.to_str().unwrap();
    let every = dir.join("every");
    run(&[rockfall().to_str().unwrap()], &every);
    let (_, _, times) = rows_by_time(&every, "blocks.csv");
    let from_scene = dir.join("scene");
    run(&[scene], &from_scene);
    let (_, _, order) = rows_by_time(&from_scene, "blocks.csv");
    assert_eq!(order, expected_times(&times, 0.5));
    let flag = dir.join("flag");
    run(&[scene, "--output-interval", "0.25"], &flag);
    let (_, _, order) = rows_by_time(&flag, "blocks.csv");
    assert_eq!(order, expected_times(&times, 0.25));
}

#[test]
fn a_run_resumed_with_an_interval_writes_the_uninterrupted_runs_rows() {
    let dir = fresh_dir("resume");
    let (full, resumed) = (dir.join("full"), dir.join("resumed"));
    let flags = ["--output-interval", "0.1", "--checkpoint-every", "0.75"];
    let mut args = vec![rockfall().to_str().unwrap().to_string()];
    args.extend(flags.iter().map(|s| s.to_string()));
    run(&args.iter().map(|s| s.as_str()).collect::<Vec<_>>(), &full);
    let ckpt = std::fs::read_dir(&full)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "ckpt"))
        .min()
        .expect("a checkpoint");
    let mut args = vec!["--resume", ckpt.to_str().unwrap()];
    args.extend(flags);
    run(&args, &resumed);
    // The resumed run starts with the checkpoint's state; after it, the same steps.
    let t1: f64 = rows_by_time(&resumed, "blocks.csv").2[0].parse().unwrap();
    assert!(t1 > 0.7, "resumed at {t1}");
    for file in ["blocks.csv", "contacts.csv"] {
        let (_, a, order_full) = rows_by_time(&full, file);
        let (_, b, order) = rows_by_time(&resumed, file);
        let after = |o: &[String]| -> Vec<String> {
            o.iter()
                .filter(|t| t.parse::<f64>().unwrap() > t1)
                .cloned()
                .collect()
        };
        assert_eq!(after(&order), after(&order_full), "{file}");
        assert!(after(&order).len() >= 10, "{file}: {order:?}");
        for t in after(&order) {
            assert_eq!(a[&t], b[&t], "{file} at t = {t}");
        }
    }
}
