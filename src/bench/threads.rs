//! What the second core buys: the generated walls on a pool of one thread and on the whole
//! pool (`RAYON_NUM_THREADS`, or every core), with the outputs compared. Detection, the block
//! terms, the ALM's per-contact work, the open–close check and the commit run in parallel; the
//! factorization and the solves do not (faer's parallel factorization was slower on these
//! matrices), so the speed-up is that of the parallel share.

use super::{BenchRun, best_of, generated_wall};

/// Prints the speed-up table for walls of `sizes` blocks, standing and struck.
pub fn thread_table(sizes: &[usize], duration: f64) -> Result<(), String> {
    let all = rayon::current_num_threads();
    println!(
        "\n## Threads: generated walls on 1 thread and on {all} (ALM, {duration} s simulated, one run each)\n"
    );
    println!(
        "| wall | N blocks | wall s, 1 thread | wall s, {all} threads | speed-up | same results |"
    );
    println!("|---|---|---|---|---|---|");
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .map_err(|e| format!("cannot make a one-thread pool: {e}"))?;
    for &n in sizes {
        for rock in [false, true] {
            let s = generated_wall(n, rock, duration)?;
            let run = || best_of(&s, 1, false).map_err(|e| format!("wall of {n}: {e}"));
            let single = one.install(run)?;
            let pooled = run()?;
            println!(
                "| {} | {n} | {:.3} | {:.3} | {:.2} | {} |",
                if rock { "struck" } else { "standing" },
                single.wall,
                pooled.wall,
                single.wall / pooled.wall,
                if same(&single, &pooled) { "yes" } else { "NO" }
            );
        }
    }
    Ok(())
}

/// The two runs took the same steps to the same state (the step count, the iteration counts
/// and the largest penetration, to the bit).
fn same(a: &BenchRun, b: &BenchRun) -> bool {
    let (x, y) = (&a.totals, &b.totals);
    x.steps == y.steps
        && x.alm_iterations == y.alm_iterations
        && x.factorizations == y.factorizations
        && x.max_penetration.to_bits() == y.max_penetration.to_bits()
        && a.simulated.to_bits() == b.simulated.to_bits()
}
