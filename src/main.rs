use clap::Parser;
use dda3d::cli::{self, Cli, Command};

fn main() {
    // `dda3d SCENE.toml` is short for `dda3d view SCENE.toml`.
    let mut args: Vec<std::ffi::OsString> = std::env::args_os().collect();
    if args
        .get(1)
        .is_some_and(|a| a.to_string_lossy().ends_with(".toml"))
    {
        args.insert(1, "view".into());
    }
    let cli = Cli::parse_from(args);
    let result = match &cli.command {
        Command::Run(args) => cli::run(args),
        Command::Generate(args) => cli::generate(args),
        Command::Bench(args) => cli::bench(args),
        Command::View(args) => dda3d::ui::run_viewer(args),
    };
    if let Err(e) = result {
        eprintln!("error: {}", e.message());
        std::process::exit(e.exit_code());
    }
}
