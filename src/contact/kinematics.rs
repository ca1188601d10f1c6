//! The kinematics of a closed contact, linearised over a step: the normal distance
//! (P3)–(P8), and the stiffness and force terms each contact adds to the two blocks' rows of the
//! global system, (P10) normal, (P15)/(5.7) shear spring of a locked contact, (P20) sliding
//! friction. Pure functions of frozen geometry; each is checked against finite differences of
//! its potential below.

use super::ContactMode;
use crate::physics::geometry::Vec3;
use crate::physics::mechanics::{Mat3x12, Mat12, Vec12, displacement_matrix};

/// Linearised normal distance of (5.1)–(5.4): d_n = d0 + G_i D_i + G_j D_j, penetration positive.
#[derive(Clone, Copy, Debug)]
pub struct NormalKinematics {
    pub d0: f64,
    pub g_i: Vec12,
    pub g_j: Vec12,
    /// A0 of (P4), frozen for the step.
    pub a0: f64,
}

impl NormalKinematics {
    /// d_n for the blocks' displacement increments `di`, `dj` (5.4).
    pub fn penetration(&self, di: &Vec12, dj: &Vec12) -> f64 {
        self.d0 + self.g_i.dot(di) + self.g_j.dot(dj)
    }
}

/// Cofactor gradients c_r = ∂V0/∂P_r of the determinant (5.1)–(5.2).
fn cofactors(p: &[Vec3; 4]) -> [Vec3; 4] {
    let [p1, p2, p3, p4] = *p;
    [
        -(p3 - p2).cross(&(p4 - p2)),
        (p3 - p1).cross(&(p4 - p1)),
        (p4 - p1).cross(&(p2 - p1)),
        (p2 - p1).cross(&(p3 - p1)),
    ]
}

/// V0 of (5.1).
pub fn determinant(p: &[Vec3; 4]) -> f64 {
    (p[1] - p[0]).dot(&(p[2] - p[0]).cross(&(p[3] - p[0])))
}

/// d0, G_i, G_j of (P6)–(P8) with the sign fixed by (5.3): translating block i along +n must
/// reduce the penetration. `ci`, `cj` are the centroids of the two blocks at the start of the step.
pub fn normal_kinematics(
    mode: ContactMode,
    p: &[Vec3; 4],
    n: &Vec3,
    ci: &Vec3,
    cj: &Vec3,
) -> NormalKinematics {
    let c = cofactors(p);
    let (on_i, a0): (&[usize], f64) = match mode {
        ContactMode::VertexFace => (&[0], (p[2] - p[1]).cross(&(p[3] - p[1])).norm()),
        ContactMode::EdgeEdge => (&[0, 1], (p[1] - p[0]).cross(&(p[3] - p[2])).norm()),
    };
    let sum_i: Vec3 = on_i.iter().map(|&r| c[r]).sum();
    let sigma = if n.dot(&sum_i) > 0.0 { -1.0 } else { 1.0 };
    let mut g_i = Vec12::zeros();
    let mut g_j = Vec12::zeros();
    for r in 0..4 {
        if on_i.contains(&r) {
            g_i += displacement_matrix(&(p[r] - ci)).transpose() * c[r];
        } else {
            g_j += displacement_matrix(&(p[r] - cj)).transpose() * c[r];
        }
    }
    NormalKinematics {
        d0: sigma * determinant(p) / a0,
        g_i: g_i * (sigma / a0),
        g_j: g_j * (sigma / a0),
        a0,
    }
}

/// Stiffness contributions of one contact to the blocks i and j. Kept apart from the forces:
/// the ALM iterations that only update λ rebuild the forces alone, and zeroing and moving these
/// three 12×12 blocks for every contact of every iteration cost more than the forces themselves.
#[derive(Clone, Debug, Default)]
pub struct ContactStiffness {
    pub k_ii: Mat12,
    pub k_ij: Mat12,
    pub k_jj: Mat12,
}

/// One of the three 12×12 blocks of a contact's stiffness. Each block is formed on its own, by
/// the same operations whether one block or all three are asked for, so K assembled block by
/// block (on the pool, `crate::solver::assemble`) is K assembled contact by contact to the bit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StiffnessBlock {
    /// K_ii, block i's own rows and columns.
    Ii,
    /// K_ij, block i's rows and block j's columns.
    Ij,
    /// K_jj.
    Jj,
}

impl ContactStiffness {
    /// The three blocks, each with which it is.
    pub fn blocks_mut(&mut self) -> [(&mut Mat12, StiffnessBlock); 3] {
        [
            (&mut self.k_ii, StiffnessBlock::Ii),
            (&mut self.k_ij, StiffnessBlock::Ij),
            (&mut self.k_jj, StiffnessBlock::Jj),
        ]
    }
}

/// Force contributions of one contact to the blocks i and j.
#[derive(Clone, Debug, Default)]
pub struct ContactForces {
    pub f_i: Vec12,
    pub f_j: Vec12,
}

/// Normal stiffness of a closed contact, (P10a)–(P10d).
pub fn add_normal_stiffness(t: &mut ContactStiffness, k: &NormalKinematics, penalty: f64) {
    for (m, which) in t.blocks_mut() {
        add_normal_stiffness_block(m, which, k, penalty);
    }
}

/// The block `which` of [`add_normal_stiffness`].
pub fn add_normal_stiffness_block(
    m: &mut Mat12,
    which: StiffnessBlock,
    k: &NormalKinematics,
    penalty: f64,
) {
    match which {
        StiffnessBlock::Ii => *m += k.g_i * k.g_i.transpose() * penalty,
        StiffnessBlock::Ij => *m += k.g_i * k.g_j.transpose() * penalty,
        StiffnessBlock::Jj => *m += k.g_j * k.g_j.transpose() * penalty,
    }
}

/// Normal force terms of a closed contact, (P10e)–(P10f): −(λ_{k−1} + p_n d0) G.
pub fn add_normal_force(t: &mut ContactForces, k: &NormalKinematics, penalty: f64, lambda: f64) {
    let s = lambda + penalty * k.d0;
    t.f_i -= k.g_i * s;
    t.f_j -= k.g_j * s;
}

/// Tangential spring of a locked contact, (P15) as corrected in (5.7): the potential
/// ½ p_τ rᵀ N r with r = Δ + T_a D_i − T_b D_j and N = I − n nᵀ. Its stiffness:
pub fn add_shear_spring_stiffness(
    t: &mut ContactStiffness,
    ta: &Mat3x12,
    tb: &Mat3x12,
    n: &Vec3,
    p_tau: f64,
) {
    for (m, which) in t.blocks_mut() {
        add_shear_spring_stiffness_block(m, which, ta, tb, n, p_tau);
    }
}

/// The block `which` of [`add_shear_spring_stiffness`].
pub fn add_shear_spring_stiffness_block(
    m: &mut Mat12,
    which: StiffnessBlock,
    ta: &Mat3x12,
    tb: &Mat3x12,
    n: &Vec3,
    p_tau: f64,
) {
    let proj = nalgebra::Matrix3::identity() - n * n.transpose();
    add_projected_stiffness(m, which, ta, tb, &proj, p_tau);
}

/// The block `which` of the stiffness of a tangential spring `k` acting on the part `proj` of
/// Δu_ab = T_a D_i − T_b D_j.
fn add_projected_stiffness(
    m: &mut Mat12,
    which: StiffnessBlock,
    ta: &Mat3x12,
    tb: &Mat3x12,
    proj: &nalgebra::Matrix3<f64>,
    k: f64,
) {
    match which {
        StiffnessBlock::Ii => *m += ta.transpose() * (proj * ta) * k,
        StiffnessBlock::Ij => *m -= ta.transpose() * (proj * tb) * k,
        StiffnessBlock::Jj => *m += tb.transpose() * (proj * tb) * k,
    }
}

/// The tangent stiffness of sliding friction's direction. Friction of magnitude F along the slip
/// s, F s/|s|, changes with s across τ = s/|s| at the rate (F/|s|)(I − ττᵀ) (see the test
/// below): `lateral` = F/|s| acting on the tangential slip across τ, the Newton linearization of
/// the direction. Without it the direction is a fixed point, τ taken from the last solve's slip;
/// that iteration diverges while the slip of a step is small against the motion friction itself
/// gives in a step, F Δt²/(2m): a slab starting to slide from rest yawed, its corners' slips
/// turned against their friction, they stuck, and a stack of three slabs on a joint at a factor
/// of safety of 0.67 stood.
pub fn add_friction_tangent(
    t: &mut ContactStiffness,
    ta: &Mat3x12,
    tb: &Mat3x12,
    n: &Vec3,
    tau: &Vec3,
    lateral: f64,
) {
    for (m, which) in t.blocks_mut() {
        add_friction_tangent_block(m, which, ta, tb, n, tau, lateral);
    }
}

/// The block `which` of [`add_friction_tangent`].
pub fn add_friction_tangent_block(
    m: &mut Mat12,
    which: StiffnessBlock,
    ta: &Mat3x12,
    tb: &Mat3x12,
    n: &Vec3,
    tau: &Vec3,
    lateral: f64,
) {
    let proj = nalgebra::Matrix3::identity() - n * n.transpose() - tau * tau.transpose();
    add_projected_stiffness(m, which, ta, tb, &proj, lateral);
}

/// The force of the tangential spring of [`add_shear_spring_stiffness`] at D = 0:
/// −p_τ T_aᵀ N Δ on i and +p_τ T_bᵀ N Δ on j.
pub fn add_shear_spring_force(
    t: &mut ContactForces,
    ta: &Mat3x12,
    tb: &Mat3x12,
    n: &Vec3,
    delta: &Vec3,
    p_tau: f64,
) {
    let nd = (delta - n * n.dot(delta)) * p_tau;
    t.f_i -= ta.transpose() * nd;
    t.f_j += tb.transpose() * nd;
}

/// Sliding friction (P20): a force of magnitude `friction` opposing the slip direction τ of
/// point a relative to point b. Loads only; the stiffness stays symmetric.
pub fn add_friction(t: &mut ContactForces, ta: &Mat3x12, tb: &Mat3x12, tau: &Vec3, friction: f64) {
    t.f_i -= ta.transpose() * tau * friction;
    t.f_j += tb.transpose() * tau * friction;
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::geometry::{Mat3, rotation_xyz_degrees};

    #[test]
    fn the_friction_tangent_is_the_derivative_of_friction_along_the_slip() {
        // F(s) = F s/|s| for tangential slips s (normal z), differentiated by central
        // differences, against (F/|s|)(I − ττᵀ − nnᵀ) of `add_friction_tangent`.
        let n = Vec3::z();
        let f = 3.0e5;
        let force = |s: &Vec3| s * (f / s.norm());
        for s0 in [Vec3::new(1e-4, 0.0, 0.0), Vec3::new(-2e-3, 5e-4, 0.0)] {
            let tau = s0.normalize();
            let want = (nalgebra::Matrix3::identity() - n * n.transpose() - tau * tau.transpose())
                * (f / s0.norm());
            for (k, e) in [Vec3::x(), Vec3::y()].iter().enumerate() {
                let h = 1e-7 * s0.norm();
                let fd = (force(&(s0 + e * h)) - force(&(s0 - e * h))) / (2.0 * h);
                let col = want.column(k);
                assert!((fd - col).norm() < 1e-6 * want.norm(), "{fd} against {col}");
            }
        }
        // In block coordinates: a pure translation of i across τ meets k⊥, along τ nothing.
        let (ta, tb) = (
            crate::physics::mechanics::displacement_matrix(&Vec3::new(0.3, -0.2, 0.0)),
            crate::physics::mechanics::displacement_matrix(&Vec3::new(-0.5, 0.1, 0.0)),
        );
        let mut t = ContactStiffness::default();
        add_friction_tangent(&mut t, &ta, &tb, &n, &Vec3::x(), 2.0);
        let mut d = Vec12::zeros();
        d[1] = 1.0;
        assert!(((t.k_ii * d)[1] - 2.0).abs() < 1e-12);
        d[1] = 0.0;
        d[0] = 1.0;
        assert!((t.k_ii * d).norm() < 1e-12);
    }

    #[test]
    fn signed_distance_of_a_vertex_above_and_inside_a_face() {
        // Face z = 0 of a unit cube below, CCW from outside (normal +z).
        let face = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        let n = Vec3::z();
        for (h, want) in [(0.001, -0.001), (-0.001, 0.001), (0.3, -0.3), (-0.05, 0.05)] {
            let p1 = Vec3::new(0.4, 0.3, h);
            let p = [p1, face[0], face[1], face[2]];
            // Raw determinant: V0/A0 = −gap (the paper's literal (P3) sign gives the gap).
            let a0 = (face[1] - face[0]).cross(&(face[2] - face[0])).norm();
            assert!((determinant(&p) / a0 + h).abs() < 1e-15);
            let k = normal_kinematics(
                ContactMode::VertexFace,
                &p,
                &n,
                &Vec3::new(0.5, 0.5, 0.5),
                &Vec3::new(0.5, 0.5, -0.5),
            );
            assert!((k.d0 - want).abs() < 1e-15, "h = {h}: d0 = {}", k.d0);
            // Translating the vertex block along +n reduces the penetration one for one.
            assert!((k.g_i[2] + 1.0).abs() < 1e-14);
            assert!((k.g_j[2] - 1.0).abs() < 1e-14);
        }
        // The sign does not depend on the order of the face triple.
        let p = [Vec3::new(0.4, 0.3, -0.002), face[2], face[1], face[0]];
        let k = normal_kinematics(
            ContactMode::VertexFace,
            &p,
            &n,
            &Vec3::zeros(),
            &Vec3::zeros(),
        );
        assert!((k.d0 - 0.002).abs() < 1e-15);
    }

    #[test]
    fn edge_edge_distance() {
        // Edge of i along x at height h above an edge of j along y.
        let h = 0.1;
        let p = [
            Vec3::new(-1.0, 0.0, h),
            Vec3::new(1.0, 0.0, h),
            Vec3::new(0.0, -1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        let k = normal_kinematics(
            ContactMode::EdgeEdge,
            &p,
            &Vec3::z(),
            &Vec3::new(0.0, 0.0, 1.0),
            &Vec3::new(0.0, 0.0, -1.0),
        );
        assert!((k.d0 + h).abs() < 1e-15);
        let k2 = normal_kinematics(
            ContactMode::EdgeEdge,
            &[p[0], p[1], p[3], p[2]],
            &Vec3::z(),
            &Vec3::z(),
            &Vec3::z(),
        );
        assert!((k2.d0 + h).abs() < 1e-15, "independent of edge direction");
    }

    /// G must be the derivative of the exact determinant distance σ V0(P + T D)/A0 (A0 frozen)
    /// for arbitrary increments, including rotations and strains, for both entrance modes.
    #[test]
    fn linearised_distance_matches_finite_differences() {
        let r = rotation_xyz_degrees([10.0, -20.0, 30.0]);
        let ci = Vec3::new(0.3, 0.1, 1.2);
        let cj = Vec3::new(-0.2, 0.4, -0.9);
        let cases = [
            (
                ContactMode::VertexFace,
                [
                    Vec3::new(0.2, 0.1, 0.01),
                    Vec3::new(-1.0, -1.0, 0.0),
                    Vec3::new(1.2, -0.8, 0.0),
                    Vec3::new(0.1, 1.1, 0.0),
                ],
            ),
            (
                ContactMode::EdgeEdge,
                [
                    Vec3::new(-1.0, 0.2, -0.02),
                    Vec3::new(1.0, 0.1, 0.03),
                    Vec3::new(0.1, -1.0, 0.0),
                    Vec3::new(-0.2, 1.0, 0.0),
                ],
            ),
        ];
        for (mode, pts) in cases {
            let pts = pts.map(|x| r * x);
            let n = match mode {
                ContactMode::VertexFace => r * Vec3::z(),
                ContactMode::EdgeEdge => {
                    let m = (pts[1] - pts[0]).cross(&(pts[3] - pts[2])).normalize();
                    if m.dot(&(r * Vec3::z())) > 0.0 { m } else { -m }
                }
            };
            let k = normal_kinematics(mode, &pts, &n, &ci, &cj);
            let on_i = |r: usize| r == 0 || (mode == ContactMode::EdgeEdge && r == 1);
            let sigma = k.d0 / (determinant(&pts) / k.a0);
            let exact = |di: &Vec12, dj: &Vec12| {
                let moved: [Vec3; 4] = std::array::from_fn(|r| {
                    let (c, d) = if on_i(r) { (ci, di) } else { (cj, dj) };
                    pts[r] + displacement_matrix(&(pts[r] - c)) * d
                });
                sigma * determinant(&moved) / k.a0
            };
            let h = 1e-7;
            for a in 0..12 {
                let mut e = Vec12::zeros();
                e[a] = h;
                let z = Vec12::zeros();
                let gi = (exact(&e, &z) - exact(&-e, &z)) / (2.0 * h);
                let gj = (exact(&z, &e) - exact(&z, &-e)) / (2.0 * h);
                assert!(
                    (gi - k.g_i[a]).abs() < 1e-6,
                    "{mode:?} G_i[{a}] {gi} vs {}",
                    k.g_i[a]
                );
                assert!(
                    (gj - k.g_j[a]).abs() < 1e-6,
                    "{mode:?} G_j[{a}] {gj} vs {}",
                    k.g_j[a]
                );
            }
            // Translating i along n reduces the penetration.
            let mut t = Vec12::zeros();
            t.fixed_rows_mut::<3>(0).copy_from(&(n * 1e-3));
            assert!(exact(&t, &Vec12::zeros()) < k.d0);
        }
    }

    /// Each contact submatrix is the Hessian, and its force minus the gradient at D = 0, of the
    /// contact potential: (P2) with the linearised d_n, (P11) with the projected relative
    /// displacement, (P16) for sliding friction.
    #[test]
    fn contact_submatrices_are_derivatives_of_their_potentials() {
        let r = rotation_xyz_degrees([5.0, 12.0, -7.0]);
        let ci = Vec3::new(0.0, 0.2, 0.7);
        let cj = Vec3::new(0.1, -0.3, -1.1);
        let pts = [
            Vec3::new(0.2, 0.1, -0.002),
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.2, -0.8, 0.0),
            Vec3::new(0.1, 1.1, 0.0),
        ]
        .map(|x| r * x);
        let n = r * Vec3::z();
        let k = normal_kinematics(ContactMode::VertexFace, &pts, &n, &ci, &cj);
        let (p, lambda) = (3.0e8, 1.5e4);
        let xa = pts[0];
        let xb = xa - n * 0.0015 + r * Vec3::new(2e-4, -1e-4, 0.0);
        let ta = displacement_matrix(&(xa - ci));
        let tb = displacement_matrix(&(xb - cj));
        let delta = xa - xb;
        let tau = (r * Vec3::new(0.6, 0.8, 0.0)).normalize();
        let (p_tau, fric) = (1.2e8, 7.0e3);
        let mut t = ContactStiffness::default();
        add_normal_stiffness(&mut t, &k, p);
        add_shear_spring_stiffness(&mut t, &ta, &tb, &n, p_tau);
        let mut f = ContactForces::default();
        add_normal_force(&mut f, &k, p, lambda);
        add_shear_spring_force(&mut f, &ta, &tb, &n, &delta, p_tau);
        add_friction(&mut f, &ta, &tb, &tau, fric);
        let proj = Mat3::identity() - n * n.transpose();
        let potential = |d: &[f64; 24]| {
            let di = Vec12::from_column_slice(&d[..12]);
            let dj = Vec12::from_column_slice(&d[12..]);
            let dn = k.d0 + k.g_i.dot(&di) + k.g_j.dot(&dj);
            let rr = delta + ta * di - tb * dj;
            let slip = ta * di - tb * dj;
            lambda * dn
                + 0.5 * p * dn * dn
                + 0.5 * p_tau * rr.dot(&(proj * rr))
                + fric * tau.dot(&slip)
        };
        let h = 1e-6;
        let z = [0.0; 24];
        let grad = |d0: &[f64; 24]| -> [f64; 24] {
            std::array::from_fn(|a| {
                let mut dp = *d0;
                dp[a] += h;
                let mut dm = *d0;
                dm[a] -= h;
                (potential(&dp) - potential(&dm)) / (2.0 * h)
            })
        };
        let g0 = grad(&z);
        let f: Vec<f64> = f.f_i.iter().chain(f.f_j.iter()).copied().collect();
        for a in 0..24 {
            assert!(
                (g0[a] + f[a]).abs() < 1e-6 * f.iter().map(|x| x.abs()).fold(0.0, f64::max),
                "force {a}: {} vs {}",
                -g0[a],
                f[a]
            );
        }
        let mut kfull = nalgebra::DMatrix::<f64>::zeros(24, 24);
        kfull.view_mut((0, 0), (12, 12)).copy_from(&t.k_ii);
        kfull.view_mut((0, 12), (12, 12)).copy_from(&t.k_ij);
        kfull
            .view_mut((12, 0), (12, 12))
            .copy_from(&t.k_ij.transpose());
        kfull.view_mut((12, 12), (12, 12)).copy_from(&t.k_jj);
        let scale = kfull.abs().max();
        for b in 0..24 {
            let mut e = z;
            e[b] = 1e-3;
            let gp = grad(&e);
            for a in 0..24 {
                let fd = (gp[a] - g0[a]) / 1e-3;
                assert!(
                    (fd - kfull[(a, b)]).abs() < 1e-6 * scale,
                    "K[{a},{b}] {fd} vs {}",
                    kfull[(a, b)]
                );
            }
        }
    }
}
