//! 3-D split-step parabolic-equation march (docs/physics.md section 4).
//!
//! Frame: z = range (the march axis), x = cross-range, y = height. The field `u[ix, iy]` is
//! stored row-major (`iy` fastest), `x = (ix - nx/2) dx`, `y = iy dy`; with a ground, row
//! `iy = 0` is the ground. One step is
//!
//! ```text
//! u <- window * mask * exp(-j k0 (n^2 - 1) dz / 2) * IFFT2[ P(kx, ky) FFT2[u] ]
//! ```
//! with the wide-angle (`exp(+j (k0 - kz) dz)`, evanescent waves decay) or narrow-angle
//! (`exp(+j (kx^2 + ky^2) dz / (2 k0))`) propagator.
//!
//! **How a step runs.** Between steps the field is held as y-spectra (each row FFT'd along
//! y). A step is two passes over memory: a *column pass* that, block by block of 32 columns,
//! gathers the columns, FFTs them along x, multiplies by `P`, inverse-FFTs and scatters them
//! back; and a *row pass* that inverse-FFTs each row along y, applies the phase screen, the
//! absorbing window and the obstacles, records the requested rows, and FFTs the row again
//! for the next step. rustfft plans are made once; the hot loop allocates nothing
//! (each rayon thread has scratch buffers in the marcher's pool, sized once).
//!
//! **Uniform medium, no obstacles.** A uniform screen commutes with both transforms (it is
//! folded into `P`), and the height window acts along y only, so with
//! `MarchSpec::x_absorber_every = M >= 2` such steps keep the field as (kx, ky) spectra: per
//! kx row, `P`, the inverse y transform, the height window, the recorded rows (brought to x
//! by one FFT of length nx each), the forward y transform. Only the lateral window needs x:
//! it is applied every M steps as the window to the M-th power, between an inverse and a
//! forward x transform. The x transforms, most of a general step's cost, then run once per M
//! steps. Inside the window's inner edges the field sees the same operations as in the
//! general step (tested to f32 rounding at M = 1); the strips' absorption is sampled M times
//! more coarsely in range (tested: rows inside within 2.4e-4 at M = 4 where the widest angle
//! crosses a sixth of a strip between windows). The field stays spectral between calls and
//! is brought back to real space when read.
//!
//! **Ground.** A flat PEC ground is the image method: the column `u(x, y >= 0)` is extended
//! to `2 ny` samples, odd (`"pec-h"`, `u(-y) = -u(y)`, a sine transform) or even (`"pec-v"`,
//! a cosine transform), and only the `ny` (+1 for the even case) independent spectral values
//! are stored. The x transforms are unchanged. The odd extension's FFT of length `2 ny` is
//! computed as the sine transform it is, through one FFT of length `ny` (`march::Dst`), so
//! `"pec-h"` costs about what the periodic step does; `"pec-v"` still FFTs the `2 ny`
//! extension (about 1.5x the periodic step). No extra memory of note.
//!
//! **Accuracy.** Storage and FFTs are complex64 (f32); the propagator and phase screens are
//! computed in f64 and rounded once to f32. The march is then accurate to f32 rounding
//! growing like `sqrt(steps) * 1e-7 * log2(n)` relative (about 1e-5 after 1000 steps). The
//! `"pec-h"` sine transform's running sum makes each of its transforms accurate to about
//! `1e-7 sqrt(ny)` instead (1.8e-6 at ny = 1296, tested against the definition), about
//! 3e-5 after 137 steps: the `paper` and `uma` maps moved by at most 0.001 dB when it
//! replaced the `2 ny` FFT.
//!
//! **Memory.** The field (one copy, `8 nx ny` bytes), the propagator table over `|kx|, |ky|`
//! (a quarter of a copy, half with a ground), and, only when the refractive index is an
//! (nx, ny) array constant along range, its precomputed phase screen (one copy), and with
//! `x_absorber_every >= 2` the uniform path's propagator table (half a copy): at most
//! 3 copies of the field plus what the caller records.

//!
//! **Files.** `spec` (what a march is: sizes, steps, medium, obstacles, recordings, and their
//! checks), `march` (the [`Marcher`] and its two passes), `source` (apertures).

mod march;
mod source;
mod spec;

pub use crate::memory::{available_memory_bytes, check_memory};
pub use march::Marcher;
pub use source::gaussian_beam;
pub use spec::{
    Ground, MarchSpec, PE_FREQ_RANGE_HZ, Propagator, Recording, StepMedium, StepObstacle,
};

use num_complex::Complex32;

/// Single-precision complex sample of the field.
pub type C32 = Complex32;
