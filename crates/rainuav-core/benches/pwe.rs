//! Criterion benchmarks of the split-step march: one step at 1024x512 and 4096x1024
//! (complex64), each propagator, with and without a ground; and a 200-step march.
#![allow(missing_docs)]

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use num_complex::Complex64;
use rainuav_core::propagation::pwe::{
    Ground, MarchSpec, Marcher, Propagator, Recording, StepMedium, StepObstacle, gaussian_beam,
};

const F: f64 = 4.9e9;

fn spec(nx: usize, ny: usize, propagator: Propagator, ground: Ground) -> MarchSpec {
    MarchSpec {
        nx,
        ny,
        dx_m: 0.05,
        dy_m: 0.05,
        dz_m: 1.0,
        freq_hz: F,
        propagator,
        ground,
        absorber: 0.1,
        x_absorber_every: 1,
    }
}

fn marcher(nx: usize, ny: usize, propagator: Propagator, ground: Ground) -> Marcher {
    let u0 = gaussian_beam(nx, ny, 0.05, 0.05, F, ny as f64 * 0.025, 2.0, 4.333).unwrap();
    Marcher::new(spec(nx, ny, propagator, ground), u0.view()).unwrap()
}

fn rain(_: usize) -> StepMedium<'static> {
    StepMedium::Uniform(Complex64::new(1.000_001, -1e-7))
}
fn nothing(_: usize) -> StepObstacle<'static> {
    StepObstacle::None
}

fn bench_step(c: &mut Criterion) {
    let mut g = c.benchmark_group("pe_step");
    g.sample_size(10);
    for (nx, ny) in [(1024, 512), (4096, 1024)] {
        g.throughput(Throughput::Elements((10 * nx * ny) as u64));
        for prop in [Propagator::Wide, Propagator::Narrow] {
            for ground in [Ground::None, Ground::PecH] {
                let mut m = marcher(nx, ny, prop, ground);
                let id = BenchmarkId::new(format!("{prop:?}/{ground:?}"), format!("{nx}x{ny}"));
                let mut rec = Recording {
                    record_rows: &[],
                    row_offsets: None,
                    rows: None,
                    column: None,
                };
                g.bench_function(id, |b| {
                    // 10 steps per iteration so the chunk's entry pass (one forward row FFT)
                    // is amortised as in a real march; reported time is per 10 steps.
                    b.iter(|| m.advance(10, &rain, &nothing, &mut rec).unwrap())
                });
            }
        }
    }
    g.finish();

    let mut g = c.benchmark_group("pe_march_200_steps");
    g.sample_size(10);
    g.throughput(Throughput::Elements(200));
    g.bench_function("1024x512_wide_pec-h", |b| {
        b.iter(|| {
            let mut m = marcher(1024, 512, Propagator::Wide, Ground::PecH);
            let mut rec = Recording {
                record_rows: &[],
                row_offsets: None,
                rows: None,
                column: None,
            };
            m.advance(200, &rain, &nothing, &mut rec).unwrap();
            m.into_field()
        })
    });
    g.finish();
}

criterion_group!(benches, bench_step);
criterion_main!(benches);
