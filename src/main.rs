//! The `deepfield` command: see `deepfield --help` and the README.

mod cli;

fn main() -> std::process::ExitCode {
    cli::main()
}
