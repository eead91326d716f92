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
use crate::sight::Sight;

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

/// Where a path's ground reflection meets the ground ([`RayScene::path`]).
#[derive(Debug, Clone, Copy)]
struct Specular {
    /// Distance along the ground from the site, m, and the fitted ground line's height there.
    sb: f64,
    zb: f64,
    /// The reflected ray's length (m) and grazing angle (rad) on the fitted line.
    d2: f64,
    psi: f64,
    /// The terrain's standard deviation about the fitted line, m, and the fit's half-length.
    sigma: f64,
    half: f64,
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
fn db_to_amplitude(loss_db: f64) -> f64 {
    if loss_db == 0.0 {
        1.0
    } else {
        10f64.powf(-loss_db / 20.0)
    }
}

/// The straight line `z = z0 + slope (s - s0)` fitted by least squares to `ground(s)` at 17
/// points evenly over `s0 - a .. s0 + a`, and the standard deviation of the ground about it:
/// `(z0, slope, sigma)` (a fixed count: the fit moves smoothly with the window).
fn fit_line(ground: &impl Fn(f64) -> f64, s0: f64, a: f64) -> (f64, f64, f64) {
    const N: usize = 17;
    let mut pts = [(0.0, 0.0); N];
    let (mut sx, mut sz, mut sxx, mut sxz) = (0.0, 0.0, 0.0, 0.0);
    for (i, p) in pts.iter_mut().enumerate() {
        let u = -a + 2.0 * a * i as f64 / (N - 1) as f64;
        let z = ground(s0 + u);
        *p = (u, z);
        sx += u;
        sz += z;
        sxx += u * u;
        sxz += u * z;
    }
    let m = N as f64;
    let den = m * sxx - sx * sx;
    let slope = if den.abs() > 1e-12 {
        (m * sxz - sx * sz) / den
    } else {
        0.0
    };
    let z0 = (sz - slope * sx) / m;
    let var = pts
        .iter()
        .map(|&(u, z)| (z - z0 - slope * u).powi(2))
        .sum::<f64>()
        / m;
    (z0, slope, var.sqrt())
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

    /// The profile of the surface (terrain + obstacles, m above sea level) along the ground
    /// line `a -> b`, as `(distance from a, height)` strictly between the ends, in order of
    /// distance: the terrain and the obstacle raster every half of their finest spacing, and
    /// each building where the line enters and leaves its footprint. Written into `out`
    /// (cleared first).
    pub fn profile(&self, a: [f64; 2], b: [f64; 2], out: &mut Vec<(f64, f64)>) {
        let mut sight = self.sight(self.bounds());
        self.profile_over(a, b, |_, _| f64::NEG_INFINITY, &mut sight);
        std::mem::swap(out, &mut sight.prof);
    }

    /// [`RayScene::profile`] into `sight.prof`, leaving out the buildings whose roof stays
    /// below `floor(lo, hi)` (m above sea level) wherever the line `a + t (b - a)`,
    /// `t in lo..=hi`, passes over their footprint's box: those the caller has shown cannot
    /// change its answer ([`crate::obstacles::Prisms::near_segment_over`]).
    pub fn profile_over(
        &self,
        a: [f64; 2],
        b: [f64; 2],
        floor: impl Fn(f64, f64) -> f64,
        sight: &mut Sight,
    ) {
        let out = &mut sight.prof;
        out.clear();
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let rho = dx.hypot(dy);
        if rho < 1e-9 {
            return;
        }
        // The samples: the terrain and the obstacle raster (the buildings' roofs over them
        // below), and the terrain alone on the terrain's own grid.
        let ground = &mut sight.ground;
        ground.clear();
        let spacing = [self.terrain.as_ref(), self.heights.as_ref()]
            .into_iter()
            .flatten()
            .map(|r| r.spacing())
            .fold(f64::INFINITY, f64::min);
        let n = if spacing.is_finite() {
            ((rho / (0.5 * spacing)).ceil() as usize).max(1)
        } else {
            0
        };
        for k in 1..n {
            let t = k as f64 / n as f64;
            let (x, y) = (a[0] + t * dx, a[1] + t * dy);
            let z = self.terrain_at(x, y);
            ground.push((t * rho, z));
            out.push((
                t * rho,
                z + self.heights.as_ref().map_or(0.0, |r| r.cell(x, y)),
            ));
        }
        if let Some(tr) = &self.terrain
            && ((rho / (0.5 * tr.spacing())).ceil() as usize).max(1) != n
        {
            let m = ((rho / (0.5 * tr.spacing())).ceil() as usize).max(1);
            ground.clear();
            ground.extend((1..m).map(|k| {
                let t = k as f64 / m as f64;
                (t * rho, self.terrain_at(a[0] + t * dx, a[1] + t * dy))
            }));
        }
        let before = out.len();
        if let Some(prisms) = self.prisms {
            // Each face a building's footprint crosses, read just inside it at its roof (a roof
            // is flat, so its faces are where the extremes of the construction lie); the
            // samples within its footprint (between crossings, inside at the middle) rise to
            // its roof.
            let eps = 1e-9_f64.max(1e-6 / rho);
            let (near, ts) = (&mut sight.near, &mut sight.ts);
            prisms.near_segment_over(a, b, floor, sight.terrain_top, near);
            for &k in near.iter() {
                let (k, top) = (k as usize, prisms.items()[k as usize].top);
                ts.clear();
                prisms.crossings(k, a, b, ts);
                for &t0 in ts.iter() {
                    for t in [t0 - eps, t0 + eps] {
                        let (x, y) = (a[0] + t * dx, a[1] + t * dy);
                        if t > 0.0 && t < 1.0 && prisms.contains(k, x, y) {
                            out.push((t * rho, self.terrain_at(x, y) + top));
                        }
                    }
                }
                if n < 2 {
                    continue;
                }
                ts.sort_by(f64::total_cmp);
                ts.insert(0, 0.0);
                ts.push(1.0);
                for w in ts.windows(2) {
                    let (t0, t1) = (w[0], w[1]);
                    let mid = 0.5 * (t0 + t1);
                    if t1 <= t0 || !prisms.contains(k, a[0] + mid * dx, a[1] + mid * dy) {
                        continue;
                    }
                    // The samples i / n strictly between t0 and t1 (i in 1..n).
                    let (lo, hi) = (
                        (t0 * n as f64) as usize + 1,
                        (t1 * n as f64).ceil() as usize,
                    );
                    for i in lo..hi.min(n) {
                        let t = i as f64 / n as f64;
                        if t > t0 && t < t1 {
                            let (x, y) = (a[0] + t * dx, a[1] + t * dy);
                            let roof = self.terrain_at(x, y) + top;
                            out[i - 1].1 = out[i - 1].1.max(roof);
                        }
                    }
                }
            }
        }
        if out.len() > before {
            out.sort_by(|p, q| p.0.total_cmp(&q.0));
        }
    }

    /// The knife-edge loss (dB, ITU-R P.526 eq. (31)) of the profile point of largest `nu` on the
    /// straight leg from `(s0, z0)` to `(s1, z1)` (distance along the ground line, height above
    /// sea level), leaving out the points within `skip` m of `s_skip`.
    fn leg_loss_db(
        prof: &[(f64, f64)],
        (s0, z0): (f64, f64),
        (s1, z1): (f64, f64),
        s_skip: f64,
        skip: f64,
        lambda: f64,
    ) -> f64 {
        let span = s1 - s0;
        let nu = prof
            .iter()
            .filter(|&&(s, _)| s > s0 && s < s1 && (s - s_skip).abs() > skip)
            .map(|&(s, h)| {
                let (a, b) = (s - s0, s1 - s);
                let line = z0 + (z1 - z0) * a / span;
                (h - line) * (2.0 * span / (lambda * a * b)).sqrt()
            })
            .fold(f64::NEG_INFINITY, f64::max);
        knife_edge_loss_db(nu)
    }

    /// The diffraction loss (dB) of the direct ray over the profile `prof` of the ground line
    /// `a -> b` between the ends at `za`, `zb` (m above sea level), and the edge toward which
    /// the antenna's gain is taken (docs/physics.md section 12). The principal edge (Deygout's:
    /// largest `nu`) decides the method: on terrain, P.526's Bullington construction with its
    /// correction for real terrain; on a building or the obstacle raster, Deygout's isolated
    /// edges without it, plus the correction of the terrain's own Bullington loss where a terrain
    /// is under the path (0 where the terrain alone clears the path), over `ground`, the
    /// terrain alone every half of its spacing.
    #[allow(clippy::too_many_arguments)]
    fn diffraction_loss(
        &self,
        prof: &[(f64, f64)],
        ground: &[(f64, f64)],
        a: [f64; 2],
        b: [f64; 2],
        za: f64,
        zb: f64,
        lambda: f64,
    ) -> (f64, Option<(f64, f64)>) {
        use crate::diffraction::{bullington, deygout};
        let rho = (b[0] - a[0]).hypot(b[1] - a[1]);
        let bull = bullington(prof, rho, za, zb, lambda);
        let obstacles = self.prisms.is_some_and(|p| !p.is_empty()) || self.heights.is_some();
        if !obstacles {
            return (bull.loss_db, bull.edge);
        }
        let (l_d, edge) = deygout(prof, rho, za, zb, lambda);
        let Some((de, _)) = edge else {
            return (bull.loss_db, bull.edge);
        };
        let t = de / rho;
        if self.obstacle_at(a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])) <= 0.0 {
            return (bull.loss_db, bull.edge);
        }
        let corr = if self.terrain.is_some() {
            let l_t = bullington(ground, rho, za, zb, lambda).knife_edge_db;
            (1.0 - (-l_t / 6.0).exp()) * (10.0 + 0.02 * rho / 1000.0)
        } else {
            0.0
        };
        (l_d + corr, edge)
    }

    /// The geometry of the rays from the transmitter at `tx` (`[x, y, height above the
    /// terrain]`) to the pixel centre `q`; `sight` holds the scene's bounds and scratch space
    /// ([`RayScene::sight`]).
    ///
    /// The profile is read only where it can change the answer: a building is left out where
    /// its roof stays more than `2 (0.78) sqrt(lambda d / 8)` plus the Earth's bulge below both
    /// the direct ray and the ground-reflected ray's legs. There every construction that reads
    /// the profile gives it `nu < -0.78` (no loss): Bullington's and Deygout's (whose
    /// principal edge, if below the direct ray, is within `0.78 sqrt(lambda d / 8)` of it),
    /// and each leg's knife edge; and beyond line of sight only the points above the direct
    /// ray set Bullington's slopes. The geometry is the whole profile's.
    pub fn path(&self, tx: [f64; 3], q: [f64; 2], sight: &mut Sight) -> PathGeometry {
        self.path_over(tx, q, sight, true)
    }

    /// [`RayScene::path`], reading the whole profile where `prune` is false (the check that
    /// what it leaves out changes nothing).
    pub(crate) fn path_over(
        &self,
        tx: [f64; 3],
        q: [f64; 2],
        sight: &mut Sight,
        prune: bool,
    ) -> PathGeometry {
        let [xs, ys, hs] = tx;
        let (ex, ey) = (q[0] - xs, q[1] - ys);
        let rho = ex.hypot(ey);
        if self.flat_open() {
            let hq = self.altitude_m;
            let (d1, d2) = ray_lengths(rho, hs, hq);
            return PathGeometry {
                d1,
                d2,
                loss_db: 0.0,
                el_direct: (hq - hs).atan2(rho),
                el_reflect: -(hq + hs).atan2(rho),
                psi: ((hs + hq) / rho.max(1e-9)).atan(),
                reflect: if self.ground != RayGround::None {
                    1.0
                } else {
                    0.0
                },
            };
        }
        let zt_s = self.terrain_at(xs, ys);
        let zs = zt_s + hs;
        let zq = self.receiver_height(q);
        let d1 = (rho * rho + (zq - zs).powi(2)).sqrt().max(1e-3);
        let lambda = crate::SPEED_OF_LIGHT_M_S / self.freq_hz;
        let spec = if self.ground == RayGround::None || rho < 1e-6 {
            None
        } else {
            self.specular(tx, q, zs, zq, lambda)
        };
        // The lowest a building must reach to matter (doc above), over t in lo..=hi.
        let margin = 1.56 * (lambda * rho / 8.0).sqrt()
            + rho * rho / (8.0 * crate::diffraction::EFFECTIVE_EARTH_RADIUS_M);
        let direct = |t: f64| zs + (zq - zs) * t;
        let floor = |lo: f64, hi: f64| {
            if !prune {
                return f64::NEG_INFINITY;
            }
            let mut z = direct(lo).min(direct(hi));
            if let Some(sp) = &spec {
                let tb = sp.sb / rho;
                let legs = |t: f64| {
                    if t <= tb {
                        zs + (sp.zb - zs) * t / tb.max(1e-12)
                    } else {
                        sp.zb + (zq - sp.zb) * (t - tb) / (1.0 - tb).max(1e-12)
                    }
                };
                z = z.min(legs(lo)).min(legs(hi));
                if lo <= tb && tb <= hi {
                    z = z.min(sp.zb);
                }
            }
            z - margin
        };
        self.profile_over([xs, ys], q, floor, sight);
        let prof = &sight.prof;
        let (loss_db, edge) =
            self.diffraction_loss(prof, &sight.ground, [xs, ys], q, zs, zq, lambda);
        let el_direct = match edge {
            Some((de, he)) => (he - zs).atan2(de),
            None => (zq - zs).atan2(rho),
        };
        let mut g = PathGeometry {
            d1,
            d2: d1,
            loss_db,
            el_direct,
            el_reflect: el_direct,
            psi: 0.0,
            reflect: 0.0,
        };
        let Some(Specular {
            sb,
            zb,
            d2,
            psi,
            sigma,
            half,
        }) = spec
        else {
            return g;
        };
        let (ux, uy) = (ex / rho, ey / rho);
        let bare = self.obstacle_at(xs + ux * sb, ys + uy * sb) <= 0.0;
        // Each leg's knife-edge loss over the profile (the reflecting zone left out): a leg
        // the terrain or a building half hides fades the ray instead of cutting it.
        let skip = self.half_spacing().max(half);
        let legs = Self::leg_loss_db(prof, (0.0, zs), (sb, zb), sb, skip, lambda)
            + Self::leg_loss_db(prof, (sb, zb), (rho, zq), sb, skip, lambda);
        g.d2 = d2;
        g.el_reflect = (zb - zs).atan2(sb);
        g.psi = psi;
        let k = crate::wavenumber(self.freq_hz);
        let sigma = if self.terrain.is_some() {
            sigma.hypot(self.roughness_m)
        } else {
            sigma
        };
        let rough = (-2.0 * (k * sigma * g.psi.sin()).powi(2)).exp();
        g.reflect = if bare {
            rough * db_to_amplitude(legs)
        } else {
            0.0
        };
        g
    }

    /// Half the terrain's spacing, m (1 without a terrain).
    fn half_spacing(&self) -> f64 {
        self.terrain.as_ref().map_or(1.0, |t| 0.5 * t.spacing())
    }

    /// The specular point of the ground reflection from the transmitter `tx` (`[x, y, height
    /// above the terrain]`, at `zs` m above sea level) to the pixel centre `q` (receiver at
    /// `zq`), on the ground line of the path's vertical plane; None where there is none.
    ///
    /// Start from the flat-ground point of the heights above the terrain at both ends, then
    /// reflect the site in the straight line fitted to the terrain over the first Fresnel
    /// zone round the point (least squares: the reflecting area, not one facet of the DEM),
    /// and move the point to where the image's line to the receiver crosses it; four rounds.
    /// The terrain's standard deviation about that line is the roughness.
    fn specular(
        &self,
        tx: [f64; 3],
        q: [f64; 2],
        zs: f64,
        zq: f64,
        lambda: f64,
    ) -> Option<Specular> {
        let [xs, ys, hs] = tx;
        let (ex, ey) = (q[0] - xs, q[1] - ys);
        let rho = ex.hypot(ey);
        let (ux, uy) = (ex / rho, ey / rho);
        let ground_at = |s: f64| {
            let (x, y) = (xs + ux * s, ys + uy * s);
            self.terrain_at(x, y)
        };
        let h = self.half_spacing();
        let (hs_g, hq_g) = (hs, zq - self.terrain_at(q[0], q[1]));
        if hq_g <= 0.0 {
            return None;
        }
        let mut sb = rho * hs_g / (hs_g + hq_g);
        let mut psi = ((hs_g + hq_g) / rho).atan();
        let (mut image, mut line) = ((0.0, 0.0), (0.0, 0.0, 0.0, 0.0, 0.0));
        for _ in 0..4 {
            let a = self.fresnel_half_length(sb, rho - sb, zs, zq, psi, lambda, h);
            let (zb, slope, sigma) = if self.terrain.is_some() {
                fit_line(&ground_at, sb, a)
            } else {
                (0.0, 0.0, 0.0)
            };
            let norm = (1.0 + slope * slope).sqrt();
            let (nx, nz) = (-slope / norm, 1.0 / norm);
            let dist_t = nx * (0.0 - sb) + nz * (zs - zb);
            let dist_r = nx * (rho - sb) + nz * (zq - zb);
            if dist_t <= 0.0 || dist_r <= 0.0 {
                return None;
            }
            image = (-2.0 * dist_t * nx, zs - 2.0 * dist_t * nz);
            let t = dist_t / (dist_t + dist_r);
            let s_new = image.0 + t * (rho - image.0);
            let d2 = ((rho - image.0).powi(2) + (zq - image.1).powi(2)).sqrt();
            psi = ((dist_t + dist_r) / d2).clamp(-1.0, 1.0).asin();
            line = (dist_t, dist_r, zb, sigma, a);
            if !(s_new > 0.0 && s_new < rho) {
                return None;
            }
            sb = s_new;
        }
        let (dist_t, dist_r, zb, sigma, half) = line;
        let d2 = ((rho - image.0).powi(2) + (zq - image.1).powi(2)).sqrt();
        Some(Specular {
            sb,
            zb,
            d2,
            psi: ((dist_t + dist_r) / d2).clamp(-1.0, 1.0).asin(),
            sigma,
            half,
        })
    }

    /// Half the length (m) along the path of the first Fresnel zone's footprint on the ground
    /// round a specular point `s1`, `s2` m (horizontally) from the ends at `zs`, `zq`, seen at
    /// grazing angle `psi`: the zone's radius `sqrt(lambda d1 d2 / (d1 + d2))` over `sin psi`,
    /// at least the terrain's spacing `2 h` (what a DEM does not resolve is not smooth: the
    /// window always spans its neighbouring cells) and at most the shorter leg.
    #[allow(clippy::too_many_arguments)]
    fn fresnel_half_length(
        &self,
        s1: f64,
        s2: f64,
        zs: f64,
        zq: f64,
        psi: f64,
        lambda: f64,
        h: f64,
    ) -> f64 {
        let (d1, d2) = (s1.hypot(zs), s2.hypot(zq));
        let r = (lambda * d1 * d2 / (d1 + d2).max(1e-9)).sqrt();
        (r / psi.sin().max(1e-3)).max(2.0 * h).min(s1.min(s2))
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
mod tests {
    use super::*;
    use ndarray::Array2;

    fn scene<'a>(x: &'a [f64], y: &'a [f64], ground: RayGround) -> RayScene<'a> {
        RayScene {
            x_m: x,
            y_m: y,
            altitude_m: 100.0,
            pixel_m: [0.0, 0.0],
            freq_hz: 4.9e9,
            ground,
            polarization: RayPolarization::H,
            rain: RainField::Uniform(0.0),
            prisms: None,
            heights: None,
            terrain: None,
            altitude_msl: false,
            roughness_m: 0.0,
        }
    }

    fn one(s: &RayScene<'_>, tx: RayTransmitter) -> f64 {
        let g = Array3::<f64>::ones((1, 1, 1));
        s.power(&[tx], g.view(), g.view()).unwrap()[[0, 0, 0]]
    }

    const TX: RayTransmitter = RayTransmitter {
        position_m: [0.0, 0.0, 25.0],
        power_mw: 1.0,
    };

    #[test]
    fn free_space_is_friis() {
        // Friis: P = Pt (lambda / (4 pi d))^2 for isotropic antennas; exact to rounding.
        let (x, y) = ([1000.0], [0.0]);
        let s = scene(&x, &y, RayGround::None);
        let d = (1000.0_f64.powi(2) + 75.0_f64.powi(2)).sqrt();
        let lam = crate::SPEED_OF_LIGHT_M_S / 4.9e9;
        let want = (lam / (4.0 * std::f64::consts::PI * d)).powi(2);
        assert!((one(&s, TX) / want - 1.0).abs() < 1e-12);
    }

    #[test]
    fn pec_two_ray_matches_closed_form_and_averages_to_the_incoherent_sum() {
        // Closed form for a PEC ground, H polarisation: |1/d1 e^{-jk d1} - 1/d2 e^{-jk d2}|^2.
        let (x, y) = ([1000.0], [0.0]);
        let mut s = scene(&x, &y, RayGround::Pec);
        let k = crate::wavenumber(4.9e9);
        let d1 = (1000.0_f64.powi(2) + 75.0_f64.powi(2)).sqrt();
        let d2 = (1000.0_f64.powi(2) + 125.0_f64.powi(2)).sqrt();
        let e = Complex64::from_polar(1.0 / d1, -k * d1) - Complex64::from_polar(1.0 / d2, -k * d2);
        let lam = crate::SPEED_OF_LIGHT_M_S / 4.9e9;
        let scale = (lam / (4.0 * std::f64::consts::PI)).powi(2);
        assert!((one(&s, TX) / (scale * e.norm_sqr()) - 1.0).abs() < 1e-9);
        // A pixel holding many fringes (fringe spacing ~12 m here; 200 m pixel) averages to
        // the incoherent sum within 2% (sinc tails: |sinc| < 0.02 at this width).
        s.pixel_m = [200.0, 200.0];
        let inc = scale * (1.0 / (d1 * d1) + 1.0 / (d2 * d2));
        assert!((one(&s, TX) / inc - 1.0).abs() < 0.02);
    }

    #[test]
    fn dielectric_reflection_limits() {
        // Grazing incidence reflects with -1 for either polarisation; normal incidence gives
        // (1 - sqrt(eps)) / (1 + sqrt(eps)) for H.
        let eps = Complex64::new(15.0, -1.0);
        for p in [RayPolarization::H, RayPolarization::V] {
            let g = reflection_coefficient(RayGround::Dielectric(eps), p, 1e-9);
            assert!((g + 1.0).norm() < 1e-6);
        }
        let g = reflection_coefficient(
            RayGround::Dielectric(eps),
            RayPolarization::H,
            std::f64::consts::FRAC_PI_2,
        );
        let want = (1.0 - eps.sqrt()) / (1.0 + eps.sqrt());
        assert!((g - want).norm() < 1e-12);
    }

    #[test]
    fn uniform_rain_is_gamma_times_length_and_a_raster_of_the_same_value_agrees() {
        let (x, y) = ([800.0], [300.0]);
        let mut s = scene(&x, &y, RayGround::None);
        let clear = one(&s, TX);
        s.rain = RainField::Uniform(0.01);
        let d = (800.0_f64.powi(2) + 300.0_f64.powi(2) + 75.0_f64.powi(2)).sqrt();
        let a = 10.0 * (clear / one(&s, TX)).log10();
        assert!((a - 0.01 * d).abs() < 1e-9);
        let vals = Array2::from_elem((3, 4), 0.01);
        s.rain = RainField::Raster(Raster {
            values: vals.view(),
            origin_step: [0.0, 500.0, 0.0, 500.0],
        });
        let a = 10.0 * (clear / one(&s, TX)).log10();
        assert!((a - 0.01 * d).abs() < 1e-9);
    }

    #[test]
    fn a_building_on_the_path_costs_its_two_isolated_edges() {
        // Transmitter at 25 m, receiver at 100 m, 1000 m away; a 200 m tall wall, 10 m thick,
        // at 500 m. By hand (docs/physics.md section 12): both faces are profile points; the
        // principal edge is the face of larger nu, the other face diffracts on its sub-path;
        // their knife-edge losses add, with no terrain correction (a building, flat ground).
        let (x, y) = ([1000.0], [0.0]);
        let mut s = scene(&x, &y, RayGround::None);
        let clear = one(&s, TX);
        let wall = Prisms::from_boxes(&[[495.0, 505.0, -50.0, 50.0, 200.0]]).unwrap();
        s.prisms = Some(&wall);
        let loss = 10.0 * (clear / one(&s, TX)).log10();
        let lam = crate::SPEED_OF_LIGHT_M_S / 4.9e9;
        let (d, hts, hrs) = (1000.0_f64, 25.0, 100.0);
        let g = |di: f64| 200.0 + di * (d - di) / (2.0 * 8.5e6);
        let nu = |s0: f64, z0: f64, s1: f64, z1: f64, di: f64| {
            let line = z0 + (z1 - z0) * (di - s0) / (s1 - s0);
            (g(di) - line) * (2.0 * (s1 - s0) / (lam * (di - s0) * (s1 - di))).sqrt()
        };
        let (n1, n2) = (nu(0.0, hts, d, hrs, 495.0), nu(0.0, hts, d, hrs, 505.0));
        let want = if n1 >= n2 {
            knife_edge_loss_db(n1) + knife_edge_loss_db(nu(495.0, g(495.0), d, hrs, 505.0))
        } else {
            knife_edge_loss_db(n2) + knife_edge_loss_db(nu(0.0, hts, 505.0, g(505.0), 495.0))
        };
        assert!((loss - want).abs() < 1e-6, "{loss} vs {want}");
    }

    #[test]
    fn a_flat_terrain_at_any_height_is_the_flat_ground() {
        // Terrain at 437 m everywhere: every height is measured from it, so the rays are
        // those of the flat ground at 0 to rounding (the general path against the closed form).
        let x: Vec<f64> = (0..9).map(|k| 120.0 * k as f64 + 5.0).collect();
        let y = [-300.0, 10.0, 700.0];
        let flat = scene(&x, &y, RayGround::Dielectric(Complex64::new(15.0, -1.0)));
        let dem = Array2::from_elem((4, 4), 437.0);
        let mut hilly = flat.clone();
        hilly.terrain = Some(Raster {
            values: dem.view(),
            origin_step: [-2000.0, 1500.0, -2000.0, 1500.0],
        });
        let g = Array3::<f64>::ones((1, 3, 9));
        let a = flat.power(&[TX], g.view(), g.view()).unwrap();
        let b = hilly.power(&[TX], g.view(), g.view()).unwrap();
        for (p, q) in a.iter().zip(b.iter()) {
            assert!((p / q - 1.0).abs() < 1e-9, "{p} vs {q}");
        }
    }

    #[test]
    fn a_ridge_hides_the_reflection_and_costs_the_direct_ray() {
        // A ridge 150 m high between the site and the pixel: the direct ray diffracts, the
        // reflection's legs cannot see its specular point.
        let (x, y) = ([1000.0], [0.0]);
        let mut s = scene(&x, &y, RayGround::Pec);
        let dem = Array2::from_shape_fn((3, 21), |(_, j)| if j == 10 { 150.0 } else { 0.0 });
        s.terrain = Some(Raster {
            values: dem.view(),
            origin_step: [0.0, 50.0, -50.0, 50.0],
        });
        let geo = s.path(TX.position_m, [1000.0, 0.0], &mut s.sight(s.bounds()));
        assert!(geo.reflect < 0.01, "{}", geo.reflect); // faded by the ridge: 40 dB or more
        assert!(geo.loss_db > 10.0, "{}", geo.loss_db);
        // The gain is taken toward the ridge's Bullington point: upward, not along the line.
        assert!(geo.el_direct > (75.0_f64).atan2(1000.0));
    }

    #[test]
    fn the_fresnel_zone_line_fits_a_plane_exactly_and_measures_a_curve_spread() {
        // A straight ground: the line itself, no spread. A parabola over -a..a: the fitted
        // line is its mean (slope 0) and the spread its standard deviation at the 17 points.
        let (z0, slope, sigma) = fit_line(&|s: f64| 2.0 + 0.1 * s, 50.0, 20.0);
        assert!((z0 - 7.0).abs() < 1e-12 && (slope - 0.1).abs() < 1e-12 && sigma < 1e-9);
        let (z0, slope, sigma) = fit_line(&|s: f64| (s - 10.0).powi(2), 10.0, 4.0);
        let u: Vec<f64> = (0..17).map(|i| -4.0 + 0.5 * i as f64).collect();
        let mean = u.iter().map(|v| v * v).sum::<f64>() / 17.0;
        let var = u.iter().map(|v| (v * v - mean).powi(2)).sum::<f64>() / 17.0;
        assert!((z0 - mean).abs() < 1e-9 && slope.abs() < 1e-9);
        assert!((sigma - var.sqrt()).abs() < 1e-9);
    }

    #[test]
    fn bad_inputs_are_errors() {
        let (x, y) = ([1000.0], [0.0]);
        let mut s = scene(&x, &y, RayGround::None);
        s.rain = RainField::Uniform(f64::NAN);
        let g = Array3::<f64>::ones((1, 1, 1));
        assert!(s.power(&[TX], g.view(), g.view()).is_err());
        let s = scene(&x, &y, RayGround::None);
        let g2 = Array3::<f64>::ones((2, 1, 1));
        assert!(s.power(&[TX], g2.view(), g.view()).is_err());
    }
}
