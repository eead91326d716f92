//! The [`Marcher`]: plans, tables and scratch made once, then steps that allocate nothing
//! (the column pass and the row pass of the module docs).

use crate::error::{CoreError, Result};
use crate::wavenumber;
use ndarray::{Array2, ArrayView2};
use num_complex::Complex64;
use rayon::prelude::*;
use rustfft::{Fft, FftPlanner};
use std::sync::{Arc, Mutex, MutexGuard};

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

/// Raw pointer to the field shared by the column pass, whose threads touch disjoint columns.
#[derive(Clone, Copy)]
struct FieldPtr(*mut C32);
// SAFETY: used only in `column_pass`, where every task reads and writes a disjoint set of
// columns of the field and nothing else borrows the field meanwhile.
#[allow(unsafe_code)]
unsafe impl Send for FieldPtr {}
#[allow(unsafe_code)]
unsafe impl Sync for FieldPtr {}
impl FieldPtr {
    fn get(self) -> *mut C32 {
        self.0
    }
}

/// Scratch buffers of one thread: `a` holds an extended row or a block of columns, `b` is
/// rustfft's scratch.
#[derive(Default)]
struct Scratch {
    a: Vec<C32>,
    b: Vec<C32>,
}

/// One [`Scratch`] per rayon thread, kept by the marcher so that steps allocate nothing.
struct ScratchPool(Vec<Mutex<Scratch>>);

/// A thread's pooled scratch, or a fresh one if its slot is busy (never in practice).
enum ScratchGuard<'a> {
    Pooled(MutexGuard<'a, Scratch>),
    Fresh(Scratch),
}

impl ScratchPool {
    fn new() -> Self {
        ScratchPool(
            (0..rayon::current_num_threads().max(1))
                .map(|_| Mutex::new(Scratch::default()))
                .collect(),
        )
    }

    /// Scratch with `a.len() >= a_len` and `b.len() >= b_len` for the calling thread.
    fn get(&self, a_len: usize, b_len: usize) -> ScratchGuard<'_> {
        let slot = rayon::current_thread_index().and_then(|i| self.0.get(i));
        let mut g = match slot.map(Mutex::try_lock) {
            Some(Ok(guard)) => ScratchGuard::Pooled(guard),
            _ => ScratchGuard::Fresh(Scratch::default()),
        };
        let s = g.scratch();
        if s.a.len() < a_len {
            s.a.resize(a_len, C32::default());
        }
        if s.b.len() < b_len {
            s.b.resize(b_len, C32::default());
        }
        g
    }
}

impl ScratchGuard<'_> {
    fn scratch(&mut self) -> &mut Scratch {
        match self {
            ScratchGuard::Pooled(g) => g,
            ScratchGuard::Fresh(s) => s,
        }
    }
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

/// cos^2 taper: 1 inside, to 0 at the edges over `frac * n` samples; `lo`/`hi` select edges.
fn taper(n: usize, frac: f64, lo: bool, hi: bool) -> Vec<f32> {
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

impl Marcher {
    /// Starts a march from the aperture field `u0` (nx, ny). Checks everything.
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

    /// Scratch a row pass needs: the larger of the y FFTs' and the sine transform's.
    fn row_scratch_len(&self) -> usize {
        self.row_inv
            .get_inplace_scratch_len()
            .max(self.row_fwd.get_inplace_scratch_len())
            .max(self.dst.as_ref().map_or(0, Dst::scratch_len))
    }

    /// Brings the field back to real space.
    fn bring_to_real_space(&mut self) {
        if self.domain == Domain::Spectra {
            self.column_op(ColumnOp::Inverse(1.0 / self.spec.nx as f32));
            self.domain = Domain::YSpectra;
        }
        if self.domain == Domain::YSpectra {
            let ny = self.spec.ny;
            let (ground, ylen) = (self.spec.ground, self.spec.y_len());
            let inv = self.row_inv.clone();
            let dst = self.dst.as_ref();
            let scratch_len = self.row_scratch_len();
            let pool = &self.pool;
            let s = 1.0 / ylen as f32;
            self.field
                .par_chunks_mut(ny)
                .zip(self.nyquist.par_iter_mut())
                .for_each_init(
                    || pool.get(ylen, scratch_len),
                    |g, (row, nq)| {
                        let Scratch { a, b } = g.scratch();
                        inverse_row(ground, (&*inv, dst), row, *nq, &mut a[..ylen], b);
                        row.iter_mut().for_each(|z| *z *= s);
                    },
                );
            self.domain = Domain::Real;
        }
    }

    /// Builds the uniform path's propagator table for this screen, unless it holds it.
    fn ensure_fast_tab(&mut self, screen: C32) {
        if self.fast_tab.as_ref().is_some_and(|(s, _)| *s == screen) {
            return;
        }
        let (nx, ny, ground) = (self.spec.nx, self.spec.ny, self.spec.ground);
        let tcols = self.ptab_cols;
        let width = fast_tab_width(ny, ground);
        let mut t = std::mem::take(&mut self.fast_tab)
            .map(|x| x.1)
            .unwrap_or_default();
        t.resize(tcols * width, C32::default());
        // ptab holds 1 / (nx ylen); the uniform path's x transforms carry their own 1 / nx.
        let scale = screen * nx as f32;
        let ptab = &self.ptab;
        t.par_chunks_mut(width).enumerate().for_each(|(kx, out)| {
            for (m, o) in out.iter_mut().enumerate() {
                let r = match ground {
                    Ground::None => m.min(ny - m),
                    _ => m,
                };
                *o = ptab[r * tcols + kx] * scale;
            }
        });
        self.fast_tab = Some((screen, t));
    }

    /// One uniform-medium step on the (kx, ky) spectra: per kx row, the propagator, the
    /// inverse y transform, the height window, the recorded rows (at kx), the forward y
    /// transform.
    fn row_pass_uniform(&mut self, rec_rows: &[usize], rec: &mut [C32]) {
        let (nx, ny) = (self.spec.nx, self.spec.ny);
        let (ground, ylen) = (self.spec.ground, self.spec.y_len());
        let width = fast_tab_width(ny, ground);
        let tab: &[C32] = &self.fast_tab.as_ref().expect("built by ensure_fast_tab").1;
        let wy = &self.window_y;
        let (inv, fwd) = (self.row_inv.clone(), self.row_fwd.clone());
        let dst = self.dst.as_ref();
        let scratch_len = self.row_scratch_len();
        let pool = &self.pool;
        let nr = rec_rows.len().max(1);
        par_rows(&mut self.field, &mut self.nyquist, rec, ny, nr).for_each_init(
            || pool.get(ylen, scratch_len),
            |g, (ix, ((row, nq), rec_row))| {
                let Scratch { a, b } = g.scratch();
                let (ext, scratch) = (&mut a[..ylen], b.as_mut_slice());
                let kx = ix.min(nx - ix);
                let trow = &tab[kx * width..(kx + 1) * width];
                row.iter_mut().zip(trow).for_each(|(z, p)| *z *= p);
                if width > ny {
                    *nq *= trow[ny];
                }
                inverse_row(ground, (&*inv, dst), row, *nq, ext, scratch);
                if !wy.is_empty() {
                    row.iter_mut().zip(wy).for_each(|(z, &w)| *z *= w);
                }
                for (r, &iy) in rec_rows.iter().enumerate() {
                    rec_row[r] = row[iy];
                }
                forward_row(ground, (&*fwd, dst), row, nq, ext, scratch);
            },
        );
    }

    fn check_recording(&self, steps: usize, rec: &Recording<'_>) -> Result<()> {
        let (nx, ny) = (self.spec.nx, self.spec.ny);
        let end = self.steps_done + steps;
        if let Some(&bad) = rec.record_rows.iter().find(|&&r| r >= ny) {
            return Err(CoreError::invalid(
                "record_rows",
                format!("must be within 0..{ny}"),
                bad,
            ));
        }
        if let Some((first, o)) = &rec.row_offsets {
            let (s, x) = o.dim();
            if *first > self.steps_done || first + s < end || x != nx {
                return Err(CoreError::invalid(
                    "row_offsets",
                    format!(
                        "must cover steps {}..{end} with {nx} columns",
                        self.steps_done
                    ),
                    format!("{:?} from step {first}", o.dim()),
                ));
            }
            let (lo, hi) = rec
                .record_rows
                .iter()
                .fold((usize::MAX, 0), |(a, b), &r| (a.min(r), b.max(r)));
            let bad = o
                .iter()
                .any(|&v| (lo as i64 + v) < 0 || (hi as i64 + v) >= ny as i64);
            if !rec.record_rows.is_empty() && bad {
                return Err(CoreError::invalid(
                    "row_offsets",
                    format!("must keep the recorded rows within 0..{ny}"),
                    "a row outside the grid",
                ));
            }
        }
        if let Some(rows) = &rec.rows {
            let (r, s, x) = rows.dim();
            if r != rec.record_rows.len() || s < end || x != nx {
                return Err(CoreError::invalid(
                    "rows",
                    format!(
                        "output must have shape ({}, >= {end}, {nx})",
                        rec.record_rows.len()
                    ),
                    format!("{:?}", rows.dim()),
                ));
            }
        }
        if let Some((col, out)) = &rec.column {
            if *col >= nx {
                return Err(CoreError::invalid(
                    "record_column",
                    format!("must be within 0..{nx}"),
                    col,
                ));
            }
            let (s, y) = out.dim();
            if s < end || y != ny {
                return Err(CoreError::invalid(
                    "column",
                    format!("output must have shape (>= {end}, {ny})"),
                    format!("{:?}", out.dim()),
                ));
            }
        }
        Ok(())
    }

    /// The real-space values of row `ix` while the field is held as y-spectra, in
    /// `self.col_buf[..ny]` (reused across steps).
    fn real_row(&mut self, ix: usize) -> &[C32] {
        let ny = self.spec.ny;
        let ylen = self.spec.y_len();
        // The sine transform's work space and FFT scratch sit after the row (sized once).
        let extra = self.dst.as_ref().map_or(0, Dst::scratch_len);
        self.col_buf.resize(ylen + extra, C32::default());
        let row = &self.field[ix * ny..(ix + 1) * ny];
        if let Some(dst) = &self.dst {
            let (out, rest) = self.col_buf.split_at_mut(ny);
            let (y, scratch) = rest.split_at_mut(ny);
            out.copy_from_slice(row);
            dst.apply(out, y, scratch, Dst::INVERSE);
        } else {
            let ext = &mut self.col_buf[..ylen];
            spectrum_to_ext(self.spec.ground, row, self.nyquist[ix], ext);
            self.row_inv.process(ext);
        }
        let s = 1.0 / ylen as f32;
        self.col_buf[..ny].iter_mut().for_each(|z| *z *= s);
        &self.col_buf[..ny]
    }

    /// Forward y transform of every row (real space -> y-spectra).
    fn forward_rows(&mut self) {
        let ny = self.spec.ny;
        let ground = self.spec.ground;
        let fft = self.row_fwd.clone();
        let dst = self.dst.as_ref();
        let ylen = self.spec.y_len();
        let scratch_len = fft
            .get_inplace_scratch_len()
            .max(dst.map_or(0, Dst::scratch_len));
        self.field
            .par_chunks_mut(ny)
            .zip(self.nyquist.par_iter_mut())
            .for_each_init(
                || self.pool.get(ylen, scratch_len),
                |g, (row, nq)| {
                    let s = g.scratch();
                    forward_row(ground, (&*fft, dst), row, nq, &mut s.a[..ylen], &mut s.b)
                },
            );
        self.domain = Domain::YSpectra;
    }

    /// x transforms, propagator and inverse x transforms, block by block of columns (the
    /// uniform screen, if any, folded into the propagator).
    fn column_pass(&mut self, uniform_screen: Option<C32>) {
        let one = C32::new(1.0, 0.0);
        let scaled = match uniform_screen {
            Some(sc) if sc != one => {
                if self.scaled.as_ref().is_none_or(|(old, _)| *old != sc) {
                    let mut t = std::mem::take(&mut self.scaled)
                        .map(|x| x.1)
                        .unwrap_or_default();
                    t.clear();
                    t.extend(self.ptab.iter().map(|p| p * sc));
                    self.scaled = Some((sc, t));
                }
                true
            }
            _ => false,
        };
        self.column_op(ColumnOp::Propagate { scaled });
    }

    /// One [`ColumnOp`] on every column of the y-spectra (and the `"pec-v"` Nyquist row),
    /// block by block of `COLUMN_BLOCK` columns gathered into contiguous scratch.
    #[allow(unsafe_code)]
    fn column_op(&mut self, op: ColumnOp) {
        let ptab: &[C32] = match op {
            ColumnOp::Propagate { scaled: true } => {
                &self.scaled.as_ref().expect("set by column_pass").1
            }
            _ => &self.ptab,
        };
        let wxm: &[f32] = &self.window_xm;
        let (nx, ny) = (self.spec.nx, self.spec.ny);
        let ground = self.spec.ground;
        let fwd = self.col_fwd.clone();
        let inv = self.col_inv.clone();
        let scratch_len = fwd
            .get_inplace_scratch_len()
            .max(inv.get_inplace_scratch_len());
        let tcols = self.ptab_cols;
        let ky_row = |m: usize| match ground {
            Ground::None => m.min(ny - m),
            _ => m,
        };
        let half = nx / 2;
        // Does `op` to `buf` (whole columns, the first at spectral column m0); rustfft
        // batches the columns in one call each way.
        let apply = |buf: &mut [C32], m0: usize, scratch: &mut [C32]| match op {
            ColumnOp::Propagate { .. } => {
                fwd.process_with_scratch(buf, scratch);
                for (j, col) in buf.chunks_exact_mut(nx).enumerate() {
                    let m = ky_row(m0 + j);
                    let prow = &ptab[m * tcols..(m + 1) * tcols];
                    // P depends on |kx|: ix <= nx/2 reads prow forwards, the rest backwards.
                    let (lo, hi) = col.split_at_mut(half + 1);
                    lo.iter_mut().zip(prow).for_each(|(z, p)| *z *= p);
                    hi.iter_mut()
                        .zip(prow[1..half + nx % 2].iter().rev())
                        .for_each(|(z, p)| *z *= p);
                }
                inv.process_with_scratch(buf, scratch);
            }
            ColumnOp::Forward => fwd.process_with_scratch(buf, scratch),
            ColumnOp::Inverse(s) => {
                inv.process_with_scratch(buf, scratch);
                buf.iter_mut().for_each(|z| *z *= s);
            }
            ColumnOp::Window => {
                inv.process_with_scratch(buf, scratch);
                for col in buf.chunks_exact_mut(nx) {
                    col.iter_mut().zip(wxm).for_each(|(z, &w)| *z *= w);
                }
                fwd.process_with_scratch(buf, scratch);
            }
        };
        let ptr = FieldPtr(self.field.as_mut_ptr());
        let blocks = ny.div_ceil(COLUMN_BLOCK);
        let pool = &self.pool;
        (0..blocks).into_par_iter().for_each_init(
            || pool.get(COLUMN_BLOCK * nx, scratch_len),
            |g, block| {
                let Scratch { a: buf, b } = g.scratch();
                let scratch = b.as_mut_slice();
                let m0 = block * COLUMN_BLOCK;
                let w = COLUMN_BLOCK.min(ny - m0);
                let base = ptr.get();
                // SAFETY (both loops): this task alone touches columns m0..m0+w of the
                // nx * ny field (blocks are disjoint), every index is < nx * ny, and no
                // reference to the field exists while the pass runs (we hold &mut self).
                // Gather as 8 x 8 tiles: 8 contiguous reads of a row, 8 contiguous writes of a
                // column, so both sides stream whole cache lines.
                let mut tile = [[C32::default(); COLUMN_BLOCK]; 8];
                let mut ix0 = 0;
                while ix0 < nx {
                    let h = 8.min(nx - ix0);
                    for r in 0..h {
                        for j in 0..w {
                            tile[r][j] = unsafe { base.add((ix0 + r) * ny + m0 + j).read() };
                        }
                    }
                    for j in 0..w {
                        for r in 0..h {
                            buf[j * nx + ix0 + r] = tile[r][j];
                        }
                    }
                    ix0 += h;
                }
                apply(&mut buf[..w * nx], m0, scratch);
                let mut ix0 = 0;
                while ix0 < nx {
                    let h = 8.min(nx - ix0);
                    for j in 0..w {
                        for r in 0..h {
                            tile[r][j] = buf[j * nx + ix0 + r];
                        }
                    }
                    for r in 0..h {
                        for j in 0..w {
                            unsafe { base.add((ix0 + r) * ny + m0 + j).write(tile[r][j]) };
                        }
                    }
                    ix0 += h;
                }
            },
        );
        if ground == Ground::PecV {
            let mut scratch = vec![C32::default(); scratch_len];
            let mut col = std::mem::take(&mut self.nyquist);
            apply(&mut col, ny, &mut scratch);
            self.nyquist = col;
        }
    }

    /// Inverse y transform of every row, then screen, window, obstacles and recording;
    /// then (if `forward_again`) the forward y transform for the next step.
    fn row_pass(
        &mut self,
        medium: &StepMedium<'_>,
        obstacle: &StepObstacle<'_>,
        record: (&[usize], Option<ndarray::ArrayView1<'_, i64>>, &mut [C32]),
        forward_again: bool,
    ) {
        let (nx, ny) = (self.spec.nx, self.spec.ny);
        let ground = self.spec.ground;
        let ylen = self.spec.y_len();
        let half_k0_dz = 0.5 * wavenumber(self.spec.freq_hz) * self.spec.dz_m;
        // A uniform screen was folded into P by the column pass.
        let uniform = match medium {
            StepMedium::Uniform(_) => Some(C32::new(1.0, 0.0)),
            _ => None,
        };
        let fixed = self.fixed_screen.as_deref();
        let (wx, wy) = (&self.window_x, &self.window_y);
        let dy = self.spec.dy_m;
        let inv = self.row_inv.clone();
        let fwd = self.row_fwd.clone();
        let dst = self.dst.as_ref();
        let scratch_len = self.row_scratch_len();
        let (rec_rows, offsets, rec) = record;
        let nr = rec_rows.len().max(1);
        debug_assert_eq!(rec.len(), nx * nr);
        let pool = &self.pool;
        par_rows(&mut self.field, &mut self.nyquist, rec, ny, nr).for_each_init(
            || pool.get(ylen, scratch_len),
            |g, (ix, ((row, nq), rec_row))| {
                let Scratch { a, b } = g.scratch();
                let (ext, scratch) = (&mut a[..ylen], b.as_mut_slice());
                inverse_row(ground, (&*inv, dst), row, *nq, ext, scratch);
                match (uniform, medium) {
                    (Some(s), _) if s != C32::new(1.0, 0.0) => {
                        row.iter_mut().for_each(|z| *z *= s);
                    }
                    (None, StepMedium::Fixed) => {
                        let scr = &fixed.expect("checked in advance")[ix * ny..(ix + 1) * ny];
                        row.iter_mut().zip(scr).for_each(|(z, s)| *z *= s);
                    }
                    (None, StepMedium::CrossRange(n)) => {
                        let f = to_c32(screen_factor(n[ix], half_k0_dz));
                        row.iter_mut().for_each(|z| *z *= f);
                    }
                    (None, StepMedium::Index(n)) => {
                        row.iter_mut().zip(n.row(ix)).for_each(|(z, &nn)| {
                            *z *= to_c32(screen_factor(nn, half_k0_dz));
                        });
                    }
                    _ => {}
                }
                if !wx.is_empty() {
                    let a = wx[ix];
                    row.iter_mut().zip(wy).for_each(|(z, &b)| *z *= a * b);
                }
                match obstacle {
                    StepObstacle::None => {}
                    StepObstacle::Mask(mask) => {
                        row.iter_mut().zip(mask.row(ix)).for_each(|(z, &blocked)| {
                            if blocked {
                                *z = C32::default();
                            }
                        });
                    }
                    StepObstacle::Heights(h) => {
                        let hh = h[ix];
                        if hh >= 0.0 {
                            let top = ((hh / dy).floor() as usize).min(ny - 1);
                            row[..=top].iter_mut().for_each(|z| *z = C32::default());
                        }
                    }
                }
                let shift = offsets.map_or(0, |o| o[ix]);
                for (r, &iy) in rec_rows.iter().enumerate() {
                    let at = (iy as i64 + shift).clamp(0, ny as i64 - 1) as usize;
                    rec_row[r] = row[at];
                }
                if forward_again {
                    forward_row(ground, (&*fwd, dst), row, nq, ext, scratch);
                }
            },
        );
    }
}

/// Forward y transform of one row: plain FFT, the sine transform (`"pec-h"`, when `dst` is
/// given), or image extension then FFT.
fn forward_row(
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
fn par_rows<'a>(
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
fn inverse_row(
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
fn fast_tab_width(ny: usize, ground: Ground) -> usize {
    match ground {
        Ground::None => ny,
        _ => ny + 1,
    }
}

/// Rebuilds the full `2 ny` image-extended spectrum from the stored half.
fn spectrum_to_ext(ground: Ground, row: &[C32], nyq: C32, ext: &mut [C32]) {
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
struct Dst {
    fft: Arc<dyn Fft<f32>>,
    /// `sin(pi j / N)`, j < N.
    sin: Vec<f32>,
}

impl Dst {
    /// Scale of the forward transform, the image extension's FFT: `-2j`.
    const FORWARD: C32 = C32::new(0.0, -2.0);
    /// Scale of the inverse transform, the image extension's unnormalised inverse FFT: `+2j`.
    const INVERSE: C32 = C32::new(0.0, 2.0);

    fn new(planner: &mut FftPlanner<f32>, n: usize) -> Self {
        let sin = (0..n)
            .map(|j| (std::f64::consts::PI * j as f64 / n as f64).sin() as f32)
            .collect();
        Dst {
            fft: planner.plan_fft_forward(n),
            sin,
        }
    }

    fn scratch_len(&self) -> usize {
        self.fft.get_inplace_scratch_len()
    }

    /// `row[m] <- scale * S[m]` (`row[0] <- 0`); `y` (the row's length) and `scratch`
    /// (`scratch_len`) are work space.
    fn apply(&self, row: &mut [C32], y: &mut [C32], scratch: &mut [C32], scale: C32) {
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

#[cfg(test)]
mod tests;
