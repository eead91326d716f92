//! Rays through weather that moves (radio maps in time): the rays are traced once
//! ([`RayScene::terms`]: gains, spreading, ground reflection, fringes, knife edges) and each
//! instant adds only its rain ([`slice_power`]).
//!
//! **One integral per site for every pixel at once.** A ray's rain loss is `gamma_bar d`, with
//! `gamma_bar` the mean specific attenuation along the horizontal line from its site to the
//! pixel ([`crate::propagation::rays`]); the cells of a site and both rays share that line. From each site
//! the rain is integrated along `N` lines fanning out at angles `2 pi a / N`, cumulatively, by
//! the trapezoid rule at the raster's node spacing `ds` ([`polar_mean_gamma`]), and each pixel
//! reads its integral by bilinear interpolation in (angle, distance) between the four nearest
//! samples. With `N = ceil(2 pi R / ds)` (`R` the farthest pixel), neighbouring lines are at
//! most `ds` apart anywhere in the map: about `2 pi (R / ds)^2` samples a site (0.5 M for a
//! 2 km map of 10 m nodes) where a line to every pixel takes `H W R / (2 ds)` (6 M).
//!
//! **Accuracy.** Interpolating across lines at most `ds` apart errs by about `(ds / L)^2 / 8`
//! of the loss for rain that varies on a scale `L` (rain cells: `L` of 100 m and more, so
//! below 0.1% of the loss); along a line the trapezoid rule is the static path's own. Tested
//! against the static ray engine and against the closed form through a Gaussian cell.

use ndarray::{Array2, Array3, ArrayView3, ArrayView4, ArrayViewMut3, Axis};
use rayon::prelude::*;

use crate::error::{CoreError, Result};
use crate::propagation::rays::{PixelTerms, RainField, Raster, RayScene, TERMS, line_gamma};

/// The terms a slicer keeps per cell-pixel: direct, reflect, cross, wall, d3 (the lengths d1,
/// d2 are kept per site).
const KEPT: usize = 5;

use std::f64::consts::TAU;

/// The fan of lines from one site over a map: where each pixel reads the cumulative
/// integrals (its line, the fraction to the next line, its distance in node spacings) and how
/// far each line must go. Geometry only: built once, used at every instant.
#[derive(Debug, Clone)]
pub struct Fan {
    from: [f64; 2],
    ds: f64,
    lines: usize,
    places: Vec<(usize, f64, f64)>,
    steps: Vec<usize>,
}

impl Fan {
    /// The fan from `from` to the pixel centres `(x_m[j], y_m[i])` for rain nodes `ds` apart.
    pub fn new(from: [f64; 2], x_m: &[f64], y_m: &[f64], ds: f64) -> Self {
        let w = x_m.len();
        let reach = y_m
            .iter()
            .flat_map(|&y| x_m.iter().map(move |&x| (x - from[0]).hypot(y - from[1])))
            .fold(0.0_f64, f64::max);
        let lines = ((TAU * reach / ds).ceil() as usize).max(16);
        let places: Vec<(usize, f64, f64)> = (0..y_m.len() * w)
            .into_par_iter()
            .map(|p| {
                let (ex, ey) = (x_m[p % w] - from[0], y_m[p / w] - from[1]);
                let fa = ey.atan2(ex).rem_euclid(TAU) / TAU * lines as f64;
                let a0 = (fa.floor() as usize).min(lines - 1);
                (a0, fa - a0 as f64, (ex * ex + ey * ey).sqrt() / ds)
            })
            .collect();
        // Each line goes as far as the farthest pixel that reads it.
        let mut steps = vec![0_usize; lines];
        for &(a0, _, fk) in &places {
            let k = fk as usize + 1;
            steps[a0] = steps[a0].max(k);
            steps[(a0 + 1) % lines] = steps[(a0 + 1) % lines].max(k);
        }
        Fan {
            from,
            ds,
            lines,
            places,
            steps,
        }
    }

    /// The mean specific attenuation (dB/m) of the raster's rain along the line from the site
    /// to every pixel, row-major `(H W)`; the raster's nodes must be `ds` apart (the fan's).
    /// Within a node spacing of the site, the line itself.
    pub fn mean_gamma(&self, r: &Raster<'_>, x_m: &[f64], y_m: &[f64]) -> Vec<f64> {
        let (from, ds, lines, w) = (self.from, self.ds, self.lines, x_m.len());
        // cum[a][k]: the integral of gamma from the site to distance k ds along line a.
        let g0 = r.bilinear(from[0], from[1]);
        let cum: Vec<Vec<f64>> = (0..lines)
            .into_par_iter()
            .map(|a| {
                let (s, c) = (TAU * a as f64 / lines as f64).sin_cos();
                let mut row = Vec::with_capacity(self.steps[a] + 1);
                row.push(0.0);
                let (mut prev, mut acc) = (g0, 0.0);
                for k in 1..=self.steps[a] {
                    let g = r.bilinear(from[0] + c * ds * k as f64, from[1] + s * ds * k as f64);
                    acc += 0.5 * ds * (prev + g);
                    row.push(acc);
                    prev = g;
                }
                row
            })
            .collect();
        self.places
            .par_iter()
            .enumerate()
            .map(|(p, &(a0, wa, fk))| {
                if fk < 1.0 {
                    return line_gamma(r, from, [x_m[p % w], y_m[p / w]]);
                }
                let k0 = fk as usize;
                let wk = fk - k0 as f64;
                let at = |a: usize| cum[a][k0] * (1.0 - wk) + cum[a][k0 + 1] * wk;
                (at(a0) * (1.0 - wa) + at((a0 + 1) % lines) * wa) / (fk * ds)
            })
            .collect()
    }
}

/// The mean specific attenuation (dB/m) of the raster's rain along the horizontal line from
/// `from` to every pixel centre `(x_m[j], y_m[i])`, `(H, W)`, by cumulative integrals along
/// lines fanning out from `from` (module docs; [`Fan`]).
pub fn polar_mean_gamma(r: &Raster<'_>, from: [f64; 2], x_m: &[f64], y_m: &[f64]) -> Array2<f64> {
    let fan = Fan::new(from, x_m, y_m, r.spacing());
    Array2::from_shape_vec((y_m.len(), x_m.len()), fan.mean_gamma(r, x_m, y_m))
        .expect("one value a pixel")
}

/// Every cell's rays over a map, traced once, and the rain of any instant added
/// ([`RaySlicer::power`]): the clear-air terms of [`RayScene::terms`], each site's [`Fan`]
/// and its rays' lengths to every pixel.
#[derive(Debug, Clone)]
pub struct RaySlicer {
    terms: Vec<f64>,
    site_of: Vec<usize>,
    fans: Vec<Fan>,
    lengths: Vec<Vec<(f64, f64)>>,
    x_m: Vec<f64>,
    y_m: Vec<f64>,
}

impl RaySlicer {
    /// From the terms and lengths `(M, H, W, 7)` ([`RayScene::terms`]), the sites (`[x, y,
    /// height]`, m), each cell's site, the pixel centres and the rain nodes' spacing `ds` (m).
    /// A site's rays' lengths are those of its first cell (its cells share their paths).
    pub fn new(
        terms: ArrayView4<'_, f64>,
        sites: &[[f64; 3]],
        site_of: &[usize],
        x_m: &[f64],
        y_m: &[f64],
        ds: f64,
    ) -> Result<Self> {
        let (h, w, m) = (y_m.len(), x_m.len(), site_of.len());
        if h == 0 || w == 0 || !x_m.iter().chain(y_m).all(|v| v.is_finite()) {
            return Err(CoreError::invalid(
                "x_m, y_m",
                "must be finite, not empty",
                "bad",
            ));
        }
        crate::error::check_range("ds", ds, 1e-3, 1e5, "must be in 0.001..1e5 m")?;
        if terms.dim() != (m, h, w, TERMS) {
            return Err(CoreError::invalid(
                "terms",
                format!(
                    "must have shape {:?} (cells, rows, columns, {TERMS})",
                    (m, h, w, TERMS)
                ),
                format!("{:?}", terms.dim()),
            ));
        }
        if !terms.iter().all(|v| v.is_finite()) {
            return Err(CoreError::invalid("terms", "must be finite", "NaN or inf"));
        }
        if let Some(bad) = site_of.iter().find(|&&s| s >= sites.len()) {
            return Err(CoreError::invalid(
                "site_of",
                format!("must index the {} sites", sites.len()),
                bad,
            ));
        }
        if !sites
            .iter()
            .all(|s| s.iter().all(|v| v.is_finite()) && s[2] > 0.0)
        {
            return Err(CoreError::invalid(
                "sites",
                "must be finite, above the ground",
                format!("{sites:?}"),
            ));
        }
        crate::memory::check_memory((KEPT * m + 6 * sites.len()) * h * w * 8)?;
        let fans = sites
            .iter()
            .map(|&[x, y, _]| Fan::new([x, y], x_m, y_m, ds))
            .collect();
        let lengths = (0..sites.len())
            .map(|k| match site_of.iter().position(|&s| s == k) {
                Some(c) => (0..h * w)
                    .map(|p| (terms[[c, p / w, p % w, 3]], terms[[c, p / w, p % w, 4]]))
                    .collect(),
                None => Vec::new(),
            })
            .collect();
        let terms: Vec<f64> = terms
            .as_standard_layout()
            .iter()
            .copied()
            .enumerate()
            .filter(|(k, _)| !matches!(k % TERMS, 3 | 4))
            .map(|(_, v)| v)
            .collect();
        Ok(RaySlicer {
            terms,
            site_of: site_of.to_vec(),
            fans,
            lengths,
            x_m: x_m.to_vec(),
            y_m: y_m.to_vec(),
        })
    }

    /// The power (mW) of every cell at every pixel, `(M, H, W)`, through `rain` (uniform, or
    /// a raster whose nodes are the slicer's `ds` apart): each site's rain integrated once
    /// ([`Fan::mean_gamma`]), each cell's terms attenuated by its site's.
    pub fn power(&self, rain: RainField<'_>) -> Result<Array3<f64>> {
        let (h, w, m) = (self.y_m.len(), self.x_m.len(), self.site_of.len());
        let plane_len = h * w;
        match rain {
            RainField::Uniform(g) => {
                crate::error::check_range("gamma_db_per_m", g, 0.0, 10.0, "must be in 0..10 dB/m")?
            }
            RainField::Raster(r) => {
                crate::propagation::rays::check_raster("rain raster", r.values, r.origin_step)?;
                let ds = self.fans.first().map_or(r.spacing(), |f| f.ds);
                if (r.spacing() - ds).abs() > 1e-9 * ds {
                    return Err(CoreError::invalid(
                        "rain raster",
                        format!("must have nodes {ds} m apart (the slicer's)"),
                        r.spacing(),
                    ));
                }
            }
        }
        crate::memory::check_memory((3 * self.fans.len() + m) * plane_len * 8)?;
        // Per site and pixel: the amplitude factors a1, a2 of the two rays, and gamma.
        let to_amplitude = -std::f64::consts::LN_10 / 20.0;
        let att: Vec<Vec<f64>> = self
            .fans
            .par_iter()
            .zip(self.lengths.par_iter())
            .map(|(fan, lengths)| {
                let gamma = match rain {
                    RainField::Uniform(g) => vec![g; plane_len],
                    RainField::Raster(r) => fan.mean_gamma(&r, &self.x_m, &self.y_m),
                };
                gamma
                    .iter()
                    .zip(lengths)
                    .flat_map(|(g, (d1, d2))| {
                        [
                            (to_amplitude * g * d1).exp(),
                            (to_amplitude * g * d2).exp(),
                            *g,
                        ]
                    })
                    .collect()
            })
            .collect();
        let mut out = Array3::<f64>::zeros((m, h, w));
        out.as_slice_mut()
            .expect("a new array is in standard layout")
            .par_chunks_mut(plane_len)
            .enumerate()
            .for_each(|(c, plane)| {
                let t = &self.terms[KEPT * c * plane_len..KEPT * (c + 1) * plane_len];
                let a = &att[self.site_of[c]];
                for (p, (t, a)) in plane
                    .iter_mut()
                    .zip(t.chunks_exact(KEPT).zip(a.chunks_exact(3)))
                {
                    *p = PixelTerms::combine(t[0], t[1], t[2], a[0], a[1])
                        + PixelTerms::wall_power(t[3], t[4], a[2]);
                }
            });
        Ok(out)
    }
}

/// The power (mW) of every cell at every pixel, `(M, H, W)`, from the clear-air `terms`
/// (`(M, H, W, 7)`, [`RayScene::terms`]) and the rain of `scene` at one instant (a
/// [`RaySlicer`] built and used once).
pub fn slice_power(
    scene: &RayScene<'_>,
    terms: ArrayView4<'_, f64>,
    sites: &[[f64; 3]],
    site_of: &[usize],
) -> Result<Array3<f64>> {
    scene.check()?;
    let ds = match scene.rain {
        RainField::Raster(r) => r.spacing(),
        RainField::Uniform(_) => 1.0,
    };
    RaySlicer::new(terms, sites, site_of, scene.x_m, scene.y_m, ds)?.power(scene.rain)
}

/// The same means as [`polar_mean_gamma`] by a line from `from` to every pixel (the static
/// ray engine's way): the reference it is tested and timed against.
pub fn line_per_pixel(r: &Raster<'_>, from: [f64; 2], x_m: &[f64], y_m: &[f64]) -> Array2<f64> {
    let mut out = Array2::<f64>::zeros((y_m.len(), x_m.len()));
    out.axis_iter_mut(Axis(0))
        .into_par_iter()
        .enumerate()
        .for_each(|(i, mut row)| {
            for (j, v) in row.iter_mut().enumerate() {
                *v = line_gamma(r, from, [x_m[j], y_m[i]]);
            }
        });
    out
}

/// `out = max(10 log10(power), floor_dbm)` as float32 (mW to dBm; 0 mW gives the floor), in
/// parallel: a slice's received powers as a map in time keeps them.
pub fn to_dbm(
    power: ArrayView3<'_, f64>,
    floor_dbm: f64,
    mut out: ArrayViewMut3<'_, f32>,
) -> Result<()> {
    if power.dim() != out.dim() {
        return Err(CoreError::invalid(
            "rss_dbm_out",
            format!("must have shape {:?}", power.dim()),
            format!("{:?}", out.dim()),
        ));
    }
    out.axis_iter_mut(Axis(0))
        .into_par_iter()
        .zip(power.axis_iter(Axis(0)).into_par_iter())
        .for_each(|(mut o, p)| {
            o.zip_mut_with(&p, |o, &p| {
                *o = if p > 0.0 {
                    (10.0 * p.log10()).max(floor_dbm) as f32
                } else {
                    floor_dbm as f32
                }
            });
        });
    Ok(())
}

#[cfg(test)]
mod tests;
