//! Ray model over flat ground (docs/physics.md section 8): for one transmitter and every pixel of
//! a horizontal map, the line-of-sight ray and the ray reflected by the ground, each with the
//! antenna gain in its own departure direction (given per pixel by the caller), free-space
//! spreading, rain attenuation integrated along the ray, and a knife-edge diffraction loss
//! where a building stands in its way.
//!
//! **Local mean.** A pixel reports the mean of `|E1 + E2|^2` over its area. With the phase
//! difference `phi = k0 (d2 - d1)` linear across the pixel (gradient `g`), the mean of the
//! cross term is the centre's times `sinc(g_x dx / 2) sinc(g_y dy / 2)`: exact for a linear
//! phase, and it tends to `|E1|^2 + |E2|^2` where many fringes fit in a pixel (the ground
//! fringes at 100 m are 12 m apart at 1 km, 4.9 GHz). The amplitudes are taken at the centre.
//!
//! **Rain.** The rain fills every column from the ground up, so the attenuation of a ray is
//! `A = (d / rho) integral_0^rho gamma(x(s), y(s)) ds` over the horizontal projection of the
//! ray (the same line for both rays: the reflection point lies on it), with `gamma` in dB/m:
//! uniform (`gamma d` exactly) or a raster of nodes, bilinear, held beyond the outermost nodes,
//! integrated by the trapezoid rule at the node spacing.
//!
//! **Ground and obstacles** (docs/physics.md section 12). Optionally a terrain (a raster of heights
//! above sea level at nodes, bilinear between them) under everything, and obstacles standing
//! on it: boxes and a raster of obstacle heights over cells. A site's antenna stands
//! `height` above the terrain at the site; the receiver flies `altitude_m` above the terrain
//! under it, or above sea level ([`RayScene::altitude_msl`]). Over flat open ground (no
//! terrain, no obstacles) the rays are the closed forms of section 8. Otherwise each
//! site-pixel path reads its profile from the surface ([`RayScene::profile`]): the direct ray
//! gets the diffraction loss of the whole profile ([`crate::propagation::diffraction`]: the terrain's
//! Bullington with its correction, or Deygout's isolated edges where a building is the
//! principal edge) and its antenna gain is taken toward that edge ([`RayScene::departures`]);
//! the ground-reflected ray bounces off the line fitted to the terrain over its first Fresnel
//! zone (the image construction iterated), weighted by the Rayleigh factor of the terrain's
//! roughness there, where its specular point is bare ground, faded by the knife-edge loss of
//! whatever half hides its legs.

use ndarray::{Array3, Array4, ArrayView2, ArrayView3, ArrayView4, Axis};
use num_complex::Complex64;
use rayon::prelude::*;

use crate::error::{CoreError, Result};

/// The ground under the rays.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RayGround {
    /// Free space: the direct ray only.
    None,
    /// A perfectly conducting plane (`Gamma_H = -1`, `Gamma_V = +1`).
    Pec,
    /// A dielectric half-space of complex relative permittivity `eps_r - j 60 lambda sigma`.
    Dielectric(Complex64),
}

/// Polarisation of the transmitted wave (sets the ground's reflection coefficient).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RayPolarization {
    /// Horizontal (electric field parallel to the ground).
    H,
    /// Vertical.
    V,
}

/// A table over a regular grid: `values[i, j]` belongs to `(x0 + j dx, y0 + i dy)`. The rain
/// reads it as nodes ([`Raster::bilinear`]), the obstacles as cells ([`Raster::cell`]).
#[derive(Debug, Clone, Copy)]
pub struct Raster<'a> {
    /// The values (rows north, columns east).
    pub values: ArrayView2<'a, f64>,
    /// `(x0, dx, y0, dy)`, metres.
    pub origin_step: [f64; 4],
}

impl Raster<'_> {
    /// Bilinear between nodes, held beyond the outermost.
    pub fn bilinear(&self, x: f64, y: f64) -> f64 {
        let [x0, dx, y0, dy] = self.origin_step;
        let (rows, cols) = self.values.dim();
        let fx = ((x - x0) / dx).clamp(0.0, (cols - 1) as f64);
        let fy = ((y - y0) / dy).clamp(0.0, (rows - 1) as f64);
        // Truncation is the floor of these non-negative numbers (and no call into libm).
        let j = (fx as usize).min(cols.saturating_sub(2));
        let i = (fy as usize).min(rows.saturating_sub(2));
        let (tx, ty) = (fx - j as f64, fy - i as f64);
        let j1 = (j + 1).min(cols - 1);
        let i1 = (i + 1).min(rows - 1);
        let v = &self.values;
        v[[i, j]] * (1.0 - tx) * (1.0 - ty)
            + v[[i, j1]] * tx * (1.0 - ty)
            + v[[i1, j]] * (1.0 - tx) * ty
            + v[[i1, j1]] * tx * ty
    }

    /// The value whose cell `x0 + j dx .. x0 + (j + 1) dx` by `y0 + i dy .. y0 + (i + 1) dy`
    /// holds the point (nearest sample); 0 outside the table.
    pub(crate) fn cell(&self, x: f64, y: f64) -> f64 {
        let [x0, dx, y0, dy] = self.origin_step;
        let (rows, cols) = self.values.dim();
        let j = ((x - x0) / dx).floor();
        let i = ((y - y0) / dy).floor();
        if j < 0.0 || i < 0.0 || j >= cols as f64 || i >= rows as f64 {
            return 0.0;
        }
        self.values[[i as usize, j as usize]]
    }

    pub(crate) fn spacing(&self) -> f64 {
        self.origin_step[1].min(self.origin_step[3])
    }
}

/// Specific attenuation of the rain field, dB per metre.
#[derive(Debug, Clone, Copy)]
pub enum RainField<'a> {
    /// The same everywhere (0 for clear air).
    Uniform(f64),
    /// Varies horizontally: nodes of a raster ([`Raster::bilinear`]).
    Raster(Raster<'a>),
}

/// The mean of `gamma` (dB/m) along the horizontal line `a -> b` of a uniform or raster rain
/// field: the trapezoid rule at the raster's spacing.
pub(crate) fn line_gamma(r: &Raster<'_>, a: [f64; 2], b: [f64; 2]) -> f64 {
    let rho = (b[0] - a[0]).hypot(b[1] - a[1]);
    let n = ((rho / r.spacing()).ceil() as usize).max(1);
    let mut sum = 0.5 * (r.bilinear(a[0], a[1]) + r.bilinear(b[0], b[1]));
    for k in 1..n {
        let t = k as f64 / n as f64;
        sum += r.bilinear(a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]));
    }
    sum / n as f64
}

pub use crate::propagation::obstacles::{Building, Prisms};

/// The map, the medium and the ground the rays travel over.
#[derive(Debug, Clone)]
pub struct RayScene<'a> {
    /// Pixel-centre east coordinates (W,), m.
    pub x_m: &'a [f64],
    /// Pixel-centre north coordinates (H,), m.
    pub y_m: &'a [f64],
    /// Receiver height, m.
    pub altitude_m: f64,
    /// Pixel size (east, north), m: the area each value is the mean over (0: no averaging).
    pub pixel_m: [f64; 2],
    /// Carrier frequency, Hz.
    pub freq_hz: f64,
    /// The ground.
    pub ground: RayGround,
    /// The polarisation.
    pub polarization: RayPolarization,
    /// The rain.
    pub rain: RainField<'a>,
    /// Buildings: prisms standing on the terrain (boxes are [`Prisms::from_boxes`]).
    pub prisms: Option<&'a Prisms>,
    /// Further obstacle heights (m, 0: none) over cells of a raster ([`Raster::cell`]).
    pub heights: Option<Raster<'a>>,
    /// The terrain: heights above sea level (m) at nodes, bilinear between them
    /// ([`Raster::bilinear`]); None: a flat ground at 0.
    pub terrain: Option<Raster<'a>>,
    /// Whether `altitude_m` is above sea level (true) or above the terrain under the receiver
    /// (false: terrain-following, the default).
    pub altitude_msl: bool,
    /// The ground's roughness that the terrain raster does not resolve (standard deviation,
    /// m), added in quadrature to the terrain's own within the first Fresnel zone of a
    /// ground reflection (0: the raster is the ground).
    pub roughness_m: f64,
}

/// One transmitter: position (east, north, height) in metres and power in mW.
#[derive(Debug, Clone, Copy)]
pub struct RayTransmitter {
    /// `[x, y, z]`, metres (z above the terrain at `(x, y)`, > 0).
    pub position_m: [f64; 3],
    /// Radiated power, mW.
    pub power_mw: f64,
}

/// The lengths (m) of the direct and the ground-reflected ray between a transmitter at height
/// `hs` and a receiver at height `hq`, `rho` apart horizontally.
pub(crate) fn ray_lengths(rho: f64, hs: f64, hq: f64) -> (f64, f64) {
    let d1 = (rho * rho + (hq - hs).powi(2)).sqrt().max(1e-3);
    let d2 = (rho * rho + (hq + hs).powi(2)).sqrt();
    (d1, d2)
}

#[cfg(test)]
impl<'a> RayScene<'a> {
    /// A scene for the tests: pixels at `x` x `y`, `altitude_m` up, at `freq_hz`; vertical
    /// polarisation, no ground, rain, buildings or terrain (set what a test needs with the
    /// struct update syntax).
    pub(crate) fn bare(x: &'a [f64], y: &'a [f64], altitude_m: f64, freq_hz: f64) -> Self {
        RayScene {
            x_m: x,
            y_m: y,
            altitude_m,
            pixel_m: [0.0, 0.0],
            freq_hz,
            ground: RayGround::None,
            polarization: RayPolarization::V,
            rain: RainField::Uniform(0.0),
            prisms: None,
            heights: None,
            terrain: None,
            altitude_msl: false,
            roughness_m: 0.0,
        }
    }
}

impl RayScene<'_> {
    pub(crate) fn check(&self) -> Result<()> {
        if self.x_m.is_empty() || self.y_m.is_empty() {
            return Err(CoreError::invalid("x_m, y_m", "must not be empty", 0));
        }
        if !(self.x_m.iter().chain(self.y_m).all(|v| v.is_finite())) {
            return Err(CoreError::invalid(
                "x_m, y_m",
                "must be finite",
                "NaN or inf",
            ));
        }
        crate::error::check_range(
            "altitude_m",
            self.altitude_m,
            1e-3,
            1e5,
            "must be in 0.001..1e5 m",
        )?;
        crate::error::check_range(
            "freq_hz",
            self.freq_hz,
            1e6,
            1e12,
            "must be in 1e6..1e12 Hz",
        )?;
        for p in self.pixel_m {
            crate::error::check_range("pixel_m", p, 0.0, 1e5, "must be in 0..1e5 m")?;
        }
        match self.rain {
            RainField::Uniform(g) => {
                crate::error::check_range("gamma_db_per_m", g, 0.0, 10.0, "must be in 0..10 dB/m")?
            }
            RainField::Raster(r) => check_raster("rain raster", r.values, r.origin_step)?,
        }
        if let RayGround::Dielectric(e) = self.ground
            && !(e.re.is_finite() && e.im.is_finite() && e.re >= 1.0 && e.im <= 0.0)
        {
            return Err(CoreError::invalid(
                "ground permittivity",
                "must be finite with Re >= 1 and Im <= 0",
                e,
            ));
        }
        if let Some(h) = &self.heights {
            check_raster("height raster", h.values, h.origin_step)?;
        }
        if let Some(t) = &self.terrain {
            let os = t.origin_step;
            let ok = t.values.nrows() >= 1
                && t.values.ncols() >= 1
                && t.values
                    .iter()
                    .all(|v| v.is_finite() && (-500.0..=9000.0).contains(v))
                && os.iter().all(|x| x.is_finite())
                && os[1] > 0.0
                && os[3] > 0.0;
            if !ok {
                return Err(CoreError::invalid(
                    "terrain",
                    "must be a non-empty table of heights in -500..9000 m with spacings > 0",
                    "a bad value",
                ));
            }
        }
        Ok(())
    }

    /// Rain attenuation (dB) of the horizontal line from `a` to `q`, per metre of
    /// horizontal distance (the mean of `gamma` along the line).
    fn mean_gamma(&self, a: [f64; 2], q: [f64; 2]) -> f64 {
        match self.rain {
            RainField::Uniform(g) => g,
            RainField::Raster(r) => line_gamma(&r, a, q),
        }
    }

    /// Whether the rays travel over flat open ground (no terrain, no obstacles): the closed
    /// forms of docs/physics.md section 8.
    pub fn flat_open(&self) -> bool {
        self.terrain.is_none() && self.prisms.is_none_or(|p| p.is_empty()) && self.heights.is_none()
    }

    /// The terrain's height above sea level at `(x, y)`, m (0 without a terrain).
    pub fn terrain_at(&self, x: f64, y: f64) -> f64 {
        self.terrain.as_ref().map_or(0.0, |t| t.bilinear(x, y))
    }

    /// The tallest obstacle standing on the terrain at `(x, y)`, m (0: none).
    pub fn obstacle_at(&self, x: f64, y: f64) -> f64 {
        let h = self.heights.as_ref().map_or(0.0, |r| r.cell(x, y));
        h.max(self.prisms.map_or(0.0, |p| p.height_at(x, y)))
    }

    /// The receiver's height above sea level over `q`, m.
    pub fn receiver_height(&self, q: [f64; 2]) -> f64 {
        if self.altitude_msl {
            self.altitude_m
        } else {
            self.terrain_at(q[0], q[1]) + self.altitude_m
        }
    }

    /// The clear-air parts of the mean received power over one pixel ([`PixelTerms`]) from
    /// its path's geometry: antenna gains (linear, toward [`PathGeometry::el_direct`] and
    /// [`PathGeometry::el_reflect`]), spreading, ground reflection, the pixel mean of the
    /// fringes and the diffraction loss; everything but the rain.
    pub fn terms_of(
        &self,
        geom: &PathGeometry,
        tx: &RayTransmitter,
        q: [f64; 2],
        g_direct: f64,
        g_reflect: f64,
    ) -> PixelTerms {
        let (ex, ey) = (q[0] - tx.position_m[0], q[1] - tx.position_m[1]);
        let (d1, d2) = (geom.d1, geom.d2);
        let k0 = crate::wavenumber(self.freq_hz);
        let lambda = crate::SPEED_OF_LIGHT_M_S / self.freq_hz;
        let scale = tx.power_mw * (lambda / (4.0 * std::f64::consts::PI)).powi(2);
        let amp1 = g_direct.max(0.0).sqrt() * db_to_amplitude(geom.loss_db) / d1;
        let mut t = PixelTerms {
            direct: scale * amp1 * amp1,
            reflect: 0.0,
            cross: 0.0,
            d1,
            d2,
            wall: 0.0,
            d3: 0.0,
        };
        if geom.reflect > 0.0 {
            let gamma_g =
                geom.reflect * reflection_coefficient(self.ground, self.polarization, geom.psi);
            let amp2 = g_reflect.max(0.0).sqrt() / d2;
            let r = gamma_g * amp2;
            t.reflect = scale * r.norm_sqr();
            // Cross term 2 Re(E1 conj(E2)) with E_i = a_i exp(-j k0 d_i), averaged over the
            // pixel: the phase k0 (d2 - d1) has gradient k0 (x - xs)(1/d2 - 1/d1) along x
            // (exact over a plane; over terrain, the same with the path's lengths).
            let phase = Complex64::from_polar(1.0, -k0 * (d1 - d2));
            let cross = 2.0 * (amp1 * (phase * r.conj())).re;
            let w = k0 * (1.0 / d2 - 1.0 / d1);
            let avg = sinc(0.5 * w * ex * self.pixel_m[0]) * sinc(0.5 * w * ey * self.pixel_m[1]);
            t.cross = scale * cross * avg;
        }
        t
    }

    /// The clear-air parts of the mean received power over one pixel ([`PixelTerms`]):
    /// [`RayScene::path`] then [`RayScene::terms_of`].
    pub fn pixel_terms(
        &self,
        tx: &RayTransmitter,
        q: [f64; 2],
        g_direct: f64,
        g_reflect: f64,
    ) -> PixelTerms {
        let geom = self.path(tx.position_m, q, &mut self.sight(self.bounds()));
        self.terms_of(&geom, tx, q, g_direct, g_reflect)
    }
}

/// How many values [`RayScene::terms`] gives a cell-pixel.
pub const TERMS: usize = 7;

pub(crate) fn check_raster(name: &'static str, v: ArrayView2<'_, f64>, os: [f64; 4]) -> Result<()> {
    if v.nrows() < 1 || v.ncols() < 1 || !v.iter().all(|x| x.is_finite() && *x >= 0.0) {
        return Err(CoreError::invalid(
            name,
            "must be a non-empty table of finite values >= 0",
            "a bad value",
        ));
    }
    if !(os.iter().all(|x| x.is_finite()) && os[1] > 0.0 && os[3] > 0.0) {
        return Err(CoreError::invalid(
            name,
            "needs finite origins and spacings > 0",
            format!("{os:?}"),
        ));
    }
    Ok(())
}

mod maps;
mod terms;

pub use crate::propagation::diffraction::knife_edge_loss_db;
pub(crate) use terms::db_to_amplitude;
use terms::sinc;
pub use terms::{KnownPaths, PathGeometry, PixelTerms, reflection_coefficient};

#[cfg(test)]
mod tests;
