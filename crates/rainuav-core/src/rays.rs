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
//! gets the diffraction loss of the whole profile ([`crate::diffraction`]: the terrain's
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

pub use crate::obstacles::{Building, Prisms};

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

/// The geometry of one site-pixel path: everything of its rays but the antenna gains, the
/// transmit power and the rain.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathGeometry {
    /// Length of the direct ray, m.
    pub d1: f64,
    /// Length of the ground-reflected ray, m.
    pub d2: f64,
    /// Diffraction loss of the direct ray (Bullington over the profile), dB.
    pub loss_db: f64,
    /// Departure elevation (rad) toward which the direct ray's antenna gain is taken: the
    /// diffracting edge where the profile costs a loss, else the receiver.
    pub el_direct: f64,
    /// Departure elevation (rad) toward the specular point.
    pub el_reflect: f64,
    /// Grazing angle (rad) on the local ground line at the specular point.
    pub psi: f64,
    /// The reflected ray's amplitude factor for the ground's roughness, `exp(-2 (k sigma_h sin
    /// psi)^2)` (1 over smooth ground), where it exists (a ground, its specular point bare
    /// and seen by both ends); 0 where it does not.
    pub reflect: f64,
}

impl PathGeometry {
    /// The geometry as a row: `[d1, d2, loss_db, el_direct, el_reflect, psi, reflect]`.
    pub fn to_row(&self) -> [f64; 7] {
        [
            self.d1,
            self.d2,
            self.loss_db,
            self.el_direct,
            self.el_reflect,
            self.psi,
            self.reflect,
        ]
    }

    /// The geometry of a row of [`PathGeometry::to_row`].
    pub fn from_row(r: &[f64]) -> Self {
        PathGeometry {
            d1: r[0],
            d2: r[1],
            loss_db: r[2],
            el_direct: r[3],
            el_reflect: r[4],
            psi: r[5],
            reflect: r[6],
        }
    }
}

/// Paths already traced ([`RayScene::geometry_table`]): the sites `[x, y, height]` and their
/// table `(S, H, W, 7)`; a transmitter at one of these sites reads its paths from the table.
#[derive(Debug, Clone, Copy)]
pub struct KnownPaths<'a> {
    /// The sites.
    pub sites: &'a [[f64; 3]],
    /// Their paths, rows of [`PathGeometry::to_row`].
    pub table: ArrayView4<'a, f64>,
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

/// One transmitter's mean power over one pixel (mW) split into what rain does not change:
/// with the rain's mean specific attenuation `gamma` (dB/m) along the rays' horizontal path,
/// `P = direct a1^2 + reflect a2^2 + cross a1 a2`, `a_i = 10^(-gamma d_i / 20)`
/// ([`PixelTerms::power`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PixelTerms {
    /// Power of the direct ray in clear air, mW.
    pub direct: f64,
    /// Power of the reflected ray in clear air, mW.
    pub reflect: f64,
    /// Their interference (the pixel mean of `2 Re(E1 conj E2)`) in clear air, mW.
    pub cross: f64,
    /// Length of the direct ray, m.
    pub d1: f64,
    /// Length of the reflected ray, m.
    pub d2: f64,
    /// Power of the rays reflected by walls in clear air (their sum, incoherent), mW
    /// ([`crate::walls`]; 0: none).
    pub wall: f64,
    /// The wall rays' mean length, weighted by their power, m.
    pub d3: f64,
}

impl PixelTerms {
    /// The power (mW) with rain of mean specific attenuation `gamma` (dB/m) along the path.
    pub fn power(&self, gamma: f64) -> f64 {
        let a1 = db_to_amplitude(gamma * self.d1);
        let a2 = db_to_amplitude(gamma * self.d2);
        Self::combine(self.direct, self.reflect, self.cross, a1, a2)
            + Self::wall_power(self.wall, self.d3, gamma)
    }

    /// The wall rays' power `wall` (mW in clear air) through rain of mean specific
    /// attenuation `gamma` (dB/m) along their mean length `d3` (m).
    pub fn wall_power(wall: f64, d3: f64, gamma: f64) -> f64 {
        if wall == 0.0 {
            0.0
        } else {
            wall * db_to_amplitude(gamma * d3).powi(2)
        }
    }

    /// `direct a1^2 + reflect a2^2 + cross a1 a2` (never below 0): the power of the terms
    /// with the rays' amplitude factors `a1`, `a2`.
    pub fn combine(direct: f64, reflect: f64, cross: f64, a1: f64, a2: f64) -> f64 {
        (direct * a1 * a1 + reflect * a2 * a2 + cross * a1 * a2).max(0.0)
    }
}

pub use crate::diffraction::knife_edge_loss_db;

/// Fresnel reflection coefficient of the ground at grazing angle `psi` (radians).
pub fn reflection_coefficient(ground: RayGround, pol: RayPolarization, psi: f64) -> Complex64 {
    match (ground, pol) {
        (RayGround::None, _) => Complex64::new(0.0, 0.0),
        (RayGround::Pec, RayPolarization::H) => Complex64::new(-1.0, 0.0),
        (RayGround::Pec, RayPolarization::V) => Complex64::new(1.0, 0.0),
        (RayGround::Dielectric(eps), p) => {
            let (s, c) = psi.sin_cos();
            let root = (eps - c * c).sqrt();
            match p {
                RayPolarization::H => (s - root) / (s + root),
                RayPolarization::V => (eps * s - root) / (eps * s + root),
            }
        }
    }
}

/// The amplitude factor `10^(-loss / 20)` of a loss in dB (1 for no loss, without a `powf`).
pub(crate) fn db_to_amplitude(loss_db: f64) -> f64 {
    if loss_db == 0.0 {
        1.0
    } else {
        10f64.powf(-loss_db / 20.0)
    }
}

fn sinc(u: f64) -> f64 {
    if u.abs() < 1e-8 { 1.0 } else { u.sin() / u }
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

    /// The geometry of every pixel's path from the site `tx`, row-major `(H W)`, rows in
    /// parallel.
    pub fn geometries(&self, tx: [f64; 3]) -> Vec<PathGeometry> {
        let w = self.x_m.len();
        let bounds = self.bounds();
        (0..self.y_m.len())
            .into_par_iter()
            .flat_map_iter(|i| {
                let mut sight = self.sight(bounds);
                (0..w)
                    .map(|j| self.path(tx, [self.x_m[j], self.y_m[i]], &mut sight))
                    .collect::<Vec<_>>()
            })
            .collect()
    }

    /// The departure elevations (degrees) toward which each site's antenna gains are taken,
    /// `(S, H, W, 2)`: the direct ray's (the diffracting edge where the profile costs a loss,
    /// else the pixel) and the reflected ray's (the specular point). `sites` are
    /// `[x, y, height above the terrain]`.
    pub fn departures(&self, sites: &[[f64; 3]]) -> Result<Array4<f64>> {
        self.check()?;
        let (h, w) = (self.y_m.len(), self.x_m.len());
        crate::memory::check_memory(sites.len() * h * w * 2 * 8)?;
        let mut out = Array4::<f64>::zeros((sites.len(), h, w, 2));
        for (k, &site) in sites.iter().enumerate() {
            let geo = self.geometries(site);
            for (p, g) in geo.iter().enumerate() {
                out[[k, p / w, p % w, 0]] = g.el_direct.to_degrees();
                out[[k, p / w, p % w, 1]] = g.el_reflect.to_degrees();
            }
        }
        Ok(out)
    }

    /// The geometry of every pixel's path from each site, `(S, H, W, 7)`: rows of
    /// [`PathGeometry::to_row`] (what [`RayScene::power_with`] takes as [`KnownPaths`], so a
    /// caller that needs the departures too traces each path once).
    pub fn geometry_table(&self, sites: &[[f64; 3]]) -> Result<Array4<f64>> {
        self.check()?;
        let (h, w) = (self.y_m.len(), self.x_m.len());
        crate::memory::check_memory(sites.len() * h * w * 7 * 8)?;
        let mut out = Array4::<f64>::zeros((sites.len(), h, w, 7));
        for (k, &site) in sites.iter().enumerate() {
            for (p, g) in self.geometries(site).iter().enumerate() {
                for (c, v) in g.to_row().into_iter().enumerate() {
                    out[[k, p / w, p % w, c]] = v;
                }
            }
        }
        Ok(out)
    }

    /// The geometries of each distinct transmitter position (read from `known` where it
    /// holds the position, else traced), and for each transmitter the index of its
    /// position's: a site's cells share their paths.
    fn shared_geometries(
        &self,
        txs: &[RayTransmitter],
        known: Option<KnownPaths<'_>>,
    ) -> Result<(Vec<Vec<PathGeometry>>, Vec<usize>)> {
        let mut places: Vec<[f64; 3]> = Vec::new();
        let index: Vec<usize> = txs
            .iter()
            .map(|t| {
                places
                    .iter()
                    .position(|p| *p == t.position_m)
                    .unwrap_or_else(|| {
                        places.push(t.position_m);
                        places.len() - 1
                    })
            })
            .collect();
        let plane = self.x_m.len() * self.y_m.len();
        crate::memory::check_memory(places.len() * plane * size_of::<PathGeometry>())?;
        let (h, w) = (self.y_m.len(), self.x_m.len());
        if let Some(k) = &known
            && (k.table.dim() != (k.sites.len(), h, w, 7) || !k.table.iter().all(|v| v.is_finite()))
        {
            return Err(CoreError::invalid(
                "geometry",
                format!("must be finite with shape ({}, {h}, {w}, 7)", k.sites.len()),
                format!("{:?}", k.table.dim()),
            ));
        }
        let traced = places
            .iter()
            .map(|&p| {
                match known.and_then(|k| k.sites.iter().position(|s| *s == p).map(|i| (k, i))) {
                    Some((k, i)) => (0..plane)
                        .map(|q| {
                            let row = k.table.slice(ndarray::s![i, q / w, q % w, ..]);
                            PathGeometry::from_row(&[
                                row[0], row[1], row[2], row[3], row[4], row[5], row[6],
                            ])
                        })
                        .collect(),
                    None => self.geometries(p),
                }
            })
            .collect();
        Ok((traced, index))
    }

    /// Checks the transmitters and their gains `(M, H, W)` against the map; the shape.
    fn check_rays(
        &self,
        txs: &[RayTransmitter],
        g_direct: &ArrayView3<'_, f64>,
        g_reflect: &ArrayView3<'_, f64>,
        walls: Option<&ArrayView4<'_, f64>>,
    ) -> Result<(usize, usize, usize)> {
        self.check()?;
        let shape = (txs.len(), self.y_m.len(), self.x_m.len());
        if let Some(wr) = walls {
            let want = (shape.0, shape.1, shape.2, 2);
            if wr.dim() != want {
                return Err(CoreError::invalid(
                    "walls",
                    format!("must have shape {want:?} (cells, rows, columns, 2)"),
                    format!("{:?}", wr.dim()),
                ));
            }
            if !wr.iter().all(|v| v.is_finite() && *v >= 0.0) {
                return Err(CoreError::invalid(
                    "walls",
                    "must be finite and >= 0",
                    "a bad value",
                ));
            }
        }
        for (name, g) in [("g_direct", g_direct), ("g_reflect", g_reflect)] {
            if g.dim() != shape {
                return Err(CoreError::invalid(
                    name,
                    format!("must have shape {shape:?} (cells, rows, columns)"),
                    format!("{:?}", g.dim()),
                ));
            }
            if !g.iter().all(|v| v.is_finite() && *v >= 0.0) {
                return Err(CoreError::invalid(
                    name,
                    "must be finite and >= 0",
                    "a bad gain",
                ));
            }
        }
        for (m, t) in txs.iter().enumerate() {
            let ok = t.position_m.iter().all(|v| v.is_finite())
                && t.position_m[2] > 0.0
                && t.power_mw.is_finite()
                && t.power_mw >= 0.0;
            if !ok {
                return Err(CoreError::invalid(
                    "transmitters",
                    "must have finite positions above the ground and power >= 0",
                    format!("cell {m}: {t:?}"),
                ));
            }
        }
        Ok(shape)
    }

    /// Received power (mW) of every transmitter at every pixel, `(M, H, W)`; `g_direct` and
    /// `g_reflect` are the linear antenna gains `(M, H, W)` of each transmitter toward each
    /// pixel along the direct and the reflected ray. Rows run in parallel (rayon).
    pub fn power(
        &self,
        txs: &[RayTransmitter],
        g_direct: ArrayView3<'_, f64>,
        g_reflect: ArrayView3<'_, f64>,
    ) -> Result<Array3<f64>> {
        self.power_with(txs, g_direct, g_reflect, None, None)
    }

    /// [`RayScene::power`] with the rays reflected by walls: `walls` `(M, H, W, 2)`, each
    /// transmitter's wall rays at each pixel as their clear-air power (mW, gains included)
    /// and power-weighted mean length (m) ([`crate::walls`]); the rain of the pixel's line
    /// attenuates them along that length. `known`: paths already traced.
    pub fn power_with(
        &self,
        txs: &[RayTransmitter],
        g_direct: ArrayView3<'_, f64>,
        g_reflect: ArrayView3<'_, f64>,
        walls: Option<ArrayView4<'_, f64>>,
        known: Option<KnownPaths<'_>>,
    ) -> Result<Array3<f64>> {
        let shape = self.check_rays(txs, &g_direct, &g_reflect, walls.as_ref())?;
        let mut out = Array3::<f64>::zeros(shape);
        crate::memory::check_memory(out.len() * 8)?;
        let (geo, index) = self.shared_geometries(txs, known)?;
        let w = shape.2;
        out.axis_iter_mut(Axis(0))
            .into_par_iter()
            .enumerate()
            .for_each(|(m, mut plane)| {
                let [xs, ys, _] = txs[m].position_m;
                let geo = &geo[index[m]];
                for ((i, j), p) in plane.indexed_iter_mut() {
                    let q = [self.x_m[j], self.y_m[i]];
                    let mut t = self.terms_of(
                        &geo[i * w + j],
                        &txs[m],
                        q,
                        g_direct[[m, i, j]],
                        g_reflect[[m, i, j]],
                    );
                    if let Some(wr) = &walls {
                        (t.wall, t.d3) = (wr[[m, i, j, 0]], wr[[m, i, j, 1]]);
                    }
                    *p = t.power(self.mean_gamma([xs, ys], q));
                }
            });
        Ok(out)
    }

    /// The clear-air parts of every transmitter's power at every pixel and its rays'
    /// lengths, `(M, H, W, 7)`: `[direct, reflect, cross, d1, d2, wall, d3]` of
    /// [`PixelTerms`] (the rain of the scene is not used; `walls` as
    /// [`RayScene::power_with`] takes them, else 0). With the rain's mean attenuation along
    /// each path they give [`RayScene::power_with`]'s power ([`crate::raytime`]: weather in
    /// time, the rays traced once).
    pub fn terms(
        &self,
        txs: &[RayTransmitter],
        g_direct: ArrayView3<'_, f64>,
        g_reflect: ArrayView3<'_, f64>,
        walls: Option<ArrayView4<'_, f64>>,
        known: Option<KnownPaths<'_>>,
    ) -> Result<Array4<f64>> {
        let (m, h, w) = self.check_rays(txs, &g_direct, &g_reflect, walls.as_ref())?;
        let mut out = Array4::<f64>::zeros((m, h, w, TERMS));
        crate::memory::check_memory(out.len() * 8)?;
        let (geo, index) = self.shared_geometries(txs, known)?;
        out.axis_iter_mut(Axis(0))
            .into_par_iter()
            .enumerate()
            .for_each(|(m, mut plane)| {
                let geo = &geo[index[m]];
                for i in 0..h {
                    for j in 0..w {
                        let q = [self.x_m[j], self.y_m[i]];
                        let t = self.terms_of(
                            &geo[i * w + j],
                            &txs[m],
                            q,
                            g_direct[[m, i, j]],
                            g_reflect[[m, i, j]],
                        );
                        plane[[i, j, 0]] = t.direct;
                        plane[[i, j, 1]] = t.reflect;
                        plane[[i, j, 2]] = t.cross;
                        plane[[i, j, 3]] = t.d1;
                        plane[[i, j, 4]] = t.d2;
                        if let Some(wr) = &walls {
                            plane[[i, j, 5]] = wr[[m, i, j, 0]];
                            plane[[i, j, 6]] = wr[[m, i, j, 1]];
                        }
                    }
                }
            });
        Ok(out)
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

#[cfg(test)]
mod tests;
