//! The paper's error tables for a run of a recognised slope ([`super::slope`]): Table 1, the
//! standing block's contact forces against N = W cos θ, F = W sin θ, and Table 2, the sliding
//! block's travel against s = ½ a t².
//!
//! Table 1 also gives each contact's own closed form, from a rigid block on a face of equal
//! springs: the normal forces vary linearly over the face and their resultant passes through
//! the centre of pressure, where the weight's line of action meets the face (h tan θ downslope
//! of the centroid's foot, h the centroid's height above the face). It is statically
//! determinate for three contacts or more not on one line, exact for the fixed penalty (every
//! spring p_n), and for the paper's block it is (P25): N1 = N2 = cos(θ+α)/(4 cos α)·W,
//! N3 = N4 = cos(θ−α)/(4 cos α)·W with tan α = H/L. Like (P25) it is taken on the scene's
//! geometry: each contact at the block's point that touches there, where it was at t = 0 (a
//! penalty block sinks 0.2 mm into the face and tilts by 7·10⁻⁵ rad, which would move the
//! closed forms by 0.005 %).

use serde::Serialize;

use super::sample::Sample;
use super::slope::{SlopeCase, cross, dot, norm, scaled, sub};
use crate::snapshot::{BlockSnapshot, ContactSnapshot, Snapshot};

/// One contact between the block and the slope, in Table 1.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ContactRow {
    /// Where the block's point in contact was at t = 0, down the slope from the contacts'
    /// mean, m.
    pub along_slope: f64,
    /// Its position across the slope (normal × downslope), m.
    pub across_slope: f64,
    pub state: &'static str,
    pub normal_force: f64,
    /// The rigid-block closed form (none for fewer than three contacts, or all on a line).
    pub theory: Option<f64>,
    pub error_percent: Option<f64>,
    pub penetration: f64,
    pub penalty: f64,
    pub lambda: f64,
}

/// Table 1 of one run: the standing block's contact forces at the end of the run.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StandingTable {
    pub time: f64,
    /// W cos θ, N.
    pub normal_theory: f64,
    /// The contacts' resultant on the block, normal to the face, N.
    pub normal: f64,
    pub normal_error_percent: f64,
    /// W sin θ, N.
    pub shear_theory: f64,
    /// The resultant's part along the face, N.
    pub shear: f64,
    /// |shear − W sin θ|, N (a level face has no relative error).
    pub shear_error: f64,
    pub shear_error_percent: Option<f64>,
    /// The deepest of the block's contacts, m.
    pub max_penetration: f64,
    /// How far the block's centroid has moved since t = 0, m.
    pub drift: f64,
    pub contacts: Vec<ContactRow>,
}

/// One run's travel at one time, in Table 2.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TravelRow {
    /// ½ a t², m.
    pub theory: f64,
    /// The block's centroid displacement along the slope, m.
    pub travel: f64,
    /// None at t = 0, where the theory is 0.
    pub error_percent: Option<f64>,
}

fn percent(x: f64, theory: f64) -> Option<f64> {
    (theory != 0.0).then(|| 100.0 * (x - theory).abs() / theory.abs())
}

/// Table 2's row of a run at the time of `s`.
pub fn travel(case: &SlopeCase, s: &Sample) -> TravelRow {
    let theory = 0.5 * case.acceleration * s.time * s.time;
    let travel = dot(s.displacements[case.block_index], case.downslope);
    TravelRow {
        theory,
        travel,
        error_percent: percent(travel, theory),
    }
}

/// Two unit vectors in the face: downslope (or any direction on a level face) and across.
fn face_axes(case: &SlopeCase) -> ([f64; 3], [f64; 3]) {
    let n = case.normal;
    let e1 = if dot(case.downslope, case.downslope) > 0.5 {
        case.downslope
    } else {
        // A level face: any direction in it.
        let t = if n[0].abs() < 0.9 {
            [1.0, 0.0, 0.0]
        } else {
            [0.0, 1.0, 0.0]
        };
        let v = sub(t, scaled(n, dot(t, n)));
        scaled(v, 1.0 / dot(v, v).sqrt())
    };
    (e1, cross(n, e1))
}

/// The rigid-block closed form of each contact's normal force, for contacts at in-face
/// positions `uv` (about their mean) under a resultant `total` through `(uc, vc)`.
pub fn linear_distribution(uv: &[(f64, f64)], total: f64, centre: (f64, f64)) -> Option<Vec<f64>> {
    let n = uv.len() as f64;
    let (suu, suv, svv) = uv.iter().fold((0.0, 0.0, 0.0), |(a, b, c), &(u, v)| {
        (a + u * u, b + u * v, c + v * v)
    });
    let det = suu * svv - suv * suv;
    if uv.len() < 3 || det <= 1e-12 * (suu + svv).powi(2) {
        return None;
    }
    let (uc, vc) = centre;
    let b = total * (svv * uc - suv * vc) / det;
    let d = total * (suu * vc - suv * uc) / det;
    Some(uv.iter().map(|&(u, v)| total / n + b * u + d * v).collect())
}

/// Where the block's point at `p` (a contact's point) was at t = 0: the block's vertex there
/// (a corner on the face, the usual contact), else `p` moved back with the block's centroid.
fn scene_point(case: &SlopeCase, block: &BlockSnapshot, p: [f64; 3]) -> [f64; 3] {
    let distance = |v: &[f64; 3]| norm(sub(*v, p));
    let size = (case.initial_vertices.iter())
        .map(|v| norm(sub(*v, case.initial_centroid)))
        .fold(0.0, f64::max);
    let nearest =
        (block.vertices.iter().enumerate()).min_by(|a, b| distance(a.1).total_cmp(&distance(b.1)));
    match nearest {
        Some((k, v)) if distance(v) <= 1e-2 * size && k < case.initial_vertices.len() => {
            case.initial_vertices[k]
        }
        _ => sub(p, block.displacement),
    }
}

/// The force of contact `c` on the free block.
fn force_on_block(c: &ContactSnapshot, block: usize) -> [f64; 3] {
    let f: [f64; 3] = std::array::from_fn(|k| c.normal_force * c.normal[k] + c.shear[k]);
    if c.block_i == block {
        f
    } else {
        scaled(f, -1.0)
    }
}

/// Table 1 of a run whose last state is `s`.
pub fn standing(case: &SlopeCase, s: &Snapshot) -> StandingTable {
    let (blk, slope) = (case.block_index, case.slope_index);
    let contacts: Vec<&ContactSnapshot> = (s.contacts.iter())
        .filter(|c| {
            (c.block_i, c.block_j) == (blk, slope) || (c.block_i, c.block_j) == (slope, blk)
        })
        .collect();
    let resultant = contacts.iter().fold([0.0; 3], |r, c| {
        let f = force_on_block(c, blk);
        [r[0] + f[0], r[1] + f[1], r[2] + f[2]]
    });
    let normal = dot(resultant, case.normal);
    let tangential = sub(resultant, scaled(case.normal, normal));
    let shear = dot(tangential, tangential).sqrt();
    let theta = case.theta_deg.to_radians();
    let (normal_theory, shear_theory) = (case.weight * theta.cos(), case.weight * theta.sin());

    let (e1, e2) = face_axes(case);
    let block = &s.blocks[blk];
    let points: Vec<[f64; 3]> = contacts
        .iter()
        .map(|c| scene_point(case, block, c.point))
        .collect();
    let count = points.len().max(1) as f64;
    let mean = points.iter().fold([0.0; 3], |m, p| {
        std::array::from_fn(|k| m[k] + p[k] / count)
    });
    let uv: Vec<(f64, f64)> = (points.iter())
        .map(|&p| (dot(sub(p, mean), e1), dot(sub(p, mean), e2)))
        .collect();
    // Where the weight's line through the centroid meets the face: the centroid's foot on the
    // face, then h tan θ down the slope.
    let g0 = case.initial_centroid;
    let h = case.centroid_height;
    let foot: [f64; 3] =
        std::array::from_fn(|k| g0[k] - h * case.normal[k] + h * theta.tan() * case.downslope[k]);
    let centre = (dot(sub(foot, mean), e1), dot(sub(foot, mean), e2));
    let theory = linear_distribution(&uv, normal_theory, centre);

    let mut rows: Vec<ContactRow> = contacts
        .iter()
        .enumerate()
        .map(|(k, c)| {
            let theory = theory.as_ref().map(|t| t[k]);
            ContactRow {
                along_slope: uv[k].0,
                across_slope: uv[k].1,
                state: c.state.as_str(),
                normal_force: c.normal_force,
                theory,
                error_percent: theory.and_then(|t| percent(c.normal_force, t)),
                penetration: c.penetration,
                penalty: c.penalty,
                lambda: c.lambda,
            }
        })
        .collect();
    rows.sort_by(|a, b| {
        (a.along_slope.total_cmp(&b.along_slope)).then(a.across_slope.total_cmp(&b.across_slope))
    });
    let d = block.displacement;
    StandingTable {
        time: s.time,
        normal_theory,
        normal,
        normal_error_percent: percent(normal, normal_theory).unwrap_or(0.0),
        shear_theory,
        shear,
        shear_error: (shear - shear_theory).abs(),
        shear_error_percent: percent(shear, shear_theory),
        max_penetration: contacts.iter().fold(0.0, |m, c| m.max(c.penetration)),
        drift: dot(d, d).sqrt(),
        contacts: rows,
    }
}

#[cfg(test)]
mod tests {
    use super::super::slope::tests::{FACTS, params, slope_scene};
    use super::super::slope::{Motion, recognise};
    use super::*;
    use crate::snapshot::{ContactMode, ContactState};

    /// The paper's block with its four base corners loaded as (P25) says.
    #[test]
    fn the_papers_block_gets_p25_and_the_resultant() {
        let mut s = slope_scene(30.0, 0.0, [2.0, 4.0, 1.0]);
        let case = recognise(&s, &FACTS, &params(35.0)).unwrap();
        assert_eq!(case.motion, Motion::Stands);
        let w = case.weight;
        let (t, alpha) = (30f64.to_radians(), 0.5f64.atan());
        let up = (t + alpha).cos() / (4.0 * alpha.cos()) * w;
        let down = (t - alpha).cos() / (4.0 * alpha.cos()) * w;
        assert!((up - 33203.8).abs() < 0.05 && (down - 60153.8).abs() < 0.05);
        // The base corners (vertices 0..4 of the block), each carrying its closed form, with
        // the friction along the slope that holds the block.
        let friction = w * t.sin() / 4.0;
        for i in 0..4 {
            let downslope_corner = i & 1 == 1;
            let n = if downslope_corner { down } else { up };
            s.contacts.push(ContactSnapshot {
                block_i: 1,
                block_j: 0,
                mode: ContactMode::VertexFace,
                state: ContactState::Lock,
                point: s.blocks[1].vertices[i],
                normal: case.normal,
                normal_force: n,
                shear_force: friction,
                shear: scaled(case.downslope, -friction),
                penetration: n / 2e8,
                penalty: 2e8,
                lambda: 0.0,
                joint: None,
            });
        }
        let table = standing(&case, &s);
        assert!(table.normal_error_percent < 1e-9, "{table:?}");
        assert!(table.shear_error_percent.unwrap() < 1e-9, "{table:?}");
        assert_eq!(table.contacts.len(), 4);
        for (k, row) in table.contacts.iter().enumerate() {
            let want = if k < 2 { up } else { down };
            assert!((row.theory.unwrap() - want).abs() < 1e-6 * want, "{row:?}");
            assert!(row.error_percent.unwrap() < 1e-9);
        }
        assert!((table.max_penetration - down / 2e8).abs() < 1e-18);
    }

    #[test]
    fn three_contacts_or_more_off_a_line_are_determinate() {
        assert!(linear_distribution(&[(0.0, 0.0), (1.0, 0.0)], 1.0, (0.0, 0.0)).is_none());
        assert!(
            linear_distribution(&[(-1.0, 0.0), (0.0, 0.0), (1.0, 0.0)], 1.0, (0.0, 0.0)).is_none()
        );
        let uv = [(-1.0, -1.0), (2.0, -1.0), (-1.0, 2.0)];
        let n = linear_distribution(&uv, 9.0, (0.5, 0.0)).unwrap();
        let sum: f64 = n.iter().sum();
        let mu: f64 = n.iter().zip(&uv).map(|(f, p)| f * p.0).sum();
        let mv: f64 = n.iter().zip(&uv).map(|(f, p)| f * p.1).sum();
        assert!((sum - 9.0).abs() < 1e-12 && (mu - 4.5).abs() < 1e-12 && mv.abs() < 1e-12);
    }

    #[test]
    fn travel_is_measured_down_the_slope() {
        let case = recognise(
            &slope_scene(30.0, 90.0, [2.0, 4.0, 1.0]),
            &FACTS,
            &params(15.0),
        )
        .unwrap();
        let t: f64 = 0.4;
        let s = 0.5 * case.acceleration * t * t;
        let sample = Sample {
            time: t,
            displacements: vec![[0.0; 3], scaled(case.downslope, s * 1.01)],
            velocities: vec![[0.0; 3]; 2],
            contact_force: 0.0,
            normal_force: 0.0,
            shear_force: 0.0,
            max_penetration: 0.0,
            kinetic_energy: 0.0,
        };
        let row = travel(&case, &sample);
        assert!((row.theory - s).abs() < 1e-15);
        assert!((row.error_percent.unwrap() - 1.0).abs() < 1e-9);
        let at_rest = Sample {
            time: 0.0,
            displacements: vec![[0.0; 3]; 2],
            ..sample
        };
        assert_eq!(travel(&case, &at_rest).error_percent, None);
    }
}
