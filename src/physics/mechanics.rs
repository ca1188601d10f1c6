//! Block kinematics and the block submatrices of Shi's 12-DOF first-order DDA.
//!
//! DOFs of a block (all increments over the current step, reference §0):
//! `[u_c, v_c, w_c, r_x, r_y, r_z, ε_x, ε_y, ε_z, γ_yz, γ_zx, γ_xy]`.

use nalgebra::{Matrix6, SMatrix, SVector, Vector6};

use crate::physics::geometry::{MassProperties, Mat3, Vec3};
use crate::physics::integrator::{Kinematics, Scheme};

pub type Mat12 = SMatrix<f64, 12, 12>;
pub type Vec12 = SVector<f64, 12>;
pub type Mat3x12 = SMatrix<f64, 3, 12>;

/// Isotropic elastic material.
#[derive(Clone, Copy, Debug, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    /// ρ, kg/m³.
    pub density: f64,
    /// E, Pa.
    pub young_modulus: f64,
    /// ν.
    pub poisson_ratio: f64,
}

/// T(x) of (1.1): the incremental displacement of the material point x is T(x) D, with
/// `rel = x − x_c` measured from the centroid at the start of the step.
pub fn displacement_matrix(rel: &Vec3) -> Mat3x12 {
    let (x, y, z) = (rel.x, rel.y, rel.z);
    #[rustfmt::skip]
    let t = Mat3x12::from_row_slice(&[
        1.0, 0.0, 0.0, 0.0,  z,   -y,  x,   0.0, 0.0, 0.0,     z / 2.0, y / 2.0,
        0.0, 1.0, 0.0, -z,   0.0, x,   0.0, y,   0.0, z / 2.0, 0.0,     x / 2.0,
        0.0, 0.0, 1.0, y,    -x,  0.0, 0.0, 0.0, z,   y / 2.0, x / 2.0, 0.0,
    ]);
    t
}

/// Mass matrix (3.1): M = ρ (V T0ᵀT0 + Σ_pq S_pq T_pᵀ T_q), exact because T is affine in x and
/// the first moments about the centroid vanish.
pub fn mass_matrix(density: f64, mp: &MassProperties) -> Mat12 {
    let t0 = displacement_matrix(&Vec3::zeros());
    let tp: [Mat3x12; 3] = [
        displacement_matrix(&Vec3::x()) - t0,
        displacement_matrix(&Vec3::y()) - t0,
        displacement_matrix(&Vec3::z()) - t0,
    ];
    let mut m = t0.transpose() * t0 * mp.volume;
    for p in 0..3 {
        for q in 0..3 {
            m += tp[p].transpose() * tp[q] * mp.second_moments[(p, q)];
        }
    }
    m * density
}

/// Isotropic elasticity matrix (1.2) for `[ε_x, ε_y, ε_z, γ_yz, γ_zx, γ_xy]`.
pub fn elasticity_matrix(e: f64, nu: f64) -> Matrix6<f64> {
    let f = e / ((1.0 + nu) * (1.0 - 2.0 * nu));
    let mut c = Matrix6::zeros();
    for i in 0..3 {
        for j in 0..3 {
            c[(i, j)] = f * if i == j { 1.0 - nu } else { nu };
        }
        c[(i + 3, i + 3)] = f * (1.0 - 2.0 * nu) / 2.0;
    }
    c
}

/// Symmetric strain tensor from `[ε_x, ε_y, ε_z, γ_yz, γ_zx, γ_xy]` (engineering shears).
pub fn strain_tensor(e: &[f64]) -> Mat3 {
    Mat3::new(
        e[0],
        e[5] / 2.0,
        e[4] / 2.0,
        e[5] / 2.0,
        e[1],
        e[3] / 2.0,
        e[4] / 2.0,
        e[3] / 2.0,
        e[2],
    )
}

/// Rodrigues rotation matrix of the rotation vector r.
pub fn rodrigues(r: &Vec3) -> Mat3 {
    let theta = r.norm();
    let k = r.cross_matrix();
    if theta < 1e-12 {
        return Mat3::identity() + k;
    }
    let k = k / theta;
    Mat3::identity() + k * theta.sin() + k * k * (1.0 - theta.cos())
}

/// The end-of-step map of a block's material points, (1.3): the rotation is applied exactly so a
/// spinning block does not grow (the linear T(x) D inflates it by √(1+|r|²) a step).
#[derive(Clone, Copy, Debug)]
pub struct StepMap {
    centroid: Vec3,
    translation: Vec3,
    rotation: Mat3,
    strain: Mat3,
}

impl StepMap {
    pub fn new(centroid: Vec3, d: &Vec12) -> Self {
        StepMap {
            centroid,
            translation: Vec3::new(d[0], d[1], d[2]),
            rotation: rodrigues(&Vec3::new(d[3], d[4], d[5])),
            strain: strain_tensor(&d.as_slice()[6..12]),
        }
    }

    pub fn apply(&self, x: &Vec3) -> Vec3 {
        let rel = x - self.centroid;
        self.centroid + self.translation + self.rotation * rel + self.strain * rel
    }

    pub fn rotation(&self) -> &Mat3 {
        &self.rotation
    }
}

/// Stress vector `[σ_x, σ_y, σ_z, τ_yz, τ_zx, τ_xy]` rotated as a tensor, R σ Rᵀ.
pub fn rotate_stress(s: &Vector6<f64>, r: &Mat3) -> Vector6<f64> {
    let t = Mat3::new(s[0], s[5], s[4], s[5], s[1], s[3], s[4], s[3], s[2]);
    let t = r * t * r.transpose();
    Vector6::new(
        t[(0, 0)],
        t[(1, 1)],
        t[(2, 2)],
        t[(1, 2)],
        t[(0, 2)],
        t[(0, 1)],
    )
}

/// Block-level terms of one step (reference §3), before contacts.
pub struct BlockTerms {
    pub k: Mat12,
    pub f: Vec12,
}

/// Everything §3 needs about one block at the start of a step.
pub struct BlockStepInput<'a> {
    pub mass_matrix: &'a Mat12,
    pub mp: &'a MassProperties,
    pub density: f64,
    pub elasticity: &'a Matrix6<f64>,
    pub stress: &'a Vector6<f64>,
    /// Velocity, acceleration and residual carried from the last step.
    pub kinematics: &'a Kinematics,
    /// How the step integrates them (Shi's (3.2) or generalized-α).
    pub scheme: &'a Scheme,
    pub gravity: &'a Vec3,
    /// Point loads: (current point, force).
    pub loads: &'a [(Vec3, Vec3)],
    /// Fixed-point springs: (current material point, anchor, stiffness N/m).
    pub springs: &'a [(Vec3, Vec3, f64)],
}

/// Assembles K_ii and F_i of (3.2)–(3.7).
pub fn block_terms(b: &BlockStepInput, dt: f64) -> BlockTerms {
    let xc = b.mp.centroid;
    // (3.2) inertia with constant acceleration over the step, or its generalized-α form (R4.3).
    let mut k = b.mass_matrix * b.scheme.mass_factor(dt);
    let mut f = b.scheme.inertia_load(b.mass_matrix, b.kinematics, dt);
    // (3.3) elastic stiffness and (3.4) carried stress.
    let v = b.mp.volume;
    let mut kss = k.fixed_view_mut::<6, 6>(6, 6);
    kss += b.elasticity * v;
    let mut fs = f.fixed_rows_mut::<6>(6);
    fs -= b.stress * v;
    // (3.5) gravity acts on the translations only (first moments vanish).
    let mass = b.density * v;
    for a in 0..3 {
        f[a] += mass * b.gravity[a];
    }
    // (3.6) point loads.
    for (p, force) in b.loads {
        f += displacement_matrix(&(p - xc)).transpose() * force;
    }
    // (3.7) fixed points on springs, with the restoring force of earlier drift.
    for (p, anchor, stiffness) in b.springs {
        let t = displacement_matrix(&(p - xc));
        k += t.transpose() * t * *stiffness;
        f += t.transpose() * (anchor - p) * *stiffness;
    }
    BlockTerms { k, f }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::geometry::{
        Topology, box_vertices, convex_hull, mass_properties, rotation_xyz_degrees,
    };

    fn sheared_block() -> (Vec<Vec3>, Topology) {
        let mut pts = box_vertices(
            [2.0, 1.5, 1.0],
            [0.4, -0.3, 2.0],
            &rotation_xyz_degrees([15.0, 25.0, -40.0]),
        );
        pts[0] += Vec3::new(0.2, 0.1, -0.15); // break the symmetry: a general hexahedron
        pts[5] += Vec3::new(-0.1, 0.2, 0.05);
        convex_hull(&pts).unwrap()
    }

    /// Integrates a function over the polyhedron by a degree-2 exact 4-point rule on each tetrahedron
    /// of the fan decomposition about the centroid.
    fn integrate<F: Fn(&Vec3) -> Mat12>(v: &[Vec3], t: &Topology, c: Vec3, f: F) -> Mat12 {
        let (a, b) = (0.5854101966249685, 0.1381966011250105);
        let mut sum = Mat12::zeros();
        for face in &t.faces {
            for m in 1..face.len() - 1 {
                let p = [c, v[face[0]], v[face[m]], v[face[m + 1]]];
                let vol = (p[1] - p[0]).dot(&(p[2] - p[0]).cross(&(p[3] - p[0]))) / 6.0;
                for q in 0..4 {
                    let mut x = Vec3::zeros();
                    for (r, pr) in p.iter().enumerate() {
                        x += pr * if r == q { a } else { b };
                    }
                    sum += f(&x) * (vol / 4.0);
                }
            }
        }
        sum
    }

    #[test]
    fn mass_matrix_equals_quadrature_and_is_spd() {
        let (v, t) = sheared_block();
        let mp = mass_properties(&v, &t.faces);
        let rho = 2750.0;
        let m = mass_matrix(rho, &mp);
        let q = integrate(&v, &t, mp.centroid, |x| {
            let tt = displacement_matrix(&(x - mp.centroid));
            tt.transpose() * tt * rho
        });
        assert!((m - q).norm() < 1e-10 * m.norm(), "{}", (m - q).norm());
        assert!((m - m.transpose()).norm() == 0.0);
        assert!(m.cholesky().is_some());
        // The rotational block is the inertia tensor ρ(tr S I − S).
        let s = mp.second_moments;
        let inertia = (Mat3::identity() * s.trace() - s) * rho;
        assert!((m.fixed_view::<3, 3>(3, 3) - inertia).norm() < 1e-9 * inertia.norm());
    }

    #[test]
    fn mass_matrix_entries_match_appendix_b() {
        let (v, t) = sheared_block();
        let mp = mass_properties(&v, &t.faces);
        let m = mass_matrix(1.0, &mp);
        let s = mp.second_moments;
        let (sxx, syy, szz, sxy, syz, szx) = (
            s[(0, 0)],
            s[(1, 1)],
            s[(2, 2)],
            s[(0, 1)],
            s[(1, 2)],
            s[(2, 0)],
        );
        let tol = 1e-12 * mp.volume;
        let checks = [
            ((3, 6 + 1), -syz),
            ((3, 6 + 2), syz),
            ((4, 6), szx),
            ((5, 6), -sxy),
            ((3, 9), (syy - szz) / 2.0),
            ((4, 10), (szz - sxx) / 2.0),
            ((5, 11), (sxx - syy) / 2.0),
            ((6, 10), szx / 2.0),
            ((9, 9), (syy + szz) / 4.0),
            ((9, 10), sxy / 4.0),
            ((10, 11), syz / 4.0),
        ];
        for ((r, c), want) in checks {
            assert!(
                (m[(r, c)] - want).abs() < tol,
                "M[{r},{c}] = {} want {want}",
                m[(r, c)]
            );
        }
    }

    /// Central finite-difference gradient of a scalar function of D.
    fn fd_gradient<F: Fn(&Vec12) -> f64>(f: F, d: &Vec12, h: f64) -> Vec12 {
        let mut g = Vec12::zeros();
        for a in 0..12 {
            let mut p = *d;
            p[a] += h;
            let mut m = *d;
            m[a] -= h;
            g[a] = (f(&p) - f(&m)) / (2.0 * h);
        }
        g
    }

    /// The block terms must be the Hessian and minus the gradient at D = 0 of the step's total
    /// potential, written out independently here from its physical definition.
    #[test]
    fn block_terms_are_derivatives_of_the_potential() {
        let (v, t) = sheared_block();
        let mp = mass_properties(&v, &t.faces);
        let rho = 2750.0;
        let m = mass_matrix(rho, &mp);
        let c = elasticity_matrix(2e10, 0.25);
        let stress = Vector6::new(1e5, -2e5, 3e4, 5e4, -1e4, 2e4);
        let vel = Vec12::from_fn(|r, _| 0.1 * (r as f64 + 1.0).sin());
        let g = Vec3::new(0.3, -0.2, -9.8);
        let loads = [(v[2], Vec3::new(1e4, -3e3, 2e3))];
        let springs = [
            (v[1] + Vec3::new(1e-4, 0.0, 0.0), v[1], 4e12),
            (v[4], v[4], 4e12),
        ];
        let dt = 0.01;
        let kinematics = Kinematics {
            velocity: vel,
            ..Kinematics::at_rest()
        };
        let input = BlockStepInput {
            mass_matrix: &m,
            mp: &mp,
            density: rho,
            elasticity: &c,
            stress: &stress,
            kinematics: &kinematics,
            scheme: &Scheme::SHI,
            gravity: &g,
            loads: &loads,
            springs: &springs,
        };
        let terms = block_terms(&input, dt);
        let xc = mp.centroid;
        let potential = |d: &Vec12| -> f64 {
            // Inertia: ½ ∫ρ|u − v0 t|² ... reduces to D'MD/dt² − 2 D'M v0/dt (constant acceleration).
            let inertia =
                (d.transpose() * m * d)[0] / (dt * dt) - 2.0 / dt * (d.transpose() * m * vel)[0];
            let eps = d.fixed_rows::<6>(6);
            let elastic = mp.volume * (0.5 * (eps.transpose() * c * eps)[0] + eps.dot(&stress));
            // Gravity as minus the work of ρg over the body, by quadrature.
            let grav = -integrate(&v, &t, xc, |x| {
                let u = displacement_matrix(&(x - xc)) * d;
                Mat12::from_element(u.dot(&g) * rho)
            })[(0, 0)];
            let load: f64 = loads
                .iter()
                .map(|(p, f)| -(displacement_matrix(&(p - xc)) * d).dot(f))
                .sum();
            let spring: f64 = springs
                .iter()
                .map(|(p, a, k)| {
                    0.5 * k * (p + displacement_matrix(&(p - xc)) * d - a).norm_squared()
                })
                .sum();
            inertia + elastic + grav + load + spring
        };
        let d0 = Vec12::from_fn(|r, _| 1e-4 * ((r * 7 % 5) as f64 - 2.0));
        let grad = fd_gradient(potential, &d0, 1e-7);
        let want = terms.k * d0 - terms.f;
        assert!(
            (grad - want).norm() < 1e-6 * want.norm().max(terms.f.norm()),
            "gradient mismatch {}",
            (grad - want).norm()
        );
        // Hessian by differencing the gradient.
        for a in 0..12 {
            let mut dp = d0;
            dp[a] += 1e-6;
            let col = (fd_gradient(potential, &dp, 1e-7) - grad) / 1e-6;
            let err = (col - terms.k.column(a)).norm();
            assert!(
                err < 1e-4 * terms.k.column(a).norm(),
                "Hessian column {a}: {err}"
            );
        }
    }

    #[test]
    fn step_map_keeps_volume_under_large_rotation() {
        let (mut v, t) = sheared_block();
        let v0 = mass_properties(&v, &t.faces).volume;
        let mut lin = v.clone();
        for _ in 0..100 {
            let mp = mass_properties(&v, &t.faces);
            let mut d = Vec12::zeros();
            d[3] = 0.02 * 0.6;
            d[5] = 0.02 * 0.8;
            let map = StepMap::new(mp.centroid, &d);
            v = v.iter().map(|x| map.apply(x)).collect();
            let mpl = mass_properties(&lin, &t.faces);
            lin = lin
                .iter()
                .map(|x| x + displacement_matrix(&(x - mpl.centroid)) * d)
                .collect();
        }
        let v1 = mass_properties(&v, &t.faces).volume;
        assert!((v1 / v0 - 1.0).abs() < 1e-12);
        // The linear update inflates by (1 + r²)^100, here 4 %.
        let vl = mass_properties(&lin, &t.faces).volume;
        assert!(
            ((vl / v0) - 1.0004f64.powi(100)).abs() < 1e-9,
            "{}",
            vl / v0
        );
    }

    #[test]
    fn rodrigues_small_and_large() {
        let r = Vec3::new(0.3, -0.4, 1.2);
        let m = rodrigues(&r);
        assert!((m * m.transpose() - Mat3::identity()).norm() < 1e-14);
        assert!((m * r - r).norm() < 1e-14);
        assert!((m.determinant() - 1.0).abs() < 1e-14);
        let s = Vector6::new(1.0, 2.0, 3.0, 0.5, -0.2, 0.1);
        let rs = rotate_stress(&s, &m);
        // The trace (mean stress) is invariant.
        assert!(((rs[0] + rs[1] + rs[2]) - 6.0).abs() < 1e-12);
    }
}
