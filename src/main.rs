fn main() -> std::process::ExitCode {
    vvgen::alloc::retain_freed_memory();
    vvgen::cli::run()
}
