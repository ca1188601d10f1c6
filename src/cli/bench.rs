//! `dda3d bench`: checks the options and hands over to [`crate::bench`], which times the
//! rockfall with both methods and the scaling on generated walls.

use std::path::PathBuf;

use clap::Args;

use super::CliError;

#[derive(Args, Debug)]
pub struct BenchArgs {
    /// The rockfall scene to time.
    #[arg(long, default_value = "scenes/rock_column_rockfall.toml")]
    pub scene: PathBuf,
    /// Generated wall sizes for the scaling study with the rockfall (comma separated).
    #[arg(long, value_delimiter = ',', num_args = 0.., default_value = "10,100")]
    pub sizes: Vec<usize>,
    /// Generated wall sizes for the scaling study of a standing wall (no rock).
    #[arg(long, value_delimiter = ',', num_args = 0.., default_value = "10,100,1000")]
    pub standing_sizes: Vec<usize>,
    /// Runs per measurement; the fastest is reported.
    #[arg(long, default_value_t = 3)]
    pub repeat: usize,
    /// Simulated time of the scaling runs, s.
    #[arg(long, default_value_t = 2.0)]
    pub scaling_duration: f64,
}

/// `dda3d bench`.
pub fn bench(args: &BenchArgs) -> Result<(), CliError> {
    if !args.scene.exists() {
        return Err(CliError::Input(format!(
            "{}: no such scene file",
            args.scene.display()
        )));
    }
    if !(args.scaling_duration.is_finite() && args.scaling_duration > 0.0) {
        return Err(CliError::Input(
            "--scaling-duration must be positive".into(),
        ));
    }
    crate::bench::run(
        &args.scene,
        &args.sizes,
        &args.standing_sizes,
        args.repeat,
        args.scaling_duration,
    )
    .map_err(CliError::Run)
}
