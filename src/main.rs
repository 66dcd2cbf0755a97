fn main() {
    std::process::exit(modellint::cli::run());
}
