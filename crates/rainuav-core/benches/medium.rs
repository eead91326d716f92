//! Criterion benchmarks of the rain medium: specific attenuation for 10^4 pairs.
#![allow(missing_docs)]
fn main() {}
