//! `dda3d study` (issue #18): the grid expands as documented, seeded draws repeat, a failing case
//! is recorded while the others complete, a study resumes where it stopped, another study's
//! directory is refused, bad study files are one line and exit status 2, and an outcome follows
//! the sliding block's closed form. Every study here runs the two-block slope scene (fast).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use dda3d::study::{CaseRecord, Study, run_task};

fn scene(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name)
        .display()
        .to_string()
}

mod cli_support;
use cli_support::tmp;

/// A study file in `dir` over the sliding block (its own duration shortened by the study when
/// `body` says so).
fn study_file(dir: &Path, name: &str, body: &str) -> PathBuf {
    let path = dir.join(name);
    let text = format!("scene = {:?}\n{body}", scene("slope_sliding.toml"));
    std::fs::write(&path, text).unwrap();
    path
}

fn study(args: &[&str], file: &Path, out: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_dda3d"))
        .arg("study")
        .arg(file)
        .arg("--out")
        .arg(out)
        .args(args)
        .output()
        .unwrap()
}

/// study.csv's rows as fields, without the wall_seconds column.
fn rows(out: &Path) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(out.join("study.csv")).unwrap();
    let mut r = csv::Reader::from_reader(text.as_bytes());
    let header: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
    let wall = header.iter().position(|h| h == "wall_seconds").unwrap();
    let mut all = vec![header];
    all.extend(
        r.records()
            .map(|rec| rec.unwrap().iter().map(String::from).collect()),
    );
    for row in &mut all {
        row.remove(wall);
    }
    all
}

const SHORT: &str = "[[parameters]]\nkey = \"solver.duration\"\nvalues = [0.1]\n";

#[test]
fn the_grid_expands_first_list_slowest_and_ignores_cases() {
    let dir = tmp("grid");
    let file = study_file(
        &dir,
        "grid.toml",
        &format!(
            "cases = 50\noutcomes = [\"max_displacement\", \"steps\"]\n{SHORT}\
             [[parameters]]\nkey = \"joint.friction_angle\"\nvalues = [10.0, 20]\n\
             [[parameters]]\nkey = \"solver.max_time_step\"\nvalues = [0.01, 0.02, 0.05]\n"
        ),
    );
    let s = Study::load(&file).unwrap();
    assert_eq!(s.len(), 6, "a pure grid sets the count");
    assert_eq!(
        s.keys(),
        [
            "solver.duration",
            "joint.friction_angle",
            "solver.max_time_step"
        ]
    );
    let out = dir.join("out");
    let o = study(&["--quiet"], &file, &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r = rows(&out);
    assert_eq!(
        r[0],
        [
            "case",
            "solver.duration",
            "joint.friction_angle",
            "solver.max_time_step",
            "max_displacement",
            "steps",
            "status",
            "error"
        ]
    );
    let grid: Vec<(&str, &str, &str)> = r[1..]
        .iter()
        .map(|row| (row[0].as_str(), row[2].as_str(), row[3].as_str()))
        .collect();
    assert_eq!(
        grid,
        [
            ("0", "10", "0.01"),
            ("1", "10", "0.02"),
            ("2", "10", "0.05"),
            ("3", "20", "0.01"),
            ("4", "20", "0.02"),
            ("5", "20", "0.05")
        ]
    );
    // The integer 20 was set as the float the key holds; the steps follow max_time_step.
    assert!(
        s.task(3)
            .unwrap()
            .scene_text
            .contains("friction_angle = 20.0")
    );
    let steps = |row: &Vec<String>| row[5].parse::<u32>().unwrap();
    assert!(steps(&r[1]) >= 10 && steps(&r[1]) > steps(&r[2]) && steps(&r[2]) > steps(&r[3]));
    assert!(r[1..].iter().all(|row| row[6] == "ok"));
}

#[test]
fn seeded_draws_repeat_and_a_case_alone_gives_its_row() {
    let dir = tmp("seed");
    let body = format!(
        "seed = 7\ncases = 4\noutcomes = [\"runout\", \"final_kinetic_energy\"]\n{SHORT}\
         [[parameters]]\nkey = \"joint.friction_angle\"\nuniform = [5.0, 25.0]\n\
         [[parameters]]\nkey = \"solver.contact.initial_penalty\"\nlog_uniform = [1e8, 1e9]\n"
    );
    let file = study_file(&dir, "seeded.toml", &body);
    let (a, b, c) = (dir.join("a"), dir.join("b"), dir.join("c"));
    assert!(
        study(&["--quiet", "--jobs", "2"], &file, &a)
            .status
            .success()
    );
    assert!(
        study(&["--quiet", "--jobs", "1"], &file, &b)
            .status
            .success()
    );
    let rows_a = rows(&a);
    assert_eq!(rows_a, rows(&b), "same seed, any jobs: the same table");
    assert_eq!(rows_a.len(), 5);
    let angles: Vec<f64> = rows_a[1..].iter().map(|r| r[2].parse().unwrap()).collect();
    assert!(angles.iter().all(|a| (5.0..25.0).contains(a)), "{angles:?}");
    assert!(angles.windows(2).all(|w| w[0] != w[1]));
    let o = study(&["--case", "2"], &file, &c);
    assert!(o.status.success());
    let printed = String::from_utf8(o.stdout).unwrap();
    let mut lines = printed.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let wall = header.iter().position(|h| *h == "wall_seconds").unwrap();
    let mut row: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    row.remove(wall);
    assert_eq!(row, rows_a[3]);
    // Another seed draws otherwise.
    let other = study_file(&dir, "other.toml", &body.replace("seed = 7", "seed = 8"));
    let d = dir.join("d");
    assert!(study(&["--quiet"], &other, &d).status.success());
    assert_ne!(rows(&d)[1][2], rows_a[1][2]);
}

#[test]
fn a_failing_case_is_recorded_and_the_others_complete() {
    let dir = tmp("fail");
    let file = study_file(
        &dir,
        "fail.toml",
        &format!(
            "outcomes = [\"max_displacement\"]\n{SHORT}\
             [[parameters]]\nkey = \"joint.friction_angle\"\nvalues = [30.0, -5.0, 35.0]\n"
        ),
    );
    let out = dir.join("out");
    let o = study(&["--quiet"], &file, &out);
    assert_eq!(o.status.code(), Some(1), "some case failed");
    let err = String::from_utf8(o.stderr).unwrap();
    assert_eq!(err.lines().count(), 1, "{err}");
    let r = rows(&out);
    assert_eq!(r.len(), 4);
    // case, solver.duration, joint.friction_angle, max_displacement, status, error
    assert_eq!((r[1][4].as_str(), r[3][4].as_str()), ("ok", "ok"));
    assert_eq!(r[2][4], "failed");
    assert_eq!(r[2][3], "", "no outcome for a failed case");
    assert!(r[2][5].contains("friction_angle"), "{}", r[2][5]);
    assert!(r[2][5].contains("(case 1)"), "{}", r[2][5]);
    assert!(r[1][3].parse::<f64>().unwrap() >= 0.0);
}

fn record(out: &Path, case: usize) -> (String, std::time::SystemTime) {
    let p = out.join("cases").join(format!("case_{case}.json"));
    let m = std::fs::metadata(&p).unwrap().modified().unwrap();
    (std::fs::read_to_string(p).unwrap(), m)
}

#[test]
fn resume_skips_finished_cases_and_assembles_single_ones() {
    let dir = tmp("resume");
    let file = study_file(
        &dir,
        "resume.toml",
        &format!(
            "outcomes = [\"max_displacement\"]\n{SHORT}\
             [[parameters]]\nkey = \"joint.friction_angle\"\nvalues = [10.0, 15.0, 20.0]\n"
        ),
    );
    let out = dir.join("out");
    // Case 1 alone first, as an array job would; then the whole study.
    assert!(study(&["--case", "1"], &file, &out).status.success());
    let single = record(&out, 1);
    assert!(study(&["--quiet"], &file, &out).status.success());
    assert_eq!(
        record(&out, 1),
        single,
        "the --case record is taken, not re-run"
    );
    let kept = record(&out, 0);
    std::fs::remove_file(out.join("cases").join("case_2.json")).unwrap();
    assert!(study(&["--quiet"], &file, &out).status.success());
    assert_eq!(record(&out, 0), kept, "a finished case is not re-run");
    assert!(out.join("cases").join("case_2.json").exists());
    let table = std::fs::read_to_string(out.join("study.csv")).unwrap();
    let rec: CaseRecord = CaseRecord::from_json(&single.0).unwrap();
    let line = table.lines().nth(2).unwrap();
    assert!(line.contains(&format!(",{},", rec.wall_seconds)), "{line}");
    assert_eq!(table.lines().count(), 4);
}

#[test]
fn another_studys_directory_is_refused() {
    let dir = tmp("other");
    let body = format!(
        "outcomes = [\"steps\"]\n{SHORT}\
         [[parameters]]\nkey = \"joint.friction_angle\"\nvalues = [10.0]\n"
    );
    let a = study_file(&dir, "a.toml", &body);
    let b = study_file(&dir, "b.toml", &body.replace("10.0", "12.0"));
    let out = dir.join("out");
    assert!(study(&["--quiet"], &a, &out).status.success());
    let o = study(&["--quiet"], &b, &out);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8(o.stderr).unwrap();
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("another study"), "{err}");
}

#[test]
fn bad_study_files_are_one_line_and_exit_2() {
    let dir = tmp("bad");
    let sliding = scene("slope_sliding.toml");
    let p = |key: &str, dist: &str| format!("[[parameters]]\nkey = \"{key}\"\n{dist}\n");
    let ok_param = p("joint.friction_angle", "uniform = [10.0, 20.0]");
    let head = "cases = 2\noutcomes = [\"runout\"]\n";
    let cases: Vec<(String, &str)> = vec![
        (
            format!("scene = \"missing.toml\"\n{head}{ok_param}"),
            "scene: cannot read",
        ),
        (
            format!(
                "scene = {sliding:?}\n{head}{}",
                p("solver.contact.initial_penaltyy", "uniform = [1e8, 2e8]")
            ),
            "parameters[0]: key \"solver.contact.initial_penaltyy\"",
        ),
        (
            format!(
                "scene = {sliding:?}\n{head}{ok_param}{}",
                p("blocks.blok.velocity[0]", "uniform = [0.0, 1.0]")
            ),
            "parameters[1]: key \"blocks.blok.velocity[0]\": no block named \"blok\" in",
        ),
        (
            format!(
                "scene = {sliding:?}\n{head}{}",
                p("blocks.block.velocity[3]", "uniform = [0.0, 1.0]")
            ),
            "index out of range",
        ),
        (
            format!(
                "scene = {sliding:?}\n{head}{}",
                p("joint.cohesion", "uniform = [2.0, 1.0]")
            ),
            "needs finite lo < hi",
        ),
        (
            format!(
                "scene = {sliding:?}\n{head}{}",
                p("joint.cohesion", "log_uniform = [0.0, 1.0]")
            ),
            "0 < lo < hi",
        ),
        (
            format!(
                "scene = {sliding:?}\n{head}{}",
                p("joint.cohesion", "values = [1.0]\nuniform = [0.0, 1.0]")
            ),
            "exactly one of values, uniform, log_uniform, normal (got values and uniform)",
        ),
        (
            format!("scene = {sliding:?}\ncases = 2\noutcomes = [\"runoff\"]\n{ok_param}"),
            "unknown outcome \"runoff\"",
        ),
        (
            format!("scene = {sliding:?}\noutcomes = [\"runout\"]\n{ok_param}"),
            "cases: missing",
        ),
        (
            format!("scene = {sliding:?}\ncases = 0\noutcomes = [\"runout\"]\n{ok_param}"),
            "cases = 0: must be 1 to 1000000",
        ),
        (
            format!("scene = {sliding:?}\n{head}seeds = 3\n{ok_param}"),
            "unknown field `seeds`",
        ),
        (
            format!(
                "scene = {sliding:?}\n{head}{}",
                p("joint.cohesion", "normal = [0.0, 1.0]\nbounds = [8.0, 9.0]")
            ),
            "less than 1e-6",
        ),
        (
            format!("scene = {sliding:?}\n{head}watch = [\"column*\"]\n{ok_param}"),
            "watch: \"column*\" matches no free block",
        ),
        // Numbers short (serde printed 1e300's 301 digits).
        (
            format!("scene = {sliding:?}\n{head}toppled_angle = 1e300\n{ok_param}"),
            "toppled_angle = 1e300: must be between 0 and 180 degrees",
        ),
        // A device that never ends is read only up to a scene file's limit (it filled the
        // memory before).
        (
            format!("scene = \"/dev/zero\"\n{head}{ok_param}"),
            "scene: the input goes on, more than the limit of 16 MiB for a scene file",
        ),
    ];
    for (k, (text, want)) in cases.iter().enumerate() {
        let file = dir.join(format!("bad{k}.toml"));
        std::fs::write(&file, text).unwrap();
        let o = study(&[], &file, &dir.join(format!("out{k}")));
        let err = String::from_utf8(o.stderr).unwrap();
        assert_eq!(o.status.code(), Some(2), "{text}\n{err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.starts_with("error: "), "{err}");
        assert!(err.contains(&file.display().to_string()), "{err}");
        assert!(err.contains(want), "{text}\nwanted {want:?} in {err}");
        assert!(
            !dir.join(format!("out{k}")).exists(),
            "nothing written for bad input"
        );
    }
}

/// A study file that never ends (`/dev/zero`) is read up to the scene files' limit, then
/// refused in one line; it used to be read until memory ran out.
#[test]
fn an_endless_study_file_is_refused_at_the_limit() {
    let dir = tmp("endless");
    let o = study(&["--quiet"], Path::new("/dev/zero"), &dir.join("out"));
    let err = String::from_utf8(o.stderr).unwrap();
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains(
            "/dev/zero: the input goes on, more than the limit of 16 MiB for a study file"
        ),
        "{err}"
    );
}

/// The sliding block's largest displacement follows s = ½ g (sin θ − cos θ tan φ) t² on the
/// 30° slope (the paper's Table 2 scene), and is nil where friction holds it (φ > θ).
#[test]
fn max_displacement_follows_the_sliding_block_closed_form() {
    let dir = tmp("closed");
    let file = study_file(
        &dir,
        "closed.toml",
        "outcomes = [\"max_displacement\", \"runout\", \"blocks_moved\", \"blocks_toppled\"]\n\
         [[parameters]]\nkey = \"joint.friction_angle\"\nvalues = [10.0, 15.0, 20.0, 35.0]\n",
    );
    let s = Study::load(&file).unwrap();
    let (theta, g, t) = (30f64.to_radians(), 9.8, 2.0);
    for case in 0..s.len() {
        let r = run_task(&s.task(case).unwrap());
        assert_eq!(r.status, "ok", "{:?}", r.error);
        let phi = r.values[0].as_f64().unwrap().to_radians();
        let got = r.outcomes[0].unwrap();
        let a = g * (theta.sin() - theta.cos() * phi.tan());
        if a > 0.0 {
            let want = 0.5 * a * t * t;
            assert!(
                (got / want - 1.0).abs() < 0.01,
                "φ = {phi}: {got} vs {want}"
            );
            // Horizontal run-out: the slope's cosine of the travel.
            let runout = r.outcomes[1].unwrap();
            assert!((runout / (want * theta.cos()) - 1.0).abs() < 0.01);
            assert_eq!(r.outcomes[2], Some(1.0));
        } else {
            assert!(got < 1e-3, "φ = {phi}: the block stands, moved {got}");
            assert_eq!(r.outcomes[2], Some(0.0));
        }
        assert_eq!(r.outcomes[3], Some(0.0), "a sliding block does not topple");
    }
}

/// A study file without `outcomes` tabulates the six, in its order.
#[test]
fn a_study_without_outcomes_takes_the_documented_six() {
    let dir = tmp("default-outcomes");
    let file = study_file(
        &dir,
        "s.toml",
        "set = { \"solver.duration\" = 0.2 }\n[[parameters]]\nkey = \"joint.friction_angle\"\nvalues = [10.0, 40.0]\n",
    );
    let out = dir.join("out");
    let o = study(&["--quiet"], &file, &out);
    assert_eq!(o.status.code(), Some(0), "{o:?}");
    let table = rows(&out);
    assert_eq!(
        table[0],
        [
            "case",
            "joint.friction_angle",
            "max_displacement",
            "runout",
            "blocks_moved",
            "peak_normal_force",
            "final_kinetic_energy",
            "max_penetration",
            "status",
            "error"
        ]
    );
    assert_eq!(table.len(), 3);
    // φ = 10° slides, φ = 40° holds on the 30° slope.
    let moved = |row: &[String]| row[2].parse::<f64>().unwrap();
    assert!(
        moved(&table[1]) > 0.05 && moved(&table[2]) < 1e-3,
        "{table:?}"
    );
}

/// `--case K --write-scene FILE` writes case K's scene; `dda3d run` of that file moves the block
/// as far as the study's record says (so a case can be watched or rerun on its own).
#[test]
fn a_case_scene_written_out_runs_to_the_recorded_outcome() {
    let dir = tmp("write-scene");
    let file = study_file(
        &dir,
        "s.toml",
        "outcomes = [\"runout\"]\nset = { \"solver.duration\" = 0.4 }\n[[parameters]]\nkey = \"joint.friction_angle\"\nvalues = [10.0, 20.0]\n",
    );
    let out = dir.join("out");
    assert_eq!(study(&["--quiet"], &file, &out).status.code(), Some(0));
    let recorded: f64 = rows(&out)[2][2].parse().unwrap();
    let case_scene = dir.join("case1.toml");
    let o = study(
        &["--case", "1", "--write-scene", case_scene.to_str().unwrap()],
        &file,
        &dir.join("unused"),
    );
    assert_eq!(o.status.code(), Some(0), "{o:?}");
    assert!(
        !dir.join("unused").join("study.csv").exists(),
        "nothing run"
    );
    let text = std::fs::read_to_string(&case_scene).unwrap();
    assert!(text.contains("friction_angle = 20.0"), "{text}");
    // A file in the way of its directory is named (status 74); a missing directory is made.
    let in_the_way = dir.join("case1.toml").join("x.toml");
    let o = study(
        &["--case", "1", "--write-scene", in_the_way.to_str().unwrap()],
        &file,
        &dir.join("unused"),
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(74), "{err}");
    assert!(
        err.contains("case1.toml is a file, not a directory"),
        "{err}"
    );
    let nested = dir.join("new").join("case1.toml");
    let o = study(
        &["--case", "1", "--write-scene", nested.to_str().unwrap()],
        &file,
        &dir.join("unused"),
    );
    assert_eq!(o.status.code(), Some(0), "{o:?}");
    assert_eq!(std::fs::read_to_string(&nested).unwrap(), text);
    let run_out = dir.join("run");
    let status = Command::new(env!("CARGO_BIN_EXE_dda3d"))
        .args(["run", case_scene.to_str().unwrap(), "--quiet", "--out"])
        .arg(&run_out)
        .status()
        .unwrap();
    assert!(status.success());
    let blocks = std::fs::read_to_string(run_out.join("blocks.csv")).unwrap();
    let xy = |line: &str| -> [f64; 2] {
        let f: Vec<f64> = line
            .split(',')
            .skip(2)
            .take(2)
            .map(|v| v.parse().unwrap())
            .collect();
        [f[0], f[1]]
    };
    let rows: Vec<&str> = blocks
        .lines()
        .skip(1)
        .filter(|l| l.split(',').nth(1) == Some("block"))
        .collect();
    let (a, b) = (xy(rows[0]), xy(rows[rows.len() - 1]));
    let travel = (b[0] - a[0]).hypot(b[1] - a[1]);
    assert!(
        (travel - recorded).abs() <= 1e-9 * recorded.max(1e-3),
        "run {travel} against the study's {recorded}"
    );
}

/// Every study shipped in studies/ loads, and its first case runs to an ok record.
#[test]
fn shipped_studies_load_and_their_first_case_runs() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("studies");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    assert!(files.len() >= 2, "{files:?}");
    for file in files {
        let study = Study::load(&file).unwrap_or_else(|e| panic!("{e}"));
        assert!(!study.is_empty());
        let record = run_task(&study.task(0).unwrap());
        assert!(record.is_ok(), "{}: {:?}", file.display(), record.error);
        assert!(
            record
                .outcomes
                .iter()
                .all(|o| o.is_some_and(f64::is_finite))
        );
    }
}
