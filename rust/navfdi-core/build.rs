//! No build step: the script exists so that its build-dependency (syn with the features of
//! pyo3's macros) gives the host crates of `cargo test --release` the features of the wheel's
//! build, which then shares every dependency with it (see Cargo.toml).
fn main() {}
