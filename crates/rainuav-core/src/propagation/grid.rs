//! A regular grid of buckets over boxes (the prisms' footprint boxes): the boxes near a point
//! or in a box, and the buckets a segment passes through, in order
//! ([`Buckets::walk`], Amanatides and Woo's traversal).

use crate::error::Result;

/// A regular grid of buckets, each listing the boxes that overlap it (compressed rows:
/// `ids[starts[c]..starts[c + 1]]`, bucket `c = row * nx + col`).
#[derive(Debug, Clone, Default)]
pub(crate) struct Buckets {
    /// The boxes' union, each grown by the margin: `[x0, x1, y0, y1]`.
    pub(crate) bounds: [f64; 4],
    origin: [f64; 2],
    size: f64,
    nx: usize,
    ny: usize,
    starts: Vec<usize>,
    pub(crate) ids: Vec<u32>,
}

impl Buckets {
    /// The grid over `boxes` (`[x0, x1, y0, y1]`), about two buckets a box (at most 2^20),
    /// each box listed in every bucket its box grown by `margin` (m) overlaps.
    pub(crate) fn build(boxes: &[[f64; 4]], margin: f64) -> Result<Self> {
        if boxes.is_empty() {
            return Ok(Self::default());
        }
        let grown = |b: &[f64; 4]| [b[0] - margin, b[1] + margin, b[2] - margin, b[3] + margin];
        let b = boxes.iter().map(grown).fold(
            [
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::INFINITY,
                f64::NEG_INFINITY,
            ],
            |b, p| {
                [
                    b[0].min(p[0]),
                    b[1].max(p[1]),
                    b[2].min(p[2]),
                    b[3].max(p[3]),
                ]
            },
        );
        let (w, h) = ((b[1] - b[0]).max(1.0), (b[3] - b[2]).max(1.0));
        let cells = (2 * boxes.len()).clamp(1, 1 << 20) as f64;
        let size = (w * h / cells).sqrt().max(1.0);
        let nx = ((w / size).ceil() as usize).max(1);
        let ny = ((h / size).ceil() as usize).max(1);
        let mut g = Buckets {
            bounds: b,
            origin: [b[0], b[2]],
            size,
            nx,
            ny,
            starts: vec![0; nx * ny + 1],
            ids: Vec::new(),
        };
        let mut counts = vec![0usize; nx * ny];
        for p in boxes {
            let (c0, c1, r0, r1) = g.range(grown(p));
            for r in r0..=r1 {
                for c in c0..=c1 {
                    counts[r * nx + c] += 1;
                }
            }
        }
        let total: usize = counts.iter().sum();
        crate::memory::check_memory_for("footprints", "use fewer or smaller buildings", total * 4)?;
        for c in 0..nx * ny {
            g.starts[c + 1] = g.starts[c] + counts[c];
        }
        let mut fill = g.starts.clone();
        g.ids = vec![0; total];
        for (k, p) in boxes.iter().enumerate() {
            let (c0, c1, r0, r1) = g.range(grown(p));
            for r in r0..=r1 {
                for c in c0..=c1 {
                    g.ids[fill[r * nx + c]] = k as u32;
                    fill[r * nx + c] += 1;
                }
            }
        }
        Ok(g)
    }

    /// How many buckets.
    pub(crate) fn len(&self) -> usize {
        self.nx * self.ny
    }

    pub(crate) fn col(&self, x: f64) -> usize {
        (((x - self.origin[0]) / self.size).floor().max(0.0) as usize).min(self.nx - 1)
    }

    pub(crate) fn row(&self, y: f64) -> usize {
        (((y - self.origin[1]) / self.size).floor().max(0.0) as usize).min(self.ny - 1)
    }

    /// The buckets (columns `c0..=c1`, rows `r0..=r1`) a box overlaps, clamped to the grid.
    pub(crate) fn range(&self, bbox: [f64; 4]) -> (usize, usize, usize, usize) {
        (
            self.col(bbox[0]),
            self.col(bbox[1]),
            self.row(bbox[2]),
            self.row(bbox[3]),
        )
    }

    /// The boxes listed in bucket `k` (`row * nx + col`).
    pub(crate) fn at(&self, k: usize) -> &[u32] {
        &self.ids[self.starts[k]..self.starts[k + 1]]
    }

    pub(crate) fn bucket(&self, r: usize, c: usize) -> &[u32] {
        self.at(r * self.nx + c)
    }

    /// The buckets the points `a + t d`, `t` in `t0..=t1`, pass through, in order, each
    /// handed to `f(bucket, t_in, t_out)` with the part of `t0..=t1` within it, until `f`
    /// returns false; whether it never did. The part of the segment outside the grid is not
    /// walked; a point on a bucket's edge may be given to either bucket (callers list their
    /// boxes with a margin).
    pub(crate) fn walk(
        &self,
        a: [f64; 2],
        d: [f64; 2],
        (t0, t1): (f64, f64),
        mut f: impl FnMut(usize, f64, f64) -> bool,
    ) -> bool {
        if self.nx == 0 || t1 < t0 {
            return true;
        }
        let (mut c, mut r) = (
            self.col(a[0] + t0 * d[0]) as isize,
            self.row(a[1] + t0 * d[1]) as isize,
        );
        // Per axis: the step between buckets, the `t` of the next bucket edge, and the `t`
        // between edges.
        let axis = |i: isize, o: f64, a: f64, d: f64| {
            if d > 0.0 {
                (1, (o + (i + 1) as f64 * self.size - a) / d, self.size / d)
            } else if d < 0.0 {
                (-1, (o + i as f64 * self.size - a) / d, -self.size / d)
            } else {
                (0, f64::INFINITY, f64::INFINITY)
            }
        };
        let (sx, mut tx, dx) = axis(c, self.origin[0], a[0], d[0]);
        let (sy, mut ty, dy) = axis(r, self.origin[1], a[1], d[1]);
        let mut t_in = t0;
        loop {
            let t_out = tx.min(ty).min(t1).max(t_in);
            if !f(r as usize * self.nx + c as usize, t_in, t_out) {
                return false;
            }
            if t_out >= t1 {
                return true;
            }
            if tx <= ty {
                c += sx;
                tx += dx;
            } else {
                r += sy;
                ty += dy;
            }
            t_in = t_out;
            if c < 0 || r < 0 || c >= self.nx as isize || r >= self.ny as isize {
                return true;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Buckets;

    #[test]
    fn a_walk_reads_the_buckets_along_the_segment_in_order() {
        // 500 boxes over 1 km; 200 segments from outside the grid to inside it and across,
        // some along a row or a column: the parts handed on tile the walked range in order,
        // each bucket holds the middle of its part, and consecutive buckets are neighbours.
        let mut u = crate::test_stream(4);
        let boxes: Vec<[f64; 4]> = (0..500)
            .map(|_| {
                let (x, y) = (1000.0 * u(), 1000.0 * u());
                [x, x + 20.0, y, y + 20.0]
            })
            .collect();
        let g = Buckets::build(&boxes, 0.0).unwrap();
        let (x1, y1) = (
            g.origin[0] + g.nx as f64 * g.size,
            g.origin[1] + g.ny as f64 * g.size,
        );
        for n in 0..200 {
            let a = [1200.0 * u() - 100.0, 1200.0 * u() - 100.0];
            let mut b = [1200.0 * u() - 100.0, 1200.0 * u() - 100.0];
            match n % 5 {
                0 => b[0] = a[0],
                1 => b[1] = a[1],
                _ => {}
            }
            let d = [b[0] - a[0], b[1] - a[1]];
            // The part of the segment over the grid (where the walk starts and ends).
            let (mut t0, mut t1) = (0.0_f64, 1.0_f64);
            for (o, dv, lo, hi) in [(a[0], d[0], g.origin[0], x1), (a[1], d[1], g.origin[1], y1)] {
                if dv == 0.0 {
                    if o < lo || o > hi {
                        (t0, t1) = (1.0, 0.0);
                    }
                } else {
                    let (p, q) = ((lo - o) / dv, (hi - o) / dv);
                    (t0, t1) = (t0.max(p.min(q)), t1.min(p.max(q)));
                }
            }
            if t0 >= t1 {
                continue;
            }
            let mut parts = Vec::new();
            g.walk(a, d, (t0, t1), |k, lo, hi| {
                parts.push((k, lo, hi));
                true
            });
            assert_eq!(parts[0].1, t0);
            assert!((parts[parts.len() - 1].2 - t1).abs() < 1e-12);
            for w in parts.windows(2) {
                assert_eq!(w[0].2, w[1].1, "the parts tile the range");
                let (r0, c0) = (w[0].0 / g.nx, w[0].0 % g.nx);
                let (r1, c1) = (w[1].0 / g.nx, w[1].0 % g.nx);
                assert_eq!(r0.abs_diff(r1) + c0.abs_diff(c1), 1, "neighbours");
            }
            for &(k, lo, hi) in &parts {
                let t = 0.5 * (lo + hi);
                let (x, y) = (a[0] + t * d[0], a[1] + t * d[1]);
                if hi - lo > 1e-9 {
                    assert_eq!(k, g.row(y) * g.nx + g.col(x), "{a:?} -> {b:?} at t = {t}");
                }
            }
        }
    }
}
