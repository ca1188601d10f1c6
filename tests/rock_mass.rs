//! Rock masses cut from joint sets (issue #14): the blocks a scene's `[[rock_masses]]` load to —
//! counts, volumes, conforming joint faces, no overlap — and `dda3d cut`'s file loading to the
//! same model.

use dda3d::model::Model;
use dda3d::scene;

const ROCK: &str =
    "[materials.rock]\ndensity = 2600.0\nyoung_modulus = 1.0e10\npoisson_ratio = 0.25\n";

fn parse(text: &str) -> scene::Scene {
    scene::parse(text, "mass.toml", "mass").unwrap_or_else(|e| panic!("{e}\n{text}"))
}

/// A joint set table.
fn set(name: &str, dip: f64, dd: f64, spacing: f64, origin: [f64; 3], extra: &str) -> String {
    format!(
        "[[rock_masses.joint_sets]]\nname = \"{name}\"\ndip = {dip}\ndip_direction = {dd}\n\
         spacing = {spacing}\norigin = [{}, {}, {}]\n{extra}\n",
        origin[0], origin[1], origin[2]
    )
}

/// Three orthogonal sets 1 m apart in a 10 m cube: exactly 1000 unit boxes, named in order of
/// the sets' planes (x slabs, then y, then z, from the lowest).
#[test]
fn three_orthogonal_sets_cut_a_cube_into_unit_boxes() {
    let text = format!(
        "{ROCK}[[rock_masses]]\nname = \"cube\"\nmaterial = \"rock\"\n\
         regions = [ {{ box = {{ size = [10, 10, 10], center = [5, 5, 5] }} }} ]\n{}{}{}",
        set("x", 90.0, 90.0, 1.0, [0.0; 3], ""),
        set("y", 90.0, 0.0, 1.0, [0.0; 3], ""),
        set("z", 0.0, 0.0, 1.0, [0.0; 3], ""),
    );
    let s = parse(&text);
    let blocks = &s.model.blocks;
    assert_eq!(blocks.len(), 1000);
    for b in blocks {
        assert!(
            (b.mp.volume - 1.0).abs() < 1e-12,
            "{} {}",
            b.name,
            b.mp.volume
        );
        assert_eq!((b.vertices.len(), b.topo.faces.len()), (8, 6), "{}", b.name);
    }
    assert_eq!(blocks[0].name, "cube/1");
    let c0 = blocks[0].mp.centroid;
    assert!((c0 - nalgebra::Vector3::new(0.5, 0.5, 0.5)).norm() < 1e-12);
    let last = blocks[999].mp.centroid;
    assert!((last - nalgebra::Vector3::new(9.5, 9.5, 9.5)).norm() < 1e-12);
    // Every interior face is a joint face of its set; the cube's own faces are not.
    let tagged: usize = blocks
        .iter()
        .map(|b| b.face_joints.iter().flatten().count())
        .sum();
    assert_eq!(tagged, 6000 - 600);
    let r = &s.rock_masses[0];
    assert_eq!((r.blocks, r.dropped, r.planes), (1000, 0, 27));
}

/// A seeded family of oblique, varied joint sets in a prism region and a box region: the
/// blocks' volumes sum to the domain's, every joint face has its partner on the other side of
/// its plane with the same area, and random points lie in exactly one block.
#[test]
fn random_sets_cut_without_gaps_or_overlaps() {
    let mut rng = 12345u64;
    let mut next = move || {
        rng = rng
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (rng >> 11) as f64 / (1u64 << 53) as f64
    };
    for case in 0..12 {
        let mut sets = String::new();
        for k in 0..3 {
            let extra = if case % 2 == 1 {
                format!(
                    "spacing_deviation = 0.3\norientation_deviation = 5.0\nseed = {}\n",
                    case * 10 + k
                )
            } else {
                String::new()
            };
            sets += &set(
                &format!("S{k}"),
                90.0 * next(),
                360.0 * next(),
                1.0 + 1.5 * next(),
                [next(), next(), next()],
                &extra,
            );
        }
        let text = format!(
            "{ROCK}[[rock_masses]]\nname = \"m\"\nmaterial = \"rock\"\nmin_volume = 0.0\n\
             regions = [ {{ prism = {{ base = [[0, 0, 0], [8, 0, 0], [8, 0, 6], [3, 0, 6]], \
             extrude = [0, 7, 0] }} }}, {{ box = {{ size = [8, 7, 2], center = [4, 3.5, -1] }} }} ]\n{sets}"
        );
        let s = parse(&text);
        let domain = (8.0 + 5.0) / 2.0 * 6.0 * 7.0 + 8.0 * 7.0 * 2.0;
        let total: f64 = s.model.blocks.iter().map(|b| b.mp.volume).sum();
        let r = &s.rock_masses[0];
        assert!(
            (r.domain_volume - domain).abs() < 1e-12 * domain,
            "case {case}: {r}"
        );
        assert!(
            (total - domain).abs() < 1e-9 * domain,
            "case {case}: blocks {total} of {domain}: {r}"
        );
        assert_joint_faces_pair_up(&s.model, case);
        assert_points_in_one_block(&s.model, case, &mut next);
    }
}

/// On every joint plane the faces on its two sides have the same total area.
fn assert_joint_faces_pair_up(model: &Model, case: usize) {
    use std::collections::HashMap;
    let mut area: HashMap<(u16, u32), [f64; 2]> = HashMap::new();
    for b in &model.blocks {
        for (f, tag) in b.face_joints.iter().enumerate() {
            let Some(tag) = tag else { continue };
            let face = &b.topo.faces[f];
            let n = dda3d::physics::geometry::newell_normal(&b.vertices, face);
            // Newell's normal is twice the area; its sign says which side the block is on.
            let side = area.entry((tag.set, tag.plane)).or_default();
            side[usize::from(!positive(&n))] += n.norm() / 2.0;
        }
    }
    for ((set, plane), [a, b]) in area {
        assert!(
            (a - b).abs() <= 1e-9 * a.max(b),
            "case {case}: set {set} plane {plane}: areas {a} and {b}"
        );
    }
}

/// Which way a face's normal points, by the sign of its largest component: the faces on one
/// plane have the same normal up to its sign, so this splits them by side.
fn positive(n: &nalgebra::Vector3<f64>) -> bool {
    let m = n.abs();
    let k = if m.z >= m.x && m.z >= m.y {
        2
    } else if m.x >= m.y {
        0
    } else {
        1
    };
    n[k] > 0.0
}

/// 2000 random points of the domain each lie inside exactly one block (1e-9 of the model's
/// size from any face counts as inside).
fn assert_points_in_one_block(model: &Model, case: usize, next: &mut impl FnMut() -> f64) {
    let mut tested = 0;
    while tested < 2000 {
        let p = nalgebra::Vector3::new(8.0 * next(), 7.0 * next(), -2.0 + 8.0 * next());
        // Inside the domain: the box (z < 0), or the prism behind its face x = z / 2.
        if p.z >= 0.0 && p.x < p.z / 2.0 {
            continue;
        }
        tested += 1;
        let inside = model
            .blocks
            .iter()
            .filter(|b| {
                b.topo
                    .faces
                    .iter()
                    .enumerate()
                    .all(|(f, face)| b.face_normals[f].dot(&(p - b.vertices[face[0]])) <= 1e-8)
            })
            .count();
        assert_eq!(inside, 1, "case {case}: point {p:?} in {inside} blocks");
    }
}

/// `dda3d cut`'s file loads to the same blocks, bit for bit, with the same joint faces and
/// fixed blocks, and the same joint sets.
#[test]
fn the_cut_file_loads_to_the_same_model() {
    let dir = std::env::temp_dir().join(format!("dda3d-cut-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("slope.toml");
    std::fs::copy(
        concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/jointed_slope.toml"),
        &path,
    )
    .unwrap();
    let direct = scene::load(&path).unwrap();
    let (text, reports) = scene::cut_scene(&path).unwrap();
    assert_eq!(reports, direct.rock_masses);
    let out = dir.join("slope_cut.toml");
    std::fs::write(&out, &text).unwrap();
    let cut = scene::load(&out).unwrap();
    assert!(cut.rock_masses.is_empty());
    assert_eq!(cut.model.rock_masses, direct.model.rock_masses);
    assert_eq!(cut.params, direct.params);
    assert_eq!(cut.model.blocks.len(), direct.model.blocks.len());
    for (a, b) in cut.model.blocks.iter().zip(&direct.model.blocks) {
        assert_eq!(a.name, b.name);
        assert_eq!(a.fixed, b.fixed, "{}", a.name);
        assert_eq!(a.vertices, b.vertices, "{}", a.name);
        assert_eq!(a.topo, b.topo, "{}", a.name);
        assert_eq!(a.face_joints, b.face_joints, "{}", a.name);
        assert_eq!(a.rock_mass, b.rock_mass, "{}", a.name);
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Bad rock masses are one-line errors at their line, found before any long work: a dip out of
/// range, a spacing that would cut the domain into more blocks than a scene may have, a region
/// that is not convex (a prism whose base has a reflex corner), overlapping regions.
#[test]
fn bad_rock_masses_are_one_line_errors() {
    let mass = |regions: &str, sets: &str| {
        format!(
            "{ROCK}[[rock_masses]]\nname = \"m\"\nmaterial = \"rock\"\nregions = [ {regions} ]\n{sets}"
        )
    };
    let cube = "{ box = { size = [4, 4, 4], center = [0, 0, 0] } }";
    let good = set("S", 30.0, 90.0, 1.0, [0.0; 3], "");
    for (text, want) in [
        (
            mass(cube, &set("S", 95.0, 90.0, 1.0, [0.0; 3], "")),
            "dip must lie in [0, 90]",
        ),
        (
            mass(cube, &set("S", 30.0, 360.0, 1.0, [0.0; 3], "")),
            "dip_direction",
        ),
        (
            mass(cube, &set("S", 30.0, 90.0, 1e-6, [0.0; 3], "")),
            "increase the spacing",
        ),
        (
            mass(cube, &set("S", 30.0, 90.0, 0.0, [0.0; 3], "")),
            "spacing must be positive",
        ),
        (
            mass(
                "{ prism = { base = [[0, 0, 0], [4, 0, 0], [4, 0, 4], [2, 0, 1], [0, 0, 4]], extrude = [0, 4, 0] } }",
                &good,
            ),
            "not convex",
        ),
        (
            mass(
                &format!("{cube}, {{ box = {{ size = [4, 4, 4], center = [1, 0, 0] }} }}"),
                &good,
            ),
            "overlaps region 1",
        ),
        // Forty sets through one point: about a thousand blocks that all meet there, each box
        // over every other (one step of sixty such sets took 10.9 GB).
        (
            mass(cube, &star_of_sets(40)),
            "a block (more than 200): block 'm/",
        ),
        // A min_volume above every piece left an empty model that ran and "completed".
        (
            format!("{}min_volume = 70.0\n{good}", mass(cube, "")),
            "min_volume = 70 m³ drops every piece of the cut (",
        ),
    ] {
        let start = std::time::Instant::now();
        let e = scene::parse(&text, "mass.toml", "mass").expect_err(want);
        let line = e.to_string();
        assert!(line.contains(want), "{line}");
        assert!(line.starts_with("mass.toml: line "), "{line}");
        assert_eq!(line.lines().count(), 1);
        assert!(start.elapsed().as_secs_f64() < 5.0, "{want}: slow");
    }
}

/// `n` joint sets through the origin, spread in dip and dip direction (golden-angle steps), one
/// plane each: every block they cut has the origin as a corner.
fn star_of_sets(n: usize) -> String {
    (0..n)
        .map(|k| {
            let dip = 5.0 + (k as f64 * 0.618_034 * 80.0) % 80.0;
            let dd = (k as f64 * 137.507_764) % 360.0;
            set(&format!("S{k}"), dip, dd, 100.0, [0.0; 3], "")
        })
        .collect()
}

/// `dda3d run` on a rock mass reports the cut in summary.json, as `dda3d cut` prints it: blocks,
/// fixed blocks, planes, the blocks' volume against the domain's, and no slivers here; and
/// contacts.csv names the set of each contact across a joint plane.
#[test]
fn a_run_reports_its_rock_masses() {
    let dir = std::env::temp_dir().join(format!("dda3d-mass-run-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let text = format!(
        "[solver]\nduration = 0.02\n{ROCK}[[rock_masses]]\nname = \"m\"\nmaterial = \"rock\"\n\
         regions = [ {{ box = {{ size = [4, 4, 4], center = [0, 0, 2] }} }} ]\n\
         fixed = {{ below = 1.5 }}\n{}{}",
        set("H", 0.0, 0.0, 2.0, [0.0, 0.0, 0.0], ""),
        set("V", 90.0, 90.0, 2.0, [0.0, 0.0, 0.0], "")
    );
    let scene = dir.join("mass.toml");
    std::fs::write(&scene, text).unwrap();
    let out = dir.join("out");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_dda3d"))
        .args(["run", "--quiet", "--out"])
        .arg(&out)
        .arg(&scene)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let m = &summary["rock_masses"][0];
    assert_eq!(m["name"], "m");
    // The horizontal planes at z = 2 and the vertical one at x = 0 (those at z = 0, 4 and
    // x = ±2 are the domain's faces): 4 blocks of 2 × 4 × 2 m, the lower two fixed.
    assert_eq!(m["blocks"], 4, "{m}");
    assert_eq!(m["fixed"], 2, "{m}");
    assert_eq!(m["dropped_slivers"], 0);
    let (v, dv) = (
        m["volume"].as_f64().unwrap(),
        m["domain_volume"].as_f64().unwrap(),
    );
    assert!((v - 64.0).abs() < 1e-9 && (dv - 64.0).abs() < 1e-9, "{m}");
    assert!((m["smallest_block"].as_f64().unwrap() - 16.0).abs() < 1e-9);
    let contacts = std::fs::read_to_string(out.join("contacts.csv")).unwrap();
    let joints: std::collections::BTreeSet<&str> = contacts
        .lines()
        .skip(1)
        .filter_map(|l| l.rsplit(',').next())
        .collect();
    assert!(joints.contains("H") && joints.contains("V"), "{joints:?}");
    std::fs::remove_dir_all(&dir).ok();
}

/// Slabs of a joint set far thinner than the model is wide slide down their set as Coulomb
/// allows, without diverging. A 45° set 5 mm apart in a 0.2 m cube on a 10 m base: the base gave
/// the mass its w0 (5 m), a step could move a slab ten times its thickness, each slab searched 25
/// slabs deep for contacts, and a step redone after an ALM loop ran away kept that loop's
/// friction (10²¹⁷ N); the run ended at 0.16 s, "the solution is not finite". Checked here:
/// every step solves, no contact penetrates a fiftieth of a slab, no slab sinks into the base,
/// and the slabs' kinetic energy stays below the potential energy they lose.
#[test]
fn thin_slabs_of_a_closely_spaced_set_slide_without_diverging() {
    for spacing in [0.005, 0.01] {
        let text = format!(
            "[solver]\nduration = 0.3\n{ROCK}[[blocks]]\nname = \"base\"\nmaterial = \"rock\"\n\
             fixed = true\nbox = {{ size = [10, 10, 1], center = [0, 0, -0.5] }}\n\
             [[rock_masses]]\nname = \"m\"\nmaterial = \"rock\"\n\
             regions = [ {{ box = {{ size = [0.2, 0.2, 0.2], center = [0, 0, 0.1] }} }} ]\n{}",
            set("J", 45.0, 90.0, spacing, [0.0, 0.0, 0.0], "")
        );
        let label = format!("{spacing} m apart");
        let penetration = runs_without_diverging(&label, &text, (0.25 / spacing) as usize);
        assert!(penetration < spacing / 50.0, "{spacing}: {penetration} m");
    }
}

/// A cube of 2 m cut by three joint sets of random orientation (seed 5 of
/// `scripts/probe-rock-masses.py`: 230 blocks, two sets steep, one at 34° with 20° friction)
/// collapses on its base without diverging. Until a step redone at a shorter Δt went back to
/// the faces its contacts had at the step's start (a failed attempt could move an open contact
/// to another face, and a sliver's corner then began behind that face's plane), the run
/// stopped at 0.045 s ("vertex displacement beyond the allowed δ·w0 … at the minimum time
/// step"). Checked here: every
/// step solves, no block sinks into the base, and the blocks' kinetic energy stays below the
/// potential energy they lose.
#[test]
fn a_cube_cut_by_three_random_sets_collapses_without_diverging() {
    let text = probe_cube(
        "duration = 0.06\n",
        1e9,
        2.0,
        "",
        "[[rock_masses.joint_sets]]\nname = \"J0\"\ndip = 71.6\ndip_direction = 339.3\n\
         spacing = 0.4\nfriction_angle = 39.6\nspacing_deviation = 0.08\n\
         [[rock_masses.joint_sets]]\nname = \"J1\"\ndip = 69.8\ndip_direction = 89.7\n\
         spacing = 0.6\nfriction_angle = 12.1\ncohesion = 1000.0\n\
         [[rock_masses.joint_sets]]\nname = \"J2\"\ndip = 34.3\ndip_direction = 36.7\n\
         spacing = 0.2\nfriction_angle = 20.0\n",
    );
    runs_without_diverging("seed 5", &text, 200);
}

/// A 0.5 m cube cut by a set dipping 3° and one dipping 52° (seed 10 of the probe: 52 blocks,
/// slabs 5 cm thick sliding on 13° friction) settles through its stage and collapses for 0.2 s
/// without diverging. A slab's contacts with its neighbour across both sets had normals 128°
/// apart at two places, both held with 3·10⁷ N, until a step gained 884 J and the run stopped
/// at 0.043 s. Checked as above.
#[test]
fn a_cube_of_slabs_on_two_sets_collapses_without_clamping_them() {
    let text = probe_cube(
        "duration = 0.2\ninitial_equilibrium = true\nequilibrium_max_steps = 30\n",
        1e10,
        0.5,
        "",
        "[[rock_masses.joint_sets]]\nname = \"J0\"\ndip = 52.0\ndip_direction = 74.2\n\
         spacing = 0.15\nfriction_angle = 42.5\n\
         [[rock_masses.joint_sets]]\nname = \"J1\"\ndip = 3.1\ndip_direction = 176.4\n\
         spacing = 0.05\nfriction_angle = 13.0\n",
    );
    runs_without_diverging("seed 10", &text, 40);
}

/// A 0.5 m cube cut by three sets (seed 14 of the probe: 91 blocks, DDA-3p) holds fragments of
/// about a cubic centimetre, 1/400 of its median block, above the default `min_volume`; one of
/// them, squeezed by its neighbours, moved beyond δ·w0 even at the Δt floor (since unloaded
/// contacts hold no more shear than a hundredth of their block's weight, a fragment of
/// 6.2·10⁻⁶ m³, 1/70 of the median, is the one). Where the run stops so, its message names the
/// block and, as a fragment of the cut, the `min_volume` that drops it, and the run with
/// `min_volume` set so goes on to its end; where it stops on the energy watchdog (as it has since DDA-3p's contacts close
/// sliding: 90 J at 0.008 s), the message names the block with the most kinetic energy; and
/// with `min_volume` set above the fragments the mass collapses for its 0.2 s.
#[test]
fn a_fragment_that_diverges_is_named_and_min_volume_drops_it() {
    let text = |min_volume: &str| {
        probe_cube(
            "method = \"penalty\"\nduration = 0.2\n",
            1e9,
            0.5,
            min_volume,
            "[[rock_masses.joint_sets]]\nname = \"J0\"\ndip = 84.6\ndip_direction = 97.6\n\
             spacing = 0.25\nfriction_angle = 20.2\n\
             [[rock_masses.joint_sets]]\nname = \"J1\"\ndip = 42.0\ndip_direction = 314.2\n\
             spacing = 0.1\nfriction_angle = 25.8\nspacing_deviation = 0.02\n\
             [[rock_masses.joint_sets]]\nname = \"J2\"\ndip = 32.2\ndip_direction = 93.7\n\
             spacing = 0.1\nfriction_angle = 42.2\nspacing_deviation = 0.02\n",
        )
    };
    let s = parse(&text(""));
    let mut solver = dda3d::solver::Solver::new(s.model, s.params);
    let mut stopped = None;
    while !solver.finished() && stopped.is_none() {
        stopped = solver.step().err().map(|e| e.to_string());
    }
    match stopped {
        Some(e) if e.contains("the energy grew") => {
            assert!(e.contains("the most kinetic energy is block \"m/"), "{e}");
        }
        Some(e) => {
            let named = number_after(&e, "min_volume drops when set above ")
                .unwrap_or_else(|| panic!("the divergence names no fragment: {e}"));
            assert!(e.contains("by block \"m/"), "{e}");
            // A fragment: under a tenth of the median block (about 4.4·10⁻⁴ m³ here).
            assert!(named < 4e-5, "{named} m³: {e}");
            // The message's advice works: min_volume above the named block.
            runs_without_diverging(
                "seed 14, min_volume as the message says",
                &text(&format!("min_volume = {}\n", 1.01 * named)),
                70,
            );
        }
        None => {}
    }
    runs_without_diverging(
        "seed 14, min_volume 2e-6",
        &text("min_volume = 2.0e-6\n"),
        80,
    );
}

/// The scene `scripts/probe-rock-masses.py` makes of a seed: a rock mass filling a cube of
/// `size` m (with the keys `mass_keys` and the joint-set tables `sets`) on a fixed base of
/// 4 × 4 × ½ its size, the `[solver]` keys `solver`, and the rock of [`ROCK`] with Young's
/// modulus `young`, Pa.
fn probe_cube(solver: &str, young: f64, size: f64, mass_keys: &str, sets: &str) -> String {
    let base = [4.0 * size, 4.0 * size, size / 2.0];
    format!(
        "[solver]\n{solver}{}[[blocks]]\nname = \"g\"\nmaterial = \"rock\"\nfixed = true\n\
         box = {{ size = {base:?}, center = [0, 0, {:?}] }}\n\
         [[rock_masses]]\nname = \"m\"\nmaterial = \"rock\"\n{mass_keys}\
         regions = [ {{ box = {{ size = {:?}, center = [0, 0, {:?}] }} }} ]\n{sets}",
        ROCK.replace("1.0e10", &format!("{young:e}")),
        -size / 4.0,
        [size; 3],
        size / 2.0,
    )
}

/// The number in `text` right after `before`, if any.
fn number_after(text: &str, before: &str) -> Option<f64> {
    let rest = &text[text.find(before)? + before.len()..];
    let end = rest.find(' ').unwrap_or(rest.len());
    rest[..end].parse().ok()
}

/// Runs a rock mass's scene (`label` names it in messages) to its end: more than `min_blocks`
/// blocks, every step solves, no block sinks into the base (its top at z = 0), the blocks'
/// kinetic energy stays below the potential energy they lost, and under DDA-3a no step gains a
/// quarter of it. Returns the run's largest penetration, m.
fn runs_without_diverging(label: &str, text: &str, min_blocks: usize) -> f64 {
    let s = parse(text);
    let alm = s.params.method == dda3d::params::Method::Alm;
    let mut solver = dda3d::solver::Solver::new(s.model, s.params);
    let start = solver.snapshot();
    assert!(
        start.blocks.len() > min_blocks,
        "{label}: {} blocks",
        start.blocks.len()
    );
    // The largest rise of kinetic + gravitational + elastic energy in one step of the run.
    let (mut before, mut largest_gain) = (None::<f64>, 0.0f64);
    while !solver.finished() {
        let in_stage = solver.in_equilibrium_stage();
        let stats = solver.step().unwrap_or_else(|e| panic!("{label}: {e}"));
        let energy = stats.kinetic_energy + stats.potential_energy + stats.elastic_energy;
        if let (Some(e0), false) = (before, in_stage) {
            largest_gain = largest_gain.max(energy - e0);
        }
        before = Some(energy);
    }
    let end = solver.snapshot();
    let (mut lost, mut kinetic) = (0.0, 0.0);
    for (a, b) in start
        .blocks
        .iter()
        .zip(&end.blocks)
        .filter(|(a, _)| !a.fixed)
    {
        assert!(
            b.centroid[2] > 0.0,
            "{label}: {} sank to {:?}",
            b.name,
            b.centroid
        );
        let mass = 2600.0 * a.volume;
        lost += mass * 9.8 * (a.centroid[2] - b.centroid[2]);
        kinetic += 0.5 * mass * b.velocity.iter().map(|v| v * v).sum::<f64>();
    }
    assert!(
        lost > 0.0 && kinetic < lost,
        "{label}: kinetic {kinetic} J, lost {lost} J"
    );
    // No step of DDA-3a creates a quarter of what the whole collapse released: seed 10's cube
    // of slabs once gained 1.49 J in a step (of 1.15 J released), pushing out a corner first
    // seen 0.18 mm deep within 0.1 ms (tests/overlaps.rs). Measured: 0.15 J of 1.03 J. DDA-3p's
    // penalty springs hold energy the balance does not count (seed 14: 0.030 J of 0.031 J).
    assert!(
        !alm || largest_gain < 0.25 * lost,
        "{label}: a step gained {largest_gain} J, the collapse released {lost} J"
    );
    let penetration = solver.totals.max_penetration;
    println!(
        "{label}, {} blocks: kinetic {kinetic:.3} J of {lost:.3} J lost, penetration {penetration:.2e} m, \
         largest gain in a step {largest_gain:.3} J",
        start.blocks.len()
    );
    penetration
}
