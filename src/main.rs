//! The `caustic` command.
fn main() -> std::process::ExitCode {
    caustic::cli::main()
}
