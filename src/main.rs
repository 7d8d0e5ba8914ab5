fn main() -> std::process::ExitCode {
    whycode::cli::main()
}
