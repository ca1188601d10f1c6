use std::path::{Path, PathBuf};

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::*;

fn column(name: &str, unit: &str, values: &[Option<f64>]) -> PlotColumn {
    PlotColumn {
        name: name.into(),
        values: values.to_vec(),
        categories: None,
        log_scale: false,
        unit: unit.into(),
    }
}

fn scratch(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("dda3d-study-plots-{test}-{}", std::process::id()));
    let _ = fs::remove_dir_all(&dir);
    dir
}

fn decode(path: &Path) -> image::RgbImage {
    image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgb8()
}

/// Pixels near the points' blue (POINT blended over white), which no text, grid or frame has.
fn blue_pixels(image: &image::RgbImage) -> usize {
    image
        .pixels()
        .filter(|p| p[2] > 150 && p[0] < 140 && p[2] as i32 - p[0] as i32 > 60)
        .count()
}

fn names(files: &[PathBuf]) -> Vec<String> {
    files
        .iter()
        .map(|f| f.file_name().unwrap().to_string_lossy().into_owned())
        .collect()
}

/// A rockfall study: the release speed, the block edge and the release height drawn at
/// random, and the two outcomes loosely following them; cases 5, 17 and 30 failed.
fn rockfall(cases: usize) -> (Vec<PlotColumn>, Vec<PlotColumn>) {
    let mut rng = ChaCha8Rng::seed_from_u64(18);
    let mut speed = Vec::new();
    let mut edge = Vec::new();
    let mut height = Vec::new();
    let mut toppled = Vec::new();
    let mut runout = Vec::new();
    for case in 0..cases {
        let v: f64 = rng.random_range(6.0..14.0);
        let a: f64 = rng.random_range(0.5..0.9);
        let h: f64 = rng.random_range(3.0..9.5);
        speed.push(Some(v));
        edge.push(Some(a));
        height.push(Some(h));
        let failed = [5, 17, 30].contains(&case);
        let n = ((v - 6.0) / 2.0 + rng.random_range(-0.8..0.8))
            .round()
            .clamp(0.0, 4.0);
        let r = (v * 0.7 + h * 0.4 - 4.0 + rng.random_range(-2.0..2.0)).clamp(0.0, 15.0);
        toppled.push((!failed).then_some(n));
        runout.push((!failed).then_some(r));
    }
    let parameters = vec![
        column("blocks.rock.velocity[0]", "m/s", &speed),
        column("rock_masses.edge", "m", &edge),
        column("blocks.rock.position[2]", "m", &height),
    ];
    let outcomes = vec![
        column("blocks_toppled", "", &toppled),
        column("runout", "m", &runout),
    ];
    (parameters, outcomes)
}

#[test]
fn every_pair_gets_its_file_and_the_overview_comes_last() {
    let dir = scratch("names");
    let (parameters, outcomes) = rockfall(40);
    let files = write_plots(&dir, &parameters, &outcomes).unwrap();
    assert_eq!(
        names(&files),
        [
            "blocks_toppled_vs_blocks_rock_velocity_0.png",
            "blocks_toppled_vs_rock_masses_edge.png",
            "blocks_toppled_vs_blocks_rock_position_2.png",
            "runout_vs_blocks_rock_velocity_0.png",
            "runout_vs_rock_masses_edge.png",
            "runout_vs_blocks_rock_position_2.png",
            "overview.png",
        ]
    );
    for file in &files {
        assert_eq!(file.parent().unwrap(), dir.join("plots"));
    }
    let single = decode(&files[0]);
    assert_eq!(single.dimensions(), SINGLE);
    assert!(
        blue_pixels(&single) > 37 * 20,
        "{} blue pixels",
        blue_pixels(&single)
    );
    let overview = decode(&files[6]);
    assert_eq!(overview.dimensions(), overview_size(2, 3));
    assert_eq!(overview.dimensions(), (1200, 600 + HEADER));
    fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_same_study_gives_the_same_bytes() {
    let (parameters, outcomes) = rockfall(25);
    let first = write_plots(&scratch("same-a"), &parameters, &outcomes).unwrap();
    let second = write_plots(&scratch("same-b"), &parameters, &outcomes).unwrap();
    for (a, b) in first.iter().zip(&second) {
        assert!(
            fs::read(a).unwrap() == fs::read(b).unwrap(),
            "{} differs",
            a.display()
        );
    }
    for file in [&first[0], &second[0]] {
        fs::remove_dir_all(file.parent().unwrap().parent().unwrap()).unwrap();
    }
}

#[test]
fn text_is_drawn() {
    // Two plots that differ only in a name differ in their pixels: the font renders.
    let dir = scratch("text");
    let values = [Some(1.0), Some(2.0)];
    let a = write_plots(
        &dir,
        &[column("speed", "m/s", &values)],
        &[column("runout", "m", &values)],
    )
    .unwrap();
    let b = write_plots(
        &dir,
        &[column("speed", "m/s", &values)],
        &[column("distance", "m", &values)],
    )
    .unwrap();
    assert_ne!(decode(&a[0]), decode(&b[0]));
    fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn awkward_columns_give_plots_without_panicking() {
    let dir = scratch("awkward");
    let parameters = vec![
        column("constant", "m", &[Some(3.0); 4]),
        column("empty", "", &[None; 4]),
        column(
            "not finite",
            "",
            &[
                Some(f64::NAN),
                Some(f64::INFINITY),
                Some(f64::NEG_INFINITY),
                None,
            ],
        ),
        column("one value", "s", &[None, Some(0.25), None, None]),
    ];
    let extreme = [Some(f64::MAX), Some(-f64::MAX), Some(1e-300), Some(0.0)];
    let outcomes = vec![
        column("all failed", "J", &[None; 4]),
        column("constant count", "", &[Some(2.0); 4]),
        column("zeros", "", &[Some(0.0); 4]),
        column("extreme", "", &extreme),
    ];
    let files = write_plots(&dir, &parameters, &outcomes).unwrap();
    assert_eq!(files.len(), parameters.len() * outcomes.len() + 1);
    for (k, file) in files.iter().enumerate() {
        let image = decode(file);
        if k + 1 < files.len() {
            assert_eq!(image.dimensions(), SINGLE);
        }
        // Points only where both columns have a value: the constant and the one value against
        // the last three outcomes (files 4 + 4·o and 7 + 4·o), and the overview.
        let drawn = blue_pixels(&image) > 0;
        let expected = [4, 7, 8, 11, 12, 15, 16].contains(&k);
        assert_eq!(drawn, expected, "{}", file.display());
    }
    fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn categories_and_log_columns_are_drawn() {
    let dir = scratch("categories");
    let mut method = column(
        "solver.contact",
        "",
        &[Some(0.0), Some(1.0), Some(1.0), Some(0.0), Some(2.0), None],
    );
    method.categories = Some(vec![
        "alm".into(),
        "penalty".into(),
        "unused-third-category".into(),
    ]);
    let mut stiffness = column(
        "penalty_scale",
        "N/m",
        &[
            Some(1e6),
            Some(3e7),
            Some(1e9),
            Some(4e8),
            Some(2e6),
            Some(5e7),
        ],
    );
    stiffness.log_scale = true;
    let runout = column(
        "runout",
        "m",
        &[Some(3.0), Some(4.5), None, Some(2.0), Some(7.0), Some(1.0)],
    );
    let files = write_plots(&dir, &[method, stiffness], &[runout]).unwrap();
    assert_eq!(
        names(&files),
        [
            "runout_vs_solver_contact.png",
            "runout_vs_penalty_scale.png",
            "overview.png"
        ]
    );
    for file in &files[..2] {
        assert!(blue_pixels(&decode(file)) > 0, "{}", file.display());
    }
    // The medians of the categories are red bars.
    let categorical = decode(&files[0]);
    let red = categorical
        .pixels()
        .filter(|p| p[0] > 180 && p[1] < 80 && p[2] < 80)
        .count();
    assert!(red > 20, "{red} red pixels");
    fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn columns_of_different_lengths_are_refused() {
    let dir = scratch("lengths");
    let error = write_plots(
        &dir,
        &[column("speed", "m/s", &[Some(1.0), Some(2.0)])],
        &[column("runout", "m", &[Some(1.0)])],
    )
    .unwrap_err();
    assert_eq!(
        error,
        "study plots: column 'runout' has 1 values but 'speed' has 2"
    );
    assert!(!dir.exists());
}

#[test]
fn no_outcome_or_parameter_still_gives_an_overview() {
    let dir = scratch("none");
    let files = write_plots(&dir, &[], &[column("runout", "m", &[Some(1.0)])]).unwrap();
    assert_eq!(names(&files), ["overview.png"]);
    assert_eq!(decode(&files[0]).dimensions(), SINGLE);
    fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn slugs_and_clashing_names() {
    assert_eq!(slug("blocks.rock.velocity[0]"), "blocks_rock_velocity_0");
    assert_eq!(slug("Runout"), "runout");
    assert_eq!(slug("[]"), "column");
    assert!(slug(&"long name ".repeat(30)).len() <= MAX_SLUG);
    let parameters = [
        column("a.b", "", &[]),
        column("a_b", "", &[]),
        column("A-B", "", &[]),
    ];
    let names: Vec<String> = pair_file_names(&parameters, &[column("x", "", &[])])
        .into_iter()
        .map(|(name, _)| name)
        .collect();
    assert_eq!(names, ["x_vs_a_b.png", "x_vs_a_b_2.png", "x_vs_a_b_3.png"]);
}

#[test]
fn the_overview_shrinks_its_panels_for_large_grids() {
    assert_eq!(overview_size(1, 1), (400, 300 + HEADER));
    assert_eq!(overview_size(6, 4), (1600, 1800 + HEADER));
    // 8 rows of 300 px fill the 2400 px; 10 need panels at 0.8.
    assert_eq!(overview_size(10, 4), (1280, 2400 + HEADER));
    assert_eq!(overview_size(12, 12), (2880, 2160 + HEADER));
    assert_eq!(overview_size(0, 3), SINGLE);
    // More outcomes than the overview shows: every pair still has its file.
    let dir = scratch("large");
    let outcomes: Vec<PlotColumn> = (0..OVERVIEW_MAX_ROWS + 1)
        .map(|k| column(&format!("o{k}"), "", &[Some(k as f64)]))
        .collect();
    let files = write_plots(&dir, &[column("p", "", &[Some(1.0)])], &outcomes).unwrap();
    assert_eq!(files.len(), OVERVIEW_MAX_ROWS + 2);
    assert_eq!(
        decode(files.last().unwrap()).dimensions(),
        overview_size(OVERVIEW_MAX_ROWS, 1)
    );
    fs::remove_dir_all(&dir).unwrap();
}
