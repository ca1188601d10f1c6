use clap::Parser;
use dda3d::cli::{self, Cli, Command};

fn main() {
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Run(args) => cli::run(args),
        Command::Render(args) => cli::render(args),
        Command::Generate(args) => cli::generate(args),
        Command::Bench(args) => cli::bench(args),
    };
    if let Err(e) = result {
        eprintln!("error: {}", e.message());
        std::process::exit(e.exit_code());
    }
}
