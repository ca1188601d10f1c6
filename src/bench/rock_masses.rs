//! Rock-mass scenes timed as they are (`bench --rock-masses SCENE,...`): the initial equilibrium
//! stage apart, then the run after it, with the same split as the walls' tables. Issue #15's
//! target for a jointed rock mass of 1000 blocks is the time per simulated second after its
//! stage, with a disturbed part moving: `scenes/jointed_mass_1000.toml` is that scene.

use std::path::{Path, PathBuf};
use std::time::Instant;

use super::walls::peak_rss_mb;
use super::{ms_per_factorization, stage_split};
use crate::scene;
use crate::solver::Solver;

/// The stage and the run after it, for one scene.
struct RockMassRun {
    blocks: usize,
    stage_steps: u64,
    stage_wall: f64,
    stage_converged: Option<bool>,
    /// Wall time of the steps after the stage, s.
    wall: f64,
    simulated: f64,
    totals: crate::snapshot::RunTotals,
}

fn time_rock_mass(path: &Path) -> Result<RockMassRun, String> {
    let s = scene::load(path).map_err(|e| e.to_string())?;
    let blocks = s.model.blocks.len();
    let mut solver = Solver::new(s.model, s.params);
    let fail = |e: crate::solver::SolverError| format!("{}: {e}", path.display());
    let (mut stage_steps, mut stage_wall, mut wall) = (0, 0.0, 0.0);
    while !solver.finished() {
        let staging = solver.in_equilibrium_stage();
        let t = Instant::now();
        solver.step().map_err(fail)?;
        let dt = t.elapsed().as_secs_f64();
        if staging {
            stage_steps += 1;
            stage_wall += dt;
        } else {
            wall += dt;
        }
    }
    Ok(RockMassRun {
        blocks,
        stage_steps,
        stage_wall,
        stage_converged: solver.equilibrium().map(|r| r.converged),
        wall,
        simulated: solver.time,
        totals: solver.totals.clone(),
    })
}

/// Prints the rock-mass table (Markdown), one run per scene.
pub fn rock_mass_table(paths: &[PathBuf]) -> Result<(), String> {
    println!("\n## Rock masses, as their scenes set them (one run each)\n");
    println!(
        "The equilibrium stage is timed apart; the rest of the row is the run after it (issue #15's target for a jointed mass of 1000 blocks: ≤ 2 s per simulated second).\n"
    );
    println!(
        "| scene | blocks | stage steps | stage wall s | stage converged | steps after | simulated s | wall s after | wall s per simulated s | contacts/step | open–close/step | solves/step | factorizations/step | ms per factorization | ms/step: detection / assembly / factorization / solve / bookkeeping | peak RSS MB |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for path in paths {
        let r = time_rock_mass(path)?;
        let t = &r.totals;
        let steps = t.steps.max(1) as f64;
        let per_sim = if r.simulated > 0.0 {
            format!("{:.1}", r.wall / r.simulated)
        } else {
            "–".into()
        };
        println!(
            "| {} | {} | {} | {:.1} | {} | {} | {:.3} | {:.1} | {per_sim} | {:.0} | {:.1} | {:.1} | {:.1} | {:.1} | {} | {} |",
            path.display(),
            r.blocks,
            r.stage_steps,
            r.stage_wall,
            r.stage_converged
                .map_or("no stage", |c| if c { "yes" } else { "no" }),
            t.steps,
            r.simulated,
            r.wall,
            t.contacts_per_step,
            t.open_close_iterations as f64 / steps,
            t.alm_iterations as f64 / steps,
            t.factorizations as f64 / steps,
            ms_per_factorization(t),
            stage_split(t),
            peak_rss_mb().map_or("–".into(), |m| format!("{m:.0}")),
        );
    }
    Ok(())
}
