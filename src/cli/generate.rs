//! `dda3d generate`: writes a generated scene file, for measuring cost as the model grows.

use std::path::PathBuf;

use clap::Args;

use super::CliError;
use crate::generate::MAX_WALL_BLOCKS;

/// Kinds of generated scenes.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub enum GeneratedKind {
    /// A jointed wall of columns of stacked blocks, struck by a rock.
    Column,
}

#[derive(Args, Debug)]
pub struct GenerateArgs {
    /// What to generate.
    #[arg(value_enum)]
    pub kind: GeneratedKind,
    /// Number of jointed blocks (not counting the ground slab and the rock), at most 99998.
    #[arg(long, default_value_t = 5, allow_negative_numbers = true)]
    pub blocks: usize,
    /// Blocks per column (at most --blocks: one column).
    #[arg(long, default_value_t = 5, allow_negative_numbers = true)]
    pub layers: usize,
    /// Leave out the rock: a standing wall (to measure the cost of the machinery alone).
    #[arg(long)]
    pub no_rock: bool,
    /// Output scene file (default: out/column_<N>.toml).
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// `dda3d generate`.
pub fn generate(args: &GenerateArgs) -> Result<(), CliError> {
    // Within the scene's block limit, so that what is written loads.
    if !(1..=MAX_WALL_BLOCKS).contains(&args.blocks) {
        return Err(CliError::Input(format!(
            "--blocks must lie in 1..={MAX_WALL_BLOCKS}, got {}",
            args.blocks
        )));
    }
    if args.layers == 0 {
        return Err(CliError::Input("--layers must be at least 1".into()));
    }
    let text = match args.kind {
        GeneratedKind::Column => {
            crate::generate::column_wall(args.blocks, args.layers, !args.no_rock)
        }
    };
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("out").join(format!("column_{}.toml", args.blocks)));
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        crate::files::create_dir_clearly(dir).map_err(|e| {
            CliError::Run(format!(
                "{}: cannot create the output directory: {e}",
                dir.display()
            ))
        })?;
    }
    std::fs::write(&out, text).map_err(|e| CliError::Run(format!("{}: {e}", out.display())))?;
    eprintln!("wrote {}", out.display());
    Ok(())
}
