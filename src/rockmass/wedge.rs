//! The Hoek–Bray tetrahedral wedge, friction only, dry, no cohesion or tension crack
//! (`shared/docs/rock-mass-reference.md` §3): the line of intersection, the normal reactions, the
//! factor of safety, the sliding acceleration, kinematic admissibility and the wedge's corners.
//! It is the analytic oracle that DDA runs of a wedge are checked against.

use super::orientation::{Vec3, apparent_dip, dip_vector, pole, trend_and_plunge};

/// How the wedge moves (or would move) once friction is overcome.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sliding {
    /// On both planes, along the line of intersection.
    TwoPlanes,
    /// On A alone, down A's dip vector, lifting off B.
    OnA,
    /// On B alone, down B's dip vector, lifting off A.
    OnB,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WedgeSolution {
    /// Unit line of intersection of A and B, pointing down (z ≤ 0), (R3.1).
    pub line: Vec3,
    /// Trend and plunge of the line, degrees.
    pub trend: f64,
    pub plunge: f64,
    /// Normal reactions on A and B divided by the weight W. For two-plane sliding these are
    /// (R3.2); when (R3.2) gives one of them ≤ 0 the wedge leaves that plane, its reaction is 0
    /// and the other plane carries cos δ.
    pub ra: f64,
    pub rb: f64,
    /// Resisting over driving force along the sliding direction; ∞ when nothing drives.
    pub factor_of_safety: f64,
    pub sliding: Sliding,
    /// m/s², along the sliding direction; zero when F ≥ 1.
    pub acceleration: Vec3,
}

/// The unit line of intersection of two planes, pointing down, or None when they are parallel
/// (|n_A × n_B| < 1e-6, §3.1).
fn intersection(na: &Vec3, nb: &Vec3) -> Option<Vec3> {
    let cross = na.cross(nb);
    let len = cross.norm();
    if len < 1e-6 {
        return None;
    }
    let line = cross / len;
    Some(if line.z > 0.0 { -line } else { line })
}

/// (R3.2): the reactions / W of the two-plane balance, from projecting it on n_A and n_B
/// (friction along the line is orthogonal to both): R_A + c R_B = cos δ_A, c R_A + R_B = cos δ_B.
fn two_plane_reactions(na: &Vec3, nb: &Vec3) -> (f64, f64) {
    let c = na.dot(nb);
    // The upward unit normal's z is cos δ (R1.1).
    let (ca, cb) = (na.z, nb.z);
    let det = 1.0 - c * c;
    ((ca - c * cb) / det, (cb - c * ca) / det)
}

/// Resisting over driving force, ∞ when nothing drives (a horizontal line or plane).
fn ratio(resisting: f64, driving: f64) -> f64 {
    if driving > 0.0 {
        resisting / driving
    } else {
        f64::INFINITY
    }
}

/// The wedge on planes A and B, given by dip / dip direction (degrees), with friction angles
/// `phi_a`, `phi_b` (degrees) and gravity `g` (m/s²). None when the planes are parallel
/// (|n_A × n_B| < 1e-6).
///
/// Two-plane sliding when both (R3.2) reactions are positive: F = (R_A tan φ_A + R_B tan φ_B) /
/// sin ψ_i and a = g (sin ψ_i − R_A tan φ_A − R_B tan φ_B) along the line (R3.3), i.e.
/// g sin ψ_i (1 − F). When R_B ≤ 0 the wedge slides on A alone down its dip vector:
/// F = tan φ_A / tan δ_A, a = g (sin δ_A − cos δ_A tan φ_A); R_A ≤ 0 likewise on B (§3.2; both
/// cannot be ≤ 0 unless both planes are vertical, where it falls along A's dip vector with F ≈ 0).
pub fn wedge(
    a: (f64, f64),
    b: (f64, f64),
    phi_a: f64,
    phi_b: f64,
    g: f64,
) -> Option<WedgeSolution> {
    let (na, nb) = (pole(a.0, a.1), pole(b.0, b.1));
    let line = intersection(&na, &nb)?;
    let (trend, plunge) = trend_and_plunge(&line);
    let (tan_a, tan_b) = (phi_a.to_radians().tan(), phi_b.to_radians().tan());
    // (R3.2); a reaction ≤ 0 would pull, so the wedge leaves that plane.
    let (r_a, r_b) = two_plane_reactions(&na, &nb);
    // (sliding, reactions, direction, resisting, driving), all per unit weight.
    let (sliding, ra, rb, direction, resisting, driving) = if r_a > 0.0 && r_b > 0.0 {
        let resisting = r_a * tan_a + r_b * tan_b;
        (Sliding::TwoPlanes, r_a, r_b, line, resisting, -line.z)
    } else if r_b <= 0.0 {
        let d = dip_vector(a.0, a.1);
        (Sliding::OnA, na.z, 0.0, d, na.z * tan_a, -d.z)
    } else {
        let d = dip_vector(b.0, b.1);
        (Sliding::OnB, 0.0, nb.z, d, nb.z * tan_b, -d.z)
    };
    let factor_of_safety = ratio(resisting, driving);
    let acceleration = if factor_of_safety < 1.0 {
        direction * (g * (driving - resisting))
    } else {
        Vec3::zeros()
    };
    Some(WedgeSolution {
        line,
        trend,
        plunge,
        ra,
        rb,
        factor_of_safety,
        sliding,
        acceleration,
    })
}

/// Kinematic admissibility of the wedge under a slope face and an upper face (dip / dip
/// direction, degrees): the line's trend lies within ±90° of the face's dip direction, and
/// apparent dip of the upper face < plunge < apparent dip of the face, both along the trend
/// (§3.1): the line daylights in the face and exits through the upper surface. This is about the
/// tetrahedron's existence; A and B decide, through the reactions, how it moves.
pub fn admissible(w: &WedgeSolution, face: (f64, f64), upper: (f64, f64)) -> bool {
    let off = (w.trend - face.1 + 180.0).rem_euclid(360.0) - 180.0;
    off.abs() < 90.0
        && apparent_dip(upper.0, upper.1, w.trend) < w.plunge
        && w.plunge < apparent_dip(face.0, face.1, w.trend)
}

/// The equal friction angle on both planes (degrees) at which F = 1. For two-plane sliding
/// tan φ = sin ψ_i / (R_A + R_B) (§3.3); when the wedge slides on one plane (the mode depends on
/// the geometry only) it is that plane's dip. None when the planes are parallel.
pub fn critical_friction(a: (f64, f64), b: (f64, f64)) -> Option<f64> {
    let w = wedge(a, b, 0.0, 0.0, 1.0)?;
    Some(match w.sliding {
        Sliding::TwoPlanes => (-w.line.z).atan2(w.ra + w.rb).to_degrees(),
        Sliding::OnA => a.0,
        Sliding::OnB => b.0,
    })
}

/// The corners of the wedge cut by A, B and a slope face F, all three through the origin (the
/// toe), and a horizontal top z = h: [origin, A∩B∩top, A∩F∩top, B∩F∩top]. Each edge from the
/// toe is a line of intersection scaled to reach z = h. None when two of the planes are parallel
/// or one of the lines is horizontal. The four points are the wedge only when it is admissible
/// ([`admissible`] with a horizontal upper face).
pub fn tetrahedron(a: (f64, f64), b: (f64, f64), face: (f64, f64), h: f64) -> Option<[Vec3; 4]> {
    let (na, nb, nf) = (pole(a.0, a.1), pole(b.0, b.1), pole(face.0, face.1));
    let corner = |n1: &Vec3, n2: &Vec3| -> Option<Vec3> {
        let line = intersection(n1, n2)?;
        (line.z < -1e-12).then(|| line * (h / line.z))
    };
    Some([
        Vec3::zeros(),
        corner(&na, &nb)?,
        corner(&na, &nf)?,
        corner(&nb, &nf)?,
    ])
}

/// The volume of a tetrahedron, |det[v1 − v0, v2 − v0, v3 − v0]| / 6.
pub fn tetrahedron_volume(v: &[Vec3; 4]) -> f64 {
    (v[1] - v[0])
        .cross(&(v[2] - v[0]))
        .dot(&(v[3] - v[0]))
        .abs()
        / 6.0
}

#[cfg(test)]
mod tests {
    use super::super::orientation::dip_and_direction;
    use super::super::orientation::tests::{assert_vec, close};
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    const G: f64 = 9.81;
    /// Reference §3.4.
    const A: (f64, f64) = (45.0, 105.0);
    const B: (f64, f64) = (70.0, 235.0);
    const FACE: (f64, f64) = (65.0, 185.0);

    #[test]
    fn the_reference_wedge() {
        let w = wedge(A, B, 20.0, 30.0, G).unwrap();
        let (na, nb) = (pole(A.0, A.1), pole(B.0, B.1));
        assert!(close(na.dot(&nb).acos().to_degrees(), 100.6765, 1e-4));
        assert_vec(&w.line, [0.324138, -0.791604, -0.517975], 1e-6);
        assert!(close(w.trend, 157.7324, 1e-4) && close(w.plunge, 31.1965, 1e-4));
        assert_eq!(w.sliding, Sliding::TwoPlanes);
        assert!(close(w.ra, 0.797855, 1e-6) && close(w.rb, 0.489834, 1e-6));
        // Hoek–Bray's factors A = R_A / (W sin ψ_i), B likewise, and the wedge factor k.
        let sin_psi = -w.line.z;
        assert!(close(w.ra / sin_psi, 1.540336, 1e-6) && close(w.rb / sin_psi, 0.945671, 1e-6));
        let k = (w.ra + w.rb) / w.plunge.to_radians().cos();
        assert!(close(k, 1.505372, 1e-6));
        assert!(close(w.factor_of_safety, 1.106620, 1e-6));
        assert_eq!(w.acceleration, Vec3::zeros());
        let slides = wedge(A, B, 20.0, 20.0, G).unwrap();
        assert!(close(slides.factor_of_safety, 0.904832, 1e-6));
        assert!(close(slides.acceleration.norm(), 0.483578, 1e-6));
        assert!((slides.acceleration.normalize() - w.line).amax() < 1e-12);
        // (R3.3): a = g sin ψ_i (1 − F).
        let a = G * sin_psi * (1.0 - slides.factor_of_safety);
        assert!(close(slides.acceleration.norm(), a, 1e-12));
        let fast = wedge(A, B, 10.0, 10.0, G).unwrap();
        assert!(close(fast.factor_of_safety, 0.438350, 1e-6));
        assert!(close(fast.acceleration.norm(), 2.853931, 1e-6));
        let firm = wedge(A, B, 30.0, 30.0, G).unwrap();
        assert!(close(firm.factor_of_safety, 1.435297, 1e-6));
        assert_eq!(firm.acceleration, Vec3::zeros());
        let crit = critical_friction(A, B).unwrap();
        assert!(close(crit, 21.9125, 1e-4));
        let at_crit = wedge(A, B, crit, crit, G).unwrap();
        assert!(close(at_crit.factor_of_safety, 1.0, 1e-12));
        // A and B swapped: the same wedge.
        let swapped = wedge(B, A, 30.0, 20.0, G).unwrap();
        assert!(close(swapped.factor_of_safety, w.factor_of_safety, 1e-12));
        assert!(close(swapped.ra, w.rb, 1e-12) && (swapped.line - w.line).amax() < 1e-12);
    }

    #[test]
    fn the_reference_wedge_is_admissible() {
        let w = wedge(A, B, 20.0, 30.0, G).unwrap();
        assert!(admissible(&w, FACE, (0.0, 0.0)));
        // Hoek & Bray's upper face 12/195: apparent dip 9.601° along the trend.
        assert!(close(apparent_dip(12.0, 195.0, w.trend), 9.601, 1e-3));
        assert!(admissible(&w, FACE, (12.0, 195.0)));
        // A face too flat to expose the line, one facing away, an upper face steeper than it.
        assert!(!admissible(&w, (25.0, 185.0), (0.0, 0.0)));
        assert!(!admissible(&w, (65.0, 5.0), (0.0, 0.0)));
        assert!(!admissible(&w, FACE, (40.0, 160.0)));
    }

    #[test]
    fn the_reference_wedge_corners_and_volume() {
        for h in [1.0, 2.5] {
            let v = tetrahedron(A, B, FACE, h).unwrap();
            assert_eq!(v[0], Vec3::zeros());
            assert_vec(&(v[1] / h), [-0.625778, 1.528267, 1.0], 1e-6);
            assert_vec(&(v[2] / h), [-0.889011, 0.545867, 1.0], 1e-6);
            assert_vec(&(v[3] / h), [0.124173, 0.457225, 1.0], 1e-6);
            // §2.5 also gets 0.169780934267878 by cutting a box.
            assert!(close(
                tetrahedron_volume(&v) / h.powi(3),
                0.169780934267878,
                1e-12
            ));
        }
        // A horizontal face meets nothing at z = h; parallel planes have no line.
        assert_eq!(tetrahedron(A, B, (0.0, 0.0), 1.0), None);
        assert_eq!(tetrahedron(A, A, FACE, 1.0), None);
    }

    /// Two planes symmetric about the vertical plane through a line of trend 0 and plunge ψ,
    /// with included angle ξ measured across the line (§3.3).
    fn symmetric(xi: f64, psi: f64) -> ((f64, f64), (f64, f64)) {
        let psi = psi.to_radians();
        // The section across the line: v is its upward axis, e the horizontal one.
        let v = Vec3::new(0.0, psi.sin(), psi.cos());
        let e = Vec3::x();
        let (s, c) = (xi / 2.0).to_radians().sin_cos();
        (
            dip_and_direction(&(v * s - e * c)),
            dip_and_direction(&(v * s + e * c)),
        )
    }

    #[test]
    fn the_symmetric_wedge_family() {
        for (xi, psi, phi, f) in [
            (90.0, 40.0, 30.0, 0.973063),
            (60.0, 35.0, 25.0, 1.331913),
            (120.0, 30.0, 20.0, 0.727940),
        ] {
            let (a, b) = symmetric(xi, psi);
            let w = wedge(a, b, phi, phi, G).unwrap();
            assert_eq!(w.sliding, Sliding::TwoPlanes);
            assert!(close(w.plunge, psi, 1e-9) && close(w.trend.min(360.0 - w.trend), 0.0, 1e-9));
            let closed = phi.to_radians().tan()
                / ((xi / 2.0_f64).to_radians().sin() * psi.to_radians().tan());
            assert!(close(w.factor_of_safety, closed, 1e-12), "{xi} {psi}");
            assert!(close(w.factor_of_safety, f, 1e-6), "{xi} {psi}");
            assert!(close(w.ra, w.rb, 1e-12));
        }
    }

    #[test]
    fn planar_sliding_when_a_reaction_would_pull() {
        let w = wedge((30.0, 180.0), (80.0, 250.0), 20.0, 20.0, G).unwrap();
        let (na, nb) = (pole(30.0, 180.0), pole(80.0, 250.0));
        let (ra, rb) = two_plane_reactions(&na, &nb);
        assert!(close(ra, 0.90238, 1e-5) && close(rb, -0.11403, 1e-5));
        assert_eq!(w.sliding, Sliding::OnA);
        assert!(close(w.ra, 30f64.to_radians().cos(), 1e-15) && w.rb == 0.0);
        assert!(close(w.acceleration.norm(), 1.812815, 1e-6));
        assert_vec(&w.acceleration.normalize(), [0.0, -0.866025, -0.5], 1e-6);
        let f = 20f64.to_radians().tan() / 30f64.to_radians().tan();
        assert!(close(w.factor_of_safety, f, 1e-12));
        assert!(close(
            critical_friction((30.0, 180.0), (80.0, 250.0)).unwrap(),
            30.0,
            0.0
        ));

        let w = wedge((35.0, 170.0), (85.0, 90.0), 20.0, 20.0, G).unwrap();
        let (ra, rb) = two_plane_reactions(&pole(35.0, 170.0), &pole(85.0, 90.0));
        assert!(close(ra, 0.82840, 1e-5) && close(rb, -0.05418, 1e-5));
        assert_eq!(w.sliding, Sliding::OnA);
        assert!(close(w.acceleration.norm(), 2.701963, 1e-6));
        // Swapped, it slides on B.
        let w = wedge((85.0, 90.0), (35.0, 170.0), 20.0, 20.0, G).unwrap();
        assert_eq!(w.sliding, Sliding::OnB);
        assert!(close(w.acceleration.norm(), 2.701963, 1e-6) && w.ra == 0.0);
        // Stable on A when φ exceeds its dip.
        let w = wedge((30.0, 180.0), (80.0, 250.0), 35.0, 0.0, G).unwrap();
        assert!(w.factor_of_safety > 1.0 && w.acceleration == Vec3::zeros());
    }

    #[test]
    fn parallel_planes_make_no_wedge() {
        assert_eq!(wedge(A, A, 30.0, 30.0, G), None);
        // The same plane named from its other side.
        assert_eq!(wedge((90.0, 10.0), (90.0, 190.0), 30.0, 30.0, G), None);
        assert_eq!(critical_friction(A, A), None);
        // A horizontal line (up to the rounding of sin 90°): nothing drives.
        let w = wedge((40.0, 90.0), (40.0, 270.0), 10.0, 10.0, G).unwrap();
        assert!(w.factor_of_safety > 1e12 && w.acceleration == Vec3::zeros());
        // A flat plane with no friction drives nothing either.
        let w = wedge((0.0, 0.0), (60.0, 90.0), 0.0, 0.0, G).unwrap();
        assert!(w.sliding == Sliding::OnA && w.factor_of_safety == f64::INFINITY);
    }

    fn random_plane(rng: &mut ChaCha8Rng) -> (f64, f64) {
        (rng.random_range(5.0..85.0), rng.random_range(0.0..360.0))
    }

    /// Hoek & Bray's closed form for the line (§3.1): the root α_i or α_i + 180° with
    /// tan ψ_a cos(α_a − α_i) > 0.
    fn closed_form_line(a: (f64, f64), b: (f64, f64)) -> Option<(f64, f64)> {
        let (ta, tb) = (a.0.to_radians().tan(), b.0.to_radians().tan());
        let (aa, ab) = (a.1.to_radians(), b.1.to_radians());
        let ai = ((ta * aa.cos() - tb * ab.cos()) / (tb * ab.sin() - ta * aa.sin())).atan();
        let tan_psi = |ai: f64| ta * (aa - ai).cos();
        let ai = if tan_psi(ai) > 0.0 {
            ai
        } else {
            ai + std::f64::consts::PI
        };
        let t = tan_psi(ai);
        (t > 1e-9).then(|| (ai.to_degrees().rem_euclid(360.0), t.atan().to_degrees()))
    }

    #[test]
    fn the_closed_form_line_agrees_with_the_vector_form() {
        let mut rng = ChaCha8Rng::seed_from_u64(21);
        let mut checked = 0;
        for _ in 0..20_000 {
            let (a, b) = (random_plane(&mut rng), random_plane(&mut rng));
            let Some(w) = wedge(a, b, 30.0, 30.0, G) else {
                continue;
            };
            if pole(a.0, a.1).cross(&pole(b.0, b.1)).norm() < 1e-2 {
                continue;
            }
            let Some((trend, plunge)) = closed_form_line(a, b) else {
                continue;
            };
            let dt = (w.trend - trend + 180.0).rem_euclid(360.0) - 180.0;
            assert!(
                dt.abs() < 1e-9 && close(w.plunge, plunge, 1e-9),
                "{a:?} {b:?}"
            );
            checked += 1;
        }
        assert!(checked > 19_000, "{checked}");
    }

    #[test]
    fn random_wedges_balance_their_forces() {
        // W ĝ + R_A n_A + R_B n_B − (R_A tan φ_A + R_B tan φ_B) ê = m a, ê the sliding
        // direction (the line, or the dip vector of the plane slid on): the residual is along ê
        // always, and equals a when F < 1; when F ≥ 1 friction could hold more than drives.
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let mut counts = [0; 3];
        for _ in 0..20_000 {
            let (a, b) = (random_plane(&mut rng), random_plane(&mut rng));
            let (phi_a, phi_b) = (rng.random_range(0.0..45.0), rng.random_range(0.0..45.0));
            let Some(w) = wedge(a, b, phi_a, phi_b, G) else {
                continue;
            };
            let (na, nb) = (pole(a.0, a.1), pole(b.0, b.1));
            let e = match w.sliding {
                Sliding::TwoPlanes => w.line,
                Sliding::OnA => dip_vector(a.0, a.1),
                Sliding::OnB => dip_vector(b.0, b.1),
            };
            counts[w.sliding as usize] += 1;
            let friction = w.ra * phi_a.to_radians().tan() + w.rb * phi_b.to_radians().tan();
            let sum = (-Vec3::z() + na * w.ra + nb * w.rb - e * friction) * G;
            let along = sum.dot(&e);
            assert!((sum - e * along).norm() < 1e-12, "{a:?} {b:?}: {sum:?}");
            assert!(w.ra >= 0.0 && w.rb >= 0.0);
            if w.factor_of_safety < 1.0 {
                assert!((sum - w.acceleration).norm() < 1e-12);
                assert!(along > 0.0);
            } else {
                assert!(w.acceleration == Vec3::zeros() && along <= 1e-12);
            }
        }
        assert!(counts.iter().all(|&c| c > 500), "{counts:?}");
    }
}
