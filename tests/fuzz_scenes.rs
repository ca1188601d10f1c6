//! Fuzzing `dda3d run` (#13, "Tests and proof"): a few thousand scenes mutated from the shipped
//! ones (extreme numbers, resized arrays, wrong types, missing or unknown keys, blocks copied,
//! moved, scaled, fixed, degenerate shapes, settings beyond their ranges, broken text, odd command
//! lines), each run in its own process under a hard timeout. A case must end in a documented way:
//! exit 0 with `summary.json` "completed" and finite `summary.json`, `blocks.csv`, `contacts.csv`;
//! exit 1 (diverged) with `summary.json` "diverged" and finite outputs if the folder was made;
//! exit 2 (bad input) or [`IO_STATUS`]; one line `error: …` on stderr for any non-zero status;
//! never a panic, a signal or a timeout. Input a mutation surely makes invalid (NaN, a wrong
//! type, an unknown key, a value out of its range, ...) must be rejected with status 2.
//!
//! Case `i` depends only on the seed and `i`. `DDA3D_FUZZ_CASES`, `DDA3D_FUZZ_SEED`,
//! `DDA3D_FUZZ_TIMEOUT` (s) and `DDA3D_FUZZ_JOBS` override the defaults. Failing cases are
//! printed and written to `target/fuzz-failures/`, each as `case-N.toml` and `case-N.txt`.
#![cfg(unix)]

use std::collections::BTreeMap;
use std::fs;
use std::os::unix::process::ExitStatusExt;
use std::path::Path;
use std::process::{Command, Stdio};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use toml::{Table, Value};

/// The exit status of an I/O error (the output cannot be written). It is being defined on another
/// branch; until it lands both candidates are accepted. Keep this in step with the CLI.
const IO_STATUS: &[i32] = &[74];
const DIVERGED: i32 = 1; // the run diverged
const BAD_INPUT: i32 = 2; // the scene or the command line

const DEFAULT_CASES: usize = 4000;
const DEFAULT_SEED: u64 = 0xdda3_d013;
/// Seconds a run may take: a case simulates ≤ 0.3 s of ≤ 100 blocks, well under 1 s of work.
const DEFAULT_TIMEOUT_S: f64 = 10.0;

const NAMES: [&str; 3] = ["rockfall", "sliding", "stable"];
const SCENES: [&str; 3] = [
    include_str!("../scenes/rock_column_rockfall.toml"),
    include_str!("../scenes/slope_sliding.toml"),
    include_str!("../scenes/slope_stable.toml"),
];

/// Replacements for any number of a scene.
const EXTREMES: &str = "
: 0 | -0.0 | -1 | 1e-300 | 5e-324 | 1e-15 | -1e-9 | 1e300 | 1e308 | -1e308 | 9223372036854775807
: -9223372036854775808 | nan! | inf! | -inf! | \"NaN\"! | \"1.0\"!";

/// Scene-wide settings at and beyond the ends of their documented ranges.
const SETTINGS: &str = "
name: \"\" | \"\\n\" | \"../../../tmp/escape\" | \"..\" | \"/\" | LONG
solver.method: \"penalty\" | \"foo\"!; solver.mode: \"static\" | \"quasi\"!
solver.spectral_radius: 0.3333333333333333 | 1.0 | 0.33! | 2.0!; solver.duration: 0.0! | 1e308
solver.max_time_step: 1e-15 | 1e-9 | 1e3 | 1e300 | 0.0! | -0.01!
solver.max_displacement_ratio: 1e-12 | 1e3 | 1e300 | 0.0!; solver.rotate_stress: true
solver.gravity: [0.0, 0.0, 0.0] | [0.0, 0.0, -1e10] | [0.0, 0.0, 9.8] | [1e308, 1e308, 1e308]
solver.gravity: [0.0, 0.0, nan]! | [0.0, -9.8]! | [0.0, 0.0, -9.8, 0.0]!
solver.fixed_spring_factor: 1e-300! | 1e300! | 0.0! | 1.0 | 1e6; solver.max_displacement_overshoot: 2.0 | 1e300! | 0.5!
solver.initial_equilibrium: true; solver.equilibrium_tolerance: 1e-300 | 0.0! | 1.0!
solver.equilibrium_max_steps: 1 | 0! | 1000001! | 9223372036854775807!
solver.contact.initial_penalty: 1e-300! | 1e300! | 1e30! | 0.0!; solver.contact.gamma: 1e-300! | 1e300!
solver.contact.alpha: 1.0000001 | 1e3 | 1e300! | 1.0!; solver.contact.beta: 1e-300 | 1.0!
solver.contact.eps1: 1e-300 | 0.0!; solver.contact.eps2: 1e300; solver.contact.warm_start: false
solver.contact.shear_penalty_ratio: 1e300! | 1e-300! | 100.0; solver.contact.close_threshold: 1e300
solver.contact.max_alm_iterations: 1 | 1000000000 | 0! | 4294967296!
solver.contact.max_open_close_iterations: 1 | 0!; solver.contact.open_threshold: -1.0!
joint.friction_angle: 0.0 | 89.999999 | 90.0! | -1.0!; joint.cohesion: 1e9 | 1e308! | -1.0!
materials.rock.density: -2750.0! | 0.0! | 1e-300! | 1e300! | 1e-9! | 0.01 | 2e5
materials.rock.young_modulus: -2e10! | 0.0! | 1e-300! | 1e300! | 1.0! | 100.0 | 1e13
materials.rock.poisson_ratio: 0.5! | 1.0! | -1.0! | 0.4999999 | -0.9999999 | 0.0 | nan!";

/// Settings of one block (a shape of its own kind replaces it, another kind is a second shape).
/// `soft` and `dense` are materials the mutation adds ([`MATERIALS`]).
const BLOCK_SETTINGS: &str = "
velocity: [1e6, 0.0, 0.0] | [0.0, 0.0, -1e3] | [1e300, 0.0, 0.0]
angular_velocity: [0.0, 0.0, 1e3] | [1e6, 1e6, 1e6] | [0.0, 0.0, 1e-300]
loads: [{ point = [0.0, 0.0, 0.0], force = [0.0, 0.0, -1e12] }]
loads: [{ point = [1e300, 0.0, 0.0], force = [1.0, 0.0, 0.0] }]
loads: [{ point = [0.0, 0.0, 0.0], force = [1e308, 1e308, 0.0] }]
fixed: true | false; box: { size = [1, 1, 1], center = [0, 0, 100] }
dodecahedron: { edge = 0.5, center = [0, 0, 100] }
prism: { base = [[0, 0, 100], [1, 0, 100], [0, 1, 100]], extrude = [0, 0, 1] }
material: \"soft\" | \"dense\" | \"no\\nsuch\"! | \"\"!
name: \"\" | \"a\\nb\" | \"Ω ≈ ç √\" | \"\\u0000\" | \"../../x\" | LONG";

const MATERIALS: &str = "{ soft = { density = 1.0, young_modulus = 1e3, poisson_ratio = 0.0 }, \
    dense = { density = 2e5, young_modulus = 1e13, poisson_ratio = 0.49 } }";

/// Command-line values, as typed; `+` adds a flag.
const CLI: &str = "
--duration: -1! | 0! | -0! | nan! | inf! | abc! | 1e-300 | 1e308
--method: foo! | penalty
--mode: foo! | static; +: --initial-equilibrium | --bogus!
--spectral-radius: 2! | 0.3! | nan! | -1! | 1 | 0.3333333333333333";

/// Keys that every table they appear in needs.
const REQUIRED: &str = "material box vertices dodecahedron density young_modulus poisson_ratio \
    size center edge blocks materials rock";

/// Raw-text and shape mutations, by number; see [`mutate_raw`] and [`reshape`].
const RAW: &str = ": cut at the byte | with a bit flipped | with a line twice | with a line deleted \
    | with invalid UTF-8! | with a control byte | replaced by a comment! | with CRLF line ends \
    | with a byte-order mark | twice!";
const SHAPES: &str = ": eight equal vertices! | collinear vertices! | coplanar vertices! \
    | a tetrahedron of edge 1e-12 or 1e-300 | 10^4 vertices in a cube | 300 on a sphere";

/// The `(key, value, must reject)` of a table above: `key: value | value | …`, a key a line (or
/// after `;`), values in TOML (in `CLI`, as typed); `!` marks a value that makes any scene
/// invalid: the case must then exit with status 2.
fn options(table: &'static str) -> Vec<(&'static str, &'static str, bool)> {
    let mut out = Vec::new();
    for entry in table.split(['\n', ';']).filter(|l| !l.trim().is_empty()) {
        let (key, values) = entry.trim().split_once(": ").expect("key: values");
        for v in values.split(" | ") {
            let (v, bad) = v.strip_suffix('!').map_or((v, false), |v| (v, true));
            out.push((key, v, bad));
        }
    }
    out
}

/// A TOML literal as a value: `lit("[0, 0, nan]")`; `LONG` is a name of 10^4 characters.
fn lit(s: &str) -> Value {
    if s == "LONG" {
        return Value::String("x".repeat(10_000));
    }
    let t: Table = toml::from_str(&format!("v = {s}")).expect("a TOML literal");
    t["v"].clone()
}

/// SplitMix64: small, seedable, the same on every platform.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
    fn pick<'a, T>(&mut self, xs: &'a [T]) -> &'a T {
        &xs[self.below(xs.len())]
    }
}

fn must(reject: bool) -> Vec<i32> {
    vec![BAD_INPUT; usize::from(reject)]
}

/// One mutated scene and its command line, which runs in the case's own folder: the scene is
/// `scene.toml` there, the output `out`.
#[derive(Clone, Debug, PartialEq)]
struct Case {
    index: usize,
    what: String,
    text: Vec<u8>,
    args: Vec<String>,
    expect: Vec<i32>,
}

fn generate(seed: u64, index: usize) -> Case {
    let mut rng = Rng(seed ^ (index as u64 + 1).wrapping_mul(0xA076_1D64_78BD_642F));
    let scene = rng.below(3);
    let duration = *rng.pick(&["0.01", "0.02", "0.03", "0.05", "0.1", "0.3"]);
    let args = format!("run scene.toml --out out --quiet --duration {duration}");
    let mut args: Vec<String> = args.split(' ').map(String::from).collect();
    let (mut text, mut what, mut expect) =
        (SCENES[scene].as_bytes().to_vec(), Vec::new(), Vec::new());
    let roll = rng.unit();
    if roll < 0.06 {
        let (w, e) = mutate_cli(&mut rng, &mut args);
        (what, expect) = (vec![w], e);
    } else if roll < 0.92 {
        let mut root = Value::Table(toml::from_str(SCENES[scene]).expect("shipped scenes parse"));
        let n = *rng.pick(&[1, 1, 1, 1, 1, 2, 2, 3]);
        for _ in 0..n {
            // A mutation with nothing to work on (no numbers left, no blocks) sets a setting.
            let choice = rng.below(16);
            let edit = tree_edit(&mut rng, &mut root, choice);
            let (w, bad) = edit.unwrap_or_else(|| tree_edit(&mut rng, &mut root, 8).unwrap());
            what.push(w);
            // A later mutation may undo an earlier one's harm.
            expect = must(bad && n == 1);
        }
        if rng.unit() < 0.1 {
            // The default folder, `out/<slug of the name>`.
            args.drain(2..4);
            what.push("no --out".into());
        }
        text = toml::to_string(&root).expect("a TOML tree").into_bytes();
    }
    if roll >= 0.84 {
        // On the shipped text or a mutated tree's: a rejecting raw mutation (invalid UTF-8, ...)
        // rejects whatever the tree was, any other may undo its harm.
        let (w, e) = mutate_raw(&mut rng, &mut text);
        what.push(w);
        expect = e;
    }
    let what = format!("[{}] {}", NAMES[scene], what.join("; "));
    Case {
        index,
        what,
        text,
        args,
        expect,
    }
}

fn mutate_cli(rng: &mut Rng, args: &mut Vec<String>) -> (String, Vec<i32>) {
    match rng.below(6) {
        0..=3 => {
            let (flag, v, bad) = *rng.pick(&options(CLI));
            match args.iter().position(|a| a == flag) {
                _ if flag == "+" => args.push(v.into()),
                Some(i) => args[i + 1] = v.into(),
                None => args.extend([flag.to_string(), v.to_string()]),
            }
            (format!("{flag} {v}"), must(bad))
        }
        4 => {
            args[1] = rng.pick(&["missing.toml", "."]).to_string();
            let codes = [&[BAD_INPUT], IO_STATUS].concat();
            (format!("scene path {}", args[1]), codes)
        }
        _ => {
            // Where no folder can be made: an I/O error.
            args[3] = rng.pick(&["scene.toml", "scene.toml/out"]).to_string();
            (format!("--out {}", args[3]), IO_STATUS.to_vec())
        }
    }
}

fn mutate_raw(rng: &mut Rng, text: &mut Vec<u8>) -> (String, Vec<i32>) {
    let lines: Vec<&[u8]> = text.split(|&b| b == b'\n').collect();
    let (l, at) = (rng.below(lines.len()), rng.below(text.len() + 1));
    let bit = rng.below(8);
    let bad = *rng.pick(&[&b"\xff"[..], b"\xc3\x28", b"\xed\xa0\x80", b"\xf8"]);
    let control = *rng.pick(&[&[0u8][..], &[7], b"\r", &[0x1b], &[0x7f]]);
    let flip = |(i, &b): (usize, &u8)| if i == at { b ^ (1 << bit) } else { b };
    let choice = rng.below(10);
    let new = match choice {
        0 => text[..at].to_vec(),
        1 => text.iter().enumerate().map(flip).collect(),
        2 => [&lines[..=l], &lines[l..]].concat().join(&b'\n'),
        3 => [&lines[..l], &lines[l + 1..]].concat().join(&b'\n'),
        4 => [&text[..at], bad, &text[at..]].concat(),
        5 => [&text[..at], control, &text[at..]].concat(),
        6 => b"# only a comment\n".to_vec(),
        7 => lines.join(&b"\r\n"[..]),
        8 => [&b"\xef\xbb\xbf"[..], &text[..]].concat(),
        _ => [&text[..], b"\n", &text[..]].concat(),
    };
    let (_, name, reject) = options(RAW)[choice];
    let what = format!("text {name} (line {l}, byte {at}, bit {bit}, {bad:?}, {control:?})");
    *text = new;
    (what, must(reject))
}

/// What to look for: a value, given its path.
type Keep<'a> = &'a dyn Fn(&[String], &Value) -> bool;

/// Every path below `v` (table keys and array indices) whose value satisfies `keep`.
fn find(v: &Value, keep: Keep) -> Vec<Vec<String>> {
    let children: Vec<(String, &Value)> = match v {
        Value::Table(t) => t.iter().map(|(k, c)| (k.clone(), c)).collect(),
        Value::Array(a) => (0..a.len()).map(|i| (i.to_string(), &a[i])).collect(),
        _ => Vec::new(),
    };
    let mut out = Vec::new();
    for (key, c) in children {
        let prefix = [key];
        let inner = |p: &[String], v: &Value| keep(&[&prefix[..], p].concat(), v);
        if keep(&prefix, c) {
            out.push(prefix.to_vec());
        }
        for p in find(c, &inner) {
            out.push([&prefix[..], &p].concat());
        }
    }
    out
}

fn at<'a>(root: &'a mut Value, path: &[String]) -> &'a mut Value {
    path.iter().fold(root, |v, k| match v {
        Value::Table(t) => t.get_mut(k).expect("a path from find"),
        Value::Array(a) => &mut a[k.parse::<usize>().expect("an index")],
        _ => unreachable!("a path from find"),
    })
}

/// Whether a path passes through one of `keys`.
fn under(path: &[String], keys: &[&str]) -> bool {
    path.iter().any(|k| keys.contains(&k.as_str()))
}

fn is_number(v: &Value) -> bool {
    matches!(v, Value::Integer(_) | Value::Float(_))
}

fn is_triple(v: &Value) -> bool {
    matches!(v.as_array(), Some(a) if a.len() == 3 && a.iter().all(is_number))
}

fn num(v: &Value) -> f64 {
    v.as_float()
        .or(v.as_integer().map(|i| i as f64))
        .unwrap_or(f64::NAN)
}

fn triple(v: &Value) -> [f64; 3] {
    [0, 1, 2].map(|i| num(&v[i]))
}

/// Sets `a.b.c`, making the tables on the way.
fn set_dotted(root: &mut Value, dotted: &str, v: Value) {
    let keys: Vec<&str> = dotted.split('.').collect();
    let mut t = root.as_table_mut().expect("the root is a table");
    for k in &keys[..keys.len() - 1] {
        let e = t.entry(*k).or_insert_with(|| Value::Table(Table::new()));
        if !e.is_table() {
            *e = Value::Table(Table::new());
        }
        t = e.as_table_mut().expect("made a table");
    }
    t.insert(keys[keys.len() - 1].to_string(), v);
}

/// A random path below `root` whose value satisfies `keep`.
fn pick_path(rng: &mut Rng, root: &Value, keep: Keep) -> Option<Vec<String>> {
    let paths = find(root, keep);
    (!paths.is_empty()).then(|| rng.pick(&paths).clone())
}

fn tree_edit(rng: &mut Rng, root: &mut Value, choice: usize) -> Option<(String, bool)> {
    Some(match choice {
        0..=3 => {
            let path = pick_path(rng, root, &|_, v| is_number(v))?;
            let (_, s, bad) = *rng.pick(&options(EXTREMES));
            *at(root, &path) = lit(s);
            (format!("{} = {s}", path.join(".")), bad)
        }
        4 => {
            let path = pick_path(rng, root, &|_, v| v.is_array())?;
            let v = at(root, &path);
            // Every array of three numbers of a scene is a fixed-size vector.
            let bad = is_triple(v);
            let a = v.as_array_mut()?;
            let n = *rng.pick(&[a.len().saturating_sub(1), a.len() + 1, 0, 1, 10_000]);
            a.resize(n, a.first().cloned().unwrap_or(Value::Float(1.0)));
            (format!("{} resized to {n}", path.join(".")), bad)
        }
        5 => change_type(rng, root)?,
        6 => {
            let path = pick_path(rng, root, &|_, _| true)?;
            let (parent, key) = (at(root, &path[..path.len() - 1]), &path[path.len() - 1]);
            let bad = is_triple(parent) || REQUIRED.split(' ').any(|r| r == key);
            let removed = match parent {
                Value::Table(t) => t.remove(key),
                Value::Array(a) => Some(a.remove(key.parse().ok()?)),
                _ => None,
            };
            removed?;
            (format!("{} deleted", path.join(".")), bad)
        }
        7 => {
            let path = match rng.unit() < 0.2 {
                true => Vec::new(),
                false => pick_path(rng, root, &|_, v| v.is_table())?,
            };
            let table = at(root, &path).as_table_mut()?;
            table.insert("fuzz".into(), lit("1"));
            (format!("unknown key in [{}]", path.join(".")), true)
        }
        8..=10 => {
            let (key, v, bad) = *rng.pick(&options(SETTINGS));
            set_dotted(root, key, lit(v));
            (format!("{key} = {v:.40}"), bad)
        }
        _ => edit_block(rng, root)?,
    })
}

fn change_type(rng: &mut Rng, root: &mut Value) -> Option<(String, bool)> {
    let path = pick_path(rng, root, &|_, _| true)?;
    let v = at(root, &path);
    let (new, bad) = match v {
        Value::Integer(i) if rng.unit() < 0.3 => (Value::Float(*i as f64), false),
        Value::Float(f) if rng.unit() < 0.3 && f.abs() < 1e15 => (Value::Integer(*f as i64), false),
        Value::Float(_) | Value::Integer(_) => {
            (lit(rng.pick::<&str>(&["\"1.5\"", "{}", "[1]"])), true)
        }
        Value::String(_) => (lit(rng.pick::<&str>(&["1", "[\"a\"]", "false"])), true),
        Value::Boolean(_) => (lit(rng.pick::<&str>(&["\"true\"", "1"])), true),
        Value::Array(_) => (lit(rng.pick::<&str>(&["{ x = 1 }", "\"[]\"", "3"])), true),
        Value::Table(_) => (lit(rng.pick::<&str>(&["[]", "\"table\"", "[{}]"])), true),
        Value::Datetime(_) => (lit("1"), true),
    };
    let what = format!("{} = {new} (was {})", path.join("."), v.type_str());
    *v = new;
    Some((what, bad))
}

/// Maps a block's points (vertices, centre, load points) by `f`, its lengths (box size,
/// dodecahedron edge) by `× len`.
fn map_block(b: &mut Value, f: &dyn Fn([f64; 3]) -> [f64; 3], len: f64) {
    let points = find(b, &|p, v| {
        under(p, &["vertices", "center", "point"]) && is_triple(v)
    });
    for path in points {
        let v = at(b, &path);
        *v = Value::Array(f(triple(v)).map(Value::Float).into());
    }
    for path in find(b, &|p, v| under(p, &["size", "edge"]) && is_number(v)) {
        let v = at(b, &path);
        *v = Value::Float(num(v) * len);
    }
}

/// The centre of a block's shape: the box's or dodecahedron's, or the mean of its vertices.
fn centre(b: &mut Value) -> [f64; 3] {
    let points = find(b, &|p, v| under(p, &["vertices", "center"]) && is_triple(v));
    let points: Vec<[f64; 3]> = points.iter().map(|p| triple(at(b, p))).collect();
    [0, 1, 2].map(|k| points.iter().map(|p| p[k]).sum::<f64>() / points.len().max(1) as f64)
}

/// Moves, scales, copies, fixes or frees a block, sets its motion, loads, material or name, or
/// gives it a degenerate or oversized shape.
fn edit_block(rng: &mut Rng, root: &mut Value) -> Option<(String, bool)> {
    let bs = root.get_mut("blocks")?.as_array_mut()?;
    let k = rng.below(bs.len());
    let c = centre(bs.get_mut(k)?);
    let (what, bad) = match rng.below(6) {
        0 => {
            let mut d = [0.0; 3];
            d[rng.below(3)] = *rng.pick(&[1e3, 1e5, -1e5, 1e15, 1e100, 1e300, 1e-7]);
            map_block(&mut bs[k], &|p| [0, 1, 2].map(|i| p[i] + d[i]), 1.0);
            (format!("moved by {d:?}"), false)
        }
        1 => {
            let f: f64 = *rng.pick(&[1e-9, 1e-6, 1e-3, 0.5, 2.0, 1e3, 1e6]);
            let scale = |p: [f64; 3]| [0, 1, 2].map(|i| c[i] + (p[i] - c[i]) * f);
            map_block(&mut bs[k], &scale, f);
            (format!("scaled by {f:e}"), false)
        }
        2 => {
            let n = *rng.pick(&[1, 1, 1, 1, 20, 100]);
            let dx = [*rng.pick(&[0.0, 0.0, 1e3, 1e6]), 50.0][usize::from(n > 1)];
            let same_name = dx == 0.0 && rng.unit() < 0.5;
            for i in 1..=n {
                let mut copy = bs[k].clone();
                if !same_name {
                    copy.as_table_mut()?
                        .insert("name".into(), format!("copy {i}").into());
                }
                map_block(&mut copy, &|p| [p[0] + dx * i as f64, p[1], p[2]], 1.0);
                bs.push(copy);
            }
            // In place, a copy overlaps its original.
            let what = format!("copied {n}× at x + {dx}·i (same name: {same_name})");
            (what, dx == 0.0)
        }
        3 | 4 => {
            let (key, v, bad) = *rng.pick(&options(BLOCK_SETTINGS));
            bs[k].as_table_mut()?.insert(key.into(), lit(v));
            if key == "material" {
                let m = lit(MATERIALS);
                set_dotted(root, "materials.soft", m["soft"].clone());
                set_dotted(root, "materials.dense", m["dense"].clone());
            }
            (format!("{key} = {v:.40}"), bad)
        }
        _ => reshape(rng, bs[k].as_table_mut()?, c),
    };
    Some((format!("blocks[{k}] {what}"), bad))
}

/// Degenerate and oversized shapes around `c`.
fn reshape(rng: &mut Rng, t: &mut Table, c: [f64; 3]) -> (String, bool) {
    let (e, choice) = (*rng.pick(&[1e-12, 1e-300]), rng.below(6));
    let mut cube = || [0; 3].map(|_| rng.unit() - 0.5);
    let norm = |p: [f64; 3]| p.map(|x| 0.5 * x / p.iter().map(|x| x * x).sum::<f64>().sqrt());
    let points: Vec<[f64; 3]> = match choice {
        0 => vec![[0.0; 3]; 8],
        1 => (0..6).map(|i| [i as f64, 0.0, 0.0]).collect(),
        2 => (0..6).map(|i| [i as f64, (i * i) as f64, 0.0]).collect(),
        3 => vec![[0.0; 3], [e, 0.0, 0.0], [0.0, e, 0.0], [0.0, 0.0, e]],
        4 => (0..10_000).map(|_| cube()).collect(),
        _ => (0..300).map(|_| norm(cube())).collect(),
    };
    t.retain(|k, _| !["box", "dodecahedron", "prism"].contains(&k));
    let vertex = |p: &[f64; 3]| Value::Array([0, 1, 2].map(|i| Value::Float(c[i] + p[i])).into());
    t.insert(
        "vertices".into(),
        Value::Array(points.iter().map(vertex).collect()),
    );
    let (_, name, reject) = options(SHAPES)[choice];
    (name.to_string(), reject)
}

/// How a run ended: `ended` is "exit N", "signal N" or "timeout".
struct Run {
    ended: String,
    code: Option<i32>,
    stderr: String,
}

/// Runs a case in `dir`, its working folder.
fn execute(case: &Case, dir: &Path, timeout: Duration) -> Run {
    fs::create_dir_all(dir).expect("case folder");
    fs::write(dir.join("scene.toml"), &case.text).expect("scene file");
    let err = dir.join("stderr.txt");
    let mut child = Command::new(env!("CARGO_BIN_EXE_dda3d"))
        .args(&case.args)
        .current_dir(dir)
        .env_clear()
        .stdout(Stdio::null())
        .stderr(fs::File::create(&err).expect("stderr file"))
        .spawn()
        .expect("start dda3d");
    let start = Instant::now();
    let status = loop {
        match child.try_wait().expect("wait for dda3d") {
            Some(status) => break Some(status),
            None if start.elapsed() > timeout => {
                let _ = child.kill().and_then(|()| child.wait());
                break None;
            }
            None => std::thread::sleep(Duration::from_millis(5)),
        }
    };
    let code = status.and_then(|s| s.code());
    let ended = match (status.and_then(|s| s.signal()), code) {
        (_, Some(c)) => format!("exit {c}"),
        (Some(signal), _) => format!("signal {signal}"),
        _ => "timeout".into(),
    };
    let stderr = String::from_utf8_lossy(&fs::read(&err).unwrap_or_default()).into();
    Run {
        ended,
        code,
        stderr,
    }
}

/// A failure: its kind and the details.
type Verdict = Result<(), (&'static str, String)>;

/// A non-zero status's stderr: one non-empty line, `error: …`, after any warnings the run gave
/// on its way (`FILE: warning: …`, one line each: an equilibrium stage that did not converge,
/// then a load of 10³⁰⁰ N made the first step's solution infinite; seed 777001, case 5457).
fn one_line(stderr: &str) -> Verdict {
    let s = stderr.strip_suffix('\n').unwrap_or(stderr);
    let s = match s.rsplit_once('\n') {
        Some((warnings, last)) if warnings.split('\n').all(|l| l.contains(": warning: ")) => last,
        _ => s,
    };
    match s.split('\n').count() {
        _ if s.is_empty() => Err(("no error message", String::new())),
        1 if s.starts_with("error:") => Ok(()),
        1 => Err(("stderr not `error: …`", s.chars().take(100).collect())),
        n => Err(("stderr not one line", format!("{n} lines"))),
    }
}

/// A run's outputs: `summary.json` with this `status` and no null (serde_json's NaN or
/// infinity); CSV files whose number columns are finite.
fn check_outputs(out: &Path, status: &str) -> Verdict {
    let summary = fs::read_to_string(out.join("summary.json")).unwrap_or_default();
    let json: serde_json::Value =
        serde_json::from_str(&summary).map_err(|e| ("bad summary.json", e.to_string()))?;
    if json["status"] != status {
        return Err(("wrong summary status", json["status"].to_string()));
    }
    let null = |l: &str| l.trim().trim_end_matches(',') == "null" || l.contains(": null");
    if let Some(l) = summary.lines().find(|l| null(l)) {
        return Err(("non-finite output", format!("summary.json: {}", l.trim())));
    }
    let names = ["block", "block_i", "block_j", "mode", "state", "joint"];
    for file in ["blocks.csv", "contacts.csv"] {
        let csv_err = |e: csv::Error| ("bad csv", format!("{file}: {e}"));
        let mut rd = csv::Reader::from_path(out.join(file)).map_err(csv_err)?;
        let head = rd.headers().map_err(csv_err)?.clone();
        for (row, record) in rd.records().enumerate() {
            let record = record.map_err(csv_err)?;
            for (col, v) in head.iter().zip(&record) {
                if !names.contains(&col) && !v.parse::<f64>().is_ok_and(f64::is_finite) {
                    let at = format!("{file} row {} {col} = {v:?}", row + 1);
                    return Err(("non-finite output", at));
                }
            }
        }
    }
    Ok(())
}

fn judge(case: &Case, run: &Run, dir: &Path) -> Verdict {
    let Some(code) = run.code else {
        let kind = ["signal", "timeout"][usize::from(run.ended == "timeout")];
        return Err((kind, run.ended.clone()));
    };
    if code == 101 || run.stderr.contains("panicked") || run.stderr.contains("RUST_BACKTRACE") {
        let line = run.stderr.lines().find(|l| l.contains("panicked"));
        return Err(("panic", line.unwrap_or("").chars().take(200).collect()));
    }
    if !case.expect.is_empty() && !case.expect.contains(&code) {
        let kind = ["wrong exit status", "invalid input accepted"][usize::from(code == 0)];
        return Err((kind, format!("exit {code}, expected {:?}", case.expect)));
    }
    // The output folder: `--out out`, or the default `out/<slug>`, both in the case's folder.
    let mut out = dir.join("out");
    if !case.args.iter().any(|a| a == "--out") {
        let subs = fs::read_dir(&out).into_iter().flatten().flatten();
        out = subs.map(|e| e.path()).find(|p| p.is_dir()).unwrap_or(out);
    }
    let out = Some(out).filter(|o| o.is_dir());
    match code {
        0 => check_outputs(&out.ok_or(("missing output", String::new()))?, "completed"),
        DIVERGED => {
            one_line(&run.stderr).and(out.map_or(Ok(()), |o| check_outputs(&o, "diverged")))
        }
        c if c == BAD_INPUT || IO_STATUS.contains(&c) => one_line(&run.stderr),
        _ => Err(("unexpected exit status", format!("exit {code}"))),
    }
}

fn env_or<T: std::str::FromStr>(key: &str, default: T) -> T {
    let parse = |v: String| v.trim().parse().ok().expect(key);
    std::env::var(key).map_or(default, parse)
}

/// Writes a failing case to `dir` and returns its line for the report.
fn record(case: &Case, run: &Run, (kind, detail): (&str, String), dir: &Path) -> String {
    let (i, first) = (case.index, run.stderr.lines().next().unwrap_or(""));
    let line = format!(
        "case {i} {:.300}: {kind}: {detail} ({}; stderr: \"{first:.160}\")",
        case.what, run.ended
    );
    let _ = fs::create_dir_all(dir);
    let _ = fs::write(dir.join(format!("case-{i}.toml")), &case.text);
    let (args, stderr) = (case.args.join(" "), &run.stderr);
    let note = format!("{line}\n\ndda3d {args}\n(scene.toml: case-{i}.toml)\n\n{stderr:.4000}\n");
    let _ = fs::write(dir.join(format!("case-{i}.txt")), note);
    line
}

/// The campaign: see the file's doc.
#[test]
fn mutated_scenes_end_in_a_documented_way() {
    let n = env_or("DDA3D_FUZZ_CASES", DEFAULT_CASES);
    let seed = env_or("DDA3D_FUZZ_SEED", DEFAULT_SEED);
    let timeout = Duration::from_secs_f64(env_or("DDA3D_FUZZ_TIMEOUT", DEFAULT_TIMEOUT_S));
    let cores = std::thread::available_parallelism().map_or(2, |c| c.get());
    let jobs = env_or("DDA3D_FUZZ_JOBS", cores.clamp(2, 4));
    let cases: Vec<Case> = (0..n).map(|i| generate(seed, i)).collect();
    let target = Path::new(env!("CARGO_TARGET_TMPDIR"));
    let work = target.join(format!("fuzz-scenes-{}", std::process::id()));
    let failed_dir = target.parent().unwrap_or(target).join("fuzz-failures");
    let _ = fs::remove_dir_all(&failed_dir);
    let (start, next) = (Instant::now(), AtomicUsize::new(0));
    let (failures, tally) = (Mutex::new(Vec::new()), Mutex::new(BTreeMap::new()));
    std::thread::scope(|s| {
        for _ in 0..jobs {
            s.spawn(|| {
                while let Some(case) = cases.get(next.fetch_add(1, Ordering::Relaxed)) {
                    let dir = work.join(format!("case-{}", case.index));
                    let run = execute(case, &dir, timeout);
                    *tally.lock().unwrap().entry(run.ended.clone()).or_insert(0) += 1;
                    if let Err(f) = judge(case, &run, &dir) {
                        let line = record(case, &run, (f.0, f.1), &failed_dir);
                        failures.lock().unwrap().push((case.index, f.0, line));
                    }
                    let _ = fs::remove_dir_all(&dir);
                }
            });
        }
    });
    let _ = fs::remove_dir_all(&work);
    let mut failures = failures.into_inner().unwrap();
    failures.sort();
    let mut kinds = BTreeMap::<&str, usize>::new();
    for (_, kind, line) in &failures {
        println!("{line}");
        *kinds.entry(kind).or_default() += 1;
    }
    let (seconds, tally) = (start.elapsed().as_secs_f64(), tally.into_inner().unwrap());
    println!("{n} cases (seed {seed:#x}, {jobs} at a time) in {seconds:.0} s: {tally:?}");
    let shown = failed_dir.display();
    assert!(failures.is_empty(), "{kinds:?}: see above and {shown}");
}

#[test]
fn the_same_seed_gives_the_same_cases() {
    let cases = |seed| (0..200).map(|i| generate(seed, i)).collect::<Vec<_>>();
    assert_eq!(cases(7), cases(7));
    assert_ne!(cases(7), cases(8));
}
