//! `dda3d bench`: checks the options and hands over to [`crate::bench`], which times the
//! rockfall with both methods, the scaling on generated walls, the struck walls with both
//! methods, rock-mass cutting and, if asked, rock-mass scenes as they are.

use std::path::PathBuf;

use clap::Args;

use super::CliError;
use crate::generate::MAX_WALL_BLOCKS;
use crate::params::SolverParams;

#[derive(Args, Debug)]
pub struct BenchArgs {
    /// The rockfall scene to time.
    #[arg(long, default_value = "scenes/rock_column_rockfall.toml")]
    pub scene: PathBuf,
    /// Generated wall sizes for the scaling study with the rockfall (comma separated, each
    /// 1..=99998).
    #[arg(long, value_delimiter = ',', num_args = 0.., default_value = "10,100", allow_negative_numbers = true)]
    pub sizes: Vec<usize>,
    /// Generated wall sizes for the scaling study of a standing wall (no rock).
    #[arg(long, value_delimiter = ',', num_args = 0.., default_value = "10,100,1000", allow_negative_numbers = true)]
    pub standing_sizes: Vec<usize>,
    /// Runs per measurement (1..=100); the fastest is reported.
    #[arg(long, default_value_t = 3, allow_negative_numbers = true)]
    pub repeat: usize,
    /// Simulated time of the scaling runs, s.
    #[arg(long, default_value_t = 2.0, allow_negative_numbers = true)]
    pub scaling_duration: f64,
    /// Wall sizes timed on one thread and on the whole pool, standing and struck (comma
    /// separated, each 1..=99998; empty: no such table).
    #[arg(long, value_delimiter = ',', num_args = 0.., default_value = "100", allow_negative_numbers = true)]
    pub thread_sizes: Vec<usize>,
    /// Struck wall sizes run with both methods, ALM (DDA-3a) and penalty (DDA-3p), for
    /// `--scaling-duration` s (comma separated, each 1..=99998; empty: no such table).
    #[arg(long, value_delimiter = ',', num_args = 0.., default_value = "100", allow_negative_numbers = true)]
    pub method_sizes: Vec<usize>,
    /// In the method table, DDA-3p also at these multiples of the walls' p_n,1 = 0.01 E (comma
    /// separated, each in (0, 10000]; e.g. 10,100,1000): what the penalty method costs at the
    /// accuracy a stiffer penalty buys.
    #[arg(long, value_delimiter = ',', num_args = 0.., allow_negative_numbers = true)]
    pub method_penalties: Vec<f64>,
    /// Rock-mass cutting: boxes cut by three joint sets into about this many blocks (comma
    /// separated, each 1..=100000).
    #[arg(long, value_delimiter = ',', num_args = 0.., default_value = "1000,10000", allow_negative_numbers = true)]
    pub cut_sizes: Vec<usize>,
    /// Rock-mass scenes timed as they are, their equilibrium stage apart (comma separated;
    /// e.g. scenes/jointed_mass_1000.toml, about 8 minutes on two cores).
    #[arg(long, value_delimiter = ',', num_args = 0..)]
    pub rock_masses: Vec<PathBuf>,
}

/// The most runs per measurement: the best of 100 is as good as a minimum gets, and a bound
/// keeps a typo (`--repeat 30000`) from running for days.
pub const MAX_REPEAT: usize = 100;

/// `dda3d bench`.
pub fn bench(args: &BenchArgs) -> Result<(), CliError> {
    check_options(args).map_err(CliError::Input)?;
    if !args.scene.exists() {
        return Err(CliError::Input(format!(
            "{}: no such scene file",
            args.scene.display()
        )));
    }
    // A scene that does not load is bad input (exit 2), not a failed benchmark; the rock masses
    // are checked before anything runs.
    crate::scene::load(&args.scene).map_err(|e| CliError::Input(e.to_string()))?;
    for path in &args.rock_masses {
        if !path.exists() {
            return Err(CliError::Input(format!(
                "{}: no such scene file (--rock-masses)",
                path.display()
            )));
        }
        crate::scene::load(path).map_err(|e| CliError::Input(e.to_string()))?;
    }
    crate::bench::run(
        &args.scene,
        &args.sizes,
        &args.standing_sizes,
        args.repeat,
        args.scaling_duration,
    )
    .map_err(CliError::Run)?;
    if !args.thread_sizes.is_empty() {
        crate::bench::thread_table(&args.thread_sizes, args.scaling_duration)
            .map_err(CliError::Run)?;
    }
    if !args.method_sizes.is_empty() {
        crate::bench::method_table(
            &args.method_sizes,
            args.scaling_duration,
            &args.method_penalties,
        )
        .map_err(CliError::Run)?;
    }
    if !args.cut_sizes.is_empty() {
        crate::bench::cut_table(&args.cut_sizes, args.repeat).map_err(CliError::Run)?;
    }
    if !args.rock_masses.is_empty() {
        crate::bench::rock_mass_table(&args.rock_masses).map_err(CliError::Run)?;
    }
    Ok(())
}

/// The wall sizes, the repeat count and the scaling runs' duration, checked before anything is
/// generated or run: a wall of 10⁹ blocks ran out of memory after 12.9 GB, and a wall of 0
/// printed `inf`.
fn check_options(args: &BenchArgs) -> Result<(), String> {
    for (flag, sizes) in [
        ("--sizes", &args.sizes),
        ("--standing-sizes", &args.standing_sizes),
        ("--thread-sizes", &args.thread_sizes),
        ("--method-sizes", &args.method_sizes),
    ] {
        if let Some(n) = sizes.iter().find(|n| !(1..=MAX_WALL_BLOCKS).contains(n)) {
            return Err(format!(
                "{flag}: each wall size must lie in 1..={MAX_WALL_BLOCKS} blocks, got {n}"
            ));
        }
    }
    if let Some(n) = args
        .cut_sizes
        .iter()
        .find(|n| !(1..=crate::scene::MAX_BLOCKS).contains(n))
    {
        return Err(format!(
            "--cut-sizes: each size must lie in 1..={} blocks, got {n}",
            crate::scene::MAX_BLOCKS
        ));
    }
    let most = crate::bench::MAX_PENALTY_FACTOR;
    if let Some(f) = args
        .method_penalties
        .iter()
        .find(|f| !(f.is_finite() && **f > 0.0 && **f <= most))
    {
        return Err(format!(
            "--method-penalties: each factor must lie in (0, {most}], got {f}"
        ));
    }
    if !(1..=MAX_REPEAT).contains(&args.repeat) {
        return Err(format!(
            "--repeat must lie in 1..={MAX_REPEAT}, got {}",
            args.repeat
        ));
    }
    let d = args.scaling_duration;
    if !(d.is_finite() && d > 0.0) {
        return Err("--scaling-duration must be positive".into());
    }
    // The generated walls' parameters, with this duration: the table's range and step limit.
    let params = SolverParams {
        duration: d,
        max_time_step: crate::generate::MAX_TIME_STEP,
        ..SolverParams::default()
    };
    params
        .validate()
        .map_err(|e| format!("--scaling-duration: {e}"))
}
