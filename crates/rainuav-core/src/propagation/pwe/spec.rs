//! What a march is: the grid, steps, propagator and ground ([`MarchSpec`]), the medium and
//! obstacles of each step, the rows to record, and the checks on each.

use crate::error::{CoreError, Result, check_range};
use ndarray::{ArrayView1, ArrayView2, ArrayViewMut2, ArrayViewMut3};
use num_complex::Complex64;
use std::str::FromStr;

use super::C32;

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
    /// On steps with a uniform medium and no obstacles (and no recorded column), the lateral
    /// part of the window is applied every this many steps, as the window to this power, so
    /// that the x transforms run only then (1-64; 1: every step, the general step).
    pub x_absorber_every: usize,
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
        if !(1..=64).contains(&self.x_absorber_every) {
            return Err(CoreError::invalid(
                "x_absorber_every",
                "must be within 1..64 steps",
                self.x_absorber_every,
            ));
        }
        Ok(())
    }

    /// Bytes the marcher itself holds (field, propagator table, the uniform path's table
    /// when `x_absorber_every > 1`, optional fixed screen).
    pub fn working_bytes(&self, fixed_screen: bool) -> usize {
        let c = size_of::<C32>();
        let field = self.nx * self.ny * c;
        let (rows, cols) = table_shape(self.nx, self.ny, self.ground);
        let fast = if self.x_absorber_every > 1 {
            (self.nx / 2 + 1) * (self.ny + 1) * c
        } else {
            0
        };
        field + rows * cols * c + fast + if fixed_screen { field } else { 0 }
    }

    /// Length of the y transform: `ny`, or `2 ny` with a ground (image extension).
    pub(super) fn y_len(&self) -> usize {
        match self.ground {
            Ground::None => self.ny,
            _ => 2 * self.ny,
        }
    }
}

/// Rows (distinct |ky|) and columns (distinct |kx|) of the propagator table.
pub(super) fn table_shape(nx: usize, ny: usize, ground: Ground) -> (usize, usize) {
    let rows = match ground {
        Ground::None => ny / 2 + 1,
        _ => ny + 1,
    };
    (rows, nx / 2 + 1)
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
/// `u[ix, record_rows[r]]` after global step `step` (with `row_offsets = (first, o)`,
/// `u[ix, record_rows[r] + o[step - first, ix]]`: a receiver surface that follows the
/// ground); `column[step, iy]` receives `u[record_column, iy]`.
pub struct Recording<'a> {
    /// Which rows (iy) to record.
    pub record_rows: &'a [usize],
    /// A shift of the recorded rows per step and column: `(first, offsets)` with `offsets`
    /// (steps, nx) for the global steps `first..`; the shifted rows must stay within the grid.
    pub row_offsets: Option<(usize, ArrayView2<'a, i64>)>,
    /// Output (len(record_rows), total steps, nx).
    pub rows: Option<ArrayViewMut3<'a, C32>>,
    /// Which column (ix) to record and the output (total steps, ny).
    pub column: Option<(usize, ArrayViewMut2<'a, C32>)>,
}

/// Checks an (nx, ny) refractive-index array: its shape and finite values.
pub(super) fn check_index(n: ArrayView2<'_, Complex64>, nx: usize, ny: usize) -> Result<()> {
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

/// Checks one step's obstacle: its shape and heights.
pub(super) fn check_obstacle(obs: &StepObstacle<'_>, nx: usize, ny: usize) -> Result<()> {
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
