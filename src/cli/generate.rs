//! `dda3d generate`: writes a generated scene file, for measuring cost as the model grows.

use std::path::PathBuf;

use clap::Args;

use super::CliError;

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
    /// Number of jointed blocks (not counting the ground slab and the rock).
    #[arg(long, default_value_t = 5)]
    pub blocks: usize,
    /// Blocks per column.
    #[arg(long, default_value_t = 5)]
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
    if args.blocks == 0 || args.blocks > 1_000_000 {
        return Err(CliError::Input(format!(
            "--blocks must lie in 1..=1000000, got {}",
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
        std::fs::create_dir_all(dir)
            .map_err(|e| CliError::Run(format!("{}: {e}", dir.display())))?;
    }
    std::fs::write(&out, text).map_err(|e| CliError::Run(format!("{}: {e}", out.display())))?;
    eprintln!("wrote {}", out.display());
    Ok(())
}
