//! Tests of the frame building: arrows, scales, colours, bad input.

use super::*;
use crate::snapshot::*;

fn cube(name: &str, at: [f64; 3], fixed: bool) -> BlockSnapshot {
    BlockSnapshot {
        fixed,
        velocity: [0.0, 0.0, -2.0],
        displacement: [0.0, 0.0, -0.5],
        rock_mass: None,
        stress: [0.0; 6],
        volume: 1.0,
        ..BlockSnapshot::test_cube(name, at, 1.0)
    }
}

fn snap(contacts: Vec<ContactSnapshot>) -> Snapshot {
    Snapshot {
        scene_name: "two cubes".into(),
        time: 0.25,
        step: 10,
        blocks: vec![
            cube("base", [0.0; 3], true),
            cube("top", [0.0, 0.0, 1.0], false),
        ],
        contacts,
        stats: StepStats::default(),
        equilibrium: None,
        rock_masses: Vec::new(),
        joint_sets: Vec::new(),
    }
}

fn contact(f: f64, state: ContactState) -> ContactSnapshot {
    ContactSnapshot {
        block_i: 1,
        block_j: 0,
        mode: ContactMode::VertexFace,
        state,
        point: [0.0, 0.0, 1.0],
        normal: [0.0, 0.0, 1.0],
        normal_force: f,
        shear_force: 0.0,
        shear: [0.0; 3],
        penetration: 0.0,
        penalty: 0.0,
        lambda: 0.0,
        joint: None,
    }
}

#[test]
fn force_arrow_length_follows_scale() {
    let s = snap(vec![contact(1000.0, ContactState::Lock)]);
    let style = SceneStyle {
        force_scale: Some(2000.0),
        grid: false,
        ..Default::default()
    };
    let frame = SceneFrame::of_snapshot(&s);
    let scene = RenderScene::build(&s, &style, &frame).unwrap();
    assert_eq!(scene.force_scale, Some(2000.0));
    // 1000 N at 2000 N/m → 0.5 m arrow from the contact point along +z.
    let base = scene.to_local([0.0, 0.0, 1.0]);
    let top = triangles(&scene)
        .iter()
        .map(|v| v.position[2] - base.z)
        .fold(f32::MIN, f32::max);
    assert!((top - 0.5).abs() < 1e-4, "arrow top {top}");
    // A force far beyond the scale is capped at 40 % of the view.
    let big = snap(vec![contact(1e6, ContactState::Lock)]);
    let capped = RenderScene::build(&big, &style, &frame).unwrap();
    let top_big = triangles(&capped)
        .iter()
        .map(|v| v.position[2] - base.z)
        .fold(f32::MIN, f32::max);
    assert!(
        (top_big - 0.4 * frame.size() as f32).abs() < 1e-3,
        "capped top {top_big}"
    );
    assert_eq!(scene.contacts_lock, 1);
    let lock = srgb_to_linear(hex(LOCK_SRGB));
    assert!(scene.arrows.iter().all(|v| v.color == lock));
}

#[test]
fn auto_scale_and_slide_colour() {
    let s = snap(vec![
        contact(60154.0, ContactState::Slide),
        contact(33204.0, ContactState::Lock),
    ]);
    let frame = SceneFrame::of_snapshot(&s);
    let scene = RenderScene::build(&s, &SceneStyle::default(), &frame).unwrap();
    let scale = scene.force_scale.unwrap();
    let longest = 60154.0 / scale;
    assert!(longest <= 0.20 * frame.size() + 1e-9 && longest > 0.08 * frame.size());
    let slide = srgb_to_linear(hex(SLIDE_SRGB));
    assert!(scene.arrows.iter().any(|v| v.color == slide));
    assert_eq!((scene.contacts_lock, scene.contacts_slide), (1, 1));
}

#[test]
fn no_contacts_no_arrows_and_grid_present() {
    let s = snap(vec![]);
    let scene =
        RenderScene::build(&s, &SceneStyle::default(), &SceneFrame::of_snapshot(&s)).unwrap();
    assert!(scene.arrows.is_empty());
    assert!(scene.force_scale.is_none());
    assert!(scene.grid_step.is_some());
    assert_eq!(scene.solids.len(), 2 * 6 * 2 * 3);
    // 24 outline segments, the rest grid.
    assert!(scene.lines.len() > 24);
}

#[test]
fn field_colouring_and_fixed_muted() {
    let s = snap(vec![]);
    let style = SceneStyle {
        coloring: Coloring::Velocity,
        ..Default::default()
    };
    let scene = RenderScene::build(&s, &style, &SceneFrame::of_snapshot(&s)).unwrap();
    let f = scene.field.clone().unwrap();
    assert_eq!((f.min, f.max), (0.0, 2.0));
    // Fixed block keeps the stone grey, the moving one takes the top of the map.
    assert_eq!(scene.solids[0].color, mesh::block_color(0, true));
    assert_eq!(scene.solids.last().unwrap().color, mesh::colormap(1.0));
}

#[test]
fn bad_input_is_an_error_or_skipped() {
    let mut s = snap(vec![contact(f64::NAN, ContactState::Lock)]);
    let frame = SceneFrame::of_snapshot(&s);
    let scene = RenderScene::build(&s, &SceneStyle::default(), &frame).unwrap();
    assert!(scene.arrows.is_empty());
    s.blocks[1].faces[0][0] = 42;
    let err = RenderScene::build(&s, &SceneStyle::default(), &frame).unwrap_err();
    assert!(err.to_string().contains("top"), "{err}");
    assert!(matches!(err, RenderError::InvalidSnapshot(_)));
}

#[test]
fn empty_snapshot_frames_a_unit_box() {
    let mut s = snap(vec![]);
    s.blocks.clear();
    let f = SceneFrame::of_snapshot(&s);
    assert!(f.size() > 1.0);
    assert!(RenderScene::build(&s, &SceneStyle::default(), &f).is_ok());
}

#[test]
fn arrows_stay_thin_next_to_small_blocks_in_a_big_scene() {
    let mut s = snap(vec![contact(1000.0, ContactState::Lock)]);
    // A 1 km fixed "slope" block and three 1 m cubes: the median block is 1 m across.
    s.blocks[0]
        .vertices
        .iter_mut()
        .for_each(|v| v.iter_mut().for_each(|x| *x *= 1000.0));
    s.blocks.push(cube("c2", [5.0, 0.0, 1.0], false));
    s.blocks.push(cube("c3", [7.0, 0.0, 1.0], false));
    let frame = SceneFrame::of_snapshot(&s);
    let scene = RenderScene::build(&s, &SceneStyle::default(), &frame).unwrap();
    let base = scene.to_local([0.0, 0.0, 1.0]);
    let radius = triangles(&scene)
        .iter()
        .map(|v| {
            let r = glam::Vec3::from(v.position) - base;
            r.truncate().length()
        })
        .fold(0.0f32, f32::max);
    // Head radius = 2.4 × shaft ≤ 2.4 × 0.06 × √3 m.
    assert!(radius < 0.3, "arrow radius {radius} m next to 1 m blocks");
}

#[test]
fn auto_scale_ties_the_longest_arrow_to_the_block_size() {
    // Two unit cubes (diagonal 1.73 m) far apart: the scene is 100 m, the arrow stays
    // block-sized instead of 20 m.
    let mut s = snap(vec![contact(5e4, ContactState::Lock)]);
    s.blocks[0] = cube("base", [100.0, 0.0, 0.0], true);
    let frame = SceneFrame::of_snapshot(&s);
    assert!(frame.size() > 90.0);
    let scene = RenderScene::build(&s, &SceneStyle::default(), &frame).unwrap();
    let longest = 5e4 / scene.force_scale.unwrap();
    let block = 3f64.sqrt();
    assert!(
        longest <= block + 1e-9 && longest > 0.4 * block,
        "{longest}"
    );
    // In a scene of a few blocks the fifth of the scene still rules.
    for (size, block) in [(2.0, 1.7), (50.0, 1.7), (1000.0, 20.0)] {
        let longest = 1e6 / auto_force_scale(1e6, size, block);
        assert!(longest <= (0.2 * size).min(block) + 1e-9);
        assert!(longest > 0.4 * (0.2 * size).min(block));
    }
}

#[test]
fn arrow_limit_keeps_the_strongest_contacts() {
    let forces = [10.0, -500.0, 30.0, 500.0, 20.0, 40.0];
    let all: Vec<ContactSnapshot> = forces
        .iter()
        .map(|&f| contact(f, ContactState::Lock))
        .collect();
    let s = snap(all);
    let frame = SceneFrame::of_snapshot(&s);
    let arrows = |limit| {
        let style = SceneStyle {
            arrow_limit: limit,
            ..SceneStyle::default()
        };
        RenderScene::build(&s, &style, &frame).unwrap()
    };
    let every = arrows(None);
    assert_eq!(every.arrows_shown, None);
    let three = arrows(Some(3));
    assert_eq!(three.arrows_shown, Some(3));
    // One instance per arrow: three arrows are half of six.
    assert_eq!(three.arrows.len() * 2, every.arrows.len());
    // The counts in the legend are of all contacts; the scale is the strongest one's.
    assert_eq!(three.contacts_lock, 6);
    assert_eq!(three.force_scale, every.force_scale);
    // The strongest three by |N|, in their order: -500, 500, 40.
    let mut kept: Vec<&ContactSnapshot> = s.contacts.iter().collect();
    strongest(&mut kept, Some(3));
    let f: Vec<f64> = kept.iter().map(|c| c.normal_force).collect();
    assert_eq!(f, vec![-500.0, 500.0, 40.0]);
    assert_eq!(arrows(Some(100)).arrows_shown, None);
}

#[test]
fn the_caption_carries_the_equilibrium_stage_only_while_it_runs() {
    let mut s = snap(vec![]);
    let caption = |s: &Snapshot| {
        RenderScene::build(s, &SceneStyle::default(), &SceneFrame::of_snapshot(s))
            .unwrap()
            .caption
    };
    assert_eq!(caption(&s).stage, None);
    let report = EquilibriumReport {
        steps: 37,
        residual: 1.245,
        tolerance: 1e-3,
        converged: false,
        running: true,
    };
    s.equilibrium = Some(report);
    assert_eq!(caption(&s).stage, Some((37, 1.245)));
    s.equilibrium = Some(EquilibriumReport {
        running: false,
        ..report
    });
    assert_eq!(caption(&s).stage, None);
}

/// The scene's arrows as the GPU draws them.
fn triangles(scene: &RenderScene) -> Vec<crate::render::mesh::SolidVertex> {
    scene.arrows.iter().flat_map(|a| a.triangles()).collect()
}
