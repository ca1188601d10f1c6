//! DDA-3a against DDA-3p on the struck walls: the issue's "DDA-3a ≤ 1.2× DDA-3p on the rockfall
//! and on the struck walls" (the rockfall's own ratio is the first table's). The same generated
//! wall is run with each method, and the table shows where the difference comes from: the
//! open–close passes and solves a step, the steps settled at the pass limit, and the accuracy
//! each method buys (the largest penetration).

use super::{best_of, generated_wall, iterations_per_step, method_name, per_step_ratio};
use crate::params::Method;

/// Prints the method comparison for struck walls of `sizes` blocks, one run each.
pub fn method_table(sizes: &[usize], duration: f64) -> Result<(), String> {
    println!(
        "\n## Methods: struck walls with ALM (DDA-3a) and penalty (DDA-3p), {duration} s simulated, one run each\n"
    );
    println!(
        "| N blocks | method | wall s | wall s per simulated s | steps | open-close/step | solves/step | factorizations/step | steps settled at the pass limit | max penetration m |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for &n in sizes {
        let mut runs = Vec::new();
        for method in [Method::Alm, Method::Penalty] {
            let mut s = generated_wall(n, true, duration)?;
            s.params.method = method;
            let r = best_of(&s, 1, false).map_err(|e| format!("wall of {n}: {e}"))?;
            let t = &r.totals;
            let steps = t.steps.max(1) as f64;
            println!(
                "| {n} | {} | {:.3} | {:.3} | {} | {} | {} | {:.2e} |",
                method_name(method),
                r.wall,
                r.wall / r.simulated,
                t.steps,
                iterations_per_step(t),
                t.unconverged_steps,
                t.max_penetration,
            );
            runs.push((r.wall, steps));
        }
        println!(
            "| {n} | ALM / penalty | {:.2} | | {:.2} per step | | | | | |",
            runs[0].0 / runs[1].0,
            per_step_ratio(runs[0], runs[1])
        );
    }
    Ok(())
}
