//! The `whycode` command line; the work is done by the library.

mod cli;

fn main() -> std::process::ExitCode {
    cli::main()
}
