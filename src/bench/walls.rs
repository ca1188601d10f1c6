//! The scaling study on generated walls (`dda3d generate column`): per size the iteration
//! counts, the wall time per simulated second, its split by stage, the cost of writing the
//! output (apart), the peak memory and the growth exponents.

use super::{best_of, generated_wall, growth_exponent, ms_per_factorization, stage_split};

/// One scaling table on generated walls, with or without the rockfall.
pub(super) fn scaling_table(
    sizes: &[usize],
    repeat: usize,
    duration: f64,
    rock: bool,
) -> Result<(), String> {
    println!(
        "\n## Scaling: generated walls (`dda3d generate column --blocks N{}`), ALM, {duration} s simulated\n",
        if rock { "" } else { " --no-rock" }
    );
    if rock {
        println!(
            "With the rockfall: the cost includes the open–close and ALM iterations of the impact.\n"
        );
    } else {
        println!(
            "Standing wall, no rock, after its initial equilibrium stage (timed apart, not in the wall time): a wall at rest, whose islands fall asleep once all their blocks have been still for `sleep_time`.\n"
        );
    }
    println!(
        "| N blocks | stage steps / s | steps | steps asleep | contacts/step | solves/step | factorizations/step | cuts | wall s | wall s per simulated s | steps/s | µs per contact-step | ms per factorization | ms/step: detection / assembly / factorization / solve / bookkeeping | output ms/step (apart) | peak RSS MB |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    let (mut ns, mut per_sim_s, mut walls, mut cs, mut cf) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for &n in sizes {
        let mut s = generated_wall(n, rock, duration)?;
        s.params.initial_equilibrium = !rock;
        let r = best_of(&s, if n >= 1000 { 1 } else { repeat }, true)
            .map_err(|e| format!("wall of {n}: {e}"))?;
        let t = &r.totals;
        let steps = t.steps.max(1) as f64;
        let contact_steps = t.contacts_per_step * t.steps as f64;
        let ms = |x: f64| format!("{:.1}", 1e3 * x / steps);
        println!(
            "| {n} | {} | {} | {} | {:.1} | {:.2} | {:.2} | {} | {:.3} | {:.3} | {:.1} | {:.2} | {:.3} | {} | {} | {} |",
            r.stage
                .map_or("–".into(), |(steps, wall)| format!("{steps} / {wall:.2}")),
            t.steps,
            t.sleeping_steps,
            t.contacts_per_step,
            t.alm_iterations as f64 / steps,
            t.factorizations as f64 / steps,
            t.time_step_cuts,
            r.wall,
            r.wall / r.simulated,
            steps / r.wall,
            1e6 * r.wall / contact_steps,
            ms_per_factorization(t),
            stage_split(t),
            r.output.map_or("–".into(), ms),
            peak_rss_mb().map_or("–".into(), |m| format!("{m:.0}")),
        );
        ns.push(n as f64);
        per_sim_s.push(r.wall / r.simulated);
        walls.push(r.wall);
        cs.push(contact_steps);
        // The work of the iterations: every factorization (and the assembly and bookkeeping
        // around it) touches every contact once.
        cf.push(t.contacts_per_step * t.factorizations as f64);
    }
    if ns.len() >= 2 {
        println!(
            "\nGrowth exponent (least squares on log-log, 1 = linear): wall time per simulated second against N: {:.2}; wall time against contact-steps: {:.2}; wall time against contact-factorizations (contacts × factorizations: the cost of the machinery for the iterations it was asked to do): {:.2}.",
            growth_exponent(&ns, &per_sim_s),
            growth_exponent(&cs, &walls),
            growth_exponent(&cf, &walls)
        );
        let segments: Vec<String> = (1..ns.len())
            .map(|i| {
                format!(
                    "{}→{}: {:.2} against contact-steps, {:.2} against contact-factorizations",
                    ns[i - 1],
                    ns[i],
                    growth_exponent(&cs[i - 1..=i], &walls[i - 1..=i]),
                    growth_exponent(&cf[i - 1..=i], &walls[i - 1..=i])
                )
            })
            .collect();
        println!("Between consecutive sizes: {}.", segments.join("; "));
    }
    Ok(())
}

/// The process's peak resident memory so far (Linux: VmHWM), MB.
pub(super) fn peak_rss_mb() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}
