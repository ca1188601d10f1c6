//! `dda3d cut`: cuts the scene's rock masses into blocks and writes the scene with explicit
//! `[[blocks]]` (and the `[[joint_sets]]` whose planes give their joints their properties), and
//! prints what each rock mass was cut into.

use std::path::PathBuf;

use clap::Args;

use super::CliError;

#[derive(Args, Debug)]
pub struct CutArgs {
    /// Scene file with [[rock_masses]].
    pub scene: PathBuf,
    /// Output scene file (default: the scene's name with `_cut` added, beside it).
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// `dda3d cut`.
pub fn cut(args: &CutArgs) -> Result<(), CliError> {
    let (text, reports) = crate::scene::cut_scene(&args.scene)?;
    if reports.is_empty() {
        return Err(CliError::Input(format!(
            "{}: no [[rock_masses]] to cut",
            args.scene.display()
        )));
    }
    let out = args.out.clone().unwrap_or_else(|| {
        let stem = args
            .scene
            .file_stem()
            .map_or_else(|| "scene".into(), |s| s.to_string_lossy().into_owned());
        args.scene.with_file_name(format!("{stem}_cut.toml"))
    });
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        crate::files::create_dir_clearly(dir).map_err(|e| {
            CliError::Run(format!(
                "{}: cannot create the output directory: {e}",
                dir.display()
            ))
        })?;
    }
    std::fs::write(&out, text).map_err(|e| CliError::Run(format!("{}: {e}", out.display())))?;
    for r in &reports {
        println!("{r}");
    }
    eprintln!("wrote {}", out.display());
    Ok(())
}
