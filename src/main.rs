fn main() {
    std::process::exit(thermostamp::cli::main());
}
