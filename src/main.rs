fn main() -> std::process::ExitCode {
    rayterm::cli::main()
}
