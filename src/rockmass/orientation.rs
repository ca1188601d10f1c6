//! Plane and line orientations (dip / dip direction, trend / plunge) and the planes of a joint
//! set, after `shared/docs/rock-mass-reference.md` §1. Axes: z up, north = +y, east = +x; angles
//! in degrees, azimuths clockwise from north in [0°, 360°).

use rand_chacha::ChaCha8Rng;
use rand_chacha::rand_core::SeedableRng;
use rand_distr::{Distribution, StandardNormal};

pub use crate::physics::geometry::Vec3;

/// The horizontal unit vector of azimuth `az` (degrees clockwise from north = +y).
fn horizontal(az_deg: f64) -> Vec3 {
    let (s, c) = az_deg.to_radians().sin_cos();
    Vec3::new(s, c, 0.0)
}

/// The azimuth of the horizontal part (x, y) of a vector, in [0°, 360°).
fn azimuth(x: f64, y: f64) -> f64 {
    let az = x.atan2(y).to_degrees().rem_euclid(360.0);
    // rem_euclid of a tiny negative angle rounds up to 360 itself.
    if az >= 360.0 { 0.0 } else { az }
}

/// The upward unit normal (upper-hemisphere pole) n of a plane, (R1.1). Horizontally it points
/// toward the dip direction.
pub fn pole(dip_deg: f64, dip_direction_deg: f64) -> Vec3 {
    let (sd, cd) = dip_deg.to_radians().sin_cos();
    let h = horizontal(dip_direction_deg);
    Vec3::new(h.x * sd, h.y * sd, cd)
}

/// The unit dip vector d, pointing down the steepest line toward the dip direction, (R1.1).
pub fn dip_vector(dip_deg: f64, dip_direction_deg: f64) -> Vec3 {
    let (sd, cd) = dip_deg.to_radians().sin_cos();
    let h = horizontal(dip_direction_deg);
    Vec3::new(h.x * cd, h.y * cd, -sd)
}

/// The unit strike vector s by the right-hand rule, azimuth dip direction − 90°, (R1.1); the
/// plane dips to the right looking along s, and n = d × s. The dip does not enter; it is taken
/// so that the three vectors share one signature.
pub fn strike_vector(_dip_deg: f64, dip_direction_deg: f64) -> Vec3 {
    horizontal(dip_direction_deg - 90.0)
}

/// Dip and dip direction (degrees) of the plane with normal `n` (any length), the inverse of
/// [`pole`]. A downward normal is flipped first; a horizontal plane gets dip direction 0. A
/// vertical plane keeps the sign it is given: α and α + 180° are the same plane.
pub fn dip_and_direction(n: &Vec3) -> (f64, f64) {
    let n = if n.z < 0.0 { -n } else { *n };
    let h = n.x.hypot(n.y);
    // atan2 rather than acos(n_z): acos loses half the digits near dip 0.
    let dip = h.atan2(n.z).to_degrees();
    if h <= f64::EPSILON * n.norm() {
        return (dip, 0.0);
    }
    (dip, azimuth(n.x, n.y))
}

/// Trend and plunge (degrees) of the line with direction `v`, flipped so that it points down
/// (v_z ≤ 0). A vertical line gets trend 0.
pub fn trend_and_plunge(v: &Vec3) -> (f64, f64) {
    let v = if v.z > 0.0 { -v } else { *v };
    let h = v.x.hypot(v.y);
    let plunge = (-v.z).atan2(h).to_degrees();
    if h <= f64::EPSILON * v.norm() {
        return (0.0, plunge);
    }
    (azimuth(v.x, v.y), plunge)
}

/// Apparent dip (degrees) of a plane along azimuth `azimuth_deg`: arctan(tan δ cos(t − α)) (§1),
/// written with atan2 so that a vertical plane gives ±90° instead of ∞·0. Negative when the
/// azimuth points up the plane.
pub fn apparent_dip(dip_deg: f64, dip_direction_deg: f64, azimuth_deg: f64) -> f64 {
    let (sd, cd) = dip_deg.to_radians().sin_cos();
    let along = (azimuth_deg - dip_direction_deg).to_radians().cos();
    (sd * along).atan2(cd).to_degrees()
}

/// A joint set's plane family: mean orientation, spacing along the mean pole, a point on plane
/// k = 0, and optional scatter (see [`planes_through`] for the random scheme).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SetGeometry {
    /// Mean dip, degrees.
    pub dip: f64,
    /// Mean dip direction, degrees.
    pub dip_direction: f64,
    /// Mean spacing along the mean pole, m (> 0).
    pub spacing: f64,
    /// A point on plane k = 0.
    pub origin: Vec3,
    /// Standard deviation of each gap between neighbouring planes, m.
    pub spacing_deviation: f64,
    /// Standard deviation of each of the two tilt components of a plane's pole, degrees.
    pub orientation_deviation: f64,
    /// Seed of the scatter; the same seed gives the same planes in any domain.
    pub seed: u64,
}

/// One plane of a set: n·x = offset.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointPlane {
    /// k: 0 through the origin, increasing along the mean pole.
    pub index: i64,
    /// Unit normal, upward (n_z ≥ 0; a plane with n_z exactly 0 keeps the sign it was drawn with,
    /// which for a vertical set without scatter is that of the set's pole).
    pub normal: Vec3,
    pub offset: f64,
}

/// True when the plane cuts strictly through the hull: its signed distances (min, max over the
/// points) leave some point on each side by more than `tol`. A plane that only touches the hull
/// (a vertex, an edge, a face, within `tol`) makes no cut (§2.2 step 1).
fn cuts(min: f64, max: f64, tol: f64) -> bool {
    min < -tol && max > tol
}

/// Min and max of n·x over the points.
fn extent(n: &Vec3, points: &[Vec3]) -> (f64, f64) {
    points
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
            let s = n.dot(p);
            (lo.min(s), hi.max(s))
        })
}

/// The nominal planes n·x = n·o + k s (§1 "Joint set") that cut the range [lo, hi] of n·x over
/// the points: the contiguous k_min..=k_max, found from the floor/ceil estimate and then nudged
/// with the very test and offsets the planes are built with, so no plane within `tol` of the
/// range's ends slips in or out by rounding. None when no plane cuts; Err(count) past `max`.
fn nominal_range(
    n_o: f64,
    s: f64,
    (lo, hi): (f64, f64),
    tol: f64,
    max: usize,
) -> Result<Option<(i64, i64)>, usize> {
    let estimate = (hi - lo) / s;
    if estimate.is_nan() || estimate >= 1e15 {
        // Far past any usable limit (and past what i64 arithmetic below may assume).
        return Err(estimate.min(usize::MAX as f64) as usize);
    }
    let offset = |k: i64| n_o + k as f64 * s;
    // lo − c < −tol holds from some k up, hi − c > tol up to some k: both monotone in k.
    let above_lo = |k: i64| lo - offset(k) < -tol;
    let below_hi = |k: i64| hi - offset(k) > tol;
    let mut k_min = ((lo - n_o) / s).floor() as i64;
    while !above_lo(k_min) {
        k_min += 1;
    }
    while above_lo(k_min - 1) {
        k_min -= 1;
    }
    let mut k_max = ((hi - n_o) / s).ceil() as i64;
    while !below_hi(k_max) {
        k_max -= 1;
    }
    while below_hi(k_max + 1) {
        k_max += 1;
    }
    if k_min > k_max {
        return Ok(None);
    }
    let count = (k_max - k_min + 1) as usize;
    if count > max {
        return Err(count);
    }
    Ok(Some((k_min, k_max)))
}

/// The planes of the set that pass strictly through the convex hull of `points` (some point on
/// each side by more than `tol`), in order of k. Err(count) when more than `max_planes` would.
///
/// **Without scatter** (both deviations 0) plane k is n·x = n·o + k·s with n = [`pole`] of the
/// mean orientation (§1 "Joint set"), and `count` in Err is exact.
///
/// **With scatter**, plane k passes through o + t_k n, with t_0 = 0, t_{k+1} = t_k + g_k and
/// t_{k−1} = t_k − g_{k−1}, summed outward from k = 0 in this order whatever the domain. Its
/// normal is n tilted by a small rotation, n_k = normalize(n + tan(σ z₁) u + tan(σ z₂) w), with
/// σ the orientation deviation in radians, u = the mean dip vector and w = the mean strike
/// vector: the projection of n_k on the (n, u) plane makes the angle σ z₁ with n, and on the
/// (n, w) plane σ z₂, so **each tilt component has standard deviation σ**. z₁, z₂ are cut off at
/// ±6 (and σ z at ±80°) so the tilt is bounded and finite, which makes the search window below
/// exact. Each gap is **g_k = max(s + σ_s z₀, s/10)**: the floor keeps the planes in order and
/// apart when σ_s is not small against s; it biases the mean gap only when σ_s > s/3 or so.
///
/// **Random scheme.** Plane k's draws (z₀, z₁, z₂), in that order, are standard normals from a
/// `ChaCha8Rng::seed_from_u64(seed)` switched to stream `k as u64` (two's complement, a bijection
/// of i64), so they depend on (seed, k) only, never on the domain: the planes of a smaller domain
/// are bitwise the same planes, same k, as those of a larger one. ChaCha8 output is value-stable
/// across rand_chacha versions. Different sets need different seeds.
///
/// The walk goes outward from k = 0 both ways and stops once t_k leaves the range of n·(x − o)
/// over the points by more than √2·tan(tilt bound)·R⊥ (R⊥ the points' largest distance from the
/// line o + t n): beyond that no tilted plane can reach the hull. Keep the origin near the
/// domain: the planes between it and the domain are drawn too, and the tilts pivot about the line
/// o + t n, so an origin far to the side swings the planes widely at the domain. Err carries the
/// nominal count (as if without scatter) when that alone exceeds `max_planes`, else
/// `max_planes + 1` as soon as that many planes cut.
///
/// # Panics
/// When the spacing is not a positive finite number, or a deviation is negative or not finite.
pub fn planes_through(
    set: &SetGeometry,
    points: &[Vec3],
    tol: f64,
    max_planes: usize,
) -> Result<Vec<JointPlane>, usize> {
    assert!(
        set.spacing > 0.0 && set.spacing.is_finite(),
        "joint spacing must be positive and finite, got {}",
        set.spacing
    );
    let deviations = [set.spacing_deviation, set.orientation_deviation];
    assert!(
        deviations.iter().all(|d| *d >= 0.0 && d.is_finite()),
        "joint set deviations must be non-negative and finite, got {deviations:?}"
    );
    if points.is_empty() {
        return Ok(Vec::new());
    }
    let n = pole(set.dip, set.dip_direction);
    let n_o = n.dot(&set.origin);
    let range = extent(&n, points);
    let nominal = nominal_range(n_o, set.spacing, range, tol, max_planes)?;
    if set.spacing_deviation == 0.0 && set.orientation_deviation == 0.0 {
        let Some((k_min, k_max)) = nominal else {
            return Ok(Vec::new());
        };
        return Ok((k_min..=k_max)
            .map(|k| JointPlane {
                index: k,
                normal: n,
                offset: n_o + k as f64 * set.spacing,
            })
            .collect());
    }
    Scatter::new(set, n, points).planes(points, tol, max_planes)
}

/// Largest |z| of a tilt draw, in standard deviations.
const TILT_CUTOFF: f64 = 6.0;
/// Largest tilt component, degrees: keeps tan finite.
const TILT_MAX_DEG: f64 = 80.0;

/// The scattered planes of one set over one domain.
struct Scatter {
    seed: u64,
    spacing: f64,
    spacing_deviation: f64,
    /// σ in radians.
    sigma: f64,
    /// The tilt bound, radians.
    tilt_max: f64,
    origin: Vec3,
    /// Mean pole, dip vector, strike vector.
    n: Vec3,
    u: Vec3,
    w: Vec3,
    /// Range of n·(x − o) over the points, widened by the reach of the tilts.
    t_lo: f64,
    t_hi: f64,
}

impl Scatter {
    fn new(set: &SetGeometry, n: Vec3, points: &[Vec3]) -> Self {
        let sigma = set.orientation_deviation.to_radians();
        let tilt_max = (TILT_CUTOFF * sigma).min(TILT_MAX_DEG.to_radians());
        let (mut t_lo, mut t_hi, mut r_perp) = (f64::INFINITY, f64::NEG_INFINITY, 0.0_f64);
        for p in points {
            let y = p - set.origin;
            let t = n.dot(&y);
            t_lo = t_lo.min(t);
            t_hi = t_hi.max(t);
            r_perp = r_perp.max((y - n * t).norm());
        }
        // n_k·(x − p_k)·|m| = n·(x − o) − t_k + a u·(x − o) + b w·(x − o), and the last two
        // terms are at most √(a² + b²) R⊥ ≤ √2 tan(tilt_max) R⊥ (Cauchy–Schwarz): a plane
        // farther than that from the range has every point on one side. Pad by a hair for
        // rounding.
        let reach = 2f64.sqrt() * tilt_max.tan() * r_perp;
        let pad = reach + 1e-9 * (r_perp + t_hi.abs().max(t_lo.abs()) + set.spacing);
        Self {
            seed: set.seed,
            spacing: set.spacing,
            spacing_deviation: set.spacing_deviation,
            sigma,
            tilt_max,
            origin: set.origin,
            n,
            u: dip_vector(set.dip, set.dip_direction),
            w: strike_vector(set.dip, set.dip_direction),
            t_lo: t_lo - pad,
            t_hi: t_hi + pad,
        }
    }

    /// Plane k's draws: its gap g_k to plane k + 1 and its unit normal.
    fn draw(&self, k: i64) -> (f64, Vec3) {
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        rng.set_stream(k as u64);
        let mut z = || -> f64 { StandardNormal.sample(&mut rng) };
        let (z0, z1, z2) = (z(), z(), z());
        let gap = (self.spacing + self.spacing_deviation * z0).max(self.spacing / 10.0);
        // tilt_max ≤ 6σ: clamping σz clamps z at ±6 too.
        let tilt = |z: f64| (self.sigma * z).clamp(-self.tilt_max, self.tilt_max).tan();
        let normal = (self.n + self.u * tilt(z1) + self.w * tilt(z2)).normalize();
        (gap, normal)
    }

    /// Plane k through o + t n with the drawn normal, made upward; Some if it cuts.
    fn plane(&self, k: i64, t: f64, normal: Vec3, points: &[Vec3], tol: f64) -> Option<JointPlane> {
        let sign = if normal.z < 0.0 { -1.0 } else { 1.0 };
        let (normal, offset) = (
            normal * sign,
            normal.dot(&(self.origin + self.n * t)) * sign,
        );
        let (lo, hi) = extent(&normal, points);
        cuts(lo - offset, hi - offset, tol).then_some(JointPlane {
            index: k,
            normal,
            offset,
        })
    }

    fn planes(&self, points: &[Vec3], tol: f64, max: usize) -> Result<Vec<JointPlane>, usize> {
        let (mut down, mut up) = (Vec::new(), Vec::new());
        // Upward: k = 0, 1, …; t_{k+1} = t_k + g_k.
        let (mut k, mut t) = (0_i64, 0.0);
        while t <= self.t_hi {
            let (gap, normal) = self.draw(k);
            if t >= self.t_lo {
                up.extend(self.plane(k, t, normal, points, tol));
                if down.len() + up.len() > max {
                    return Err(max + 1);
                }
            }
            t += gap;
            k += 1;
        }
        // Downward: k = −1, −2, …; t_k = t_{k+1} − g_k.
        let (mut k, mut t) = (0_i64, 0.0);
        loop {
            k -= 1;
            let (gap, normal) = self.draw(k);
            t -= gap;
            if t < self.t_lo {
                break;
            }
            if t <= self.t_hi {
                down.extend(self.plane(k, t, normal, points, tol));
                if down.len() + up.len() > max {
                    return Err(max + 1);
                }
            }
        }
        down.reverse();
        down.extend(up);
        Ok(down)
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use rand::Rng;

    /// Shared with the wedge's tests.
    pub(in crate::rockmass) fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol
    }

    pub(in crate::rockmass) fn assert_vec(a: &Vec3, b: [f64; 3], tol: f64) {
        assert!(
            (a - Vec3::from(b)).amax() <= tol,
            "{a:?} is not {b:?} within {tol}"
        );
    }

    /// The difference of two azimuths, in (−180°, 180°].
    fn az_diff(a: f64, b: f64) -> f64 {
        let d = (a - b).rem_euclid(360.0);
        if d > 180.0 { d - 360.0 } else { d }
    }

    fn box_points(lo: [f64; 3], hi: [f64; 3]) -> Vec<Vec3> {
        (0..8)
            .map(|i| {
                let pick = |j: usize| if i >> j & 1 == 0 { lo[j] } else { hi[j] };
                Vec3::new(pick(0), pick(1), pick(2))
            })
            .collect()
    }

    #[test]
    fn the_reference_table_is_reproduced() {
        // dip, dd, n, d, strike azimuth: reference §1 (0.707107 written as 1/√2 for clippy).
        const R: f64 = std::f64::consts::FRAC_1_SQRT_2;
        #[rustfmt::skip]
        let rows: [[f64; 9]; 5] = [
            [35.0, 90.0, 0.573576, 0.0, 0.819152, 0.819152, 0.0, -0.573576, 0.0],
            [35.0, 0.0, 0.0, 0.573576, 0.819152, 0.0, 0.819152, -0.573576, 270.0],
            [45.0, 105.0, 0.683013, -0.183013, R, 0.683013, -0.183013, -R, 15.0],
            [70.0, 235.0, -0.769751, -0.538986, 0.342020, -0.280166, -0.196175, -0.939693, 145.0],
            [65.0, 185.0, -0.078990, -0.902859, 0.422618, -0.036834, -0.421010, -0.906308, 95.0],
        ];
        for [dip, dd, nx, ny, nz, dx, dy, dz, strike] in rows {
            let (n, d) = ([nx, ny, nz], [dx, dy, dz]);
            assert_vec(&pole(dip, dd), n, 1e-6);
            assert_vec(&dip_vector(dip, dd), d, 1e-6);
            let (s_trend, s_plunge) = trend_and_plunge(&strike_vector(dip, dd));
            assert!(close(az_diff(s_trend, strike), 0.0, 1e-6), "{dip}/{dd}");
            assert!(close(s_plunge, 0.0, 1e-12));
            let (dip2, dd2) = dip_and_direction(&pole(dip, dd));
            assert!(close(dip2, dip, 1e-12) && close(az_diff(dd2, dd), 0.0, 1e-12));
        }
    }

    #[test]
    fn random_orientations_are_orthonormal_and_round_trip() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        for _ in 0..20_000 {
            let dip = rng.random_range(0.0..90.0);
            let dd = rng.random_range(0.0..360.0);
            let (n, d, s) = (pole(dip, dd), dip_vector(dip, dd), strike_vector(dip, dd));
            for v in [n, d, s] {
                assert!(close(v.norm(), 1.0, 1e-15));
            }
            assert!(n.dot(&d).abs() < 1e-15 && n.dot(&s).abs() < 1e-15 && d.dot(&s).abs() < 1e-15);
            assert!((d.cross(&s) - n).amax() < 1e-15);
            let (dip2, dd2) = dip_and_direction(&n);
            assert!(close(dip2, dip, 1e-12), "{dip} -> {dip2}");
            assert!(close(az_diff(dd2, dd), 0.0, 1e-12), "{dd} -> {dd2}");
            // A downward normal is the same plane.
            let (dip3, dd3) = dip_and_direction(&(-n * 3.0));
            assert!(close(dip3, dip, 1e-12) && close(az_diff(dd3, dd), 0.0, 1e-12));
            // The dip vector is the line of trend dd and plunge dip.
            let (trend, plunge) = trend_and_plunge(&-d);
            assert!(close(az_diff(trend, dd), 0.0, 1e-12) && close(plunge, dip, 1e-12));
            // The apparent dip along the dip direction is the dip, and 0 along the strike.
            assert!(close(apparent_dip(dip, dd, dd), dip, 1e-12));
            // (cos 90° rounds to 6e-17, which tan δ magnifies for near-vertical planes.)
            assert!(close(apparent_dip(dip, dd, dd + 90.0), 0.0, 1e-9));
        }
    }

    #[test]
    fn degenerate_orientations() {
        assert_eq!(dip_and_direction(&Vec3::z()), (0.0, 0.0));
        assert_eq!(dip_and_direction(&pole(0.0, 123.0)), (0.0, 0.0));
        assert_eq!(trend_and_plunge(&Vec3::z()), (0.0, 90.0));
        // Vertical: the sign given is kept; 90/045 and 90/225 are one plane.
        let (dip, dd) = dip_and_direction(&pole(90.0, 225.0));
        assert!(close(dip, 90.0, 1e-12) && close(dd, 225.0, 1e-12));
        assert!(close(apparent_dip(90.0, 0.0, 30.0), 90.0, 1e-12));
        assert!(close(apparent_dip(90.0, 0.0, 150.0), -90.0, 1e-12));
        // Reference §3.4: the face 65/185 along the wedge's trend.
        assert!(close(apparent_dip(65.0, 185.0, 157.7324), 62.318, 5e-4));
    }

    fn set(dip: f64, dd: f64, spacing: f64, origin: [f64; 3]) -> SetGeometry {
        SetGeometry {
            dip,
            dip_direction: dd,
            spacing,
            origin: Vec3::from(origin),
            spacing_deviation: 0.0,
            orientation_deviation: 0.0,
            seed: 0,
        }
    }

    #[test]
    fn the_reference_joint_set_example() {
        // §1: 60/030, s = 0.7, o = (0.3, 0.1, 0.2), box [0,5]×[0,4]×[0,3]: k = 0..9.
        let s = set(60.0, 30.0, 0.7, [0.3, 0.1, 0.2]);
        let points = box_points([0.0; 3], [5.0, 4.0, 3.0]);
        let planes = planes_through(&s, &points, 1e-9, 100).unwrap();
        let ks: Vec<i64> = planes.iter().map(|p| p.index).collect();
        assert_eq!(ks, (0..=9).collect::<Vec<_>>());
        let n = pole(60.0, 30.0);
        let (lo, hi) = extent(&n, &points);
        assert!(close(lo, 0.0, 1e-12) && close(hi, 6.6651, 1e-4));
        for p in &planes {
            assert_eq!(p.normal, n);
            let expected = n.dot(&s.origin) + 0.7 * p.index as f64;
            assert!(close(p.offset, expected, 1e-15));
        }
        assert_eq!(planes_through(&s, &points, 1e-9, 9), Err(10));
        assert_eq!(planes_through(&s, &[], 1e-9, 9), Ok(Vec::new()));
    }

    #[test]
    fn touching_planes_make_no_cut() {
        // Horizontal set through z = 0, 1, 2, 3 over a box 0 ≤ z ≤ 3: only 1 and 2 cut; a plane
        // a hair inside a face is snapped onto it by tol.
        let points = box_points([0.0; 3], [2.0, 2.0, 3.0]);
        let ks = |spacing, z, tol| -> Vec<i64> {
            let s = set(0.0, 0.0, spacing, [5.0, 5.0, z]);
            let planes = planes_through(&s, &points, tol, 100).unwrap();
            planes.iter().map(|p| p.index).collect()
        };
        assert_eq!(ks(1.0, 0.0, 1e-9), vec![1, 2]);
        assert_eq!(ks(1.0, 1e-12, 1e-9), vec![1, 2]);
        assert_eq!(ks(1.0, 1e-6, 1e-9), vec![0, 1, 2]);
        assert_eq!(ks(1.0, 0.5, 0.6), vec![1]);
        assert!(ks(5.0, -1.0, 1e-9).is_empty());
    }

    fn scattered(seed: u64) -> SetGeometry {
        SetGeometry {
            spacing_deviation: 0.15,
            orientation_deviation: 4.0,
            seed,
            ..set(60.0, 30.0, 0.7, [0.3, 0.1, 0.2])
        }
    }

    #[test]
    fn the_same_seed_gives_the_same_planes() {
        let points = box_points([0.0; 3], [5.0, 4.0, 3.0]);
        let a = planes_through(&scattered(7), &points, 1e-9, 100).unwrap();
        let b = planes_through(&scattered(7), &points, 1e-9, 100).unwrap();
        let c = planes_through(&scattered(8), &points, 1e-9, 100).unwrap();
        assert!(a.len() >= 5, "{a:?}");
        assert_eq!(a, b);
        assert_ne!(a, c);
        assert!(a.iter().zip(&c).all(|(p, q)| p.normal != q.normal));
        assert!(a.windows(2).all(|w| w[0].index < w[1].index));
        for p in &a {
            assert!(close(p.normal.norm(), 1.0, 1e-15) && p.normal.z >= 0.0);
            let (lo, hi) = extent(&p.normal, &points);
            assert!(cuts(lo - p.offset, hi - p.offset, 1e-9));
        }
    }

    #[test]
    fn a_smaller_domain_gets_a_subset_of_the_same_planes() {
        for seed in 0..20 {
            let s = scattered(seed);
            let large = planes_through(&s, &box_points([-3.0; 3], [8.0, 7.0, 6.0]), 1e-9, 1000);
            let small = planes_through(&s, &box_points([1.0; 3], [2.5, 2.0, 1.7]), 1e-9, 1000);
            let (large, small) = (large.unwrap(), small.unwrap());
            assert!(!small.is_empty() && large.len() > small.len());
            for p in &small {
                let q = large.iter().find(|q| q.index == p.index).expect("same k");
                assert_eq!(p.offset.to_bits(), q.offset.to_bits());
                let bits = |v: &Vec3| v.map(f64::to_bits);
                assert_eq!(bits(&p.normal), bits(&q.normal));
            }
        }
    }

    #[test]
    fn a_plane_search_finds_every_cutting_plane() {
        // Brute force over a generous k range against the walk's window, with strong tilts and
        // an origin off to the side.
        let s = SetGeometry {
            orientation_deviation: 15.0,
            origin: Vec3::new(9.0, -4.0, 2.0),
            ..scattered(3)
        };
        let points = box_points([0.0; 3], [5.0, 4.0, 3.0]);
        let found = planes_through(&s, &points, 1e-9, 10_000).unwrap();
        let scatter = Scatter::new(&s, pole(s.dip, s.dip_direction), &points);
        let (mut t, mut brute) = (0.0, Vec::new());
        for k in 0..400 {
            let (gap, normal) = scatter.draw(k);
            brute.extend(scatter.plane(k, t, normal, &points, 1e-9));
            t += gap;
        }
        let mut t = 0.0;
        for k in (-400..0).rev() {
            let (gap, normal) = scatter.draw(k);
            t -= gap;
            brute.extend(scatter.plane(k, t, normal, &points, 1e-9));
        }
        brute.sort_by_key(|p| p.index);
        assert!(found.len() > 5);
        assert_eq!(found, brute);
    }

    #[test]
    fn scatter_has_the_stated_statistics() {
        // A thin prism 2000 spacings long along the pole: ~2000 planes. Tolerances are 5
        // standard errors of each estimate.
        let n = pole(60.0, 30.0);
        let (u, w) = (dip_vector(60.0, 30.0), strike_vector(60.0, 30.0));
        let len = 2000.0;
        let points: Vec<Vec3> = [-0.5, 0.5]
            .iter()
            .flat_map(|&e| {
                [u * 0.01, -u * 0.01, w * 0.01, -w * 0.01].map(|side| n * (e * len) + side)
            })
            .collect();
        let (sd_gap, sd_tilt) = (0.1, 2.0_f64);
        let gaps_only = SetGeometry {
            spacing: 1.0,
            spacing_deviation: sd_gap,
            ..set(60.0, 30.0, 1.0, [0.0; 3])
        };
        let planes = planes_through(&gaps_only, &points, 1e-9, 5000).unwrap();
        let gaps: Vec<f64> = planes
            .windows(2)
            .map(|p| p[1].offset - p[0].offset)
            .collect();
        assert!(gaps.len() > 1900);
        assert_mean_sd(&gaps, 1.0, sd_gap);

        let tilts_only = SetGeometry {
            orientation_deviation: sd_tilt,
            seed: 5,
            ..set(60.0, 30.0, 1.0, [0.0; 3])
        };
        let planes = planes_through(&tilts_only, &points, 1e-9, 5000).unwrap();
        assert!(planes.len() > 1900);
        let sigma = sd_tilt.to_radians();
        for axis in [u, w] {
            let angles: Vec<f64> = planes
                .iter()
                .map(|p| p.normal.dot(&axis).atan2(p.normal.dot(&n)))
                .collect();
            assert_mean_sd(&angles, 0.0, sigma);
        }
    }

    /// The sample's mean and standard deviation are those of N(mean, sd²) within 5 standard
    /// errors (sd/√m and, for normal data, sd/√(2m)).
    fn assert_mean_sd(x: &[f64], mean: f64, sd: f64) {
        let m = x.len() as f64;
        let sample_mean = x.iter().sum::<f64>() / m;
        let var = x.iter().map(|v| (v - sample_mean).powi(2)).sum::<f64>() / (m - 1.0);
        assert!(
            (sample_mean - mean).abs() < 5.0 * sd / m.sqrt(),
            "{sample_mean} vs {mean}"
        );
        assert!(
            (var.sqrt() - sd).abs() < 5.0 * sd / (2.0 * m).sqrt(),
            "{var} vs {sd}²"
        );
    }

    #[test]
    fn too_many_planes_fail_fast() {
        let points = box_points([0.0; 3], [5.0, 4.0, 3.0]);
        let start = std::time::Instant::now();
        let tiny = set(60.0, 30.0, 1e-7, [0.3, 0.1, 0.2]);
        let count = planes_through(&tiny, &points, 1e-9, 1000).unwrap_err();
        assert!(close(count as f64, 6.6651e7, 1e3), "{count}");
        assert!(planes_through(&set(60.0, 30.0, 1e-300, [0.0; 3]), &points, 0.0, 5).is_err());
        // With scatter: the nominal count when that overflows, …
        let scattered_tiny = SetGeometry {
            spacing: 1e-7,
            ..scattered(1)
        };
        assert!(planes_through(&scattered_tiny, &points, 1e-9, 1000).unwrap_err() > 1000);
        assert_eq!(planes_through(&scattered(1), &points, 1e-9, 3), Err(10));
        // … else max + 1 once that many cut: wide gap scatter (floored gaps) packs more planes
        // into the box than the nominal 10.
        let errors: Vec<usize> = (0..50)
            .filter_map(|seed| {
                let s = SetGeometry {
                    spacing_deviation: 0.6,
                    ..scattered(seed)
                };
                planes_through(&s, &points, 1e-9, 10).err()
            })
            .collect();
        assert!(
            !errors.is_empty() && errors.iter().all(|&c| c == 11),
            "{errors:?}"
        );
        assert!(start.elapsed().as_secs_f64() < 1.0);
    }

    #[test]
    fn near_vertical_scattered_normals_are_upward() {
        let s = SetGeometry {
            orientation_deviation: 3.0,
            ..set(89.5, 120.0, 0.5, [1.0, 1.0, 1.0])
        };
        let planes = planes_through(&s, &box_points([0.0; 3], [10.0, 10.0, 5.0]), 1e-9, 1000);
        let planes = planes.unwrap();
        assert!(planes.len() > 20);
        assert!(planes.iter().all(|p| p.normal.z >= 0.0));
        // Some were flipped: their horizontal part points away from the set's dip direction.
        let h = horizontal(120.0);
        assert!(planes.iter().any(|p| p.normal.dot(&h) < 0.0));
    }
}
