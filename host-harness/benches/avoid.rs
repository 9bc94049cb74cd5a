//! Avoidance benchmarks (filled below).
fn main() {}
