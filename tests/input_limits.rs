//! Issue #13, the input half: no input is silently cut short, run for ever or read without end.
//! Families of bad values for every bounded input of a scene file, each through the binary: exit
//! status 2, one line on stderr naming the file, the TOML line and the key, no panic. The
//! command line's flags: `flag_limits.rs`.

use std::path::Path;

mod cli_support;
mod limits_support;
use cli_support::{bin, tmp};
use limits_support::{one_line_error, run_briefly, run_error, scene, shaped};

/// A value of the wrong kind, or a table that lacks a key, is named by its key: an inline
/// table where a number belongs, and a block without its material (before: "line 2: invalid
/// type: map, expected f64" and "line 5: missing field `material`", no key).
#[test]
fn wrong_values_and_incomplete_tables_are_named() {
    let dir = tmp("named");
    let map = scene("").replace("density = 2750.0", "density = { a = 1 }");
    let err = run_error(&dir, &map, "a map");
    assert!(
        err.contains("line 2: materials.rock.density: invalid type: map"),
        "{err}"
    );
    let text =
        scene("[[blocks]]\nname = \"b\"\nbox = { size = [1, 1, 1], center = [3, 0, 0.5] }\n");
    let err = run_error(&dir, &text, "no material");
    assert!(
        err.contains("line 9: blocks[1]: missing field `material`"),
        "{err}"
    );
    // A key given twice is named with its table (before: "line 4: duplicate key").
    let twice = format!(
        "[solver]\nduration = 1.0\nmax_time_step = 0.01\nduration = 2.0\n{}",
        scene("")
    );
    let err = run_error(&dir, &twice, "a key twice");
    assert!(
        err.ends_with("bad.toml: line 4: solver.duration: duplicate key\n"),
        "{err}"
    );
    let err = run_error(&dir, &scene("name = \"b\"\n"), "a block's key twice");
    assert!(
        err.ends_with("line 9: blocks[0].name: duplicate key\n"),
        "{err}"
    );
}

/// Lists of the wrong length, in every field that takes one.
#[test]
fn lists_of_numbers_take_exactly_their_length() {
    let dir = tmp("arity");
    let lists = |n: usize| format!("[{}]", vec!["0.5"; n].join(", "));
    let million = lists(1_000_000);
    for n in [0, 1, 2, 4, 5, 1000] {
        let l = lists(n);
        let cases = [
            (scene(&format!("velocity = {l}\n")), 9, "blocks[0].velocity"),
            (
                scene(&format!("angular_velocity = {l}\n")),
                9,
                "blocks[0].angular_velocity",
            ),
            (
                scene(&format!("loads = [{{ point = {l}, force = [0, 0, 1] }}]\n")),
                9,
                "blocks[0].loads[0].point",
            ),
            (
                scene(&format!("loads = [{{ point = [0, 0, 0], force = {l} }}]\n")),
                9,
                "blocks[0].loads[0].force",
            ),
            (
                format!("[solver]\ngravity = {l}\n{}", scene("")),
                2,
                "solver.gravity",
            ),
            (
                shaped(&format!("box = {{ size = {l}, center = [0, 0, 0.5] }}")),
                8,
                "blocks[0].box.size",
            ),
            (
                shaped(&format!("box = {{ size = [1, 1, 1], center = {l} }}")),
                8,
                "blocks[0].box.center",
            ),
            (
                shaped(&format!(
                    "box = {{ size = [1, 1, 1], center = [0, 0, 0], rotation = {l} }}"
                )),
                8,
                "blocks[0].box.rotation",
            ),
            (
                shaped(&format!("dodecahedron = {{ edge = 1, center = {l} }}")),
                8,
                "blocks[0].dodecahedron.center",
            ),
            (
                shaped(&format!("vertices = [[0,0,0],[1,0,0],[0,1,0],{l},[0,0,1]]")),
                8,
                "blocks[0].vertices",
            ),
            (
                shaped(&format!(
                    "prism = {{ base = [[0,0,0],[1,0,0],{l}], extrude = [0, 0, 1] }}"
                )),
                8,
                "blocks[0].prism.base",
            ),
            (
                shaped(&format!(
                    "prism = {{ base = [[0,0,0],[1,0,0],[0,1,0]], extrude = {l} }}"
                )),
                8,
                "blocks[0].prism.extrude",
            ),
        ];
        for (text, line, key) in cases {
            let what = format!("{key} of {n}");
            let err = run_error(&dir, &text, &what);
            assert!(
                err.contains(&format!("line {line}: {key}: expected 3 numbers, got {n}")),
                "{what}: {err}"
            );
        }
    }
    // The examples: a vertex of four numbers, a gravity of four, a velocity of 10⁶.
    let err = run_error(
        &dir,
        &shaped("vertices = [[0,0,0],[1,0,0],[0,1,0],[0,-1,0,99],[0,0,1]]"),
        "vertex",
    );
    assert!(err.contains("got 4"), "{err}");
    let err = run_error(&dir, &scene(&format!("velocity = {million}\n")), "10⁶");
    assert!(err.contains("got 1000000") && err.len() < 200, "{err}");
}

/// Zero-length, never-ending and absurd time controls, in the scene file: each names its key
/// and its line, with the number short.
#[test]
fn absurd_time_controls_in_the_scene_are_rejected_at_their_line() {
    let dir = tmp("controls");
    let with = |key: &str, value: &str| format!("[solver]\n{key} = {value}\n{}", scene(""));
    let families: [(&str, &[&str]); 3] = [
        (
            "max_time_step",
            &[
                "0.0", "-1.0", "1e-15", "9.9e-8", "1.5", "1e9", "2e9", "3e9", "1e308", "nan",
                "inf", "-inf",
            ],
        ),
        (
            "duration",
            &[
                "0.0", "-1.0", "1e-300", "1e-12", "9e-8", "1.1e7", "1e308", "nan", "inf",
            ],
        ),
        (
            "max_displacement_ratio",
            &["0.0", "-0.01", "1e-12", "9e-8", "0.11", "1.0", "1e300"],
        ),
    ];
    for (key, values) in families {
        for value in values {
            let what = format!("{key} = {value}");
            let err = run_error(&dir, &with(key, value), &what);
            assert!(
                err.contains(&format!("line 2: solver.{key} must")),
                "{what}: {err}"
            );
            // Short numbers: no run of digits from printing 1e308 in full.
            let message = err.split("bad.toml: ").nth(1).unwrap();
            assert!(message.len() < 100, "{what}: {err}");
        }
    }
    let err = run_error(&dir, &with("max_time_step", "3e9"), "3e9");
    assert!(
        err.ends_with("must lie in [1e-7, 1] s, got 3e9 s\n"),
        "{err}"
    );
    let err = run_error(&dir, &with("duration", "1e308"), "1e308");
    assert!(err.ends_with("got 1e308 s\n"), "{err}");
    // More steps than the limit: at the duration's line, or Δt_max's when the duration is the
    // default.
    for (text, line) in [
        (
            format!(
                "[solver]\nduration = 1e6\nmax_time_step = 0.01\n{}",
                scene("")
            ),
            2,
        ),
        (format!("[solver]\nmax_time_step = 1e-7\n{}", scene("")), 2),
        (
            format!(
                "[solver]\n\nmax_time_step = 1e-6\nduration = 100\n{}",
                scene("")
            ),
            4,
        ),
    ] {
        let err = run_error(&dir, &text, "steps");
        assert!(
            err.contains(&format!("line {line}: solver.duration = "))
                && err.contains("more than the limit of 1e7"),
            "{err}"
        );
    }
    // The contact tolerances and iteration caps of the same table.
    for (table, key, value) in [
        ("solver.contact", "eps1", "1.0"),
        ("solver.contact", "eps2", "1e300"),
        ("solver.contact", "max_alm_iterations", "4294967295"),
        ("solver.contact", "max_open_close_iterations", "0"),
        ("solver.contact", "close_threshold", "0.5"),
        ("solver.contact", "open_threshold", "1e308"),
        ("joint", "friction_angle", "90.0"),
        ("solver", "equilibrium_max_steps", "1000001"),
        // Unbounded above until these: each changed or slowed the run.
        ("solver", "max_displacement_overshoot", "1e300"),
        ("solver", "max_displacement_overshoot", "2.01"),
        ("solver", "sleep_time", "1e300"),
        ("solver.contact", "alpha", "1e300"),
        ("solver.contact", "alpha", "1001"),
        ("joint", "cohesion", "1e308"),
        ("joint", "cohesion", "1.1e9"),
    ] {
        let text = format!("{}[{table}]\n\n{key} = {value}\n", scene(""));
        let err = run_error(&dir, &text, key);
        assert!(
            err.contains(&format!("line 11: {table}.{key} must")),
            "{key}: {err}"
        );
    }
}

/// Scene files: a bounded read, UTF-8 with the line of the first bad byte.
#[test]
fn files_are_read_within_bounds() {
    let dir = tmp("files");
    let run = |path: &Path| bin().arg("run").arg(path).output().unwrap();
    // A sparse file just over the limit, and an endless device.
    let big = dir.join("big.toml");
    std::fs::File::create(&big)
        .unwrap()
        .set_len((16 << 20) + 1)
        .unwrap();
    let err = one_line_error(&run(&big), "big");
    assert!(
        err.contains("big.toml: the file is 16777217 bytes, more than the limit of 16 MiB"),
        "{err}"
    );
    std::fs::File::create(&big)
        .unwrap()
        .set_len(1 << 34)
        .unwrap();
    let err = one_line_error(&run(&big), "16 GiB");
    assert!(err.contains("the file is 16380 MiB"), "{err}");
    if Path::new("/dev/zero").exists() {
        let err = one_line_error(&run(Path::new("/dev/zero")), "/dev/zero");
        assert!(
            err.contains("/dev/zero: ") && err.contains("16 MiB"),
            "{err}"
        );
    }
    let err = one_line_error(&run(&dir), "a directory");
    assert!(err.contains("cannot read"), "{err}");
    // A bad byte on line 1, 3 and 12, at the start, middle and end of a line.
    for (line, column) in [(1, 1), (3, 5), (9, 1), (12, 1)] {
        let mut text = scene("velocity = [0, 0, 0]\n\n\n").into_bytes();
        let start: usize = text
            .split(|&b| b == b'\n')
            .take(line - 1)
            .map(|l| l.len() + 1)
            .sum();
        text.insert(start + column - 1, 0xff);
        let path = dir.join("utf8.toml");
        std::fs::write(&path, &text).unwrap();
        let err = one_line_error(&run(&path), "utf-8");
        assert!(
            err.contains(&format!(
                "utf8.toml: line {line}: not UTF-8 text: byte 0xff at column {column}"
            )),
            "{err}"
        );
    }
}

/// Blocks and points per block: at most 100 000 of each.
#[test]
fn blocks_and_points_are_bounded() {
    let dir = tmp("counts");
    let mut text = scene("").split("[[blocks]]").next().unwrap().to_string();
    for k in 0..100_001 {
        text += &format!(
            "[[blocks]]\nname = \"b{k}\"\nmaterial = \"rock\"\n\
             box = {{ size = [1, 1, 1], center = [{}, 0, 0.5] }}\n",
            2 * k
        );
    }
    let err = run_error(&dir, &text, "blocks");
    // The first block over the limit starts at line 5 + 4·100 000.
    assert!(
        err.contains("line 400005: 100001 blocks, more than the limit of 100000"),
        "{err}"
    );
    for n in [100_001, 250_000] {
        let points: Vec<String> = (0..n)
            .map(|k| {
                let a = k as f64 * 1e-3;
                format!("[{}, {}, {}]", a.cos(), a.sin(), (k % 7) as f64)
            })
            .collect();
        let err = run_error(
            &dir,
            &shaped(&format!("vertices = [{}]", points.join(","))),
            "vertices",
        );
        assert!(
            err.contains(&format!(
                "line 5: block 'a': vertices: {n} points, more than the limit of 100000"
            )),
            "{err}"
        );
        let base: Vec<String> = (0..n / 2 + 1)
            .map(|k| {
                let a = k as f64 * 1e-4;
                format!("[{}, {}, 0]", a.cos(), a.sin())
            })
            .collect();
        let err = run_error(
            &dir,
            &shaped(&format!(
                "prism = {{ base = [{}], extrude = [0, 0, 1] }}",
                base.join(",")
            )),
            "prism",
        );
        assert!(err.contains("prism: a base of"), "{err}");
    }
    // Within the point limit, a hull of more than 4096 corners (points on a sphere, every one
    // a corner) is refused too; one of 4000 loads.
    let sphere = |n: usize| {
        let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        let points: Vec<String> = (0..n)
            .map(|k| {
                let z = 1.0 - 2.0 * (k as f64 + 0.5) / n as f64;
                let r = (1.0 - z * z).sqrt();
                let a = golden * k as f64;
                format!("[{}, {}, {}]", r * a.cos(), r * a.sin(), z + 1.0)
            })
            .collect();
        shaped(&format!("vertices = [{}]", points.join(",")))
    };
    let err = run_error(&dir, &sphere(5000), "hull");
    assert!(
        err.contains("convex hull has 5000 corners, more than the limit of 4096"),
        "{err}"
    );
    run_briefly(&dir, "sphere", &sphere(4000));
}

/// A rock mass of one joint set, with `fixed` and `origin` as given (the set's line is 19).
fn rock_mass(fixed: &str, spacing: f64, origin: &str) -> String {
    format!(
        "[materials.rock]\ndensity = 2600.0\nyoung_modulus = 1.0e10\npoisson_ratio = 0.25\n\
         [[blocks]]\nname = \"ground\"\nmaterial = \"rock\"\nfixed = true\n\
         box = {{ size = [20, 20, 2], center = [0, 0, -1] }}\n\
         [[rock_masses]]\nname = \"m\"\nmaterial = \"rock\"\n\
         regions = [ {{ box = {{ size = [4, 4, 4], center = [0, 0, 2] }} }} ]\n\
         fixed = {fixed}\n\
         [[rock_masses.joint_sets]]\nname = \"J1\"\ndip = 45.0\ndip_direction = 90.0\n\
         spacing = {spacing}\norigin = {origin}\n"
    )
}

/// Rock masses: an origin too far out to resolve the spacing (wrong planes at 1e17 m, a walk
/// that never ended at 1e300 m), and coordinate selectors that are not numbers, are bad input;
/// an origin within 10⁹ spacings cuts the same blocks as one at the domain.
#[test]
fn rock_mass_origins_and_selectors_are_bounded() {
    let dir = tmp("rock-mass-bounds");
    for (spacing, origin) in [
        (1.0, "[1e17, 0, 0]"),
        (1.0, "[0, 0, -1e300]"),
        (0.5, "[0, 1e9, 0]"),
    ] {
        let text = rock_mass("{ below = 1.0 }", spacing, origin);
        let err = run_error(&dir, &text, origin);
        assert!(err.contains("cannot resolve a spacing"), "{origin}: {err}");
    }
    for selector in ["below", "x_above", "y_below"] {
        for value in ["nan", "inf", "-inf"] {
            let text = rock_mass(&format!("{{ {selector} = {value} }}"), 1.0, "[0, 0, 0]");
            let err = run_error(&dir, &text, selector);
            assert!(
                err.contains(&format!("fixed.{selector}")),
                "{selector}: {err}"
            );
        }
    }
    let blocks = |origin: &str| {
        let path = dir.join("good.toml");
        std::fs::write(&path, rock_mass("{ below = 1.0 }", 1.0, origin)).unwrap();
        let out = dir.join("cut.toml");
        let status = bin()
            .arg("cut")
            .arg(&path)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        assert!(status.status.success(), "{origin}: {status:?}");
        std::fs::read_to_string(&out)
            .unwrap()
            .matches("[[blocks]]")
            .count()
    };
    assert_eq!(blocks("[1e9, 0, 0]"), blocks("[0, 0, 0]"));
}

/// A joint set spaced far closer than the domain is long cuts thousands of slabs whose
/// bounding boxes, at 45°, each overlap most of the others: the scene is refused at its load,
/// one line naming the pairs, instead of checking every pair for overlap (1 mm slabs in a 2 m
/// box took 3.6 s, 0.1 mm slabs 4.7 GB and minutes, and the solver then refused them anyway).
#[test]
fn slabs_thinner_than_long_by_thousands_are_refused_at_load() {
    let dir = tmp("thin-slabs");
    let text = rock_mass("{ below = 0.5 }", 0.001, "[0, 0, 0]");
    let err = run_error(&dir, &text, "1 mm slabs");
    assert!(
        err.contains("more than 2e6 pairs of blocks have overlapping bounding boxes"),
        "{err}"
    );
    // Slabs a tenth of the domain thick are a rock mass like any other.
    run_briefly(
        &dir,
        "good",
        &rock_mass("{ below = 0.5 }", 0.4, "[0, 0, 0]"),
    );
}

#[test]
fn gravity_is_bounded_in_magnitude() {
    let dir = tmp("gravity");
    for g in [
        "[0, 0, -1e300]",
        "[1e300, 1e300, 0]",
        "[0, 0, -1.1e4]",
        "[8e3, 0, -8e3]",
    ] {
        let err = run_error(&dir, &format!("[solver]\ngravity = {g}\n{}", scene("")), g);
        assert!(
            err.contains("line 2: solver.gravity's magnitude must lie in [0, 10000] m/s², got "),
            "{g}: {err}"
        );
        assert!(!err.contains("inf"), "{g}: {err}");
    }
    // A centrifuge's hundred g, and none at all, run.
    for (name, g) in [("centrifuge", "[0, 0, -981]"), ("weightless", "[0, 0, 0]")] {
        run_briefly(
            &dir,
            name,
            &format!("[solver]\ngravity = {g}\n{}", scene("")),
        );
    }
}
