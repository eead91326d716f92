//! Line of sight among buildings, terrain and the obstacle raster (docs/physics.md section 12):
//! whether a straight leg of a ray clears everything between its ends.
//!
//! A [`Sight`] holds the scene's upper bounds (the highest terrain node, the tallest roof and
//! raster obstacle) found once, and its scratch space, so that the millions of legs a map of
//! reflected and diffracted rays checks read only the part of each leg low enough to meet
//! something: above the highest terrain plus the tallest obstacle nothing can stand in a
//! line's way, and a building whose roof is below the line where it passes under the line's
//! ground track is skipped without reading its footprint. The answers are those of checking
//! the whole leg: the bounds are exact upper bounds (bilinear terrain never exceeds its
//! highest node).

use crate::propagation::rays::RayScene;

/// Line-of-sight checks on one scene, with its bounds and scratch space (one per thread).
pub struct Sight<'s, 'a> {
    scene: &'s RayScene<'a>,
    /// The highest terrain node, m above sea level (0 without a terrain).
    pub(crate) terrain_top: f64,
    /// The highest the terrain plus the obstacle raster reaches, m above sea level.
    raster_top: f64,
    pub(crate) near: Vec<u32>,
    pub(crate) ts: Vec<f64>,
    /// A path's profile ([`RayScene::profile_over`]).
    pub(crate) prof: Vec<(f64, f64)>,
    /// The terrain alone along it, on the terrain's grid.
    pub(crate) ground: Vec<(f64, f64)>,
}

/// The scene's bounds that a [`Sight`] prunes with: `(terrain_top, raster_top)`.
#[derive(Debug, Clone, Copy)]
pub struct Bounds(f64, f64);

impl<'a> RayScene<'a> {
    /// The scene's upper bounds for [`Sight`]s (a pass over the rasters: find them once a
    /// map, not once a leg).
    pub fn bounds(&self) -> Bounds {
        let top = |r: Option<&crate::propagation::rays::Raster>| {
            r.map_or(0.0, |r| {
                r.values.iter().copied().fold(f64::NEG_INFINITY, f64::max)
            })
        };
        let terrain = top(self.terrain.as_ref());
        Bounds(terrain, terrain + top(self.heights.as_ref()).max(0.0))
    }

    /// Line-of-sight checks with the bounds `b` ([`RayScene::bounds`]).
    pub fn sight<'s>(&'s self, b: Bounds) -> Sight<'s, 'a> {
        Sight {
            scene: self,
            terrain_top: b.0,
            raster_top: b.1,
            near: Vec::new(),
            ts: Vec::new(),
            prof: Vec::new(),
            ground: Vec::new(),
        }
    }
}

impl Sight<'_, '_> {
    /// Whether the straight line from `(a, za)` to `(b, zb)` (ground points, heights above
    /// sea level) passes above every point of the surface's profile between them
    /// ([`RayScene::profile`]): the buildings first (each face the line's ground track
    /// crosses, read just inside it), then the terrain and the obstacle raster every half of
    /// their finest spacing, stopping at the first point in the way.
    pub fn clear(&mut self, a: [f64; 2], za: f64, b: [f64; 2], zb: f64) -> bool {
        self.walk((a, za), (b, zb), false, |_, _| false)
    }

    /// [`Sight::clear`], and afterwards `near` holds every building that could be in the way
    /// (in index order), read whole even where the first already blocks the line.
    pub fn clear_listing(&mut self, a: [f64; 2], za: f64, b: [f64; 2], zb: f64) -> bool {
        self.walk((a, za), (b, zb), true, |_, _| false)
    }

    /// Every point of the surface's profile between `a` and `b` (as [`Sight::clear`] reads
    /// them) at or above the line from `(a, za)` to `(b, zb)`, handed to `seen(t, height)` (`t`
    /// the fraction of the way from `a`, buildings in no particular order) until it returns
    /// false; whether it never did.
    pub fn above(
        &mut self,
        (a, za): ([f64; 2], f64),
        (b, zb): ([f64; 2], f64),
        seen: impl FnMut(f64, f64) -> bool,
    ) -> bool {
        self.walk((a, za), (b, zb), false, seen)
    }

    /// The height `m` that splits the lines from `(a, pa + qa z)` to `(b, pb + qb z)` (ground
    /// points; heights above sea level linear in `z`, `qa, qb >= 0`, not both 0): for every
    /// `z >= z_lo`, [`Sight::clear`] holds for the line at `z` exactly where `z > m`
    /// (`-inf`: nothing in the way). Raising `z` raises the line everywhere between the ends,
    /// so each point of the profile asks for a least `z`; `m` is the largest such ask. What
    /// the line at `z_lo` already clears is not read.
    pub fn lowest(
        &mut self,
        (a, pa, qa): ([f64; 2], f64, f64),
        (b, pb, qb): ([f64; 2], f64, f64),
        z_lo: f64,
    ) -> f64 {
        // The line at z is p(t) + q(t) z; the least z over a point of height h is (h - p) / q.
        let mut m = f64::NEG_INFINITY;
        self.walk((a, pa + qa * z_lo), (b, pb + qb * z_lo), false, |t, h| {
            let (p, q) = (pa + (pb - pa) * t, qa + (qb - qa) * t);
            m = m.max((h - p) / q);
            true
        });
        m
    }

    /// Every point of the surface's profile between `a` and `b` (as [`Sight::clear`] reads
    /// them) at or above the line from `(a, za)` to `(b, zb)`, handed to `seen(t, height)`
    /// until it returns false; whether it never did. What the bounds show to be below the
    /// line is not read. `list`: `near` holds every building that could be in the way.
    fn walk(
        &mut self,
        (a, za): ([f64; 2], f64),
        (b, zb): ([f64; 2], f64),
        list: bool,
        mut seen: impl FnMut(f64, f64) -> bool,
    ) -> bool {
        let s = self.scene;
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let rho = (dx * dx + dy * dy).sqrt();
        if rho < 1e-9 {
            return true;
        }
        let line = |t: f64| za + (zb - za) * t;
        if let Some(prisms) = s.prisms {
            let eps = 1e-9_f64.max(1e-6 / rho);
            let ts = &mut self.ts;
            // Whether building k leaves the line clear (every point of it in the way seen).
            let mut passes = |k: u32| {
                ts.clear();
                prisms.crossings(k as usize, a, b, ts);
                for &t0 in ts.iter() {
                    for t in [t0 - eps, t0 + eps] {
                        if t > 0.0 && t < 1.0 {
                            let (x, y) = (a[0] + t * dx, a[1] + t * dy);
                            let top = s.terrain_at(x, y) + prisms.items()[k as usize].top;
                            if top >= line(t) && prisms.contains(k as usize, x, y) && !seen(t, top)
                            {
                                return false;
                            }
                        }
                    }
                }
                true
            };
            let open = if list {
                prisms.near_segment_under((a, za), (b, zb), self.terrain_top, &mut self.near);
                self.near.iter().all(|&k| passes(k))
            } else {
                prisms.each_under((a, za), (b, zb), self.terrain_top, &mut passes)
            };
            if !open {
                return false;
            }
        }
        let spacing = [s.terrain.as_ref(), s.heights.as_ref()]
            .into_iter()
            .flatten()
            .map(|r| r.spacing())
            .fold(f64::INFINITY, f64::min);
        if !spacing.is_finite() || za.min(zb) > self.raster_top {
            return true;
        }
        let n = ((rho / (0.5 * spacing)).ceil() as usize).max(1);
        for k in 1..n {
            let t = k as f64 / n as f64;
            if line(t) > self.raster_top {
                continue;
            }
            let (x, y) = (a[0] + t * dx, a[1] + t * dy);
            let h = s.terrain_at(x, y) + s.heights.as_ref().map_or(0.0, |r| r.cell(x, y));
            if h >= line(t) && !seen(t, h) {
                return false;
            }
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::propagation::obstacles::Prisms;
    use crate::propagation::rays::{Raster, RayGround};
    use ndarray::Array2;
    use num_complex::Complex64;

    /// 300 boxes 5-60 m tall over 2 km of hills (20 m spacing, 0-40 m), a dielectric ground.
    fn city(dem: &Array2<f64>) -> (Prisms, Raster<'_>) {
        let mut u = crate::test_stream(7);
        let boxes: Vec<[f64; 5]> = (0..300)
            .map(|_| {
                let (x, y) = (2000.0 * u(), 2000.0 * u());
                [
                    x,
                    x + 10.0 + 40.0 * u(),
                    y,
                    y + 10.0 + 40.0 * u(),
                    5.0 + 55.0 * u(),
                ]
            })
            .collect();
        let terrain = Raster {
            values: dem.view(),
            origin_step: [0.0, 20.0, 0.0, 20.0],
        };
        (Prisms::from_boxes(&boxes).unwrap(), terrain)
    }

    fn hills() -> Array2<f64> {
        Array2::from_shape_fn((101, 101), |(i, j)| {
            let (x, y) = (j as f64 / 100.0, i as f64 / 100.0);
            20.0 + 20.0 * (6.0 * x).sin() * (4.0 * y).cos()
        })
    }

    fn scene<'a>(prisms: &'a Prisms, terrain: Option<Raster<'a>>, altitude_m: f64) -> RayScene<'a> {
        RayScene {
            ground: RayGround::Dielectric(Complex64::new(15.0, -1.0)),
            prisms: Some(prisms),
            terrain,
            roughness_m: 0.3,
            ..RayScene::bare(&[], &[], altitude_m, 3.5e9)
        }
    }

    #[test]
    fn a_path_read_where_it_can_matter_is_the_path_read_whole() {
        // The pruning's claim (RayScene::path): leaving out the buildings below the margin
        // changes no geometry, bit for bit, on 3 000 random paths at three heights, over the
        // hills and over flat ground (where the bounds are tight).
        let dem = hills();
        let (prisms, terrain) = city(&dem);
        let mut u = crate::test_stream(11);
        for (altitude, ground) in [10.0, 40.0, 120.0]
            .into_iter()
            .flat_map(|a| [(a, Some(terrain)), (a, None)])
        {
            let s = scene(&prisms, ground, altitude);
            let (mut pruned, mut whole) = (s.sight(s.bounds()), s.sight(s.bounds()));
            let mut lossy = 0;
            for _ in 0..500 {
                let tx = [2000.0 * u(), 2000.0 * u(), 15.0 + 30.0 * u()];
                let q = [2000.0 * u(), 2000.0 * u()];
                let a = s.path_over(tx, q, &mut pruned, true);
                let b = s.path_over(tx, q, &mut whole, false);
                assert_eq!(a, b, "{tx:?} -> {q:?} at {altitude} m");
                lossy += usize::from(a.loss_db > 0.0);
            }
            // The paths are not all clear: the check has diffractions to keep.
            assert!(lossy > 50, "{lossy} diffracted paths at {altitude} m");
        }
    }

    #[test]
    fn the_lowest_clear_height_splits_the_lines_that_clear_from_those_that_do_not() {
        let dem = hills();
        let (prisms, terrain) = city(&dem);
        let s = scene(&prisms, Some(terrain), 30.0);
        let mut sight = s.sight(s.bounds());
        let mut u = crate::test_stream(3);
        let (mut blocked, mut clear) = (0, 0);
        for _ in 0..300 {
            let (a, b) = ([2000.0 * u(), 2000.0 * u()], [2000.0 * u(), 2000.0 * u()]);
            // One end fixed, the other rising with z (a corner's legs), or both rising.
            let (pa, qa) = (40.0 * u() + 10.0, if u() < 0.5 { 0.0 } else { 0.5 * u() });
            let (pb, qb) = (0.0, 0.5 + u());
            let z_lo = 20.0;
            let m = sight.lowest((a, pa, qa), (b, pb, qb), z_lo);
            for k in 0..80 {
                let z = z_lo + k as f64;
                if (z - m).abs() < 1e-6 {
                    continue;
                }
                let seen = sight.clear(a, pa + qa * z, b, pb + qb * z);
                assert_eq!(seen, z > m, "{a:?} -> {b:?} at z = {z}: lowest {m}");
                if seen { clear += 1 } else { blocked += 1 }
            }
        }
        assert!(
            blocked > 1000 && clear > 1000,
            "{blocked} blocked, {clear} clear"
        );
    }
}
