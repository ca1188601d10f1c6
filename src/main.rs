//! The `dda3d` binary: everything it does is in [`dda3d::cli`].

fn main() -> std::process::ExitCode {
    dda3d::cli::main_entry()
}
