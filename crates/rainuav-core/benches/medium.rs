//! Criterion benchmarks of the rain medium: specific attenuation for 10^4 (frequency, rate)
//! pairs, cold (Mie kernels built) and warm (kernels cached), and one kernel build.
#![allow(missing_docs)]

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use ndarray::Array1;
use rainuav_core::medium::{
    MediumOptions, RainKernel, clear_kernel_cache, specific_attenuation_many,
};
use std::hint::black_box;

/// `nf` frequencies log-spaced over 1-100 GHz times `nr` rates over 0.5-150 mm/h.
fn grid(nf: usize, nr: usize) -> (Array1<f64>, Array1<f64>) {
    let mut f = Vec::with_capacity(nf * nr);
    let mut r = Vec::with_capacity(nf * nr);
    for i in 0..nf {
        let fi = 1e9 * 100f64.powf(i as f64 / (nf.max(2) - 1) as f64);
        for j in 0..nr {
            f.push(fi);
            r.push(0.5 + 149.5 * j as f64 / (nr.max(2) - 1) as f64);
        }
    }
    (Array1::from(f), Array1::from(r))
}

fn bench_medium(c: &mut Criterion) {
    let opts = MediumOptions::default();
    let mut g = c.benchmark_group("specific_attenuation_1e4_pairs");
    g.sample_size(10);
    for (name, nf, nr) in [
        ("10000_freqs_cold", 10_000, 1),
        ("100x100_cold", 100, 100),
        ("1_freq_x_10000_rates_cold", 1, 10_000),
    ] {
        let (f, r) = grid(nf, nr);
        g.bench_function(name, |b| {
            b.iter_batched(
                clear_kernel_cache,
                |_| specific_attenuation_many(f.view(), r.view(), &opts).unwrap(),
                BatchSize::PerIteration,
            )
        });
    }
    let (f, r) = grid(100, 100);
    specific_attenuation_many(f.view(), r.view(), &opts).unwrap();
    g.bench_function("100x100_warm", |b| {
        b.iter(|| specific_attenuation_many(black_box(f.view()), r.view(), &opts).unwrap())
    });
    g.finish();

    let mut k = c.benchmark_group("kernel_build");
    for f in [4.9e9, 28e9, 300e9] {
        k.bench_function(format!("{}GHz", f / 1e9), |b| {
            b.iter(|| RainKernel::new(black_box(f), &opts).unwrap())
        });
    }
    k.finish();
}

criterion_group!(benches, bench_medium);
criterion_main!(benches);
