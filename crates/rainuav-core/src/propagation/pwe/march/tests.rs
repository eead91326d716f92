//! Unit tests of [`super`].

use super::rows::forward_row;
use super::*;

/// The sine transform against its definition, summed in f64 (an independent brute-force
/// reference), for even and odd lengths. Tolerance: a relative L2 error of
/// `1e-7 sqrt(N) + 2e-7`. The running sum adds up N / 2 FFT outputs, each with its f32
/// rounding, so the error grows like `sqrt(N)`: 1.8e-6 at N = 1296, against 1.3e-7 for the
/// image extension's FFT of length `2N` (printed on failure). What it does to the maps
/// (at most 0.001 dB) is in the module docs.
#[test]
fn dst_matches_its_definition() {
    for n in [2usize, 3, 8, 15, 64, 1296, 2500] {
        let x: Vec<C32> = (0..n)
            .map(|j| {
                let t = j as f32;
                C32::new((0.37 * t).sin() + 0.1 * t.cos(), (1.3 * t).cos() - 0.2)
            })
            .collect();
        let mut planner = FftPlanner::<f32>::new();
        let dst = Dst::new(&mut planner, n);
        let mut row = x.clone();
        let mut y = vec![C32::default(); n];
        let mut scratch = vec![C32::default(); dst.scratch_len()];
        dst.apply(&mut row, &mut y, &mut scratch, Dst::FORWARD);
        let ext_fft = planner.plan_fft_forward(2 * n);
        let mut ext = vec![C32::default(); 2 * n];
        let mut nyq = C32::default();
        let mut via_ext = x.clone();
        let mut scratch = vec![C32::default(); ext_fft.get_inplace_scratch_len()];
        forward_row(
            Ground::PecH,
            (&*ext_fft, None),
            &mut via_ext,
            &mut nyq,
            &mut ext,
            &mut scratch,
        );
        let (mut err, mut err_ext, mut total) = (0.0f64, 0.0f64, 0.0f64);
        for m in 0..n {
            let s: Complex64 = (1..n)
                .map(|j| {
                    let w = (std::f64::consts::PI * (j * m) as f64 / n as f64).sin();
                    Complex64::new(x[j].re as f64, x[j].im as f64) * w
                })
                .sum();
            let want = s * Complex64::new(0.0, -2.0);
            let c = |z: C32| Complex64::new(z.re as f64, z.im as f64);
            err += (c(row[m]) - want).norm_sqr();
            err_ext += (c(via_ext[m]) - want).norm_sqr();
            total += want.norm_sqr();
        }
        let (rel, rel_ext) = ((err / total).sqrt(), (err_ext / total).sqrt());
        assert!(
            rel < 1e-7 * (n as f64).sqrt() + 2e-7,
            "n = {n}: relative error {rel:e}, the image extension's {rel_ext:e}"
        );
    }
}

/// A tilted beam, off-centre in x and y, on an nx x ny grid with a window: the fixture of
/// the uniform path's tests.
fn uniform_case(ground: Ground, every: usize) -> (MarchSpec, Array2<C32>) {
    let (nx, ny) = (96usize, 80usize);
    let spec = MarchSpec {
        nx,
        ny,
        dx_m: 0.05,
        dy_m: 0.05,
        dz_m: 0.05,
        freq_hz: 4.9e9,
        propagator: Propagator::Wide,
        ground,
        absorber: 0.2,
        x_absorber_every: every,
    };
    let u0 = super::super::source::gaussian_beam(nx, ny, 0.05, 0.05, 4.9e9, 1.6, 8.0, 20.0)
        .expect("valid beam");
    // Shift the beam off the x centre so that both lateral strips see different fields.
    let u0 = Array2::from_shape_fn((nx, ny), |(ix, iy)| u0[((ix + 7) % nx, iy)]);
    (spec, u0)
}

/// Marches `u0` through `plan` (steps, with obstacles or not), recording rows 10 and 30;
/// `fast_from` picks the uniform path's threshold.
fn run(
    spec: &MarchSpec,
    u0: &Array2<C32>,
    fast_from: usize,
    plan: &[(usize, bool)],
) -> (Array2<C32>, ndarray::Array3<C32>) {
    let total: usize = plan.iter().map(|p| p.0).sum();
    let mut m = Marcher::new(spec.clone(), u0.view()).expect("valid march");
    m.fast_from = fast_from;
    let rows = [10usize, 30];
    let mut out = ndarray::Array3::<C32>::zeros((2, total, spec.nx));
    let heights = ndarray::Array1::from_elem(spec.nx, 0.06);
    let rain = Complex64::new(1.0 + 2e-6, -3e-7);
    for &(steps, blocked) in plan {
        let mut rec = Recording {
            record_rows: &rows,
            row_offsets: None,
            rows: Some(out.view_mut()),
            column: None,
        };
        let obstacle = |_k: usize| {
            if blocked {
                StepObstacle::Heights(heights.view())
            } else {
                StepObstacle::None
            }
        };
        m.advance(steps, &|_k| StepMedium::Uniform(rain), &obstacle, &mut rec)
            .expect("valid step");
    }
    (m.into_field(), out)
}

fn rel(a: impl Iterator<Item = (C32, C32)>) -> f64 {
    let (mut e, mut t) = (0.0f64, 0.0f64);
    for (x, y) in a {
        e += ((x - y).norm() as f64).powi(2);
        t += (y.norm() as f64).powi(2);
    }
    (e / t).sqrt()
}

/// The uniform path with the lateral window every step does what the general step does:
/// the same operations in another order (they commute), so the final field agrees to f32
/// rounding (tolerance 1e-5 relative L2, about 100 roundings of 1e-7), also when a
/// march switches between the paths (steps with a building's heights go the general
/// way). Recorded rows are read before the lateral window in the uniform path, after it
/// in the general one: they agree where the window is 1.
#[test]
fn uniform_path_matches_the_general_step() {
    for ground in [Ground::None, Ground::PecH, Ground::PecV] {
        let (spec, u0) = uniform_case(ground, 1);
        for plan in [vec![(12, false)], vec![(5, false), (3, true), (4, false)]] {
            let (f_gen, r_gen) = run(&spec, &u0, usize::MAX, &plan);
            let (f_uni, r_uni) = run(&spec, &u0, 1, &plan);
            let e = rel(f_uni.iter().copied().zip(f_gen.iter().copied()));
            assert!(e < 1e-5, "{ground:?} {plan:?}: field differs by {e:e}");
            let inner = taper(spec.nx, spec.absorber, true, true);
            let pairs = r_uni
                .indexed_iter()
                .filter(|((_, _, ix), _)| inner[*ix] == 1.0);
            let e = rel(pairs.map(|(i, &v)| (v, r_gen[i])));
            assert!(e < 1e-5, "{ground:?} {plan:?}: rows differ by {e:e}");
        }
    }
}

/// The lateral window every 4 steps (as its 4th power) leaves the recorded rows inside
/// the window's inner region as they were to 1e-3 relative (about 0.01 dB), where the
/// widest angle the grid carries crosses a sixth of a strip between windows (what the
/// engine allows is an eighth): only the strips' absorption is sampled more coarsely.
#[test]
fn coarse_lateral_window_leaves_the_inner_region() {
    for ground in [Ground::None, Ground::PecH] {
        let (spec1, u0) = uniform_case(ground, 1);
        let (spec4, _) = uniform_case(ground, 4);
        let plan = [(96, false)];
        let (_, r1) = run(&spec1, &u0, usize::MAX, &plan);
        let (_, r4) = run(&spec4, &u0, 2, &plan);
        let none = MarchSpec {
            absorber: 0.0,
            ..spec1.clone()
        };
        let (_, r0) = run(&none, &u0, usize::MAX, &plan);
        let inner = taper(spec1.nx, spec1.absorber, true, true);
        let pairs = r4
            .indexed_iter()
            .filter(|((_, _, ix), _)| inner[*ix] == 1.0);
        let e = rel(pairs.map(|(i, &v)| (v, r1[i])));
        let pairs = r0
            .indexed_iter()
            .filter(|((_, _, ix), _)| inner[*ix] == 1.0);
        let e0 = rel(pairs.map(|(i, &v)| (v, r1[i])));
        // The window matters here (without it the rows move by 0.9-12%, measured), and
        // applied every 4 steps it moves them by 2.4e-4 (measured).
        assert!(
            e0 > 5e-3,
            "{ground:?}: the absorber does nothing here ({e0:e})"
        );
        assert!(e < 1e-3, "{ground:?}: rows differ by {e:e}");
    }
}
