//! `dda3d run SCENE --compare ...`: the paper's Tables 1 and 2 read from compare.json (the
//! bounds of tests/slope_validation.rs), each side's files byte for byte those of a plain run,
//! B alone changed by `--compare-set`, bad specs as one line with exit status 2, and the
//! closed forms of slopes of other angles recognised from their geometry.

use std::path::{Path, PathBuf};
use std::process::Output;

use serde_json::Value;

mod cli_support;
use cli_support::{bin, tmp};

fn scene(file: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(file)
}

/// `dda3d run SCENE ARGS --out OUT --quiet`.
fn run(scene: &Path, args: &[&str], out: &Path) -> Output {
    bin()
        .arg("run")
        .arg(scene)
        .args(args)
        .arg("--out")
        .arg(out)
        .arg("--quiet")
        .output()
        .unwrap()
}

fn run_ok(scene: &Path, args: &[&str], out: &Path) {
    let o = run(scene, args, out);
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
}

fn compare_json(out: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(out.join("compare.json")).unwrap()).unwrap()
}

fn num(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("a number: {v}"))
}

/// The CSV files of two output directories are byte-identical.
fn same_rows(a: &Path, b: &Path) {
    for f in ["blocks.csv", "contacts.csv"] {
        let (x, y) = (
            std::fs::read(a.join(f)).unwrap(),
            std::fs::read(b.join(f)).unwrap(),
        );
        assert!(
            x == y,
            "{} and {} differ",
            a.join(f).display(),
            b.join(f).display()
        );
    }
}

/// Table 1 from compare.json: the bounds tests/slope_validation.rs puts on the same runs.
#[test]
fn table1_from_compare_json() {
    let out = tmp("table1");
    let stable = scene("slope_stable.toml");
    run_ok(&stable, &["--compare", "penalty"], &out.join("cmp"));
    // Each side is its plain run, byte for byte.
    run_ok(&stable, &[], &out.join("alm"));
    run_ok(&stable, &["--method", "penalty"], &out.join("penalty"));
    same_rows(&out.join("cmp/A"), &out.join("alm"));
    same_rows(&out.join("cmp/B"), &out.join("penalty"));

    let r = compare_json(&out.join("cmp"));
    assert_eq!(r["a"]["labels"], serde_json::json!(["method=alm"]));
    assert_eq!(r["b"]["labels"], serde_json::json!(["method=penalty"]));
    let case = &r["closed_form"]["a"];
    assert_eq!(case["motion"], "stands");
    assert!((num(&case["theta_deg"]) - 30.0).abs() < 1e-9);
    assert!(r.get("table2").is_none(), "a standing block has no Table 2");
    let (n_up, n_down) = (33203.8, 60153.8);
    let mut worst = [0.0f64; 2];
    println!("\nTable 1 from compare.json (t = 2 s)");
    for (k, side) in ["a", "b"].into_iter().enumerate() {
        let t = &r["table1"][side];
        assert_eq!(num(&t["time"]), 2.0);
        assert!(num(&t["drift"]) < 1e-3, "{side}: the block crept");
        // The resultant is W cos θ and W sin θ whatever the method: the block is at rest.
        assert!(num(&t["normal_error_percent"]) < 1e-6, "{t}");
        assert!(num(&t["shear_error_percent"]) < 1e-6, "{t}");
        let contacts = t["contacts"].as_array().unwrap();
        assert_eq!(contacts.len(), 4, "{side}: the four base corners");
        for c in contacts {
            let (n, theory) = (num(&c["normal_force"]), num(&c["theory"]));
            let (dn, pn) = (num(&c["penetration"]), num(&c["penalty"]));
            let err = num(&c["error_percent"]);
            println!("{side} {n:>12.1} theory {theory:>10.1} error {err:.5} % d_n {dn:.3e}");
            assert_eq!(c["state"], "lock", "φ = 35° > 30°: every contact holds");
            let paper = if num(&c["along_slope"]) < 0.0 {
                n_up
            } else {
                n_down
            };
            assert!((theory - paper).abs() < 0.05, "(P25): {theory}");
            worst[k] = worst[k].max(err);
            if side == "a" {
                assert!(err <= 0.04, "ALM: error {err} % > 0.04 %");
                assert!(dn <= 1.3e-5, "ALM: penetration {dn:e} m > 1.3e-5 m");
            } else {
                // DDA-3p carries the force by penetration alone: N = p_n d_n.
                assert!((n - pn * dn).abs() < 1e-6 * n);
                assert!(
                    (dn - theory / 2.0e8).abs() < 0.01 * theory / 2.0e8,
                    "{dn:e}"
                );
            }
        }
    }
    assert!(
        worst[1] > worst[0],
        "the penalty method is the less accurate one"
    );
    let b = num(&r["table1"]["b"]["max_penetration"]);
    assert!((b - n_down / 2.0e8).abs() < 0.01 * n_down / 2.0e8, "{b}");
}

/// Table 2 from compare.json, row by row against the paper's DDA-3a errors.
#[test]
fn table2_from_compare_json() {
    let out = tmp("table2");
    let sliding = scene("slope_sliding.toml");
    run_ok(&sliding, &["--compare", "penalty"], &out.join("cmp"));
    run_ok(&sliding, &[], &out.join("alm"));
    run_ok(&sliding, &["--method", "penalty"], &out.join("penalty"));
    same_rows(&out.join("cmp/A"), &out.join("alm"));
    same_rows(&out.join("cmp/B"), &out.join("penalty"));

    let r = compare_json(&out.join("cmp"));
    let case = &r["closed_form"]["a"];
    assert_eq!(case["motion"], "slides");
    assert!((num(&case["acceleration"]) - 9.8 * 15f64.to_radians().tan()).abs() < 1e-9);
    assert!(r.get("table1").is_none(), "a sliding block has no Table 1");
    let paper_3a = [0.34, 0.20, 0.13, 0.09, 0.07, 0.06, 0.05, 0.08, 0.07, 0.02];
    let rows = r["table2"].as_array().unwrap();
    assert_eq!(rows.len(), 201, "every 0.01 s from 0 to 2 s");
    println!("\nTable 2 from compare.json");
    for (k, bound) in paper_3a.iter().enumerate() {
        let t = 0.2 * (k + 1) as f64;
        let row = rows
            .iter()
            .find(|row| (num(&row["time"]) - t).abs() < 1e-9)
            .unwrap_or_else(|| panic!("a row at {t} s"));
        let (a, b) = (&row["a"], &row["b"]);
        let theory = num(&a["theory"]);
        assert!((theory - 0.5 * 9.8 * 15f64.to_radians().tan() * t * t).abs() < 1e-12);
        let (ea, eb) = (num(&a["error_percent"]), num(&b["error_percent"]));
        println!(
            "{t:.1} {theory:.4} ALM {:.4} ({ea:.3} %) penalty {:.4} ({eb:.3} %)",
            num(&a["travel"]),
            num(&b["travel"])
        );
        assert!(
            ea <= *bound,
            "t = {t}: ALM error {ea} % above the paper's {bound} %"
        );
        assert!(ea < eb, "t = {t}: ALM must beat the penalty baseline");
    }
    // The comparison itself: the blocks part by what the penalty run gains.
    let largest = &r["largest_difference"];
    assert_eq!(largest["block"], "block");
    assert_eq!(num(&largest["time"]), 2.0);
    let last = rows.last().unwrap();
    let apart = num(&last["b"]["travel"]) - num(&last["a"]["travel"]);
    assert!((num(&largest["max_displacement_difference"]) - apart).abs() < 1e-3 * apart);
}

/// `--compare-set` changes B alone: A is the plain run, B the plain run of the scene with the
/// key changed in the file.
#[test]
fn compare_set_changes_only_b() {
    let out = tmp("set");
    let stable = scene("slope_stable.toml");
    let text = std::fs::read_to_string(&stable).unwrap();
    let stiff = out.join("stiff.toml");
    let changed = text.replace("initial_penalty = 2.0e8", "initial_penalty = 2.0e9");
    assert_ne!(changed, text);
    std::fs::write(&stiff, changed).unwrap();
    let args = ["--compare-set", "initial_penalty=2e9", "--duration", "0.5"];
    run_ok(&stable, &args, &out.join("cmp"));
    run_ok(&stable, &["--duration", "0.5"], &out.join("a"));
    run_ok(&stiff, &["--duration", "0.5"], &out.join("b"));
    same_rows(&out.join("cmp/A"), &out.join("a"));
    same_rows(&out.join("cmp/B"), &out.join("b"));
    let r = compare_json(&out.join("cmp"));
    assert_eq!(r["a"]["labels"], serde_json::json!(["initial_penalty=2e8"]));
    assert_eq!(r["b"]["labels"], serde_json::json!(["initial_penalty=2e9"]));
    assert_eq!(
        (&r["a"]["method"], &r["b"]["method"]),
        (&"alm".into(), &"alm".into())
    );

    // With --compare too: a penalty of 2e9 sinks the block a tenth as far.
    run_ok(
        &stable,
        &[
            "--compare",
            "penalty",
            "--compare-set",
            "initial_penalty=2e9",
        ],
        &out.join("both"),
    );
    let r = compare_json(&out.join("both"));
    assert_eq!(
        r["b"]["labels"],
        serde_json::json!(["method=penalty", "initial_penalty=2e9"])
    );
    for c in r["table1"]["b"]["contacts"].as_array().unwrap() {
        let (dn, theory) = (num(&c["penetration"]), num(&c["theory"]));
        assert!((dn - theory / 2e9).abs() < 0.01 * theory / 2e9, "{c}");
    }
}

/// A bad spec is one line naming the key, exit status 2, and nothing written.
#[test]
fn bad_specs_exit_2_with_one_line() {
    let out = tmp("bad");
    let cases: &[(&[&str], &str)] = &[
        (
            &["--compare", "lagrange"],
            "--compare: expected alm or penalty",
        ),
        (&["--compare-set", "bogus=1"], "unknown key 'bogus'"),
        (&["--compare-set", "eps1=abc"], "eps1: expected a number"),
        (
            &["--compare-set", "eps1=2"],
            "solver.contact.eps1 must lie in (0, 1)",
        ),
        (
            &["--compare-set", "beta=0"],
            "solver.contact.beta must lie in (0, 1)",
        ),
        (
            &["--compare-set", "max_alm_iterations=0"],
            "max_alm_iterations",
        ),
        (&["--compare-set", ""], "--compare-set: empty"),
        (&["--compare-set", "eps1"], "expected key=value"),
        (&["--compare-set", "eps1="], "eps1: no value"),
        (&["--compare-set", "eps1=0.1,"], "an empty entry"),
        (
            &["--compare-set", "method=fast"],
            "method: expected alm or penalty",
        ),
        (
            &["--compare", "alm", "--compare-set", "method=penalty"],
            "already set by --compare",
        ),
        (
            &["--compare", "penalty", "--compare-interval", "0"],
            "--compare-interval",
        ),
        (&["--compare-interval", "0.1"], "add --compare"),
    ];
    for (args, want) in cases {
        let dir = out.join("run");
        let o = run(&scene("slope_sliding.toml"), args, &dir);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
        assert!(
            err.starts_with("error: ") && err.contains(want),
            "{args:?}: {err}"
        );
        assert!(!dir.exists(), "{args:?}: nothing is written for bad input");
    }
    // --resume takes one run's checkpoint: it cannot start two.
    let o = bin()
        .args(["run", "--resume", "x.ckpt", "--compare", "penalty"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(String::from_utf8_lossy(&o.stderr).lines().count(), 1);
}

/// A block of 2 × 4 × 1 m on a slope of `theta`° falling toward azimuth `azimuth`° (0: +x),
/// with friction `phi`°, as a scene file.
fn slope_scene(theta: f64, phi: f64, azimuth: f64, mode: &str) -> String {
    let (t, az) = (theta.to_radians(), azimuth.to_radians());
    let turn = |p: [f64; 3]| {
        let (c, s) = (az.cos(), az.sin());
        format!(
            "[{:?}, {:?}, {:?}]",
            c * p[0] - s * p[1],
            s * p[0] + c * p[1],
            p[2]
        )
    };
    let h = 10.0 * t.tan();
    let wedge: Vec<String> = [
        [0.0, -5.0, 0.0],
        [10.0, -5.0, 0.0],
        [0.0, -5.0, h],
        [0.0, 5.0, 0.0],
        [10.0, 5.0, 0.0],
        [0.0, 5.0, h],
    ]
    .into_iter()
    .map(turn)
    .collect();
    let (down, up) = ([t.cos(), 0.0, -t.sin()], [t.sin(), 0.0, t.cos()]);
    let start = [2.0 * t.cos(), -2.0, h - 2.0 * t.sin()];
    let block: Vec<String> = (0..8)
        .map(|i| {
            let (a, b, c) = (
                2.0 * (i & 1) as f64,
                4.0 * ((i >> 1) & 1) as f64,
                ((i >> 2) & 1) as f64,
            );
            turn(std::array::from_fn(|k| {
                start[k] + a * down[k] + c * up[k] + if k == 1 { b } else { 0.0 }
            }))
        })
        .collect();
    format!(
        "name = \"slope {theta}/{phi}/{azimuth}\"\n[solver]\nmode = \"{mode}\"\nduration = 0.5\n\
         [joint]\nfriction_angle = {phi:?}\n\
         [materials.rock]\ndensity = 2750.0\nyoung_modulus = 2.0e10\npoisson_ratio = 0.25\n\
         [[blocks]]\nname = \"slope\"\nmaterial = \"rock\"\nfixed = true\nvertices = [{}]\n\
         [[blocks]]\nname = \"block\"\nmaterial = \"rock\"\nvertices = [{}]\n",
        wedge.join(", "),
        block.join(", ")
    )
}

/// Slopes of other angles, friction angles and directions get the closed form of their own
/// geometry: the block slides at Coulomb's rate, or stands on W cos θ and W sin θ.
#[test]
fn a_family_of_slopes_gets_its_own_closed_form() {
    let out = tmp("family");
    for (theta, phi, azimuth, mode) in [
        (20.0, 10.0, 0.0, "dynamic"),
        (40.0, 30.0, 135.0, "dynamic"),
        (35.0, 20.0, 270.0, "dynamic"),
        (25.0, 35.0, 60.0, "static"),
        (40.0, 45.0, 200.0, "dynamic"),
    ] {
        let file = out.join(format!("slope_{theta}_{phi}_{azimuth}.toml"));
        std::fs::write(&file, slope_scene(theta, phi, azimuth, mode)).unwrap();
        let dir = out.join(format!("run_{theta}_{phi}_{azimuth}"));
        run_ok(&file, &["--compare", "penalty"], &dir);
        let r = compare_json(&dir);
        let case = &r["closed_form"]["a"];
        assert_eq!(
            case, &r["closed_form"]["b"],
            "the same scene, the same closed form"
        );
        assert!((num(&case["theta_deg"]) - theta).abs() < 1e-9, "{case}");
        assert_eq!(num(&case["phi_deg"]), phi);
        let (t, f) = (theta.to_radians(), phi.to_radians());
        let az = azimuth.to_radians();
        if phi < theta {
            assert_eq!(case["motion"], "slides");
            let a = 9.8 * (t.sin() - t.cos() * f.tan());
            assert!((num(&case["acceleration"]) - a).abs() < 1e-9, "{case}");
            let want = [t.cos() * az.cos(), t.cos() * az.sin(), -t.sin()];
            let down = case["downslope"].as_array().unwrap();
            assert!(
                (0..3).all(|k| (num(&down[k]) - want[k]).abs() < 1e-9),
                "{case}"
            );
            let last = r["table2"].as_array().unwrap().last().unwrap().clone();
            assert_eq!(num(&last["time"]), 0.5);
            let (err, penalty) = (
                num(&last["a"]["error_percent"]),
                num(&last["b"]["error_percent"]),
            );
            println!(
                "{theta}/{phi}/{azimuth}: a = {a:.4} m/s², travel error at 0.5 s: ALM {err:.4} %, \
                 penalty {penalty:.3} %"
            );
            // The paper's DDA-3a errors at 0.4–0.6 s are 0.13–0.20 %.
            assert!(
                err < 0.2,
                "{theta}/{phi}: ALM {err} % from Coulomb's travel"
            );
            assert!(
                err < penalty,
                "{theta}/{phi}: ALM must beat the penalty baseline"
            );
        } else {
            assert_eq!(case["motion"], "stands");
            let table = &r["table1"]["a"];
            let w = num(&case["weight"]);
            assert!((num(&table["normal_theory"]) - w * t.cos()).abs() < 1e-6 * w);
            assert!((num(&table["shear_theory"]) - w * t.sin()).abs() < 1e-6 * w);
            let worst = table["contacts"]
                .as_array()
                .unwrap()
                .iter()
                .map(|c| num(&c["error_percent"]))
                .fold(0.0, f64::max);
            println!(
                "{theta}/{phi}/{azimuth}: stands; resultant error {:.2e} %, corners within {worst:.4} %",
                num(&table["normal_error_percent"])
            );
            // At 0.5 s a block in dynamic mode still rings a little after gravity came on.
            assert!(num(&table["normal_error_percent"]) < 0.1, "{table}");
            assert!(worst < 0.5, "{table}");
        }
    }
}

/// A scene without a closed form says why, and still gets its comparison.
#[test]
fn other_scenes_are_compared_without_a_table() {
    let out = tmp("rockfall");
    let rockfall = scene("rock_column_rockfall.toml");
    run_ok(
        &rockfall,
        &["--compare", "penalty", "--duration", "0.1"],
        &out,
    );
    let r = compare_json(&out);
    assert!(r["closed_form"]["a"].is_null());
    assert!(
        r["closed_form"]["a_none"]
            .as_str()
            .unwrap()
            .contains("blocks")
    );
    assert!(r.get("table1").is_none() && r.get("table2").is_none());
    let times = r["times"].as_array().unwrap();
    assert_eq!(times.len(), 11);
    assert_eq!(num(&times[0]["max_displacement_difference"]), 0.0);
    assert_eq!(num(&times[10]["time"]), 0.1);
    assert!(times[10]["block"].is_string());
}
