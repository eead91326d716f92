//! The [`Marcher`]: plans, tables and scratch made once, then steps that allocate nothing
//! (the column pass and the row pass of the module docs).

use crate::error::{CoreError, Result};
use crate::wavenumber;
use ndarray::{Array2, ArrayView2};
use num_complex::Complex64;
use rayon::prelude::*;
use rustfft::{Fft, FftPlanner};
use std::sync::Arc;

use super::C32;
use super::spec::{
    Ground, MarchSpec, Propagator, Recording, StepMedium, StepObstacle, check_index,
    check_obstacle, table_shape,
};

/// Columns handled together in the column pass: 32 x 8 bytes = four cache lines per row and
/// TLB entry, and the gather buffer (32 nx samples, 1 MiB at nx = 4096) stays in L2.
/// Measured at 4096 x 1024 (30-step march, best of 6): 8 -> 689 ms, 16 -> 642 ms,
/// 32 -> 595-610 ms, 64 -> 645 ms.
const COLUMN_BLOCK: usize = 32;

/// Phase-screen factor `exp(-j k0 (n^2 - 1) dz / 2)` in f64.
fn screen_factor(n: Complex64, half_k0_dz: f64) -> Complex64 {
    let q = n * n - 1.0;
    // -j * half_k0_dz * q = half_k0_dz * (q.im - j q.re)
    Complex64::from_polar((half_k0_dz * q.im).exp(), -half_k0_dz * q.re)
}

pub(super) fn to_c32(z: Complex64) -> C32 {
    C32::new(z.re as f32, z.im as f32)
}

/// A field being marched. Build with [`Marcher::new`], advance with [`Marcher::advance`].
pub struct Marcher {
    spec: MarchSpec,
    field: Vec<C32>,
    /// Nyquist coefficient of each row's cosine transform (`"pec-v"`; zeros otherwise).
    nyquist: Vec<C32>,
    ptab: Vec<C32>,
    /// `ptab` times the phase screen of the last homogeneous medium, and that screen: a
    /// uniform screen commutes with the transforms, so it is folded into `P` (rebuilt only
    /// when the medium changes) instead of costing a multiply per sample per step.
    scaled: Option<(C32, Vec<C32>)>,
    ptab_cols: usize,
    window_x: Vec<f32>,
    window_y: Vec<f32>,
    fixed_screen: Option<Vec<C32>>,
    row_fwd: Arc<dyn Fft<f32>>,
    row_inv: Arc<dyn Fft<f32>>,
    /// The y transform of `"pec-h"` rows: a sine transform of length `ny` in place of the
    /// image extension's FFT of length `2 ny` (the same values, half the work).
    dst: Option<Dst>,
    col_fwd: Arc<dyn Fft<f32>>,
    col_inv: Arc<dyn Fft<f32>>,
    /// Where the field is held between calls and between steps.
    domain: Domain,
    /// The uniform-medium path's propagator, `|kx|` index major (one row of `ny` (+1) `ky`
    /// values per `|kx|`), with the y normalisation and the uniform screen folded in; built
    /// on first use and when the screen changes.
    fast_tab: Option<(C32, Vec<C32>)>,
    /// `window_x ^ x_absorber_every / nx`: the lateral window as the uniform-medium path
    /// applies it, every `x_absorber_every` steps, with the x transforms' normalisation.
    window_xm: Vec<f32>,
    /// The uniform-medium path runs when `x_absorber_every >= fast_from` (2; tests set 1 to
    /// check it against the general path).
    fast_from: usize,
    steps_done: usize,
    /// Recorded rows of the current step, `rec_buf[ix * n_rows + r]` (reused across steps).
    rec_buf: Vec<C32>,
    /// One image-extended column for recording the vertical plane (reused across steps).
    col_buf: Vec<C32>,
    /// Per-thread scratch of the passes.
    pool: ScratchPool,
}

/// Where the field is held: real space, y-spectra (x real), or full (kx, ky) spectra.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Domain {
    Real,
    YSpectra,
    Spectra,
}

/// What a column pass does to each column (along x) of the y-spectra.
#[derive(Clone, Copy)]
enum ColumnOp {
    /// x FFT, the propagator table (over |ky|, |kx|; `scaled`: times the uniform screen),
    /// inverse x FFT.
    Propagate { scaled: bool },
    /// x FFT only (y-spectra -> spectra).
    Forward,
    /// Inverse x FFT and a scale (spectra -> y-spectra).
    Inverse(f32),
    /// Inverse x FFT, `window_xm` (the lateral window to the power `x_absorber_every`, over
    /// nx), x FFT.
    Window,
}

impl Marcher {
    /// Starts a march from the aperture field `u0` (nx, ny). Checks everything.
    // Long: every input is checked, then the propagator table, the windows and the buffers are
    // built once, before the first step.
    pub fn new(spec: MarchSpec, u0: ArrayView2<'_, C32>) -> Result<Self> {
        spec.validate()?;
        if u0.dim() != (spec.nx, spec.ny) {
            return Err(CoreError::invalid(
                "u0",
                format!("must have shape ({}, {})", spec.nx, spec.ny),
                format!("{:?}", u0.dim()),
            ));
        }
        if u0.iter().any(|z| !(z.re.is_finite() && z.im.is_finite())) {
            return Err(CoreError::invalid(
                "u0",
                "must be finite everywhere",
                "NaN or inf",
            ));
        }
        let (nx, ny) = (spec.nx, spec.ny);
        let mut planner = FftPlanner::<f32>::new();
        let ylen = spec.y_len();
        let row_fwd = planner.plan_fft_forward(ylen);
        let row_inv = planner.plan_fft_inverse(ylen);
        let dst = (spec.ground == Ground::PecH).then(|| Dst::new(&mut planner, ny));
        let col_fwd = planner.plan_fft_forward(nx);
        let col_inv = planner.plan_fft_inverse(nx);

        // Propagator table over (|ky| index, |kx| index), normalisation of both FFTs folded in.
        let (trows, tcols) = table_shape(nx, ny, spec.ground);
        let k0 = wavenumber(spec.freq_hz);
        let norm = 1.0 / (nx as f64 * ylen as f64);
        let two_pi = 2.0 * std::f64::consts::PI;
        let mut ptab = vec![C32::default(); trows * tcols];
        ptab.par_chunks_mut(tcols)
            .enumerate()
            .for_each(|(my, prow)| {
                let ky = match spec.ground {
                    Ground::None => two_pi * my as f64 / (ny as f64 * spec.dy_m),
                    _ => std::f64::consts::PI * my as f64 / (ny as f64 * spec.dy_m),
                };
                for (fx, out) in prow.iter_mut().enumerate() {
                    let kx = two_pi * fx as f64 / (nx as f64 * spec.dx_m);
                    let k2 = kx * kx + ky * ky;
                    let p = match spec.propagator {
                        Propagator::Narrow => {
                            Complex64::from_polar(1.0, k2 * spec.dz_m / (2.0 * k0))
                        }
                        Propagator::Wide => {
                            if k2 <= k0 * k0 {
                                let kz = (k0 * k0 - k2).sqrt();
                                // k0 - kz without cancellation for small k.
                                Complex64::from_polar(1.0, k2 / (k0 + kz) * spec.dz_m)
                            } else {
                                let s = (k2 - k0 * k0).sqrt();
                                Complex64::from_polar((-s * spec.dz_m).exp(), k0 * spec.dz_m)
                            }
                        }
                    };
                    *out = to_c32(p * norm);
                }
            });

        let (window_x, window_y) = if spec.absorber > 0.0 {
            let bottom = spec.ground == Ground::None;
            (
                taper(nx, spec.absorber, true, true),
                taper(ny, spec.absorber, bottom, true),
            )
        } else {
            (Vec::new(), Vec::new())
        };

        let every = spec.x_absorber_every.max(1);
        let window_xm = window_x
            .iter()
            .map(|&w| (w as f64).powi(every as i32) as f32 / nx as f32)
            .collect();
        let m = Marcher {
            // `iter()` walks in logical (ix, iy) order whatever u0's memory layout.
            field: u0.iter().copied().collect(),
            // Used by "pec-v" only; zeros (and untouched by the column pass) otherwise, so the
            // row passes can zip over it unconditionally.
            nyquist: vec![C32::default(); nx],
            ptab,
            scaled: None,
            ptab_cols: tcols,
            window_x,
            window_y,
            fixed_screen: None,
            row_fwd,
            row_inv,
            dst,
            col_fwd,
            col_inv,
            domain: Domain::Real,
            fast_tab: None,
            window_xm,
            fast_from: 2,
            steps_done: 0,
            rec_buf: Vec::new(),
            col_buf: Vec::new(),
            pool: ScratchPool::new(),
            spec,
        };
        Ok(m)
    }

    /// The spec this marcher was built with.
    pub fn spec(&self) -> &MarchSpec {
        &self.spec
    }

    /// Steps done so far.
    pub fn steps_done(&self) -> usize {
        self.steps_done
    }

    /// Sets the (nx, ny) refractive index used by [`StepMedium::Fixed`] (its screen is
    /// computed once, in f64).
    pub fn set_fixed_index(&mut self, n: ArrayView2<'_, Complex64>) -> Result<()> {
        let (nx, ny) = (self.spec.nx, self.spec.ny);
        check_index(n, nx, ny)?;
        let h = 0.5 * wavenumber(self.spec.freq_hz) * self.spec.dz_m;
        self.fixed_screen = Some(n.iter().map(|&v| to_c32(screen_factor(v, h))).collect());
        Ok(())
    }

    /// The current field (nx, ny), in real space (brought back there first if a uniform
    /// march left it as spectra).
    pub fn field(&mut self) -> ArrayView2<'_, C32> {
        self.bring_to_real_space();
        ArrayView2::from_shape((self.spec.nx, self.spec.ny), &self.field)
            .expect("field buffer has nx * ny samples")
    }

    /// Takes the field out as an owned (nx, ny) array, in real space.
    pub fn into_field(mut self) -> Array2<C32> {
        self.bring_to_real_space();
        let (nx, ny) = (self.spec.nx, self.spec.ny);
        Array2::from_shape_vec((nx, ny), self.field).expect("field buffer has nx * ny samples")
    }

    /// Checks one step's medium.
    fn check_medium(&self, med: &StepMedium<'_>) -> Result<()> {
        match med {
            StepMedium::Index(n) => check_index(*n, self.spec.nx, self.spec.ny)?,
            StepMedium::CrossRange(n) => {
                if n.len() != self.spec.nx {
                    return Err(CoreError::invalid(
                        "n_cross_range",
                        format!("must have {} values per step", self.spec.nx),
                        n.len(),
                    ));
                }
                if n.iter().any(|z| !(z.re.is_finite() && z.im.is_finite())) {
                    return Err(CoreError::invalid(
                        "n_cross_range",
                        "must be finite",
                        "NaN or inf",
                    ));
                }
            }
            StepMedium::Fixed if self.fixed_screen.is_none() => {
                return Err(CoreError::invalid(
                    "n",
                    "fixed index requested before set_fixed_index",
                    "none",
                ));
            }
            StepMedium::Uniform(n) if !(n.re.is_finite() && n.im.is_finite()) => {
                return Err(CoreError::invalid("n", "must be finite", n));
            }
            _ => {}
        }
        Ok(())
    }

    /// Advances `steps` steps. `medium(k)` and `obstacle(k)` give the medium and obstacles
    /// of global step `k` (0-based); recordings land at global step indices. Every step's
    /// inputs are checked before the first step runs.
    ///
    /// When every step has a uniform medium and no obstacles, no column is recorded and
    /// `x_absorber_every >= 2`, the march runs in the spectral domain
    /// ([`Marcher::advance_uniform`]): the x transforms run only every `x_absorber_every`
    /// steps, for the lateral window.
    pub fn advance<'m>(
        &mut self,
        steps: usize,
        medium: &dyn Fn(usize) -> StepMedium<'m>,
        obstacle: &dyn Fn(usize) -> StepObstacle<'m>,
        recording: &mut Recording<'_>,
    ) -> Result<()> {
        self.check_recording(steps, recording)?;
        let mut uniform_path = self.spec.x_absorber_every >= self.fast_from
            && recording.column.is_none()
            && recording.row_offsets.is_none();
        for global in self.steps_done..self.steps_done + steps {
            let med = medium(global);
            self.check_medium(&med)?;
            let obs = obstacle(global);
            check_obstacle(&obs, self.spec.nx, self.spec.ny)?;
            uniform_path &=
                matches!(med, StepMedium::Uniform(_)) && matches!(obs, StepObstacle::None);
        }
        if uniform_path {
            self.advance_uniform(steps, medium, recording);
            return Ok(());
        }
        let inv_nx = 1.0 / self.spec.nx as f32;
        for k in 0..steps {
            let global = self.steps_done;
            let med = medium(global);
            let obs = obstacle(global);
            match self.domain {
                Domain::Real => self.forward_rows(),
                Domain::Spectra => self.column_op(ColumnOp::Inverse(inv_nx)),
                Domain::YSpectra => {}
            }
            let half_k0_dz = 0.5 * wavenumber(self.spec.freq_hz) * self.spec.dz_m;
            let uniform = match med {
                StepMedium::Uniform(n) => Some(to_c32(screen_factor(n, half_k0_dz))),
                _ => None,
            };
            self.column_pass(uniform);
            let rec_rows = recording.record_rows;
            let mut rec = std::mem::take(&mut self.rec_buf);
            rec.resize(self.spec.nx * rec_rows.len().max(1), C32::default());
            let last = k + 1 == steps;
            let offsets = recording
                .row_offsets
                .as_ref()
                .map(|(first, o)| o.index_axis(ndarray::Axis(0), global - first));
            self.row_pass(&med, &obs, (rec_rows, offsets, &mut rec), !last);
            self.domain = if last { Domain::Real } else { Domain::YSpectra };
            if let Some(rows) = recording.rows.as_mut() {
                let nr = rec_rows.len();
                for r in 0..nr {
                    let mut dst = rows.slice_mut(ndarray::s![r, global, ..]);
                    for (ix, d) in dst.iter_mut().enumerate() {
                        *d = rec[ix * nr + r];
                    }
                }
            }
            self.rec_buf = rec;
            if let Some((col, out)) = recording.column.as_mut() {
                // Between steps the rows hold y-spectra; one inverse FFT recovers this row.
                let ny = self.spec.ny;
                let row: &[C32] = if self.domain == Domain::YSpectra {
                    // Recover the real-space row: cheap (one row).
                    self.real_row(*col)
                } else {
                    &self.field[*col * ny..(*col + 1) * ny]
                };
                out.slice_mut(ndarray::s![global, ..])
                    .iter_mut()
                    .zip(row)
                    .for_each(|(d, v)| *d = *v);
            }
            self.steps_done += 1;
        }
        Ok(())
    }

    /// Steps through a uniform medium without obstacles, holding the field as (kx, ky)
    /// spectra. A uniform screen commutes with every transform and is folded into the
    /// propagator; the height window acts along y only, so it is applied to each kx row
    /// between an inverse and a forward y transform; the rows to record are read there and
    /// brought to x by one FFT of length nx each. Only the lateral window needs x, and it is
    /// applied every `x_absorber_every` steps as the window to that power: the x transforms,
    /// most of a general step's work, run that much less often. Inside the absorber's inner
    /// edges the window is 1, so the field there sees the same operations as the general
    /// step's; only the strips' absorption is sampled more coarsely in range.
    fn advance_uniform<'m>(
        &mut self,
        steps: usize,
        medium: &dyn Fn(usize) -> StepMedium<'m>,
        recording: &mut Recording<'_>,
    ) {
        match self.domain {
            Domain::Real => {
                self.forward_rows();
                self.column_op(ColumnOp::Forward);
            }
            Domain::YSpectra => self.column_op(ColumnOp::Forward),
            Domain::Spectra => {}
        }
        self.domain = Domain::Spectra;
        let (nx, every) = (self.spec.nx, self.spec.x_absorber_every.max(1));
        let half_k0_dz = 0.5 * wavenumber(self.spec.freq_hz) * self.spec.dz_m;
        let rec_rows = recording.record_rows;
        let nr = rec_rows.len();
        let inv = self.col_inv.clone();
        // One recorded row and its FFT scratch, in the marcher's reused buffer (this path
        // records no column, the buffer's other use).
        let mut buf = std::mem::take(&mut self.col_buf);
        buf.resize(nx + inv.get_inplace_scratch_len(), C32::default());
        let (line, scratch) = buf.split_at_mut(nx);
        for _ in 0..steps {
            let global = self.steps_done;
            let StepMedium::Uniform(n) = medium(global) else {
                unreachable!("advance() checked every step's medium is uniform");
            };
            self.ensure_fast_tab(to_c32(screen_factor(n, half_k0_dz)));
            let mut rec = std::mem::take(&mut self.rec_buf);
            rec.resize(nx * nr.max(1), C32::default());
            self.row_pass_uniform(rec_rows, &mut rec);
            if let Some(rows) = recording.rows.as_mut() {
                let s = 1.0 / nx as f32;
                for r in 0..nr {
                    for (ix, v) in line.iter_mut().enumerate() {
                        *v = rec[ix * nr + r];
                    }
                    inv.process_with_scratch(line, scratch);
                    let mut dst = rows.slice_mut(ndarray::s![r, global, ..]);
                    for (d, v) in dst.iter_mut().zip(line.iter()) {
                        *d = v * s;
                    }
                }
            }
            self.rec_buf = rec;
            if (global + 1) % every == 0 && !self.window_xm.is_empty() {
                self.column_op(ColumnOp::Window);
            }
            self.steps_done += 1;
        }
        self.col_buf = buf;
    }
}

mod passes;
mod rows;
mod scratch;

use rows::{Dst, taper};
use scratch::{FieldPtr, Scratch, ScratchPool};

#[cfg(test)]
mod tests;
