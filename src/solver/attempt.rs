//! One attempt at a step of length Δt: the open–close iteration around the ALM loop (paper
//! Fig. 3), then the step-size checks. A failed attempt tells why ([`Retry`]); the solver then
//! redoes the step with a shorter Δt.

use super::active::Active;
use super::alm::{AlmInputs, System, alm_loop};
use super::assemble::{StiffnessSync, block_terms};
use super::counters::{Counters, Stopwatch};
use super::open_close::{self, CheckInputs};
use super::step_control::{self, Retry};
use crate::contact::groups::ContactGroups;
use crate::model::Block;
use crate::params::{Method, Mode, SolverParams};
use crate::physics::integrator::Scheme;
use crate::physics::linear::{BlockMatrix, SparseCholesky};

/// What an attempt reads.
pub(crate) struct AttemptInputs<'a> {
    pub params: &'a SolverParams,
    pub blocks: &'a [Block],
    /// The step's contact groups, with their w0 (`crate::contact::groups`).
    pub groups: &'a ContactGroups,
    pub time: f64,
    pub dt: f64,
    /// The time integrator of this step.
    pub scheme: Scheme,
    /// The first step of the run (or after the equilibrium stage).
    pub first_step: bool,
    /// The step is at the Δt floor: stragglers at the pass limit are settled, not redone.
    pub at_floor: bool,
    /// The sleeping blocks, held where they are (empty: none).
    pub held: &'a [bool],
    /// The step belongs to the initial equilibrium stage.
    pub in_stage: bool,
    /// The attempt may be redone at the time a sliding contact stopped ([`Retry::Stop`]).
    pub stop_cuts: bool,
}

/// The solution of one attempt at a step.
pub(crate) struct Solved {
    pub d: Vec<f64>,
    pub oc_passes: u32,
    pub solves: u32,
    /// The open–close iteration hit its limit and was settled.
    pub settled: bool,
}

/// The attempt a step accepted, with what it took to reach it.
pub(crate) struct Accepted {
    pub solved: Solved,
    /// The Δt of the accepted attempt.
    pub dt: f64,
    /// Attempts redone with a shorter Δt before it.
    pub cuts: u32,
    /// One of those cuts ended the step where a block stopped ([`Retry::Stop`]).
    pub stop_cut: bool,
    /// Factorizations over all the step's attempts.
    pub factorizations: u32,
}

/// Runs one attempt. `kmat` holds the step's sparsity pattern.
pub(crate) fn attempt(
    inp: &AttemptInputs,
    kmat: &mut BlockMatrix,
    chol: &mut SparseCholesky,
    active: &mut [Active],
    counters: &mut Counters,
) -> Result<Solved, Retry> {
    let result = open_close_iteration(inp, kmat, chol, active, counters);
    counters.flush();
    let solved = result?;
    let watch = Stopwatch::start();
    let checked =
        step_control::check_solution(inp.params, inp.blocks, inp.groups, &solved.d, active);
    counters.totals.timings.bookkeeping += watch.seconds();
    checked?;
    // A step settled at the pass limit is not redone for a stop: its states did not converge,
    // so neither did the stops read from them (the jointed mass of 1000, every step of which is
    // settled, redid a step of 31 passes and 70 factorizations for one).
    if !inp.stop_cuts || solved.settled {
        return Ok(solved);
    }
    match stopped_blocks(inp.blocks, active) {
        Some(f) => Err(Retry::Stop(f)),
        None => Ok(solved),
    }
}

/// The open–close passes, each an ALM loop followed by the open–close check, until no contact
/// changes state. If the iteration has not converged after its pass limit, the attempt is
/// redone with a shorter Δt (Shi); at the Δt floor, or where the stragglers are few, they are
/// settled for one more solve instead (see [`open_close::settle_stragglers`]), and solved again
/// where that solve leaves contacts pulling ([`open_close::open_pulling`]).
fn open_close_iteration(
    inp: &AttemptInputs,
    kmat: &mut BlockMatrix,
    chol: &mut SparseCholesky,
    active: &mut [Active],
    counters: &mut Counters,
) -> Result<Solved, Retry> {
    let p = inp.params;
    let cp = &p.contact;
    let watch = Stopwatch::start();
    // (K0, F0): the block terms of §3, fixed for the attempt.
    let (k0, f0) = block_terms(p, inp.blocks, inp.held, &inp.scheme, inp.dt);
    counters.assembly += watch.elapsed();
    for c in active.iter_mut() {
        c.flips = 0;
        c.frozen = false;
        c.stopped = false;
        c.onset_slip = 0.0;
        c.stop_fraction = None;
        c.release_overlap(inp.dt);
        c.predict_lateral(p, inp.blocks, inp.dt);
    }
    let mut sync = StiffnessSync::default();
    let mut solved = Solved {
        d: Vec::new(),
        oc_passes: 0,
        solves: 0,
        settled: false,
    };
    for pass in 0..=cp.max_open_close_iterations {
        if pass == cp.max_open_close_iterations {
            open_close::settle_stragglers(active, p, inp.at_floor, counters)?;
            solved.settled = true;
        }
        solved.oc_passes += 1;
        let alm = AlmInputs {
            params: p,
            blocks: inp.blocks,
            k0: &k0,
            f0: &f0,
            first_step: inp.first_step,
            settling: solved.settled,
            held: inp.held,
        };
        let mut sys = System {
            kmat,
            sync: &mut sync,
            chol,
        };
        solve_pass(inp, &alm, &mut sys, active, counters, &mut solved)?;
        if solved.settled {
            // The settled solve is checked for tension only: a contact it left pulling
            // beyond the law's opening tension holds blocks together by a state that did
            // not converge (a sliding jointed slope's settled step pulled 207 contacts, up
            // to 12 MN, and lost 60 % of its kinetic energy in that step). Those are
            // opened and the attempt solved again, a few times at most; if it still pulls,
            // the attempt is redone with a shorter Δt, as Shi redoes a step whose open–close
            // iteration did not converge (with the re-solves alone that slope's step kept
            // 2.41 of its 3.31 MJ, and the next step lost more). Not in the equilibrium
            // stage, whose static steps hold the joints: opened there, the shipped jointed
            // slope's blocks flew 5 m once released.
            if !inp.in_stage {
                settled_tension(inp, &alm, &mut sys, active, counters, &mut solved)?;
            }
            break;
        }
        let watch = Stopwatch::start();
        let check = CheckInputs {
            params: p,
            blocks: inp.blocks,
            warm: cp.warm_start && p.method == Method::Alm,
            time: inp.time,
            dt: inp.dt,
            pass: solved.oc_passes,
            onset_turns: p.method == Method::Alm && !inp.in_stage,
            carries: !inp.in_stage && p.mode == Mode::Dynamic,
            stop_cuts: inp.stop_cuts,
            holding: &Default::default(),
            sliding_blocks: &Default::default(),
            pair_shear: &Default::default(),
        };
        let changed = open_close::check(&check, &solved.d, active, counters);
        counters.assembly += watch.elapsed();
        if !changed {
            break;
        }
    }
    Ok(solved)
}

/// Solves after the settled one at the pass limit, each after opening the contacts the last
/// left pulling ([`open_close::open_pulling`]).
const SETTLED_TENSION_SOLVES: u32 = 3;

/// After the settled solve: while it leaves contacts pulling ([`open_close::open_pulling`]
/// opens them), solves again, at most [`SETTLED_TENSION_SOLVES`] times; `Err` (the attempt is
/// redone shorter) if the last still pulls, except at the Δt floor.
fn settled_tension(
    inp: &AttemptInputs,
    alm: &AlmInputs,
    sys: &mut System,
    active: &mut [Active],
    counters: &mut Counters,
    solved: &mut Solved,
) -> Result<(), Retry> {
    for k in 0..=SETTLED_TENSION_SOLVES {
        if open_close::open_pulling(active, inp.params) == 0 {
            break;
        }
        if k == SETTLED_TENSION_SOLVES {
            if inp.at_floor {
                break;
            }
            return Err(Retry::OpenClose);
        }
        solved.oc_passes += 1;
        solve_pass(inp, alm, sys, active, counters, solved)?;
    }
    Ok(())
}

/// One ALM loop of an open–close pass, its solution kept in `solved`.
fn solve_pass(
    inp: &AttemptInputs,
    alm: &AlmInputs,
    sys: &mut System,
    active: &mut [Active],
    counters: &mut Counters,
    solved: &mut Solved,
) -> Result<(), Retry> {
    let out = alm_loop(alm, sys, active, counters)?;
    // An ALM loop that ran to its cap without converging may have run away (friction
    // feeding a frozen sliding contact's λ, which fed its friction: the jointed mass of
    // 1000 moved a block 17 m in one such loop, 105 m in the next pass, and the step went on
    // to classify every contact from those solutions and ended with 0.8 GJ of kinetic
    // energy). Such a solution classifies nothing: the attempt is redone with a shorter Δt
    // at once.
    if !out.converged {
        counters.totals.alm_cap_hits += 1;
        runaway(inp, &out.d)?;
    }
    solved.d = out.d;
    solved.solves += out.solves;
    Ok(())
}

/// The earliest share of the step at which a free block that slid on all its contacts stopped on
/// all of them ([`step_control::stop_within`]), if one did: the step is then redone to end
/// there. A block whose contacts did not all stop (a block of a wall, held by neighbours while
/// one contact's slip turns back) is not: the step is global, and a struck wall of 100 blocks,
/// cut at every such contact, took 549 steps for 0.6 s instead of 87.
fn stopped_blocks(blocks: &[Block], active: &[Active]) -> Option<f64> {
    let mut per_block: Vec<(u32, u32, f64)> = vec![(0, 0, f64::INFINITY); blocks.len()];
    for c in active
        .iter()
        .filter(|c| c.rec.state.is_closed() || c.stop_fraction.is_some())
    {
        let (i, j) = c.blocks();
        for b in [i, j].into_iter().filter(|&b| !blocks[b].fixed) {
            let e = &mut per_block[b];
            e.0 += 1;
            if let Some(f) = c.stop_fraction {
                e.1 += 1;
                e.2 = e.2.min(f);
            }
        }
    }
    per_block
        .into_iter()
        .filter(|&(closed, stopped, _)| closed > 0 && stopped == closed)
        .map(|(_, _, f)| f)
        .reduce(f64::min)
}

/// How far beyond the step's displacement bound (`max_displacement_overshoot · δ·w0`) an
/// unconverged ALM loop's solution must reach to count as run away. The rockfall's loops that
/// end at their cap reach at most just past the bound (1.01 times it), and the open–close
/// passes after them bring the attempt back within it; the jointed mass of 1000's runaway
/// reached 1112 times it.
const RUNAWAY: f64 = 10.0;

/// `Err` when the solution `d` of an ALM loop that did not converge moves a block more than
/// [`RUNAWAY`] times as far as the step allows.
fn runaway(inp: &AttemptInputs, d: &[f64]) -> Result<(), Retry> {
    let p = inp.params;
    match step_control::check_displacement(p, inp.blocks, inp.groups, d) {
        Err(Retry::Displacement(r, block)) if r > RUNAWAY * p.max_displacement_overshoot => {
            Err(Retry::Displacement(r, block))
        }
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solver::activate::contact_groups;

    /// A 1 m cube resting on a fixed slab, and the solution moving the cube straight up by `lift`.
    fn cube_lifted(lift: f64) -> (SolverParams, Vec<Block>, Vec<f64>) {
        let s = crate::scene::parse(crate::solver::CUBE_ON_SLAB, "cube.toml", "cube")
            .expect("scene parses");
        let mut d = vec![0.0; 24];
        d[12 + 2] = lift;
        (s.params, s.model.blocks, d)
    }

    /// Only a solution far beyond the step's displacement bound is a runaway: one just past it
    /// is left to the open–close passes, which may bring the attempt back.
    #[test]
    fn only_a_solution_far_beyond_the_step_bound_runs_away() {
        let (p, blocks, _) = cube_lifted(0.0);
        let boxes: Vec<_> = blocks.iter().map(|b| (b.lo, b.hi)).collect();
        let groups = contact_groups(&p, &blocks, &boxes);
        let inp = AttemptInputs {
            params: &p,
            blocks: &blocks,
            groups: &groups,
            time: 0.0,
            dt: p.max_time_step,
            scheme: Scheme::SHI,
            first_step: false,
            at_floor: false,
            held: &[],
            in_stage: false,
            stop_cuts: false,
        };
        // The bound: r = 1 at a lift of δ·w0 · overshoot; measure it from the check itself.
        let (_, _, d) = cube_lifted(1.0);
        let Err(Retry::Displacement(r_per_metre, _)) =
            step_control::check_displacement(&p, &blocks, &groups, &d)
        else {
            panic!("a lift of 1 m is beyond the bound");
        };
        let bound = p.max_displacement_overshoot / r_per_metre;
        for (times, runs_away) in [(0.5, false), (1.01, false), (9.0, false), (11.0, true)] {
            let (_, _, d) = cube_lifted(times * bound);
            let got = runaway(&inp, &d);
            assert_eq!(got.is_err(), runs_away, "{times} times the bound");
        }
    }
}
