//! 3-D split-step parabolic-equation march (PHYSICS.md section 4).
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
//! y). A step is two passes over memory: a *column pass* that, block by block of 16 columns,
//! gathers the columns, FFTs them along x, multiplies by `P`, inverse-FFTs and scatters them
//! back; and a *row pass* that inverse-FFTs each row along y, applies the phase screen, the
//! absorbing window and the obstacles, records the requested rows, and FFTs the row again
//! for the next step. rustfft plans are made once; the hot loop allocates nothing
//! (each rayon thread has scratch buffers in the marcher's pool, sized once).
//!
//! **Ground.** A flat PEC ground is the image method: the column `u(x, y >= 0)` is extended
//! to `2 ny` samples, odd (`"pec-h"`, `u(-y) = -u(y)`, a sine transform) or even (`"pec-v"`,
//! a cosine transform), and only the `ny` (+1 for the even case) independent spectral values
//! are stored. The x transforms are unchanged, so a ground costs one y-FFT of length `2 ny`
//! per row instead of `ny`, about 1.5x the periodic step, and no extra memory of note.
//!
//! **Accuracy.** Storage and FFTs are complex64 (f32); the propagator and phase screens are
//! computed in f64 and rounded once to f32. The march is then accurate to f32 rounding
//! growing like `sqrt(steps) * 1e-7 * log2(n)` relative (about 1e-5 after 1000 steps).
//!
//! **Memory.** The field (one copy, `8 nx ny` bytes), the propagator table over `|kx|, |ky|`
//! (a quarter of a copy, half with a ground), and, only when the refractive index is an
//! (nx, ny) array constant along range, its precomputed phase screen (one copy): at most
//! 2.5 copies of the field plus what the caller records.

use crate::error::{CoreError, Result, check_range};
use crate::wavenumber;
use ndarray::{Array2, ArrayView1, ArrayView2, ArrayViewMut2, ArrayViewMut3};
use num_complex::{Complex32, Complex64};
use rayon::prelude::*;
use rustfft::{Fft, FftPlanner};
use std::str::FromStr;
use std::sync::{Arc, Mutex, MutexGuard};

/// Single-precision complex sample of the field.
pub type C32 = Complex32;

/// Columns handled together in the column pass: 32 x 8 bytes = four cache lines per row and
/// TLB entry, and the gather buffer (32 nx samples, 1 MiB at nx = 4096) stays in L2.
/// Measured at 4096 x 1024 (30-step march, best of 6): 8 -> 689 ms, 16 -> 642 ms,
/// 32 -> 595-610 ms, 64 -> 645 ms.
const COLUMN_BLOCK: usize = 32;

/// Propagator of the spectral step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Propagator {
    /// Exact spectral (wide-angle) propagator; evanescent waves decay. Default.
    Wide,
    /// Paraxial (narrow-angle) propagator, the paper's.
    Narrow,
}

impl FromStr for Propagator {
    type Err = CoreError;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "wide" => Ok(Propagator::Wide),
            "narrow" => Ok(Propagator::Narrow),
            _ => Err(CoreError::invalid(
                "propagator",
                "must be 'wide' or 'narrow'",
                format!("{s:?}"),
            )),
        }
    }
}

/// Lower boundary of the domain.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Ground {
    /// None: the domain is periodic in y (for tests and free space).
    None,
    /// Flat PEC ground, horizontal polarisation: odd images (sine transform).
    PecH,
    /// Flat PEC ground, vertical polarisation: even images (cosine transform).
    PecV,
}

impl FromStr for Ground {
    type Err = CoreError;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "none" => Ok(Ground::None),
            "pec-h" => Ok(Ground::PecH),
            "pec-v" => Ok(Ground::PecV),
            _ => Err(CoreError::invalid(
                "ground",
                "must be None, 'pec-h' or 'pec-v'",
                format!("{s:?}"),
            )),
        }
    }
}

/// The grid and the physics that stay fixed during a march.
#[derive(Debug, Clone, PartialEq)]
pub struct MarchSpec {
    /// Cross-range samples.
    pub nx: usize,
    /// Height samples.
    pub ny: usize,
    /// Cross-range step, m.
    pub dx_m: f64,
    /// Height step, m.
    pub dy_m: f64,
    /// Range step, m.
    pub dz_m: f64,
    /// Frequency, Hz.
    pub freq_hz: f64,
    /// Spectral propagator.
    pub propagator: Propagator,
    /// Ground.
    pub ground: Ground,
    /// Fraction of the lateral edges and the top (and bottom without a ground) over which
    /// the absorbing window tapers (cos^2) from 1 to 0; 0 disables it.
    pub absorber: f64,
}

/// Frequencies the PE accepts, Hz.
pub const PE_FREQ_RANGE_HZ: (f64, f64) = (1e6, 1e12);

impl MarchSpec {
    /// Checks the spec.
    pub fn validate(&self) -> Result<()> {
        if self.nx < 4 || self.nx > 1 << 20 {
            return Err(CoreError::invalid(
                "nx",
                "must be within 4..1048576",
                self.nx,
            ));
        }
        if self.ny < 4 || self.ny > 1 << 20 {
            return Err(CoreError::invalid(
                "ny",
                "must be within 4..1048576",
                self.ny,
            ));
        }
        for (name, v) in [
            ("dx_m", self.dx_m),
            ("dy_m", self.dy_m),
            ("dz_m", self.dz_m),
        ] {
            check_range(name, v, f64::MIN_POSITIVE, 1e6, "must be finite and > 0 m")?;
        }
        check_range(
            "freq_hz",
            self.freq_hz,
            PE_FREQ_RANGE_HZ.0,
            PE_FREQ_RANGE_HZ.1,
            "must be finite and within 1e6..1e12 Hz",
        )?;
        check_range(
            "absorber",
            self.absorber,
            0.0,
            0.45,
            "must be finite and within 0..0.45 (fraction of each edge)",
        )?;
        Ok(())
    }

    /// Bytes the marcher itself holds (field, propagator table, optional fixed screen).
    pub fn working_bytes(&self, fixed_screen: bool) -> usize {
        let c = size_of::<C32>();
        let field = self.nx * self.ny * c;
        let (rows, cols) = table_shape(self.nx, self.ny, self.ground);
        field + rows * cols * c + if fixed_screen { field } else { 0 }
    }

    /// Length of the y transform: `ny`, or `2 ny` with a ground (image extension).
    fn y_len(&self) -> usize {
        match self.ground {
            Ground::None => self.ny,
            _ => 2 * self.ny,
        }
    }
}

/// Rows (distinct |ky|) and columns (distinct |kx|) of the propagator table.
fn table_shape(nx: usize, ny: usize, ground: Ground) -> (usize, usize) {
    let rows = match ground {
        Ground::None => ny / 2 + 1,
        _ => ny + 1,
    };
    (rows, nx / 2 + 1)
}

/// Memory this machine reports as available (Linux `MemAvailable`), bytes.
pub fn available_memory_bytes() -> Option<usize> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: usize = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Refuses a job needing `bytes` if it exceeds 80% of the available memory.
pub fn check_memory(bytes: usize) -> Result<()> {
    if let Some(avail) = available_memory_bytes()
        && bytes as f64 > 0.8 * avail as f64
    {
        return Err(CoreError::invalid(
            "grid",
            format!(
                "needs {:.2} GB but this machine has {:.2} GB available (at most 80% may be used); \
                 use fewer samples, steps or recorded rows",
                bytes as f64 / 1e9,
                avail as f64 / 1e9
            ),
            bytes,
        ));
    }
    Ok(())
}

/// The refractive index for one step.
#[derive(Debug, Clone, Copy)]
pub enum StepMedium<'a> {
    /// The same complex index everywhere (1 is clear air).
    Uniform(Complex64),
    /// The (nx, ny) index given to [`Marcher::set_fixed_index`], constant along range.
    Fixed,
    /// An (nx, ny) index for this step only; its screen is computed on the fly.
    Index(ArrayView2<'a, Complex64>),
    /// An index varying with cross-range only, (nx,), for this step (rain cells whose rate
    /// varies horizontally but not with height): one screen factor per row.
    CrossRange(ArrayView1<'a, Complex64>),
}

/// What blocks the field at one step.
#[derive(Debug, Clone, Copy)]
pub enum StepObstacle<'a> {
    /// Nothing.
    None,
    /// An (nx, ny) mask: `true` zeroes the field there.
    Mask(ArrayView2<'a, bool>),
    /// Heights (nx,) in metres: the field is zeroed at every `y = iy dy <= height[ix]`
    /// (buildings standing on the ground). Negative heights block nothing.
    Heights(ArrayView1<'a, f64>),
}

/// Where the caller wants recordings written. `rows[r, step, ix]` receives
/// `u[ix, record_rows[r]]` after global step `step`; `column[step, iy]` receives
/// `u[record_column, iy]`.
pub struct Recording<'a> {
    /// Which rows (iy) to record.
    pub record_rows: &'a [usize],
    /// Output (len(record_rows), total steps, nx).
    pub rows: Option<ArrayViewMut3<'a, C32>>,
    /// Which column (ix) to record and the output (total steps, ny).
    pub column: Option<(usize, ArrayViewMut2<'a, C32>)>,
}

/// Phase-screen factor `exp(-j k0 (n^2 - 1) dz / 2)` in f64.
fn screen_factor(n: Complex64, half_k0_dz: f64) -> Complex64 {
    let q = n * n - 1.0;
    // -j * half_k0_dz * q = half_k0_dz * (q.im - j q.re)
    Complex64::from_polar((half_k0_dz * q.im).exp(), -half_k0_dz * q.re)
}

fn to_c32(z: Complex64) -> C32 {
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
    col_fwd: Arc<dyn Fft<f32>>,
    col_inv: Arc<dyn Fft<f32>>,
    spectral: bool,
    steps_done: usize,
    /// Recorded rows of the current step, `rec_buf[ix * n_rows + r]` (reused across steps).
    rec_buf: Vec<C32>,
    /// One image-extended column for recording the vertical plane (reused across steps).
    col_buf: Vec<C32>,
    /// Per-thread scratch of the passes.
    pool: ScratchPool,
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
            col_fwd,
            col_inv,
            spectral: false,
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

    /// The current field (nx, ny). Between calls to [`Marcher::advance`] it is in real space.
    pub fn field(&self) -> ArrayView2<'_, C32> {
        debug_assert!(!self.spectral, "advance() always ends in real space");
        ArrayView2::from_shape((self.spec.nx, self.spec.ny), &self.field)
            .expect("field buffer has nx * ny samples")
    }

    /// Takes the field out as an owned (nx, ny) array.
    pub fn into_field(self) -> Array2<C32> {
        debug_assert!(!self.spectral, "advance() always ends in real space");
        let (nx, ny) = (self.spec.nx, self.spec.ny);
        Array2::from_shape_vec((nx, ny), self.field).expect("field buffer has nx * ny samples")
    }

    /// Advances `steps` steps. `medium(k)` and `obstacle(k)` give the medium and obstacles
    /// of global step `k` (0-based); recordings land at global step indices.
    pub fn advance<'m>(
        &mut self,
        steps: usize,
        medium: &dyn Fn(usize) -> StepMedium<'m>,
        obstacle: &dyn Fn(usize) -> StepObstacle<'m>,
        recording: &mut Recording<'_>,
    ) -> Result<()> {
        self.check_recording(steps, recording)?;
        for k in 0..steps {
            let global = self.steps_done;
            let med = medium(global);
            match med {
                StepMedium::Index(n) => check_index(n, self.spec.nx, self.spec.ny)?,
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
            let obs = obstacle(global);
            check_obstacle(&obs, self.spec.nx, self.spec.ny)?;
            if !self.spectral {
                self.forward_rows();
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
            self.row_pass(&med, &obs, (rec_rows, &mut rec), !last);
            self.spectral = !last;
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
                let row: &[C32] = if self.spectral {
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
        self.col_buf.resize(ylen, C32::default());
        let row = &self.field[ix * ny..(ix + 1) * ny];
        spectrum_to_ext(self.spec.ground, row, self.nyquist[ix], &mut self.col_buf);
        self.row_inv.process(&mut self.col_buf);
        let s = 1.0 / ylen as f32;
        self.col_buf[..ny].iter_mut().for_each(|z| *z *= s);
        &self.col_buf[..ny]
    }

    /// Forward y transform of every row (real space -> y-spectra).
    fn forward_rows(&mut self) {
        let ny = self.spec.ny;
        let ground = self.spec.ground;
        let fft = self.row_fwd.clone();
        let ylen = self.spec.y_len();
        let scratch_len = fft.get_inplace_scratch_len();
        self.field
            .par_chunks_mut(ny)
            .zip(self.nyquist.par_iter_mut())
            .for_each_init(
                || self.pool.get(ylen, scratch_len),
                |g, (row, nq)| {
                    let s = g.scratch();
                    forward_row(ground, &*fft, row, nq, &mut s.a[..ylen], &mut s.b)
                },
            );
        self.spectral = true;
    }

    /// x transforms, propagator and inverse x transforms, block by block of columns.
    #[allow(unsafe_code)]
    fn column_pass(&mut self, uniform_screen: Option<C32>) {
        let one = C32::new(1.0, 0.0);
        let ptab: &[C32] = match uniform_screen {
            Some(sc) if sc != one => {
                if self.scaled.as_ref().is_none_or(|(old, _)| *old != sc) {
                    let mut t = std::mem::take(&mut self.scaled)
                        .map(|x| x.1)
                        .unwrap_or_default();
                    t.clear();
                    t.extend(self.ptab.iter().map(|p| p * sc));
                    self.scaled = Some((sc, t));
                }
                &self.scaled.as_ref().expect("just set").1
            }
            _ => &self.ptab,
        };
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
        // Transforms `buf` (whole columns, the first at spectral column m0) along x, applies
        // P and transforms back; rustfft batches the columns in one call each way.
        let apply = |buf: &mut [C32], m0: usize, scratch: &mut [C32]| {
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
        record: (&[usize], &mut [C32]),
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
        let scratch_len = inv
            .get_inplace_scratch_len()
            .max(fwd.get_inplace_scratch_len());
        let (rec_rows, rec) = record;
        debug_assert_eq!(rec.len(), nx * rec_rows.len().max(1));
        let pool = &self.pool;
        self.field
            .par_chunks_mut(ny)
            .zip(self.nyquist.par_iter_mut())
            .zip(rec.par_chunks_mut(rec_rows.len().max(1)))
            .enumerate()
            .for_each_init(
                || pool.get(ylen, scratch_len),
                |g, (ix, ((row, nq), rec_row))| {
                    let Scratch { a, b } = g.scratch();
                    let (ext, scratch) = (&mut a[..ylen], b.as_mut_slice());
                    if ground == Ground::None {
                        inv.process_with_scratch(row, scratch);
                    } else {
                        spectrum_to_ext(ground, row, *nq, ext);
                        inv.process_with_scratch(ext, scratch);
                        row.copy_from_slice(&ext[..ny]);
                    }
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
                    for (r, &iy) in rec_rows.iter().enumerate() {
                        rec_row[r] = row[iy];
                    }
                    if forward_again {
                        forward_row(ground, &*fwd, row, nq, ext, scratch);
                    }
                },
            );
        self.spectral = forward_again;
    }
}

/// Forward y transform of one row: plain FFT, or image extension then FFT with a ground.
fn forward_row(
    ground: Ground,
    fft: &dyn Fft<f32>,
    row: &mut [C32],
    nyq: &mut C32,
    ext: &mut [C32],
    scratch: &mut [C32],
) {
    let ny = row.len();
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

fn check_index(n: ArrayView2<'_, Complex64>, nx: usize, ny: usize) -> Result<()> {
    if n.dim() != (nx, ny) {
        return Err(CoreError::invalid(
            "n",
            format!("must be a scalar or have shape ({nx}, {ny}) per step"),
            format!("{:?}", n.dim()),
        ));
    }
    if n.iter().any(|z| !(z.re.is_finite() && z.im.is_finite())) {
        return Err(CoreError::invalid(
            "n",
            "must be finite everywhere",
            "NaN or inf",
        ));
    }
    Ok(())
}

fn check_obstacle(obs: &StepObstacle<'_>, nx: usize, ny: usize) -> Result<()> {
    match obs {
        StepObstacle::None => Ok(()),
        StepObstacle::Mask(m) if m.dim() != (nx, ny) => Err(CoreError::invalid(
            "obstacles",
            format!("masks must have shape ({nx}, {ny}) per step"),
            format!("{:?}", m.dim()),
        )),
        StepObstacle::Heights(h) if h.len() != nx => Err(CoreError::invalid(
            "obstacles",
            format!("heights must have {nx} values per step"),
            h.len(),
        )),
        StepObstacle::Heights(h) if h.iter().any(|v| v.is_nan()) => Err(CoreError::invalid(
            "obstacles",
            "heights must not be NaN",
            "NaN",
        )),
        _ => Ok(()),
    }
}

/// Gaussian-beam aperture (PHYSICS.md section 4): height `height_m`, elevation tilt
/// `elevation_deg`, half-power beamwidth `beamwidth_deg`, on the grid `x = (ix - nx/2) dx`,
/// `y = iy dy`. Computed in f64, stored as complex64.
// Mirrors `rainuav.pwe.gaussian_beam`'s signature one to one.
#[allow(clippy::too_many_arguments)]
pub fn gaussian_beam(
    nx: usize,
    ny: usize,
    dx_m: f64,
    dy_m: f64,
    freq_hz: f64,
    height_m: f64,
    elevation_deg: f64,
    beamwidth_deg: f64,
) -> Result<Array2<C32>> {
    check_range(
        "beamwidth_deg",
        beamwidth_deg,
        1e-3,
        179.0,
        "must be finite and within 0.001..179 degrees",
    )?;
    check_range(
        "elevation_deg",
        elevation_deg,
        -89.0,
        89.0,
        "must be finite and within -89..89 degrees",
    )?;
    check_range("height_m", height_m, -1e6, 1e6, "must be finite")?;
    let spec = MarchSpec {
        nx,
        ny,
        dx_m,
        dy_m,
        dz_m: 1.0,
        freq_hz,
        propagator: Propagator::Wide,
        ground: Ground::None,
        absorber: 0.0,
    };
    spec.validate()?;
    check_memory(nx * ny * size_of::<C32>())?;
    let k0 = wavenumber(freq_hz);
    let a = k0 * (0.5 * beamwidth_deg.to_radians()).sin();
    let c = a * a / (2.0 * std::f64::consts::LN_2);
    let kt = k0 * elevation_deg.to_radians().sin();
    let mut out = Array2::<C32>::zeros((nx, ny));
    out.axis_iter_mut(ndarray::Axis(0))
        .into_par_iter()
        .enumerate()
        .for_each(|(ix, mut row)| {
            let x = (ix as f64 - (nx / 2) as f64) * dx_m;
            for (iy, v) in row.iter_mut().enumerate() {
                let y = iy as f64 * dy_m - height_m;
                let amp = (-c * (x * x + y * y)).exp();
                *v = to_c32(Complex64::from_polar(amp, -kt * y));
            }
        });
    Ok(out)
}
