//! A whole map's paths and terms: every pixel's geometry from a site, traced once for several
//! sites and read back, and the terms or the power of every cell-pixel (rows in parallel).

use super::*;

impl RayScene<'_> {
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
    /// and power-weighted mean length (m) ([`crate::propagation::walls`]); the rain of the pixel's line
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
    /// each path they give [`RayScene::power_with`]'s power ([`crate::propagation::raytime`]: weather in
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
