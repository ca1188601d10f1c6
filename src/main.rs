use clap::Parser;
use dda3d::cli::{self, Cli, Command};

fn main() {
    // Mesa's drivers warn on every start when XDG_RUNTIME_DIR is unset (common over SSH and in
    // CI); point it at a private temporary directory before any thread or GPU library starts.
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        let dir = std::env::temp_dir().join("dda3d-xdg-runtime");
        if std::fs::create_dir_all(&dir).is_ok() {
            // SAFETY: single-threaded at this point; nothing reads the environment concurrently.
            unsafe { std::env::set_var("XDG_RUNTIME_DIR", &dir) };
        }
    }
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
        Command::Render(args) => cli::render(args),
        Command::Generate(args) => cli::generate(args),
        Command::Bench(args) => cli::bench(args),
        Command::View(args) => dda3d::ui::run_viewer(args),
    };
    if let Err(e) = result {
        eprintln!("error: {}", e.message());
        std::process::exit(e.exit_code());
    }
}
