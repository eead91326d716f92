//! Times the FFT work of one split-step (rows and columns forward and inverse, as contiguous
//! batches, no gathering) and a plain copy of the field, to compare a PE step against its
//! compute and memory floors. `cargo run --release --example fft_floor -- 4096 1024`.
use num_complex::Complex32;
use rayon::prelude::*;
use rustfft::FftPlanner;
use std::time::Instant;

fn main() {
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .map(|a| a.parse().unwrap())
        .collect();
    let (nx, ny) = (
        args.first().copied().unwrap_or(4096),
        args.get(1).copied().unwrap_or(1024),
    );
    let mut p = FftPlanner::<f32>::new();
    let (rf, ri, cf, ci) = (
        p.plan_fft_forward(ny),
        p.plan_fft_inverse(ny),
        p.plan_fft_forward(nx),
        p.plan_fft_inverse(nx),
    );
    let mut a = vec![Complex32::new(1.0, 0.5); nx * ny];
    let mut t = vec![Complex32::new(1.0, 0.5); nx * ny];
    let reps = 20;
    let t0 = Instant::now();
    for _ in 0..reps {
        a.par_chunks_mut(ny * 8).for_each(|c| {
            rf.process(c);
            ri.process(c);
        });
        t.par_chunks_mut(nx * 8).for_each(|c| {
            cf.process(c);
            ci.process(c);
        });
    }
    let fft = t0.elapsed().as_secs_f64() / reps as f64;
    let t0 = Instant::now();
    for _ in 0..reps {
        t.par_chunks_mut(ny * 64)
            .zip(a.par_chunks(ny * 64))
            .for_each(|(d, s)| d.copy_from_slice(s));
    }
    let copy = t0.elapsed().as_secs_f64() / reps as f64;
    let gb = (nx * ny * 8 * 2) as f64 / 1e9;
    println!(
        "{nx}x{ny}: FFTs of one step {:.2} ms; one field copy {:.2} ms ({:.1} GB/s)",
        fft * 1e3,
        copy * 1e3,
        gb / copy
    );
}
