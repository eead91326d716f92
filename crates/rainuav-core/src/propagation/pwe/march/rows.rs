//! One row's transforms (plain FFT, image extension, the sine transform of a PEC ground under
//! horizontal polarisation) and the lateral taper.

use super::*;

/// cos^2 taper: 1 inside, to 0 at the edges over `frac * n` samples; `lo`/`hi` select edges.
pub(super) fn taper(n: usize, frac: f64, lo: bool, hi: bool) -> Vec<f32> {
    let width = (frac * n as f64).round();
    (0..n)
        .map(|i| {
            if width < 1.0 {
                return 1.0;
            }
            let mut w = 1.0f64;
            let from_lo = i as f64;
            let from_hi = (n - 1 - i) as f64;
            if lo && from_lo < width {
                w *= (std::f64::consts::FRAC_PI_2 * (1.0 - from_lo / width))
                    .cos()
                    .powi(2);
            }
            if hi && from_hi < width {
                w *= (std::f64::consts::FRAC_PI_2 * (1.0 - from_hi / width))
                    .cos()
                    .powi(2);
            }
            w as f32
        })
        .collect()
}

/// Forward y transform of one row: plain FFT, the sine transform (`"pec-h"`, when `dst` is
/// given), or image extension then FFT.
pub(super) fn forward_row(
    ground: Ground,
    (fft, dst): (&dyn Fft<f32>, Option<&Dst>),
    row: &mut [C32],
    nyq: &mut C32,
    ext: &mut [C32],
    scratch: &mut [C32],
) {
    let ny = row.len();
    if let Some(dst) = dst {
        return dst.apply(row, &mut ext[..ny], scratch, Dst::FORWARD);
    }
    match ground {
        Ground::None => fft.process_with_scratch(row, scratch),
        Ground::PecH | Ground::PecV => {
            let sign = if ground == Ground::PecH { -1.0 } else { 1.0 };
            ext[0] = if ground == Ground::PecH {
                C32::default()
            } else {
                row[0]
            };
            for j in 1..ny {
                ext[j] = row[j];
                ext[2 * ny - j] = row[j] * sign;
            }
            ext[ny] = C32::default();
            fft.process_with_scratch(ext, scratch);
            row.copy_from_slice(&ext[..ny]);
            *nyq = ext[ny];
        }
    }
}

/// One row of a row pass: its index, the row, its Nyquist coefficient, its recording slots.
type RowItem<'a> = (usize, ((&'a mut [C32], &'a mut C32), &'a mut [C32]));

/// The rows of the field (length `ny`), each with its Nyquist coefficient and its `nr` slots
/// of the recording buffer, in parallel, with the row index.
pub(super) fn par_rows<'a>(
    field: &'a mut [C32],
    nyquist: &'a mut [C32],
    rec: &'a mut [C32],
    ny: usize,
    nr: usize,
) -> impl IndexedParallelIterator<Item = RowItem<'a>> {
    field
        .par_chunks_mut(ny)
        .zip(nyquist.par_iter_mut())
        .zip(rec.par_chunks_mut(nr))
        .enumerate()
}

/// Inverse y transform of one row (unnormalised): plain inverse FFT, the sine transform
/// (`"pec-h"`, when `dst` is given), or the image extension's inverse FFT.
pub(super) fn inverse_row(
    ground: Ground,
    (inv, dst): (&dyn Fft<f32>, Option<&Dst>),
    row: &mut [C32],
    nyq: C32,
    ext: &mut [C32],
    scratch: &mut [C32],
) {
    let ny = row.len();
    if ground == Ground::None {
        inv.process_with_scratch(row, scratch);
    } else if let Some(dst) = dst {
        dst.apply(row, &mut ext[..ny], scratch, Dst::INVERSE);
    } else {
        spectrum_to_ext(ground, row, nyq, ext);
        inv.process_with_scratch(ext, scratch);
        row.copy_from_slice(&ext[..ny]);
    }
}

/// Values per `|kx|` row of the uniform path's table: `ny` ky values, and the Nyquist
/// coefficient's with a ground.
pub(super) fn fast_tab_width(ny: usize, ground: Ground) -> usize {
    match ground {
        Ground::None => ny,
        _ => ny + 1,
    }
}

/// Rebuilds the full `2 ny` image-extended spectrum from the stored half.
pub(super) fn spectrum_to_ext(ground: Ground, row: &[C32], nyq: C32, ext: &mut [C32]) {
    let ny = row.len();
    match ground {
        Ground::None => ext[..ny].copy_from_slice(row),
        Ground::PecH | Ground::PecV => {
            let sign = if ground == Ground::PecH { -1.0 } else { 1.0 };
            ext[0] = row[0];
            for m in 1..ny {
                ext[m] = row[m];
                ext[2 * ny - m] = row[m] * sign;
            }
            ext[ny] = if ground == Ground::PecV {
                nyq
            } else {
                C32::default()
            };
        }
    }
}

/// The sine transform (DST-I) of a complex row through one FFT of the row's own length.
///
/// The image method's odd extension of `x` (`x[0] = 0`, `x[2N - j] = -x[j]`) has the FFT
/// `-2j S[m]` and the inverse FFT `+2j S[m]`, with `S[m] = sum_{j=1}^{N-1} x[j] sin(pi j m / N)`
/// (`m < N`; the rest of the length-`2N` result repeats it). `S` comes from one FFT `Z` of
/// `y[j] = sin(pi j / N) (x[j] + x[N-j]) + (x[j] - x[N-j]) / 2` (Numerical Recipes' `sinft`,
/// on complex data): `S[2k] = j (Z[k] - Z[N-k]) / 2`, `S[1] = Z[0] / 2` and
/// `S[2k+1] = S[2k-1] + (Z[k] + Z[N-k]) / 2`; the running sum is kept in f64.
pub(super) struct Dst {
    fft: Arc<dyn Fft<f32>>,
    /// `sin(pi j / N)`, j < N.
    sin: Vec<f32>,
}

impl Dst {
    /// Scale of the forward transform, the image extension's FFT: `-2j`.
    pub(super) const FORWARD: C32 = C32::new(0.0, -2.0);
    /// Scale of the inverse transform, the image extension's unnormalised inverse FFT: `+2j`.
    pub(super) const INVERSE: C32 = C32::new(0.0, 2.0);

    pub(super) fn new(planner: &mut FftPlanner<f32>, n: usize) -> Self {
        let sin = (0..n)
            .map(|j| (std::f64::consts::PI * j as f64 / n as f64).sin() as f32)
            .collect();
        Dst {
            fft: planner.plan_fft_forward(n),
            sin,
        }
    }

    pub(super) fn scratch_len(&self) -> usize {
        self.fft.get_inplace_scratch_len()
    }

    /// `row[m] <- scale * S[m]` (`row[0] <- 0`); `y` (the row's length) and `scratch`
    /// (`scratch_len`) are work space.
    pub(super) fn apply(&self, row: &mut [C32], y: &mut [C32], scratch: &mut [C32], scale: C32) {
        let n = row.len();
        debug_assert_eq!(y.len(), n);
        y[0] = C32::default();
        for j in 1..n {
            let (a, b) = (row[j], row[n - j]);
            y[j] = (a + b) * self.sin[j] + (a - b) * 0.5;
        }
        self.fft.process_with_scratch(y, scratch);
        let even = scale * C32::new(0.0, 0.5); // j / 2, times the scale
        let half = scale * 0.5;
        row[0] = C32::default();
        let mut odd = Complex64::new(y[0].re as f64, y[0].im as f64);
        if n > 1 {
            row[1] = to_c32(odd) * half;
        }
        for k in 1..n.div_ceil(2) {
            let (zk, znk) = (y[k], y[n - k]);
            row[2 * k] = (zk - znk) * even;
            if 2 * k + 1 < n {
                let term = zk + znk;
                odd += Complex64::new(term.re as f64, term.im as f64);
                row[2 * k + 1] = to_c32(odd) * half;
            }
        }
    }
}
