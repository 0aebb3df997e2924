fn main() -> std::process::ExitCode {
    vvgen::cli::run()
}
