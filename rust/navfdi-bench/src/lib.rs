//! Criterion benchmarks of `navfdi-core` live in `benches/*.rs` at the repository root; this
//! crate only hosts them, so that `cargo test` on the core does not compile criterion.
//! Run them with `cargo bench -p navfdi-bench` (or `--bench NAME`).
