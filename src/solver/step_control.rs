//! Step control (reference §6.3, §8): the predicted Δt, the checks of a solved attempt
//! (displacement within δ·w0, penetration within the contact window), what a failed attempt is
//! retried with, and how Δt grows back. The numbers are Shi's rules in
//! [`crate::params::step_rules`].

use super::active::Active;
use super::counters::debug_log;
use crate::contact::DetectionParams;
use crate::contact::groups::{ContactGroups, MAX_BLOCK_PAIRS};
use crate::model::Block;
use crate::params::step_rules::{
    DISPLACEMENT_CUT_SAFETY, DT_CUT, DT_FLOOR_DIVISOR, DT_GROWTH, PREDICT_SAFETY, STOP_CUT_RANGE,
    STOP_CUT_SPEED,
};
use crate::params::{Mode, SolverParams};
use crate::physics::geometry::Vec3;
use crate::physics::mechanics::{Vec12, displacement_matrix};
use crate::text::short;

/// Why an attempt at a step failed and must be redone with a shorter Δt.
pub(crate) enum Retry {
    /// The open–close iteration did not converge within its pass limit.
    OpenClose,
    /// The largest vertex displacement was this many times δ·w0, by this block.
    Displacement(f64, usize),
    /// A closed contact penetrated this many times its contact window d_pen.
    Penetration(f64),
    /// The factorization failed or the solution is not finite.
    NotFinite,
    /// The solution would create this many times the energy a step may gain
    /// ([`super::watchdog::EnergyWatch::step_gain`]).
    EnergyGain(f64),
    /// A sliding contact stopped at this share of the step ([`stop_within`]):
    /// the step is redone to end there.
    Stop(f64),
}

impl Retry {
    /// The reason a run diverges when this failure happens at the Δt floor (`blocks` name the
    /// block that moved too far).
    pub fn divergence(&self, blocks: &[Block]) -> String {
        match self {
            Retry::OpenClose => unreachable!("settled at the floor"),
            Retry::NotFinite => "the solution is not finite".to_string(),
            Retry::EnergyGain(_) => unreachable!("accepted at the floor"),
            Retry::Stop(_) => unreachable!("no stop cut at the floor"),
            Retry::Penetration(r) => format!(
                "a contact penetrated {} times its contact window at the minimum time step",
                short(*r)
            ),
            Retry::Displacement(r, block) => displacement_divergence(*r, &culprit(blocks, *block)),
        }
    }

    /// A short description for the debug log.
    pub fn describe(&self) -> String {
        match self {
            Retry::OpenClose => "open-close".to_string(),
            Retry::Displacement(r, _) => format!("displacement r={r:.2}"),
            Retry::Penetration(r) => format!("penetration r={r:.2}"),
            Retry::NotFinite => "not finite".to_string(),
            Retry::EnergyGain(r) => format!("energy gain r={r:.2}"),
            Retry::Stop(f) => format!("stop f={f:.3}"),
        }
    }

    /// The Δt of the next attempt: cut by [`DT_CUT`], or for too large a displacement by the
    /// square root of the excess (a step's displacement grows as Δt²), never below the floor.
    pub fn shortened(&self, dt: f64, floor: f64) -> f64 {
        match self {
            Retry::Displacement(r, _) => dt / r.sqrt() * DISPLACEMENT_CUT_SAFETY,
            Retry::Stop(f) => dt * f,
            _ => dt * DT_CUT,
        }
        .max(floor)
    }
}

/// The share of Δt at which a sliding contact stopped, for a contact that slid along τ by
/// `carried` (its relative velocity at the step's start times Δt, along τ) and whose slip over
/// the step was `slip` along τ, with kinetic friction along τ all the step: under constant
/// deceleration the end velocity is 2·slip/Δt − v0 (Shi's step, (3.2)), so the velocity
/// crossed zero at v0/(v0 − v1) of the step. `None` when it did not stop, or stopped slower
/// than [`STOP_CUT_SPEED`] slip tolerances a step, or outside [`STOP_CUT_RANGE`].
///
/// Why the step is cut there: a block thrown up a slope stops within a step, but the step's
/// kinetic friction acts all through it. Either the block ended the step moving back down faster
/// than Coulomb allows (friction and gravity both down the slope for the whole step), or its slip
/// reversed, its contacts stuck, their springs held it where it was (D ≈ 0), and Shi's
/// v1 = 2D/Δt − v0 sent it back down at about the speed it had come up with. On 34° with φ = 26°
/// a 0.5 m block ended 4.5 cm beyond Coulomb after 1.5 s, 12.8 % of the 0.35 m it went up
/// (`tests/sliding_accuracy.rs`; 0.01 % now).
pub(crate) fn stop_within(carried: f64, slip: f64, tolerance: f64) -> Option<f64> {
    let end = 2.0 * slip - carried;
    if carried <= STOP_CUT_SPEED * tolerance || end >= 0.0 {
        return None;
    }
    let f = carried / (carried - end);
    (STOP_CUT_RANGE.0..=STOP_CUT_RANGE.1)
        .contains(&f)
        .then_some(f)
}

/// A rock-mass block smaller than this share of its rock mass's median block is called a
/// fragment in the message of a run that diverges by its displacement. The divergences of
/// random jointed cubes (`scripts/probe-rock-masses.py`, seeds 14 and 28) were fragments of
/// 1/410 and 1/89 of the median (1.1 and 4.0 cm³), squeezed by their neighbours at the Δt
/// floor; with `min_volume` = 10⁻⁵ m³ neither diverged, and seed 14 ran with 2·10⁻⁶ m³.
const FRAGMENT_SHARE: f64 = 0.1;

/// What the message of a displacement divergence says of the block that moved too far.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Culprit {
    pub name: String,
    pub volume: f64,
    /// The median block volume of its rock mass, m³ (`None` for a block of its own).
    pub median: Option<f64>,
}

/// The block `i` of `blocks` as the divergence message names it.
pub(crate) fn culprit(blocks: &[Block], i: usize) -> Culprit {
    let b = &blocks[i];
    let median = b.rock_mass.map(|of| {
        let mut v: Vec<f64> = blocks
            .iter()
            .filter(|o| o.rock_mass.is_some_and(|m| m.mass == of.mass))
            .map(|o| o.mp.volume)
            .collect();
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    });
    Culprit {
        name: b.name.clone(),
        volume: b.mp.volume,
        median,
    }
}

/// The reason of a run that diverged because block `c` moved `r` times δ·w0 at the Δt floor,
/// with the remedies: a smaller Δt_max and, for a fragment of a rock mass, a `min_volume`
/// that drops it.
pub(crate) fn displacement_divergence(r: f64, c: &Culprit) -> String {
    // "Beyond": an overshoot of 1.0004 printed as "1 times" read as none at all. A small block
    // fast for its size (2 cm at 10 m/s, whose w0 its size caps) reaches the floor Δt_max/100
    // this way: the remedy is a smaller Δt_max.
    let times = if r < 10.0 {
        format!("{r:.4}")
    } else {
        short(r)
    };
    let mut s = format!(
        "vertex displacement beyond the allowed δ·w0 ({times} times) at the minimum time step \
         (max_time_step/100), by block \"{}\" ({} m³); a block this fast for its size needs a \
         smaller max_time_step",
        c.name,
        short(c.volume)
    );
    s += &fragment_remedy(c);
    s
}

/// For a block `c` that is a fragment of a rock mass (under [`FRAGMENT_SHARE`] of its median
/// block), the clause that says so and gives the `min_volume` that drops it; empty otherwise.
pub(crate) fn fragment_remedy(c: &Culprit) -> String {
    match c.median.filter(|m| c.volume < FRAGMENT_SHARE * m) {
        Some(median) => format!(
            "; it is 1/{} of its rock mass's median block: a fragment of the cut, which the rock \
             mass's min_volume drops when set above {} m³ (by default blocks under 10⁻³ of the \
             median are dropped)",
            short((median / c.volume).round()),
            short(c.volume)
        ),
        None => String::new(),
    }
}

/// d_n,max = 2 δ w0 of (P22): the largest penetration a step can make, m.
pub(crate) fn max_step_penetration(p: &SolverParams, w0: f64) -> f64 {
    2.0 * p.max_displacement_ratio * w0
}

/// The smallest step, Δt_max / [`DT_FLOOR_DIVISOR`]; a step that fails there diverges.
pub(crate) fn dt_floor(p: &SolverParams) -> f64 {
    p.max_time_step / DT_FLOOR_DIVISOR
}

/// The first attempt's Δt: `base`, shortened to land on the time limit when `remaining` is
/// within one step of it, and split in two when it is within two (so that no sliver of a step
/// is left before the target time).
pub(crate) fn first_attempt(base: f64, remaining: f64) -> f64 {
    if remaining <= base * (1.0 + 1e-9) {
        remaining
    } else if remaining < 2.0 * base {
        remaining / 2.0
    } else {
        base
    }
}

/// The next step's Δt: grows back by at most [`DT_GROWTH`] a step (Shi), up to Δt_max. A step
/// shortened only to land on a time limit does not hold the next one back, so growth starts
/// from the predicted `base` unless the step was cut.
pub(crate) fn next_dt(p: &SolverParams, base: f64, taken: f64, cuts: u32) -> f64 {
    let grown_from = if cuts > 0 { taken } else { base };
    (grown_from * DT_GROWTH).min(p.max_time_step)
}

/// Δt such that the fastest vertex moves at most δ·w0 under its current velocity and gravity
/// (Shi's prediction from ½ a Δt² + v Δt = δ w0), w0 being that of the contacts the block may
/// make within Δt_max (see [`ContactGroups::w0_near`]).
///
/// A block that comes near no other block within Δt_max is in free flight: the step integrates
/// its motion exactly, and δ·w0, which keeps the contact linearisation and the detection window
/// valid, need not limit its step. (A rock that bounced off the ground slab's edge fell for
/// 90 s at the Δt floor and was then reported as diverged.)
pub(crate) fn predict_dt(p: &SolverParams, blocks: &[Block], groups: &ContactGroups) -> f64 {
    let a = Vec3::from(p.gravity).norm().max(1e-12);
    let mut dt = p.max_time_step;
    if p.mode == Mode::Static {
        return dt;
    }
    let dt_max = p.max_time_step;
    // Δt from ½ a Δt² + v Δt = δ w0 (with the safety factor).
    let limit = |speed: f64, w0: f64| {
        let allowed = p.max_displacement_ratio * w0 * PREDICT_SAFETY;
        (-speed + (speed * speed + 2.0 * a * allowed).sqrt()) / a
    };
    for (i, b) in blocks.iter().enumerate().filter(|(_, b)| !b.fixed) {
        let speed = b.peak_speed();
        if limit(speed, groups.max_w0(i)) < dt {
            let motion = speed * dt_max + 0.5 * a * dt_max * dt_max;
            if let Some(w0) = groups.w0_near(i, motion) {
                dt = dt.min(limit(speed, w0));
            }
        }
    }
    dt.max(dt_floor(p))
}

/// The step-size checks of a solved attempt: no vertex of a block in contact range moves more
/// than `max_displacement_overshoot · δ·w0` (w0 of the contacts it may make,
/// [`ContactGroups::w0_near`]), and no closed contact penetrates beyond its contact window d_pen.
pub(crate) fn check_solution(
    p: &SolverParams,
    blocks: &[Block],
    groups: &ContactGroups,
    d: &[f64],
    active: &[Active],
) -> Result<(), Retry> {
    check_displacement(p, blocks, groups, d)?;
    let delta = p.max_displacement_ratio;
    let window = |c: &Active| {
        let (i, j) = c.blocks();
        DetectionParams::new(groups.pair_w0(i, j), delta).max_penetration
    };
    let beyond = active
        .iter()
        .filter(|c| c.rec.state.is_closed() && c.dn > window(c));
    match beyond.map(|c| c.dn / window(c)).reduce(f64::max) {
        Some(worst) => Err(Retry::Penetration(worst)),
        None => Ok(()),
    }
}

/// The displacement check of [`check_solution`] alone: no vertex of a block in contact range
/// moves more than `max_displacement_overshoot · δ·w0`.
pub(crate) fn check_displacement(
    p: &SolverParams,
    blocks: &[Block],
    groups: &ContactGroups,
    d: &[f64],
) -> Result<(), Retry> {
    let delta = p.max_displacement_ratio;
    let mut r: f64 = 0.0;
    // The block that moved furthest for its w0, for `DDA3D_DEBUG`.
    let mut worst = (0, 0.0, 0.0);
    for (i, b) in blocks.iter().enumerate() {
        let di = Vec12::from_column_slice(&d[12 * i..12 * i + 12]);
        let u = b
            .vertices
            .iter()
            .map(|v| (displacement_matrix(&(v - b.mp.centroid)) * di).norm())
            .fold(0.0, f64::max);
        // A block in free flight may move further (see `predict_dt`). (Its r would be at most
        // 1 where it did not: `max_displacement_overshoot` is at least 1.)
        if u > 0.0
            && let Some(w0) = groups.w0_near(i, u)
        {
            let ratio = u / (delta * w0);
            if ratio > r {
                (r, worst) = (ratio, (i, u, w0));
            }
        }
    }
    if r > p.max_displacement_overshoot {
        if debug_log() {
            let (i, u, w0) = worst;
            eprintln!(
                "displacement: block {i} moved {u:.3e} m (w0 {w0:.3e} m, volume {:.3e} m3)",
                blocks[i].mp.volume
            );
        }
        return Err(Retry::Displacement(r, worst.0));
    }
    Ok(())
}

/// `Err` with the reason when a step would search more than [`MAX_BLOCK_PAIRS`] block pairs
/// (the search stops counting just past it).
pub(crate) fn check_pair_count(pairs: usize, w0: f64, delta: f64) -> Result<(), String> {
    if pairs <= MAX_BLOCK_PAIRS {
        return Ok(());
    }
    Err(format!(
        "the contact search finds more block pairs than the {} a step can hold in memory: \
         blocks far thinner than the search distance {} m (2.5·δ·w0) each reach hundreds of \
         others; make them thicker or lower max_displacement_ratio",
        short(MAX_BLOCK_PAIRS as f64),
        short(crate::contact::groups::search_distance(w0, delta))
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_step_of_too_many_block_pairs_is_refused_with_its_search_distance() {
        assert!(check_pair_count(MAX_BLOCK_PAIRS, 10.0, 0.01).is_ok());
        let e = check_pair_count(MAX_BLOCK_PAIRS + 1, 10.0, 0.01).unwrap_err();
        assert!(
            e.contains("2e6 a step can hold") && e.contains("0.25 m"),
            "{e}"
        );
    }

    /// The message names the block and its volume; a rock-mass block under a tenth of its
    /// mass's median is called a fragment, with the min_volume that drops it; a block of its
    /// own, or a rock-mass block near the median, is told only of Δt_max.
    #[test]
    fn a_displacement_divergence_names_the_block_and_the_remedy_for_a_fragment() {
        let block = |volume: f64, median: Option<f64>| Culprit {
            name: "m/268".into(),
            volume,
            median,
        };
        let fragment = displacement_divergence(11.93, &block(4.034e-6, Some(3.59e-4)));
        assert!(fragment.contains("(11.93 times)"), "{fragment}");
        assert!(
            fragment.contains("block \"m/268\" (4.034e-6 m³)"),
            "{fragment}"
        );
        assert!(fragment.contains("smaller max_time_step"), "{fragment}");
        assert!(
            fragment.contains("1/89 of its rock mass's median"),
            "{fragment}"
        );
        assert!(
            fragment.contains("min_volume drops when set above 4.034e-6 m³"),
            "{fragment}"
        );
        for (volume, median) in [(4e-5, Some(3.59e-4)), (4e-6, None)] {
            let m = displacement_divergence(1.0775, &block(volume, median));
            assert!(
                m.contains("(1.0775 times)") && m.contains("smaller max_time_step"),
                "{m}"
            );
            assert!(!m.contains("min_volume"), "{m}");
        }
    }

    /// A rock mass's median is taken over its own blocks only, not over the other blocks of the
    /// scene (the test cube on its slab): over all four it would be the cube's 1 m³.
    #[test]
    fn the_culprit_median_is_its_own_rock_mass() {
        // A 1 m cube beside the test cube on its slab, cut into two layers of 0.5 m³.
        let text = format!(
            "{}[[rock_masses]]\nname = \"m\"\nmaterial = \"rock\"\n\
             regions = [ {{ box = {{ size = [1.0, 1.0, 1.0], center = [0, 1.5, 0.5] }} }} ]\n\
             [[rock_masses.joint_sets]]\nname = \"J\"\ndip = 0.0\ndip_direction = 0.0\n\
             spacing = 0.5\n",
            crate::solver::CUBE_ON_SLAB
        );
        let s = crate::scene::parse(&text, "mass.toml", "mass").expect("scene parses");
        let blocks = &s.model.blocks;
        let slab = blocks.iter().position(|b| b.name == "slab").expect("slab");
        assert_eq!(culprit(blocks, slab).median, None);
        let layer = blocks
            .iter()
            .position(|b| b.name.starts_with("m/"))
            .expect("a layer");
        let c = culprit(blocks, layer);
        assert!(
            (c.median.expect("in a rock mass") - 0.5).abs() < 1e-9,
            "{c:?}"
        );
        assert!((c.volume - 0.5).abs() < 1e-9, "{c:?}");
    }

    #[test]
    fn the_first_attempt_lands_on_the_limit_without_a_sliver() {
        assert_eq!(first_attempt(0.01, 1.0), 0.01);
        assert_eq!(first_attempt(0.01, 0.01), 0.01);
        assert_eq!(first_attempt(0.01, 0.004), 0.004);
        // 1.5 steps left: two steps of 0.0075 s, not 0.01 s and a 0.005 s sliver.
        assert_eq!(first_attempt(0.01, 0.015), 0.0075);
    }

    #[test]
    fn a_failed_attempt_is_cut_and_the_next_step_grows_back() {
        let p = SolverParams::default();
        let floor = dt_floor(&p);
        assert!((Retry::OpenClose.shortened(0.01, floor) - 0.003).abs() < 1e-15);
        let by_4 = Retry::Displacement(4.0, 0).shortened(0.01, floor);
        assert!((by_4 - 0.01 / 2.0 * DISPLACEMENT_CUT_SAFETY).abs() < 1e-15);
        assert_eq!(Retry::NotFinite.shortened(1.5 * floor, floor), floor);
        assert!((next_dt(&p, 0.001, 0.0005, 0) - 0.0013).abs() < 1e-15);
        assert!((next_dt(&p, 0.001, 0.0005, 1) - 0.00065).abs() < 1e-15);
        assert_eq!(next_dt(&p, 0.009, 0.009, 0), p.max_time_step);
    }

    /// A contact sliding at v0 under a constant deceleration that stops it at 0.4 of the step
    /// (slip v0 Δt − ½ a Δt², the end velocity v0 − a Δt): the stop is found at 0.4, exactly.
    #[test]
    fn a_stop_within_the_step_is_found_where_the_velocity_crossed_zero() {
        let (v0, dt, tol) = (0.05, 0.01, 1e-6);
        for share in [0.15, 0.4, 0.85] {
            let a = v0 / (share * dt);
            let slip = v0 * dt - 0.5 * a * dt * dt;
            let f = stop_within(v0 * dt, slip, tol).expect("stopped within the step");
            assert!((f - share).abs() < 1e-12, "{f} against {share}");
        }
    }

    #[test]
    fn no_stop_is_found_where_the_contact_still_slides_or_hardly_moved() {
        let (dt, tol) = (0.01, 1e-6);
        // Slowing down but still sliding at the end: v1 = 2 slip/Δt − v0 = 0.01 m/s.
        assert_eq!(stop_within(0.05 * dt, 0.03 * dt, tol), None);
        // Reversed, but slower than 10 slip tolerances a step (micro-slips of a block at rest).
        assert_eq!(stop_within(9.0 * tol, -tol, tol), None);
        // Stopped at 5 % or 95 % of the step: too near its start or its end to cut.
        let carried = 0.05 * dt;
        let at = |share: f64| carried - 0.5 * carried / share;
        assert_eq!(stop_within(carried, at(0.05), tol), None);
        assert_eq!(stop_within(carried, at(0.95), tol), None);
        assert!(stop_within(carried, at(0.5), tol).is_some());
    }
}
