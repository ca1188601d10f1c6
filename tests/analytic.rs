//! Closed-form checks of the integrator and the kinematics (reference §9(d)).

use dda3d::model::{Block, Model};
use dda3d::params::{Mode, SolverParams};
use dda3d::physics::geometry::{
    Mat3, Vec3, box_vertices, convex_hull, mass_properties, rotation_xyz_degrees,
};
use dda3d::physics::mechanics::Material;
use dda3d::solver::Solver;

const ROCK: Material = Material {
    density: 2750.0,
    young_modulus: 2.0e10,
    poisson_ratio: 0.25,
};

fn single(center: [f64; 3], velocity: Vec3, spin: Vec3, params: SolverParams) -> Solver {
    let pts = box_vertices(
        [1.0, 2.0, 0.5],
        center,
        &rotation_xyz_degrees([10.0, 20.0, 30.0]),
    );
    let (v, t) = convex_hull(&pts).unwrap();
    let b = Block::new("b".into(), ROCK, false, v, t, velocity, spin, vec![]);
    Solver::new(Model::new("single", vec![b]), params)
}

/// The constant-acceleration scheme (3.2) is exact for a constant force: a projectile must follow
/// x0 + v0 t + ½ g t² to round-off, whatever the step sizes the controller picks. In open space
/// it flies at Δt_max (δ·w0 does not hold back a block in free flight); beside a fixed wall,
/// 0.2 m away and so inside the contact search distance, δ·w0 shortens its steps.
#[test]
fn projectile_is_exact() {
    for beside_wall in [false, true] {
        let params = SolverParams {
            duration: 2.0,
            ..Default::default()
        };
        let v0 = Vec3::new(3.0, 0.0, 10.0);
        let mut s = single([0.0, 0.0, 5.0], v0, Vec3::zeros(), params);
        if beside_wall {
            let y_min = s.model.blocks[0].lo.y;
            let (v, t) = convex_hull(&box_vertices(
                [12.0, 1.0, 12.0],
                [3.0, y_min - 0.7, 6.0],
                &Mat3::identity(),
            ))
            .unwrap();
            let wall = Block::new(
                "wall".into(),
                ROCK,
                true,
                v,
                t,
                Vec3::zeros(),
                Vec3::zeros(),
                vec![],
            );
            s = Solver::new(
                Model::new("beside a wall", vec![s.model.blocks[0].clone(), wall]),
                s.params.clone(),
            );
        }
        let x0 = Vec3::from(s.snapshot().blocks[0].centroid);
        while !s.finished() {
            s.step().unwrap();
        }
        let x = Vec3::from(s.snapshot().blocks[0].centroid);
        let want = x0 + v0 * 2.0 + Vec3::new(0.0, 0.0, -9.8) * 2.0;
        assert!(
            (x - want).norm() < 1e-9,
            "error {:e} m after {} steps",
            (x - want).norm(),
            s.step
        );
        let v = Vec3::from(s.snapshot().blocks[0].velocity);
        assert!((v - Vec3::new(3.0, 0.0, 10.0 - 19.6)).norm() < 1e-9);
        if beside_wall {
            assert!(
                s.step > 220,
                "beside the wall δ·w0 must have shortened the steps: {}",
                s.step
            );
        } else {
            assert_eq!(s.step, 200, "free flight at Δt_max");
        }
    }
}

/// Static mode resets the velocity each step: a free block creeps by ½ g Δt² per step instead of
/// falling freely.
#[test]
fn static_mode_discards_velocity() {
    let params = SolverParams {
        duration: 0.1,
        mode: Mode::Static,
        ..Default::default()
    };
    let mut s = single([0.0, 0.0, 5.0], Vec3::zeros(), Vec3::zeros(), params);
    let z0 = s.snapshot().blocks[0].centroid[2];
    while !s.finished() {
        s.step().unwrap();
    }
    let drop = z0 - s.snapshot().blocks[0].centroid[2];
    assert!(
        (drop - 10.0 * 0.5 * 9.8 * 0.01f64.powi(2)).abs() < 1e-12,
        "{drop}"
    );
}

/// A block spinning freely (no gravity) keeps its volume with the Rodrigues update (1.3) and
/// does not gain energy.
#[test]
fn free_rotation_keeps_volume_and_energy() {
    let params = SolverParams {
        duration: 1.0,
        gravity: [0.0; 3],
        ..Default::default()
    };
    let mut s = single([0.0; 3], Vec3::zeros(), Vec3::new(0.0, 0.0, 2.0), params);
    let angle = |s: &Solver| {
        let b = &s.model.blocks[0];
        let d = b.vertices[0] - b.mp.centroid;
        d.y.atan2(d.x)
    };
    let b0 = &s.model.blocks[0];
    let v0 = mass_properties(&b0.vertices, &b0.topo.faces).volume;
    let e0 = s.last.kinetic_energy;
    let a0 = angle(&s);
    while !s.finished() {
        s.step().unwrap();
    }
    let b = &s.model.blocks[0];
    let v1 = mass_properties(&b.vertices, &b.topo.faces).volume;
    assert!((v1 / v0 - 1.0).abs() < 1e-9, "volume ratio {}", v1 / v0);
    let e1 = s.last.kinetic_energy;
    assert!(e1 <= e0 * (1.0 + 1e-9), "energy grew from {e0} to {e1}");
    assert!(
        e1 > 0.9 * e0,
        "free rotation is nearly conservative: {e0} → {e1}"
    );
    // 2 rad/s about the vertical for 1 s turns a vertex about the z axis through 2 rad.
    let turned = (angle(&s) - a0).rem_euclid(std::f64::consts::TAU);
    assert!((turned - 2.0).abs() < 0.02, "turned {turned} rad");
    assert!(b.mp.centroid.norm() < 1e-9);
}

/// A point load adds F/m to the centroid's acceleration (3.6), through the centroid or off it (then
/// it also spins the block).
#[test]
fn point_load_accelerates_the_centroid() {
    let params = SolverParams {
        duration: 0.5,
        ..Default::default()
    };
    for offset in [Vec3::zeros(), Vec3::new(0.3, -0.2, 0.1)] {
        let pts = box_vertices(
            [1.0, 2.0, 0.5],
            [0.0, 0.0, 5.0],
            &rotation_xyz_degrees([0.0; 3]),
        );
        let (v, t) = convex_hull(&pts).unwrap();
        let c = mass_properties(&v, &t.faces).centroid;
        let force = Vec3::new(2.0e5, 0.0, 1.0e5);
        let b = Block::new(
            "b".into(),
            ROCK,
            false,
            v,
            t,
            Vec3::zeros(),
            Vec3::zeros(),
            vec![(c + offset, force)],
        );
        let m = b.mass;
        let mut s = Solver::new(Model::new("load", vec![b]), params.clone());
        let x0 = Vec3::from(s.snapshot().blocks[0].centroid);
        while !s.finished() {
            s.step().unwrap();
        }
        let x = Vec3::from(s.snapshot().blocks[0].centroid);
        // A dead load keeps its direction while the block spins, so the centroid's motion is
        // exact either way.
        let a = force / m + Vec3::new(0.0, 0.0, -9.8);
        let want = x0 + a * 0.5 * 0.25;
        assert!(
            (x - want).norm() < 1e-9,
            "offset {offset:?}: error {:e} m",
            (x - want).norm()
        );
    }
}
